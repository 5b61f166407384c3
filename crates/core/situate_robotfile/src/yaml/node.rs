//! The node tree: positions, positioned values, and YAML nodes typed by the
//! core schema.

use std::fmt;
use std::sync::Arc;

use situate_core::value::Value;
use yaml_rust2::scanner::Marker;

/// A position in a source file; line and column both start at 1. Columns
/// count characters (not bytes). `src` says which file: 0 for the file
/// parsed, and for a robot file that includes others, the index of the
/// included file in [`RobotFile::sources`](crate::config::RobotFile::sources)
/// (positions order by file first).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Pos {
    pub src: usize,
    pub line: usize,
    pub col: usize,
}

impl Pos {
    /// Line 1, column 1.
    pub const START: Pos = Pos { src: 0, line: 1, col: 1 };

    pub fn new(line: usize, col: usize) -> Pos {
        Pos { src: 0, line, col }
    }

    /// This position in source file `src`.
    pub fn in_src(self, src: usize) -> Pos {
        Pos { src, ..self }
    }

    /// `yaml-rust2` markers have a 1-based line and a 0-based column.
    pub(super) fn from_marker(m: &Marker) -> Pos {
        Pos { src: 0, line: m.line().max(1), col: m.col() + 1 }
    }
}

impl Default for Pos {
    fn default() -> Pos {
        Pos::START
    }
}

impl fmt::Display for Pos {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.col)
    }
}

/// A value together with the position it was read from.
#[derive(Debug, Clone, PartialEq)]
pub struct Spanned<T> {
    pub value: T,
    pub pos: Pos,
}

impl<T> Spanned<T> {
    pub fn new(value: T, pos: Pos) -> Spanned<T> {
        Spanned { value, pos }
    }

    /// The same position with another value.
    pub fn map<U>(self, f: impl FnOnce(T) -> U) -> Spanned<U> {
        Spanned { value: f(self.value), pos: self.pos }
    }
}

/// One YAML node.
#[derive(Debug, Clone, PartialEq)]
pub enum Node {
    /// `null`, `~` or nothing at all.
    Null,
    /// A scalar's text; `plain` is false for quoted and block (`|`, `>`)
    /// scalars, which are always strings.
    Scalar { text: String, plain: bool },
    /// A list.
    Seq(Vec<Spanned<Node>>),
    /// A mapping, in file order; keys are unique.
    Map(Vec<(Spanned<String>, Spanned<Node>)>),
}

impl Node {
    /// A plain scalar, as typed by the YAML 1.2 core schema.
    pub fn plain(text: &str) -> Node {
        Node::Scalar { text: text.to_string(), plain: true }
    }

    /// A quoted scalar: always a string.
    pub fn quoted(text: &str) -> Node {
        Node::Scalar { text: text.to_string(), plain: false }
    }

    /// The scalar's value: `Bool`, `I64`, `F64` or `Str`. `None` for null,
    /// lists and mappings.
    pub fn to_value(&self) -> Option<Value> {
        match self {
            Node::Scalar { text, plain: true } => Some(type_plain(text)),
            Node::Scalar { text, plain: false } => Some(Value::Str(Arc::from(text.as_str()))),
            _ => None,
        }
    }

    /// A list of numbers as `Value::F64s` (integers widen); `None` if this is
    /// not a list or an item is not a number.
    pub fn to_f64s(&self) -> Option<Value> {
        match self {
            Node::Seq(items) => {
                let xs: Option<Vec<f64>> = items.iter().map(|n| n.value.as_f64()).collect();
                xs.map(|xs| Value::F64s(xs.into()))
            }
            _ => None,
        }
    }

    /// A scalar number (integer or float) as `f64`.
    pub fn as_f64(&self) -> Option<f64> {
        match self.to_value()? {
            Value::I64(x) => Some(x as f64),
            Value::F64(x) => Some(x),
            _ => None,
        }
    }

    /// A scalar integer.
    pub fn as_i64(&self) -> Option<i64> {
        match self.to_value()? {
            Value::I64(x) => Some(x),
            _ => None,
        }
    }

    /// A scalar boolean.
    pub fn as_bool(&self) -> Option<bool> {
        match self.to_value()? {
            Value::Bool(b) => Some(b),
            _ => None,
        }
    }

