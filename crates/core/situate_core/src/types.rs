//! Signal types.
//!
//! Every port of a skill carries a [`SignalType`]. Producers are matched to
//! consumers by signal name *and* type, so types are compared structurally:
//! two record types are equal when they have the same fields with the same
//! types in the same order.
//!
//! Types have a short textual form used in robot files, manifests and error
//! messages: `bool`, `i64`, `f64`, `string`, `bytes`, `f32[]`, `f64[24]`,
//! `{x: f64, y: f64}`. [`SignalType::parse`] reads it and `Display` writes it.

use std::fmt;
use std::sync::Arc;

/// The element type of a numeric array.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElemType {
    F32,
    F64,
    I64,
}

impl ElemType {
    pub fn name(self) -> &'static str {
        match self {
            ElemType::F32 => "f32",
            ElemType::F64 => "f64",
            ElemType::I64 => "i64",
        }
    }
}

/// The type of a signal or a port.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SignalType {
    Bool,
    I64,
    F64,
    Str,
    Bytes,
    /// A numeric array; `len` is `Some(n)` for a fixed length.
    Array {
        elem: ElemType,
        len: Option<usize>,
    },
    Record(Arc<RecordType>),
}

/// The fields of a record type, in declaration order.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct RecordType {
    pub fields: Vec<(String, SignalType)>,
}

impl RecordType {
    pub fn new(fields: Vec<(String, SignalType)>) -> Self {
        RecordType { fields }
    }

    pub fn field(&self, name: &str) -> Option<(usize, &SignalType)> {
        self.fields.iter().enumerate().find(|(_, (n, _))| n == name).map(|(i, (_, t))| (i, t))
    }
}

impl SignalType {
    pub fn array(elem: ElemType, len: Option<usize>) -> Self {
        SignalType::Array { elem, len }
    }

    pub fn record(fields: Vec<(&str, SignalType)>) -> Self {
        SignalType::Record(Arc::new(RecordType::new(fields.into_iter().map(|(n, t)| (n.to_string(), t)).collect())))
    }

    pub fn as_record(&self) -> Option<&RecordType> {
        match self {
            SignalType::Record(r) => Some(r),
            _ => None,
        }
    }

    /// Whether a value of type `self` (a producer's) may feed a port of type
    /// `consumer`. Equal types always do; a variable-length array port accepts
    /// a fixed-length array of the same element type.
    pub fn feeds(&self, consumer: &SignalType) -> bool {
        match (self, consumer) {
            (SignalType::Array { elem: a, len: la }, SignalType::Array { elem: b, len: lb }) => {
                a == b && (lb.is_none() || la == lb)
            }
            (a, b) => a == b,
        }
    }

    /// Parses the textual form (see the module docs).
    pub fn parse(text: &str) -> Result<SignalType, TypeParseError> {
        let mut p = TypeParser { s: text.as_bytes(), pos: 0, depth: 0 };
        p.skip_ws();
        let t = p.parse_type()?;
        p.skip_ws();
        if p.pos != p.s.len() {
            return Err(p.err("unexpected text after the type"));
        }
        Ok(t)
    }
}

impl fmt::Display for SignalType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SignalType::Bool => f.write_str("bool"),
            SignalType::I64 => f.write_str("i64"),
            SignalType::F64 => f.write_str("f64"),
            SignalType::Str => f.write_str("string"),
            SignalType::Bytes => f.write_str("bytes"),
            SignalType::Array { elem, len: None } => write!(f, "{}[]", elem.name()),
            SignalType::Array { elem, len: Some(n) } => write!(f, "{}[{n}]", elem.name()),
            SignalType::Record(r) => {
                f.write_str("{")?;
                for (i, (name, t)) in r.fields.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    write!(f, "{name}: {t}")?;
                }
                f.write_str("}")
            }
        }
    }
}

/// A type string that does not parse; `column` is 1-based.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct TypeParseError {
    pub column: usize,
    pub message: String,
}

/// The deepest nesting of records a type may have (a type comes from files and the network: its
/// parser recurses once per level).
pub const MAX_TYPE_DEPTH: usize = 32;

struct TypeParser<'a> {
    s: &'a [u8],
    pos: usize,
    /// Records open around the position.
    depth: usize,
}