    /// A plain scalar written as an integer (`42`, `-7`, `0x1f`, `0o17`),
    /// whether or not it fits in 64 bits.
    pub fn is_integer_literal(&self) -> bool {
        let Node::Scalar { text, plain: true } = self else { return false };
        let digits = |s: &str, radix: u32| !s.is_empty() && s.chars().all(|c| c.is_digit(radix));
        match (text.strip_prefix("0x"), text.strip_prefix("0o")) {
            (Some(hex), _) => digits(hex, 16),
            (_, Some(oct)) => digits(oct, 8),
            _ => digits(text.strip_prefix(['-', '+']).unwrap_or(text), 10),
        }
    }

    /// The source text of any scalar (plain or quoted, whatever its type).
    pub fn as_text(&self) -> Option<&str> {
        match self {
            Node::Scalar { text, .. } => Some(text),
            _ => None,
        }
    }

    pub fn is_null(&self) -> bool {
        matches!(self, Node::Null)
    }

    /// The entries of a mapping.
    pub fn as_map(&self) -> Option<&[(Spanned<String>, Spanned<Node>)]> {
        match self {
            Node::Map(entries) => Some(entries),
            _ => None,
        }
    }

    /// The items of a list.
    pub fn as_seq(&self) -> Option<&[Spanned<Node>]> {
        match self {
            Node::Seq(items) => Some(items),
            _ => None,
        }
    }

    /// A mapping's value for `key`.
    pub fn get(&self, key: &str) -> Option<&Spanned<Node>> {
        self.as_map()?.iter().find(|(k, _)| k.value == key).map(|(_, v)| v)
    }

    /// What kind of node this is, with an article: "a list", "a string", …
    pub fn kind_name(&self) -> &'static str {
        match self {
            Node::Null => "null",
            Node::Seq(_) => "a list",
            Node::Map(_) => "a mapping",
            Node::Scalar { .. } => match self.to_value() {
                Some(Value::Bool(_)) => "a boolean",
                Some(Value::I64(_)) => "an integer",
                Some(Value::F64(_)) => "a number",
                _ => "a string",
            },
        }
    }

    /// How the node reads in an error message after "got": scalars as
    /// written (strings quoted, long ones shortened), others by kind.
    pub fn describe(&self) -> String {
        match self {
            Node::Scalar { text, .. } => match self.to_value() {
                Some(Value::Str(_)) => {
                    let short: String = text.chars().take(40).collect();
                    if short.len() < text.len() {
                        format!("{:?}", short + "…")
                    } else {
                        format!("{text:?}")
                    }
                }
                _ => text.clone(),
            },
            other => other.kind_name().to_string(),
        }
    }
}

/// Types a plain scalar by the YAML 1.2 core schema (null is handled by the
/// tree builder).
fn type_plain(text: &str) -> Value {
    match text {
        "true" | "True" | "TRUE" => return Value::Bool(true),
        "false" | "False" | "FALSE" => return Value::Bool(false),
        ".inf" | ".Inf" | ".INF" | "+.inf" | "+.Inf" | "+.INF" => return Value::F64(f64::INFINITY),
        "-.inf" | "-.Inf" | "-.INF" => return Value::F64(f64::NEG_INFINITY),
        ".nan" | ".NaN" | ".NAN" => return Value::F64(f64::NAN),
        _ => {}
    }
    let radix = |prefix: &str, radix: u32| {
        text.strip_prefix(prefix)
            .filter(|d| !d.is_empty() && d.chars().all(|c| c.is_digit(radix)))
            .and_then(|d| i64::from_str_radix(d, radix).ok())
    };
    if let Some(x) = radix("0x", 16).or_else(|| radix("0o", 8)) {
        return Value::I64(x);
    }
    let digits = text.strip_prefix(['-', '+']).unwrap_or(text);
    if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
        return match text.parse::<i64>() {
            Ok(x) => Value::I64(x),
            // Too large for i64: keep the magnitude as a float.
            Err(_) => Value::F64(text.parse::<f64>().unwrap_or(f64::NAN)),
        };
    }
    if is_core_float(digits) {
        if let Ok(x) = text.parse::<f64>() {
            return Value::F64(x);
        }
    }
    Value::Str(Arc::from(text))
}