impl TypeParser<'_> {
    fn err(&self, message: &str) -> TypeParseError {
        TypeParseError { column: self.pos + 1, message: message.to_string() }
    }

    fn skip_ws(&mut self) {
        while self.pos < self.s.len() && self.s[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
    }

    fn ident(&mut self) -> Option<String> {
        let start = self.pos;
        while self.pos < self.s.len() && (self.s[self.pos].is_ascii_alphanumeric() || self.s[self.pos] == b'_') {
            self.pos += 1;
        }
        (self.pos > start).then(|| String::from_utf8_lossy(&self.s[start..self.pos]).into_owned())
    }

    fn eat(&mut self, c: u8) -> bool {
        self.skip_ws();
        if self.s.get(self.pos) == Some(&c) {
            self.pos += 1;
            true
        } else {
            false
        }
    }

    fn parse_type(&mut self) -> Result<SignalType, TypeParseError> {
        self.skip_ws();
        if self.eat(b'{') {
            self.depth += 1;
            if self.depth > MAX_TYPE_DEPTH {
                return Err(self.err(&format!("records nest too deeply (more than {MAX_TYPE_DEPTH} levels)")));
            }
            let mut fields: Vec<(String, SignalType)> = Vec::new();
            loop {
                self.skip_ws();
                if self.eat(b'}') {
                    break;
                }
                let name = self.ident().ok_or_else(|| self.err("expected a field name"))?;
                if fields.iter().any(|(n, _)| *n == name) {
                    return Err(self.err(&format!("duplicate field `{name}`")));
                }
                if !self.eat(b':') {
                    return Err(self.err("expected `:` after the field name"));
                }
                let t = self.parse_type()?;
                fields.push((name, t));
                self.skip_ws();
                if self.eat(b',') {
                    continue;
                }
                if self.eat(b'}') {
                    break;
                }
                return Err(self.err("expected `,` or `}`"));
            }
            self.depth -= 1;
            return Ok(SignalType::Record(Arc::new(RecordType::new(fields))));
        }
        let start = self.pos;
        let name = self.ident().ok_or_else(|| self.err("expected a type"))?;
        let scalar = match name.as_str() {
            "bool" => Some(SignalType::Bool),
            "i64" | "int" => Some(SignalType::I64),
            "f64" | "float" => Some(SignalType::F64),
            "string" | "str" => Some(SignalType::Str),
            "bytes" => Some(SignalType::Bytes),
            _ => None,
        };
        let elem = match name.as_str() {
            "f32" => Some(ElemType::F32),
            "f64" | "float" => Some(ElemType::F64),
            "i64" | "int" => Some(ElemType::I64),
            _ => None,
        };
        if self.eat(b'[') {
            let Some(elem) = elem else {
                self.pos = start;
                return Err(self.err(&format!("arrays hold f32, f64 or i64, not `{name}`")));
            };
            self.skip_ws();
            let len_start = self.pos;
            while self.pos < self.s.len() && self.s[self.pos].is_ascii_digit() {
                self.pos += 1;
            }
            let len = if self.pos > len_start {
                let digits = std::str::from_utf8(&self.s[len_start..self.pos]).unwrap_or("0");
                Some(digits.parse::<usize>().map_err(|_| self.err("array length too large"))?)
            } else {
                None
            };
            if !self.eat(b']') {
                return Err(self.err("expected `]`"));
            }
            return Ok(SignalType::Array { elem, len });
        }
        scalar.ok_or_else(|| {
            self.pos = start;
            TypeParseError {
                column: start + 1,
                message: format!(
                    "unknown type `{name}` (expected bool, i64, f64, string, bytes, f32[N], f64[], {{field: type, ...}})"
                ),
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_and_parse_round_trip() {
        for text in [
            "bool",
            "i64",
            "f64",
            "string",
            "bytes",
            "f32[]",
            "f64[24]",
            "{x: f64, y: f64}",
            "{range: f32[24], ok: {a: bool}}",
        ] {
            let t = SignalType::parse(text).unwrap();
            assert_eq!(t.to_string(), text);
        }
    }

    #[test]
    fn records_nested_past_the_limit_are_an_error_not_a_stack_overflow() {
        let nested = |n: usize| format!("{}f64{}", "{a: ".repeat(n), "}".repeat(n));
        assert!(SignalType::parse(&nested(MAX_TYPE_DEPTH)).is_ok());
        let e = SignalType::parse(&nested(MAX_TYPE_DEPTH + 1)).unwrap_err();
        assert!(e.message.contains("nest too deeply"), "{e}");
        // A hundred thousand levels, as a hostile file may hold: refused at the limit.
        let e = SignalType::parse(&"{a:".repeat(100_000)).unwrap_err();
        assert!(e.column <= 3 * (MAX_TYPE_DEPTH + 1), "refused at the limit, not at the end: {e}");
    }

    #[test]
    fn parse_errors_point_at_the_column() {
        let e = SignalType::parse("{x: f64, y: quux}").unwrap_err();
        assert_eq!(e.column, 13);
        assert!(e.message.contains("quux"));
        let e = SignalType::parse("bool[3]").unwrap_err();
        assert!(e.message.contains("arrays hold"), "{e}");
    }

    #[test]
    fn fixed_arrays_feed_variable_ports_but_not_the_reverse() {
        let fixed = SignalType::array(ElemType::F32, Some(24));
        let var = SignalType::array(ElemType::F32, None);
        assert!(fixed.feeds(&var));
        assert!(!var.feeds(&fixed));
        assert!(!fixed.feeds(&SignalType::array(ElemType::F64, None)));
    }
}