/// `(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?`, the sign already removed.
fn is_core_float(s: &str) -> bool {
    fn digits(s: &str) -> usize {
        s.bytes().take_while(u8::is_ascii_digit).count()
    }
    let int = digits(s);
    let mut rest = &s[int..];
    let mut frac = 0;
    if let Some(r) = rest.strip_prefix('.') {
        frac = digits(r);
        rest = &r[frac..];
    }
    if int == 0 && frac == 0 {
        return false;
    }
    if let Some(r) = rest.strip_prefix(['e', 'E']) {
        let r = r.strip_prefix(['-', '+']).unwrap_or(r);
        let exp = digits(r);
        return exp > 0 && exp == r.len();
    }
    rest.is_empty()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::yaml::parse;

    fn p(line: usize, col: usize) -> Pos {
        Pos::new(line, col)
    }

    #[test]
    fn plain_scalars_follow_the_core_schema() {
        let cases: &[(&str, Option<Value>)] = &[
            ("true", Some(Value::Bool(true))),
            ("FALSE", Some(Value::Bool(false))),
            ("-3", Some(Value::I64(-3))),
            ("+7", Some(Value::I64(7))),
            ("0x1f", Some(Value::I64(31))),
            ("0o17", Some(Value::I64(15))),
            ("0.5", Some(Value::F64(0.5))),
            ("1e-3", Some(Value::F64(1e-3))),
            ("-.5E+2", Some(Value::F64(-50.0))),
            ("3.", Some(Value::F64(3.0))),
            (".inf", Some(Value::F64(f64::INFINITY))),
            ("-.inf", Some(Value::F64(f64::NEG_INFINITY))),
            ("inf", Some(Value::Str("inf".into()))),
            ("nan", Some(Value::Str("nan".into()))),
            ("1e", Some(Value::Str("1e".into()))),
            (".", Some(Value::Str(".".into()))),
            ("0x", Some(Value::Str("0x".into()))),
            ("yes", Some(Value::Str("yes".into()))),
            ("toy.sonar", Some(Value::Str("toy.sonar".into()))),
            ("99999999999999999999", Some(Value::F64(1e20))),
        ];
        for (text, want) in cases {
            let src = format!("v: {text}\n");
            let root = parse(&src).unwrap();
            assert_eq!(&root.value.get("v").unwrap().value.to_value(), want, "{text}");
        }
        let root = parse("v: .nan\n").unwrap();
        assert!(root.value.get("v").unwrap().value.as_f64().unwrap().is_nan());
        // An empty value sits at its key; an explicit null where it is.
        let root = parse("a:\n  b:\n  c: ~\n").unwrap();
        let a = &root.value.get("a").unwrap().value;
        assert_eq!(a.get("b"), Some(&Spanned::new(Node::Null, p(2, 3))));
        assert_eq!(a.get("c"), Some(&Spanned::new(Node::Null, p(3, 6))));
        for text in ["", "~", "null", "Null", "NULL"] {
            let root = parse(&format!("v: {text}\n")).unwrap();
            assert_eq!(root.value.get("v").unwrap().value, Node::Null, "{text:?}");
        }
    }

    #[test]
    fn quoted_and_block_scalars_are_strings() {
        let root = parse("a: \"3\"\nb: 'true'\nc: \"null\"\nd: |\n  5\n").unwrap();
        let v = |k: &str| root.value.get(k).unwrap().value.to_value();
        assert_eq!(v("a"), Some(Value::Str("3".into())));
        assert_eq!(v("b"), Some(Value::Str("true".into())));
        assert_eq!(v("c"), Some(Value::Str("null".into())));
        assert_eq!(v("d"), Some(Value::Str("5\n".into())));
        assert_eq!(root.value.get("a").unwrap().pos, p(1, 4));
        assert_eq!(root.value.get("d").unwrap().pos, p(5, 3));
    }

    #[test]
    fn describe_quotes_strings_only() {
        assert_eq!(Node::plain("fast").describe(), "\"fast\"");
        assert_eq!(Node::plain("0").describe(), "0");
        assert_eq!(Node::quoted("0").describe(), "\"0\"");
        assert_eq!(Node::Seq(vec![]).describe(), "a list");
        assert_eq!(Node::Null.describe(), "null");
        let long = Node::plain(&"x".repeat(100)).describe();
        assert_eq!(long, format!("\"{}…\"", "x".repeat(40)));
    }
}
