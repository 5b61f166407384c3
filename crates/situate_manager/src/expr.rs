//! The monitor condition language.
//!
//! A monitor watches a condition over signal values and fires when it holds,
//! for example
//!
//! ```text
//! sonar.range[0] < 0.25 && barcode.id == 3
//! ```
//!
//! Conditions arrive as text (from the sequencer, possibly over the network).
//! [`Condition::compile`] parses and type-checks the text once, resolving
//! every name through a caller-given [`Resolver`]; [`Condition::eval`] then
//! evaluates it every cycle against the current values handed out by a
//! [`Lookup`], without allocating.
//!
//! # Grammar
//!
//! From lowest to highest precedence:
//!
//! ```text
//! condition := or
//! or        := and ( "||" and )*
//! and       := equality ( "&&" equality )*
//! equality  := compare ( ( "==" | "!=" ) compare )?            does not chain
//! compare   := sum ( ( "<" | "<=" | ">" | ">=" ) sum )?         does not chain
//! sum       := product ( ( "+" | "-" ) product )*              left to right
//! product   := unary ( ( "*" | "/" | "%" ) unary )*            left to right
//! unary     := ( "!" | "-" ) unary | postfix
//! postfix   := primary ( "[" or "]" )*
//! primary   := number | string | "true" | "false" | name | call | "(" or ")"
//! call      := name "(" ( or ( "," or )* )? ")"
//! name      := ident ( "." ident )*        ident := [A-Za-z_][A-Za-z0-9_]*
//! number    := digits ( "." digits )? ( ( "e" | "E" ) ( "+" | "-" )? digits )?
//! string    := '"' chars '"' | "'" chars "'"     escapes: \\  \"  \'
//! ```
//!
//! Spaces, tabs and line breaks may separate tokens, but not the parts of a
//! dotted name. A number needs a digit before its decimal point (`0.5`, not
//! `.5`). `a < b < c` is an error (write `a < b && b < c`); so is
//! `a == b == c` (add parentheses). `-x[0]` is `-(x[0])`.
//!
//! A name is the whole dotted path as written (`sonar.range`,
//! `runaway.safe_distance`, `pose.x`); the [`Resolver`] decides what it means
//! and what type it has. A name directly followed by `(` is a function call.
//!
//! # Types
//!
//! | type   | comes from                            | operators                             |
//! |--------|---------------------------------------|---------------------------------------|
//! | bool   | `bool` signals, `true`, `false`, comparisons | `!` `&&` `\|\|` `==` `!=`      |
//! | number | `i64` and `f64` signals, literals, `x[i]` | `-` `+ - * / %` `< <= > >=` `== !=` |
//! | string | `string` signals, literals            | `==` `!=`, `len`                      |
//! | array  | `f32[]`, `f64[]`, `i64[]` signals     | `x[i]`, `len`                         |
//! | bytes  | `bytes` signals                       | `len`                                 |
//!
//! All numbers are `f64` when evaluated: `i64` values and `f32`/`i64` array
//! elements convert to `f64` (so an `f32` element holding `0.1` is not
//! `== 0.1`; compare with `<`/`>` instead). Records cannot be used whole:
//! name one of their fields (`pose.x`, not `pose`). `==` and `!=` need two
//! values of the same type, bool, number or string. The whole condition must
//! be a bool.
//!
//! Functions:
//!
//! - `abs(x)`: the absolute value of a number;
//! - `min(a, b, …)`, `max(a, b, …)`: the smallest / largest of two or more
//!   numbers (NaN if any of them is NaN);
//! - `len(x)`: the length of an array, or of a string or bytes value in bytes.
//!
//! `x[i]` is element `i` (counting from 0) of the array `x`; `i` may be any
//! number expression. A constant index that is negative or not a whole number
//! (`x[-1]`, `x[0.5]`) is a compile error.
//!
//! # Missing values
//!
//! A signal may have no value yet, an index may be out of range at run time,
//! and a number may be NaN. Evaluation is three-valued: a missing value makes
//! every operator that needs it missing, and [`Condition::eval`] returns
//! `None`, which the caller treats as "does not hold". The exceptions are
//! `&&` and `||`, which evaluate left to right, stop as soon as the result is
//! known, and follow Kleene's logic: `missing || true` is `true` and
//! `missing && false` is `false`.
//!
//! - A comparison with NaN on either side (`<`, `==`, `!=`, …) is missing.
//! - An index that is negative, not a whole number or out of range is
//!   missing.
//! - Division by zero follows IEEE 754: `1 / 0` is infinity, `0 / 0` and
//!   `x % 0` are NaN.
//!
//! # Limits
//!
//! Conditions may come from untrusted peers, so a source is at most
//! [`MAX_SOURCE_BYTES`] bytes, nests at most [`MAX_DEPTH`] levels (each
//! `(`, `[`, function call and unary operator is a level) and has at most
//! [`MAX_NODES`] parts (literals, names, operators, calls, indexings).
//! Exceeding any of them is a compile error. No input makes compilation or
//! evaluation panic.
//!
//! # Examples
//!
//! ```text
//! sonar.range[0] < 0.25 && barcode.id == 3
//! min(sonar.range[0], sonar.range[1], sonar.range[23]) < runaway.safe_distance
//! abs(odom.speed) > 0.5 || !motors.enabled
//! len(sonar.range) > 0 && sonar.range[len(sonar.range) - 1] >= 1e-3
//! label == 'dock' && battery.level % 10 != 0
//! ```
//!
//! # Errors
//!
//! A compile error carries a 1-based column, in characters, and a message
//! that says what is wrong; type errors name the operator and the types
//! involved, e.g. for `label < 3`:
//!
//! ```text
//! column 7: `<` needs two numbers, got a string and a number
//! label < 3
//!       ^
//! ```

use situate_core::{SignalType, Value};

/// The longest accepted condition source, in bytes.
pub const MAX_SOURCE_BYTES: usize = 4096;
/// The deepest accepted nesting of `(`, `[`, function calls and unary
/// operators.
pub const MAX_DEPTH: usize = 64;
/// The most parts (literals, names, operators, calls, indexings) a condition
/// may have.
pub const MAX_NODES: usize = 256;

/// The caller resolves a dotted name to an id of its choice and the type found there.
pub trait Resolver {
    /// `path` is the whole dotted name as written, e.g. "sonar.range" or "runaway.safe_distance".
    /// Err(message) is reported as the compile error for that name (at its column); the message
    /// already names the problem (e.g. "unknown signal `sonr` — did you mean `sonar`?").
    fn resolve(&self, path: &str) -> Result<(usize, SignalType), String>;
}

/// At evaluation time the caller hands out current values by id; None = no value yet.
pub trait Lookup {
    /// The current value with id `id` (as the resolver handed it out), or None if there is none yet.
    fn value(&self, id: usize) -> Option<&Value>;
}

/// A compile error; `column` is 1-based, in characters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct ExprError {
    /// 1-based, in characters (not bytes).
    pub column: usize,
    /// What is wrong, without the column.
    pub message: String,
}

impl ExprError {
    /// Two lines: the source, then a caret under the column ("    ^").
    ///
    /// Line breaks in the source are shown as spaces and tabs are repeated in
    /// the caret line, so the caret stays under the right character.
    pub fn pointer(&self, source: &str) -> String {
        let mut line = String::with_capacity(source.len());
        let mut caret = String::new();
        let before = self.column.saturating_sub(1);
        let mut count = 0;
        for ch in source.chars() {
            let ch = if ch == '\n' || ch == '\r' { ' ' } else { ch };
            line.push(ch);
            if count < before {
                caret.push(if ch == '\t' { '\t' } else { ' ' });
            }
            count += 1;
        }
        for _ in count..before {
            caret.push(' ');
        }
        caret.push('^');
        format!("{line}\n{caret}")
    }
}

/// A compiled condition.
#[derive(Debug, Clone)]
pub struct Condition {
    source: String,
    program: Program,
    ref_names: Vec<String>,
}

impl Condition {
    /// Parses and type-checks `source`, resolving its names with `resolver`.
    pub fn compile(source: &str, resolver: &dyn Resolver) -> Result<Condition, ExprError> {
        let (program, ref_names, _) = compile_program(source, resolver, "condition", |ty| {
            (ty != Ty::Bool).then(|| format!("a monitor condition must be true or false, this is {}", ty.name()))
        })?;
        Ok(Condition { source: source.to_string(), program, ref_names })
    }

    /// The source it was compiled from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The resolved ids it reads, each once, in first-use order (for reporting values when it fires).
    pub fn refs(&self) -> &[usize] {
        &self.program.refs
    }

    /// Maps every reference id through `map` (a condition compiled with
    /// local ids, made the evaluator's own).
    pub(crate) fn remap_refs(&mut self, map: impl Fn(usize) -> usize) {
        for r in &mut self.program.refs {
            *r = map(*r);
        }
    }

    /// The dotted names, same order as refs().
    pub fn ref_names(&self) -> &[String] {
        &self.ref_names
    }

    /// Some(true/false), or None when a value it needs is missing (no value yet, index out of
    /// range, NaN compared): the caller treats None as "does not hold".
    pub fn eval(&self, lookup: &dyn Lookup) -> Option<bool> {
        self.program.bool_at(self.program.root, lookup)
    }
}

/// Parses and type-checks `source` (a condition or a formula), resolving its
/// names with `resolver`; `want` refuses the whole expression's type with a
/// message (None: accepted).
fn compile_program(
    source: &str,
    resolver: &dyn Resolver,
    noun: &'static str,
    want: impl Fn(Ty) -> Option<String>,
) -> Result<(Program, Vec<String>, Ty), ExprError> {
    if source.len() > MAX_SOURCE_BYTES {
        return Err(ExprError {
            column: 1,
            message: format!("the {noun} is too long: {} bytes, at most {MAX_SOURCE_BYTES}", source.len()),
        });
    }
    let toks = lex(source)?;
    let mut p = Parser {
        src: source,
        toks,
        pos: 0,
        depth: 0,
        resolver,
        program: Program::default(),
        ref_names: Vec::new(),
        fixed: Vec::new(),
        noun,
    };
    if p.peek().tok == Tok::End {
        return Err(p.err(0, format!("the {noun} is empty")));
    }
    let e = p.parse_expr()?;
    if p.peek().tok != Tok::End {
        return Err(p.unexpected(&format!("an operator or the end of the {noun}")));
    }
    if let Some(message) = want(e.ty) {
        return Err(p.err(e.at, message));
    }
    p.program.root = e.node;
    Ok((p.program, p.ref_names, e.ty))
}

/// A compiled formula: an expression of the condition language whose value is
/// a number (or a bool, read as 1 or 0), such as `abs(drive.w) * 2`,
/// `odom.x * odom.x + odom.y * odom.y` or `sonar.range[0] < 0.25`: a derived
/// series to plot. The same grammar, types and missing-value rules as a
/// [`Condition`].
#[derive(Debug, Clone)]
pub struct Formula {
    source: String,
    program: Program,
    ref_names: Vec<String>,
    boolean: bool,
}

impl Formula {
    /// Parses and type-checks `source`, resolving its names with `resolver`:
    /// it must be a number or a bool.
    pub fn compile(source: &str, resolver: &dyn Resolver) -> Result<Formula, ExprError> {
        let (program, ref_names, ty) = compile_program(source, resolver, "formula", |ty| {
            (!matches!(ty, Ty::Num | Ty::Bool))
                .then(|| format!("a formula to plot must be a number or true/false, this is {}", ty.name()))
        })?;
        Ok(Formula { source: source.to_string(), program, ref_names, boolean: ty == Ty::Bool })
    }

    /// The source it was compiled from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The resolved ids it reads, each once, in first-use order.
    pub fn refs(&self) -> &[usize] {
        &self.program.refs
    }

    /// The dotted names, same order as refs().
    pub fn ref_names(&self) -> &[String] {
        &self.ref_names
    }

    /// Its value (a bool as 1 or 0), or None when a value it needs is missing
    /// or the result is not a finite number.
    pub fn eval(&self, lookup: &dyn Lookup) -> Option<f64> {
        let v = if self.boolean {
            f64::from(u8::from(self.program.bool_at(self.program.root, lookup)?))
        } else {
            self.program.num_at(self.program.root, lookup)?
        };
        v.is_finite().then_some(v)
    }
}

// ---------------------------------------------------------------------------
// Representation: a typed tree of enums in one arena.
//
// Every node's type is known after compilation, so evaluation dispatches on
// the expected type (`bool_at`, `num_at`, `str_at`, ...) and never builds a
// dynamically typed value. Children are indices into `nodes`; function
// arguments of `min`/`max` are a range of `args`. Evaluation recurses at most
// as deep as the tree, which is bounded by `MAX_NODES`.

#[derive(Debug, Clone, Default)]
struct Program {
    nodes: Vec<Node>,
    args: Vec<u32>,
    refs: Vec<usize>,
    root: u32,
}

#[derive(Debug, Clone)]
enum Node {
    Bool(bool),
    Num(f64),
    Str(Box<str>),
    /// The current value of `refs[slot]`; its type is the one the context expects.
    Ref(u32),
    Not(u32),
    And(u32, u32),
    Or(u32, u32),
    /// A comparison of two numbers.
    Cmp(CmpOp, u32, u32),
    /// `==` (true) or `!=` (false) of two bools.
    EqBool(bool, u32, u32),
    /// `==` (true) or `!=` (false) of two strings.
    EqStr(bool, u32, u32),
    Neg(u32),
    Arith(ArithOp, u32, u32),
    Abs(u32),
    /// `min` (false) or `max` (true) of `args[start..start + len]`.
    MinMax {
        max: bool,
        start: u32,
        len: u32,
    },
    /// Element of an array (a `Ref`) at a number.
    Index(u32, u32),
    /// Length of a string, array or bytes value of the given type.
    Len(u32, Ty),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CmpOp {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ArithOp {
    Add,
    Sub,
    Mul,
    Div,
    Rem,
}

/// The compile-time type of an expression.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Ty {
    Bool,
    Num,
    Str,
    Array,
    Bytes,
}

impl Ty {
    /// The type with an article, for messages.
    fn name(self) -> &'static str {
        match self {
            Ty::Bool => "a bool",
            Ty::Num => "a number",
            Ty::Str => "a string",
            Ty::Array => "an array",
            Ty::Bytes => "bytes",
        }
    }
}

/// A lookup without values: evaluating a number expression with it gives
/// `Some` exactly when the expression is a constant.
struct NoValues;

impl Lookup for NoValues {
    fn value(&self, _id: usize) -> Option<&Value> {
        None
    }
}

impl Program {
    fn node(&self, n: u32) -> Option<&Node> {
        self.nodes.get(n as usize)
    }

    fn value<'a>(&self, slot: u32, lk: &'a dyn Lookup) -> Option<&'a Value> {
        let id = *self.refs.get(slot as usize)?;
        lk.value(id)
    }

    fn bool_at(&self, n: u32, lk: &dyn Lookup) -> Option<bool> {
        match self.node(n)? {
            Node::Bool(b) => Some(*b),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::Bool(b) => Some(*b),
                _ => None,
            },
            Node::Not(a) => self.bool_at(*a, lk).map(|b| !b),
            Node::And(l, r) => match self.bool_at(*l, lk) {
                Some(false) => Some(false),
                left => match self.bool_at(*r, lk) {
                    Some(false) => Some(false),
                    Some(true) => left,
                    None => None,
                },
            },
            Node::Or(l, r) => match self.bool_at(*l, lk) {
                Some(true) => Some(true),
                left => match self.bool_at(*r, lk) {
                    Some(true) => Some(true),
                    Some(false) => left,
                    None => None,
                },
            },
            Node::Cmp(op, l, r) => {
                let a = self.num_at(*l, lk)?;
                let b = self.num_at(*r, lk)?;
                let ord = a.partial_cmp(&b)?;
                Some(match op {
                    CmpOp::Lt => ord.is_lt(),
                    CmpOp::Le => ord.is_le(),
                    CmpOp::Gt => ord.is_gt(),
                    CmpOp::Ge => ord.is_ge(),
                    CmpOp::Eq => ord.is_eq(),
                    CmpOp::Ne => ord.is_ne(),
                })
            }
            Node::EqBool(eq, l, r) => {
                let a = self.bool_at(*l, lk)?;
                let b = self.bool_at(*r, lk)?;
                Some((a == b) == *eq)
            }
            Node::EqStr(eq, l, r) => {
                let a = self.str_at(*l, lk)?;
                let b = self.str_at(*r, lk)?;
                Some((a == b) == *eq)
            }
            _ => None,
        }
    }

    fn num_at(&self, n: u32, lk: &dyn Lookup) -> Option<f64> {
        match self.node(n)? {
            Node::Num(x) => Some(*x),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::F64(x) => Some(*x),
                Value::I64(x) => Some(*x as f64),
                _ => None,
            },
            Node::Neg(a) => self.num_at(*a, lk).map(|x| -x),
            Node::Abs(a) => self.num_at(*a, lk).map(f64::abs),
            Node::Arith(op, l, r) => {
                let a = self.num_at(*l, lk)?;
                let b = self.num_at(*r, lk)?;
                Some(match op {
                    ArithOp::Add => a + b,
                    ArithOp::Sub => a - b,
                    ArithOp::Mul => a * b,
                    ArithOp::Div => a / b,
                    ArithOp::Rem => a % b,
                })
            }
            Node::MinMax { max, start, len } => {
                let start = *start as usize;
                let args = self.args.get(start..start.checked_add(*len as usize)?)?;
                let mut acc: Option<f64> = None;
                for &arg in args {
                    let x = self.num_at(arg, lk)?;
                    acc = Some(match acc {
                        None => x,
                        Some(a) if a.is_nan() || x.is_nan() => f64::NAN,
                        Some(a) if *max => a.max(x),
                        Some(a) => a.min(x),
                    });
                }
                acc
            }
            Node::Index(arr, idx) => {
                let i = self.num_at(*idx, lk)?;
                // Infinities fail too: their fractional part is NaN.
                if i.is_nan() || i < 0.0 || i.fract() != 0.0 {
                    return None;
                }
                // Saturates for huge indexes, which are then out of range.
                let i = i as usize;
                match self.val_at(*arr, lk)? {
                    v @ (Value::F32s(_) | Value::F64s(_) | Value::I64s(_)) => v.index_f64(i),
                    _ => None,
                }
            }
            Node::Len(a, ty) => {
                let len = match ty {
                    Ty::Str => self.str_at(*a, lk)?.len(),
                    Ty::Array => match self.val_at(*a, lk)? {
                        v @ (Value::F32s(_) | Value::F64s(_) | Value::I64s(_)) => v.len()?,
                        _ => return None,
                    },
                    Ty::Bytes => match self.val_at(*a, lk)? {
                        Value::Bytes(b) => b.len(),
                        _ => return None,
                    },
                    Ty::Bool | Ty::Num => return None,
                };
                Some(len as f64)
            }
            _ => None,
        }
    }

    fn str_at<'a>(&'a self, n: u32, lk: &'a dyn Lookup) -> Option<&'a str> {
        match self.node(n)? {
            Node::Str(s) => Some(s),
            Node::Ref(slot) => match self.value(*slot, lk)? {
                Value::Str(s) => Some(s),
                _ => None,
            },
            _ => None,
        }
    }

    /// The value of an array or bytes expression (always a `Ref`).
    fn val_at<'a>(&self, n: u32, lk: &'a dyn Lookup) -> Option<&'a Value> {
        match self.node(n)? {
            Node::Ref(slot) => self.value(*slot, lk),
            _ => None,
        }
    }
}

// ---------------------------------------------------------------------------
// Lexer

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Str(String),
    Name(String),
    True,
    False,
    OrOr,
    AndAnd,
    EqEq,
    NotEq,
    Lt,
    Le,
    Gt,
    Ge,
    Plus,
    Minus,
    Star,
    Slash,
    Percent,
    Bang,
    LParen,
    RParen,
    LBracket,
    RBracket,
    Comma,
    End,
}

#[derive(Debug, Clone)]
struct Token {
    tok: Tok,
    /// Byte offsets into the source.
    start: usize,
    end: usize,
}

/// The 1-based character column of a byte offset.
fn column_of(src: &str, at: usize) -> usize {
    src.get(..at).map_or(at, |s| s.chars().count()) + 1
}

fn lex_err(src: &str, at: usize, message: impl Into<String>) -> ExprError {
    ExprError { column: column_of(src, at), message: message.into() }
}

fn is_ident_start(c: u8) -> bool {
    c.is_ascii_alphabetic() || c == b'_'
}

fn is_ident(c: u8) -> bool {
    c.is_ascii_alphanumeric() || c == b'_'
}

fn lex(src: &str) -> Result<Vec<Token>, ExprError> {
    let b = src.as_bytes();
    let n = b.len();
    let at = |i: usize| b.get(i).copied();
    let mut out = Vec::new();
    let mut i = 0;
    while i < n {
        let c = b[i];
        let start = i;
        let tok = match c {
            b' ' | b'\t' | b'\n' | b'\r' => {
                i += 1;
                continue;
            }
            b'0'..=b'9' => {
                while at(i).is_some_and(|c| c.is_ascii_digit()) {
                    i += 1;
                }
                if at(i) == Some(b'.') {
                    if !at(i + 1).is_some_and(|c| c.is_ascii_digit()) {
                        return Err(lex_err(src, i + 1, "expected digits after the decimal point"));
                    }
                    i += 1;
                    while at(i).is_some_and(|c| c.is_ascii_digit()) {
                        i += 1;
                    }
                }
                if matches!(at(i), Some(b'e' | b'E')) {
                    let mut j = i + 1;
                    if matches!(at(j), Some(b'+' | b'-')) {
                        j += 1;
                    }
                    if !at(j).is_some_and(|c| c.is_ascii_digit()) {
                        return Err(lex_err(src, j, "expected the digits of the exponent"));
                    }
                    i = j;
                    while at(i).is_some_and(|c| c.is_ascii_digit()) {
                        i += 1;
                    }
                }
                if let Some(c) = at(i).filter(|&c| is_ident(c) || c == b'.') {
                    return Err(lex_err(src, i, format!("unexpected `{}` right after a number", char::from(c))));
                }
                match src[start..i].parse::<f64>() {
                    Ok(x) if x.is_finite() => Tok::Num(x),
                    _ => return Err(lex_err(src, start, "this number is too large")),
                }
            }
            b'.' => {
                if at(i + 1).is_some_and(|c| c.is_ascii_digit()) {
                    return Err(lex_err(src, i, "a number needs a digit before its decimal point (`0.5`, not `.5`)"));
                }
                return Err(lex_err(src, i, "unexpected `.`"));
            }
            b'"' | b'\'' => {
                let quote = c;
                let mut s = String::new();
                i += 1;
                loop {
                    let Some(ch) = src.get(i..).and_then(|rest| rest.chars().next()) else {
                        return Err(lex_err(src, start, "this string is not closed"));
                    };
                    if ch == char::from(quote) {
                        i += 1;
                        break;
                    }
                    if ch == '\\' {
                        match src.get(i + 1..).and_then(|rest| rest.chars().next()) {
                            Some(e @ ('\\' | '"' | '\'')) => {
                                s.push(e);
                                i += 2;
                            }
                            Some(e) => {
                                return Err(lex_err(
                                    src,
                                    i,
                                    format!("unknown escape `\\{e}` in a string (the escapes are \\\\, \\\" and \\')"),
                                ))
                            }
                            None => return Err(lex_err(src, start, "this string is not closed")),
                        }
                        continue;
                    }
                    s.push(ch);
                    i += ch.len_utf8();
                }
                Tok::Str(s)
            }
            c if is_ident_start(c) => {
                loop {
                    while at(i).is_some_and(is_ident) {
                        i += 1;
                    }
                    if at(i) != Some(b'.') {
                        break;
                    }
                    if !at(i + 1).is_some_and(is_ident_start) {
                        return Err(lex_err(src, i + 1, "expected a field name after `.`"));
                    }
                    i += 1;
                }
                match &src[start..i] {
                    "true" => Tok::True,
                    "false" => Tok::False,
                    name => Tok::Name(name.to_string()),
                }
            }
            _ => {
                let next = at(i + 1);
                let (tok, len) = match (c, next) {
                    (b'|', Some(b'|')) => (Tok::OrOr, 2),
                    (b'&', Some(b'&')) => (Tok::AndAnd, 2),
                    (b'=', Some(b'=')) => (Tok::EqEq, 2),
                    (b'!', Some(b'=')) => (Tok::NotEq, 2),
                    (b'<', Some(b'=')) => (Tok::Le, 2),
                    (b'>', Some(b'=')) => (Tok::Ge, 2),
                    (b'|', _) => return Err(lex_err(src, i, "`|` is not an operator; for \"or\" write `||`")),
                    (b'&', _) => return Err(lex_err(src, i, "`&` is not an operator; for \"and\" write `&&`")),
                    (b'=', _) => return Err(lex_err(src, i, "`=` is not an operator; to compare, write `==`")),
                    (b'!', _) => (Tok::Bang, 1),
                    (b'<', _) => (Tok::Lt, 1),
                    (b'>', _) => (Tok::Gt, 1),
                    (b'+', _) => (Tok::Plus, 1),
                    (b'-', _) => (Tok::Minus, 1),
                    (b'*', _) => (Tok::Star, 1),
                    (b'/', _) => (Tok::Slash, 1),
                    (b'%', _) => (Tok::Percent, 1),
                    (b'(', _) => (Tok::LParen, 1),
                    (b')', _) => (Tok::RParen, 1),
                    (b'[', _) => (Tok::LBracket, 1),
                    (b']', _) => (Tok::RBracket, 1),
                    (b',', _) => (Tok::Comma, 1),
                    _ => {
                        let ch = src.get(i..).and_then(|r| r.chars().next()).unwrap_or('?');
                        return Err(lex_err(src, i, format!("unexpected character `{}`", ch.escape_debug())));
                    }
                };
                i += len;
                tok
            }
        };
        out.push(Token { tok, start, end: i });
    }
    out.push(Token { tok: Tok::End, start: n, end: n });
    Ok(out)
}

// ---------------------------------------------------------------------------
// Parser and type checker (one pass)

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum BinOp {
    Or,
    And,
    Eq,
    Ne,
    Lt,
    Le,
    Gt,
    Ge,
    Add,
    Sub,
    Mul,
    Div,
    Rem,
}

impl BinOp {
    fn from_tok(t: &Tok) -> Option<BinOp> {
        Some(match t {
            Tok::OrOr => BinOp::Or,
            Tok::AndAnd => BinOp::And,
            Tok::EqEq => BinOp::Eq,
            Tok::NotEq => BinOp::Ne,
            Tok::Lt => BinOp::Lt,
            Tok::Le => BinOp::Le,
            Tok::Gt => BinOp::Gt,
            Tok::Ge => BinOp::Ge,
            Tok::Plus => BinOp::Add,
            Tok::Minus => BinOp::Sub,
            Tok::Star => BinOp::Mul,
            Tok::Slash => BinOp::Div,
            Tok::Percent => BinOp::Rem,
            _ => return None,
        })
    }

    fn prec(self) -> u8 {
        match self {
            BinOp::Or => 1,
            BinOp::And => 2,
            BinOp::Eq | BinOp::Ne => 3,
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => 4,
            BinOp::Add | BinOp::Sub => 5,
            BinOp::Mul | BinOp::Div | BinOp::Rem => 6,
        }
    }

    fn chains(self) -> bool {
        self.prec() != 3 && self.prec() != 4
    }

    fn text(self) -> &'static str {
        match self {
            BinOp::Or => "||",
            BinOp::And => "&&",
            BinOp::Eq => "==",
            BinOp::Ne => "!=",
            BinOp::Lt => "<",
            BinOp::Le => "<=",
            BinOp::Gt => ">",
            BinOp::Ge => ">=",
            BinOp::Add => "+",
            BinOp::Sub => "-",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Rem => "%",
        }
    }
}

/// A compiled, typed subexpression; `at` is the byte offset where it starts.
#[derive(Debug, Clone, Copy)]
struct Typed {
    node: u32,
    ty: Ty,
    at: usize,
}

const FUNCTIONS: [&str; 4] = ["abs", "min", "max", "len"];

struct Parser<'s, 'r> {
    src: &'s str,
    toks: Vec<Token>,
    pos: usize,
    depth: usize,
    resolver: &'r dyn Resolver,
    program: Program,
    ref_names: Vec<String>,
    /// Name nodes of fixed-length arrays: their name and length, so that a
    /// constant index beyond the end is refused where it is written.
    fixed: Vec<(u32, String, usize)>,
    /// What is parsed, for messages: "condition" or "formula".
    noun: &'static str,
}

type PResult<T> = Result<T, ExprError>;

impl Parser<'_, '_> {
    // The functions on the recursion path (`parse_expr`, `parse_operand`,
    // `parse_primary`, `call`) only steer; everything else, in particular
    // formatting error messages, happens in helpers kept out of line, so the
    // recursive frames stay small even in debug builds.

    fn err(&self, at: usize, message: impl Into<String>) -> ExprError {
        lex_err(self.src, at, message)
    }

    fn peek(&self) -> &Token {
        // The token list always ends with `End`, and `pos` never passes it.
        &self.toks[self.pos.min(self.toks.len() - 1)]
    }

    fn bump(&mut self) {
        if self.peek().tok != Tok::End {
            self.pos += 1;
        }
    }

    fn describe(&self, t: &Token) -> String {
        if t.tok == Tok::End {
            return format!("the end of the {}", self.noun);
        }
        let text = self.src.get(t.start..t.end).unwrap_or("?");
        if text.chars().count() > 24 {
            let short: String = text.chars().take(20).collect();
            format!("`{short}…`")
        } else {
            format!("`{text}`")
        }
    }

    /// "expected {what}, found …" at the next token.
    #[cold]
    #[inline(never)]
    fn unexpected(&self, what: &str) -> ExprError {
        let t = self.peek();
        self.err(t.start, format!("expected {what}, found {}", self.describe(t)))
    }

    #[inline(never)]
    fn push(&mut self, node: Node, at: usize) -> PResult<u32> {
        if self.program.nodes.len() >= MAX_NODES {
            return Err(self.err(
                at,
                format!("the {} is too large: more than {MAX_NODES} parts (names, literals, operators)", self.noun),
            ));
        }
        self.program.nodes.push(node);
        Ok((self.program.nodes.len() - 1) as u32)
    }

    #[inline(never)]
    fn enter(&mut self, at: usize) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(self.err(at, format!("the {} nests too deeply (more than {MAX_DEPTH} levels)", self.noun)));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth = self.depth.saturating_sub(1);
    }

    /// Expects the `)` or `]` that closes the bracket opened at `open`.
    #[inline(never)]
    fn expect_close(&mut self, open: usize) -> PResult<()> {
        let (close, text, opener) = if self.src.as_bytes().get(open) == Some(&b'[') {
            (Tok::RBracket, "]", "[")
        } else {
            (Tok::RParen, ")", "(")
        };
        if self.peek().tok == close {
            self.bump();
            return Ok(());
        }
        let what = format!("`{text}` to close the `{opener}` at column {}", column_of(self.src, open));
        Err(self.unexpected(&what))
    }

    /// An expression: operands joined by binary operators, parsed with an
    /// operator stack (shunting yard); equal precedences reduce left to
    /// right, and comparisons refuse to chain.
    fn parse_expr(&mut self) -> PResult<Typed> {
        let mut operands: Vec<Typed> = Vec::new();
        let mut ops: Vec<(BinOp, usize)> = Vec::new();
        operands.push(self.parse_operand()?);
        while let Some(op) = BinOp::from_tok(&self.peek().tok) {
            let at = self.peek().start;
            while let Some(&(top, top_at)) = ops.last() {
                if top.prec() < op.prec() {
                    break;
                }
                if top.prec() == op.prec() && !op.chains() {
                    return Err(self.chain_error(top, op, at));
                }
                ops.pop();
                self.reduce(&mut operands, top, top_at)?;
            }
            ops.push((op, at));
            self.bump();
            operands.push(self.parse_operand()?);
        }
        while let Some((op, at)) = ops.pop() {
            self.reduce(&mut operands, op, at)?;
        }
        match (operands.pop(), operands.is_empty()) {
            (Some(e), true) => Ok(e),
            _ => Err(self.err(0, "internal error: unbalanced expression")),
        }
    }

    #[cold]
    #[inline(never)]
    fn chain_error(&self, prev: BinOp, op: BinOp, at: usize) -> ExprError {
        self.err(
            at,
            format!(
                "comparisons don't chain: `{}` cannot follow `{}`; combine two comparisons with `&&` (`a < b && b < c`) or add parentheses",
                op.text(),
                prev.text()
            ),
        )
    }

    #[inline(never)]
    fn reduce(&mut self, operands: &mut Vec<Typed>, op: BinOp, at: usize) -> PResult<()> {
        let (Some(r), Some(l)) = (operands.pop(), operands.pop()) else {
            return Err(self.err(at, "internal error: missing operand"));
        };
        let e = self.binary(op, at, l, r)?;
        operands.push(e);
        Ok(())
    }

    #[inline(never)]
    fn binary(&mut self, op: BinOp, at: usize, l: Typed, r: Typed) -> PResult<Typed> {
        let mismatch = |p: &Self, need: &str| {
            Err(p.err(at, format!("`{}` needs {need}, got {} and {}", op.text(), l.ty.name(), r.ty.name())))
        };
        let (node, ty) = match op {
            BinOp::Or | BinOp::And => {
                if l.ty != Ty::Bool || r.ty != Ty::Bool {
                    return mismatch(self, "true or false on both sides");
                }
                let node = if op == BinOp::Or { Node::Or(l.node, r.node) } else { Node::And(l.node, r.node) };
                (node, Ty::Bool)
            }
            BinOp::Eq | BinOp::Ne => {
                let eq = op == BinOp::Eq;
                let node = match (l.ty, r.ty) {
                    (Ty::Bool, Ty::Bool) => Node::EqBool(eq, l.node, r.node),
                    (Ty::Num, Ty::Num) => Node::Cmp(if eq { CmpOp::Eq } else { CmpOp::Ne }, l.node, r.node),
                    (Ty::Str, Ty::Str) => Node::EqStr(eq, l.node, r.node),
                    _ => return mismatch(self, "two bools, two numbers or two strings"),
                };
                (node, Ty::Bool)
            }
            BinOp::Lt | BinOp::Le | BinOp::Gt | BinOp::Ge => {
                if l.ty != Ty::Num || r.ty != Ty::Num {
                    return mismatch(self, "two numbers");
                }
                let cmp = match op {
                    BinOp::Lt => CmpOp::Lt,
                    BinOp::Le => CmpOp::Le,
                    BinOp::Gt => CmpOp::Gt,
                    _ => CmpOp::Ge,
                };
                (Node::Cmp(cmp, l.node, r.node), Ty::Bool)
            }
            BinOp::Add | BinOp::Sub | BinOp::Mul | BinOp::Div | BinOp::Rem => {
                if l.ty != Ty::Num || r.ty != Ty::Num {
                    return mismatch(self, "two numbers");
                }
                let arith = match op {
                    BinOp::Add => ArithOp::Add,
                    BinOp::Sub => ArithOp::Sub,
                    BinOp::Mul => ArithOp::Mul,
                    BinOp::Div => ArithOp::Div,
                    _ => ArithOp::Rem,
                };
                (Node::Arith(arith, l.node, r.node), Ty::Num)
            }
        };
        let node = self.push(node, at)?;
        Ok(Typed { node, ty, at: l.at })
    }

    /// Prefix operators, a primary, then indexes: `-x[0]` is `-(x[0])`.
    fn parse_operand(&mut self) -> PResult<Typed> {
        // (is `!`, offset) of each prefix operator, innermost last.
        let mut prefix: Vec<(bool, usize)> = Vec::new();
        loop {
            let not = match self.peek().tok {
                Tok::Bang => true,
                Tok::Minus => false,
                _ => break,
            };
            let at = self.peek().start;
            self.enter(at)?;
            self.bump();
            prefix.push((not, at));
        }
        let mut e = self.parse_primary()?;
        while self.peek().tok == Tok::LBracket {
            let open = self.peek().start;
            self.check_indexable(e, open)?;
            self.bump();
            self.enter(open)?;
            let idx = self.parse_expr()?;
            self.expect_close(open)?;
            self.leave();
            e = self.index(e, idx, open)?;
        }
        while let Some((not, at)) = prefix.pop() {
            self.leave();
            e = self.unary(not, at, e)?;
        }
        Ok(e)
    }

    #[inline(never)]
    fn unary(&mut self, not: bool, at: usize, e: Typed) -> PResult<Typed> {
        let (want, node) = if not { (Ty::Bool, Node::Not(e.node)) } else { (Ty::Num, Node::Neg(e.node)) };
        if e.ty != want {
            let (name, need) = if not { ("!", "true or false") } else { ("-", "a number") };
            return Err(self.err(at, format!("`{name}` needs {need}, got {}", e.ty.name())));
        }
        let node = self.push(node, at)?;
        Ok(Typed { node, ty: want, at })
    }

    #[inline(never)]
    fn check_indexable(&self, e: Typed, open: usize) -> PResult<()> {
        if e.ty != Ty::Array {
            return Err(self.err(open, format!("`[]` indexes an array, but this is {}", e.ty.name())));
        }
        Ok(())
    }

    #[inline(never)]
    fn index(&mut self, e: Typed, idx: Typed, open: usize) -> PResult<Typed> {
        if idx.ty != Ty::Num {
            return Err(self.err(idx.at, format!("`[]` needs a number as the index, got {}", idx.ty.name())));
        }
        if let Some(i) = self.program.num_at(idx.node, &NoValues) {
            if i < 0.0 {
                return Err(self.err(idx.at, format!("the index is negative ({i}); indexes count from 0")));
            }
            if !i.is_finite() || i.fract() != 0.0 {
                return Err(self.err(idx.at, format!("the index must be a whole number, this is {i}")));
            }
            if let Some((_, name, len)) = self.fixed.iter().find(|(n, _, _)| *n == e.node) {
                if i >= *len as f64 {
                    // It would never have a value: a monitor on it would silently never fire.
                    return Err(self.err(
                        idx.at,
                        format!(
                            "index {i} is out of range: `{name}` has {len} element{} (indexes 0 to {})",
                            if *len == 1 { "" } else { "s" },
                            len.saturating_sub(1)
                        ),
                    ));
                }
            }
        }
        let node = self.push(Node::Index(e.node, idx.node), open)?;
        Ok(Typed { node, ty: Ty::Num, at: e.at })
    }

    fn parse_primary(&mut self) -> PResult<Typed> {
        let at = self.peek().start;
        match &self.peek().tok {
            Tok::LParen => {
                self.bump();
                self.enter(at)?;
                let e = self.parse_expr()?;
                self.expect_close(at)?;
                self.leave();
                Ok(Typed { at, ..e })
            }
            Tok::Name(name) => {
                let name = name.clone();
                self.bump();
                if self.peek().tok == Tok::LParen {
                    self.call(name, at)
                } else {
                    self.reference(&name, at)
                }
            }
            _ => self.literal(),
        }
    }

    #[inline(never)]
    fn literal(&mut self) -> PResult<Typed> {
        let at = self.peek().start;
        let (node, ty) = match &self.peek().tok {
            Tok::Num(x) => (Node::Num(*x), Ty::Num),
            Tok::Str(s) => (Node::Str(s.as_str().into()), Ty::Str),
            Tok::True => (Node::Bool(true), Ty::Bool),
            Tok::False => (Node::Bool(false), Ty::Bool),
            _ => return Err(self.unexpected("a value (a number, a string, `true`, `false`, a name or `(`)")),
        };
        self.bump();
        let node = self.push(node, at)?;
        Ok(Typed { node, ty, at })
    }

    #[inline(never)]
    fn reference(&mut self, name: &str, at: usize) -> PResult<Typed> {
        let (id, st) = self.resolver.resolve(name).map_err(|m| self.err(at, m))?;
        let ty = match &st {
            SignalType::Bool => Ty::Bool,
            SignalType::I64 | SignalType::F64 => Ty::Num,
            SignalType::Str => Ty::Str,
            SignalType::Bytes => Ty::Bytes,
            SignalType::Array { .. } => Ty::Array,
            SignalType::Record(r) => {
                let message = if r.fields.is_empty() {
                    format!("`{name}` is a record without fields; it cannot be used in a condition")
                } else {
                    let fields: Vec<&str> = r.fields.iter().map(|(n, _)| n.as_str()).collect();
                    format!("`{name}` is a record; name one of its fields: {}", fields.join(", "))
                };
                return Err(self.err(at, message));
            }
        };
        let slot = match self.program.refs.iter().position(|&r| r == id) {
            Some(slot) => slot,
            None => {
                self.program.refs.push(id);
                self.ref_names.push(name.to_string());
                self.program.refs.len() - 1
            }
        };
        let node = self.push(Node::Ref(slot as u32), at)?;
        if let SignalType::Array { len: Some(len), .. } = st {
            self.fixed.push((node, name.to_string(), len));
        }
        Ok(Typed { node, ty, at })
    }

    /// A call of the function `name` at `at`; the next token is its `(`.
    fn call(&mut self, name: String, at: usize) -> PResult<Typed> {
        self.check_function(&name, at)?;
        let open = self.peek().start;
        self.bump();
        self.enter(open)?;
        let mut args: Vec<Typed> = Vec::new();
        if self.peek().tok == Tok::RParen {
            self.bump();
        } else {
            loop {
                args.push(self.parse_expr()?);
                match self.peek().tok {
                    Tok::Comma => self.bump(),
                    Tok::RParen => {
                        self.bump();
                        break;
                    }
                    _ => return Err(self.unexpected(&format!("`,` or `)` in the call to `{name}`"))),
                }
            }
        }
        self.leave();
        self.build_call(&name, at, &args)
    }

    #[inline(never)]
    fn check_function(&self, name: &str, at: usize) -> PResult<()> {
        if FUNCTIONS.contains(&name) {
            return Ok(());
        }
        let hint = situate_core::suggestion(name, FUNCTIONS);
        Err(self.err(
            at,
            format!("unknown function `{name}`{hint}; the functions are abs(x), min(a, b, …), max(a, b, …) and len(x)"),
        ))
    }

    #[inline(never)]
    fn build_call(&mut self, name: &str, at: usize, args: &[Typed]) -> PResult<Typed> {
        let count = |n: usize| if n == 1 { "1 argument".to_string() } else { format!("{n} arguments") };
        let node = match (name, args) {
            ("abs", [a]) => {
                if a.ty != Ty::Num {
                    return Err(self.err(a.at, format!("`abs` needs a number, got {}", a.ty.name())));
                }
                Node::Abs(a.node)
            }
            ("len", [a]) => {
                if !matches!(a.ty, Ty::Str | Ty::Array | Ty::Bytes) {
                    return Err(self.err(a.at, format!("`len` needs an array, a string or bytes, got {}", a.ty.name())));
                }
                Node::Len(a.node, a.ty)
            }
            ("abs", _) => return Err(self.err(at, format!("`abs` takes one number, got {}", count(args.len())))),
            ("len", _) => {
                let got = count(args.len());
                return Err(self.err(at, format!("`len` takes one array, string or bytes value, got {got}")));
            }
            (_, [_, _, ..]) => {
                if let Some(a) = args.iter().find(|a| a.ty != Ty::Num) {
                    return Err(self.err(a.at, format!("`{name}` needs numbers, got {}", a.ty.name())));
                }
                let start = self.program.args.len() as u32;
                self.program.args.extend(args.iter().map(|a| a.node));
                Node::MinMax { max: name == "max", start, len: args.len() as u32 }
            }
            _ => return Err(self.err(at, format!("`{name}` takes two or more numbers, got {}", count(args.len())))),
        };
        let node = self.push(node, at)?;
        Ok(Typed { node, ty: Ty::Num, at })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use situate_core::ElemType;
    use std::cell::Cell;
    use std::sync::Arc;

    /// The signals the tests know; ids are 100 + position.
    fn signals() -> Vec<(&'static str, SignalType)> {
        vec![
            ("sonar.range", SignalType::array(ElemType::F32, None)),
            ("sonar.ok", SignalType::Bool),
            ("barcode.id", SignalType::I64),
            ("odom.speed", SignalType::F64),
            ("label", SignalType::Str),
            ("raw", SignalType::Bytes),
            ("pose", SignalType::record(vec![("x", SignalType::F64), ("y", SignalType::F64)])),
            ("pose.x", SignalType::F64),
            ("counts", SignalType::array(ElemType::I64, Some(3))),
            ("gains", SignalType::array(ElemType::F64, None)),
            ("flag", SignalType::Bool),
            ("empty", SignalType::record(vec![])),
        ]
    }

    struct Sigs(Vec<(&'static str, SignalType)>);

    impl Resolver for Sigs {
        fn resolve(&self, path: &str) -> Result<(usize, SignalType), String> {
            match self.0.iter().position(|(n, _)| *n == path) {
                Some(i) => Ok((100 + i, self.0[i].1.clone())),
                None => {
                    let first = path.split('.').next().unwrap_or(path);
                    let names = self.0.iter().map(|(n, _)| n.split('.').next().unwrap_or(n));
                    Err(format!("unknown signal `{first}`{}", situate_core::suggestion(first, names)))
                }
            }
        }
    }

    fn id(name: &str) -> usize {
        100 + signals().iter().position(|(n, _)| *n == name).unwrap()
    }

    #[derive(Default)]
    struct Vals {
        vals: Vec<(usize, Value)>,
        reads: Cell<usize>,
    }

    impl Vals {
        fn with(mut self, name: &str, v: Value) -> Self {
            self.vals.push((id(name), v));
            self
        }
    }

    impl Lookup for Vals {
        fn value(&self, id: usize) -> Option<&Value> {
            self.reads.set(self.reads.get() + 1);
            self.vals.iter().find(|(i, _)| *i == id).map(|(_, v)| v)
        }
    }

    #[test]
    fn a_formula_is_a_number_or_a_bool_read_as_one_or_zero() {
        let sigs = Sigs(signals());
        let f = |src: &str| Formula::compile(src, &sigs).unwrap_or_else(|e| panic!("{src}: {e}"));
        let vals = standard();
        assert_eq!(f("abs(odom.speed) * 2").eval(&vals), Some(1.5));
        assert_eq!(f("sonar.range[1] + barcode.id").eval(&vals), Some(3.25));
        assert_eq!(f("pose.x").eval(&vals), Some(1.5));
        assert_eq!(f("sonar.range[0] < 0.25").eval(&vals), Some(0.0));
        assert_eq!(f("sonar.ok && barcode.id == 3").eval(&vals), Some(1.0));
        // Missing (no value, out of range) and not finite (a division by zero): no point.
        assert_eq!(f("sonar.range[7] * 2").eval(&vals), None);
        assert_eq!(f("pose.x + 1").eval(&Vals::default()), None);
        assert_eq!(f("odom.speed / 0").eval(&vals), None);
        let formula = f("min(pose.x, odom.speed)");
        assert_eq!(formula.source(), "min(pose.x, odom.speed)");
        assert_eq!(formula.ref_names(), ["pose.x", "odom.speed"]);
        assert_eq!(formula.refs(), [id("pose.x"), id("odom.speed")]);
        // What is not a number nor a bool is refused, naming the type and the column.
        let e = Formula::compile("label", &sigs).unwrap_err();
        assert_eq!(e.column, 1);
        assert!(e.message.contains("must be a number or true/false, this is a string"), "{e}");
        let e = Formula::compile("odom.speed + lable", &sigs).unwrap_err();
        assert_eq!(e.column, 14);
        assert!(e.message.contains("unknown signal `lable`"), "{e}");
        // Its messages say formula, not condition.
        assert!(Formula::compile("", &sigs).unwrap_err().message.contains("the formula is empty"));
        assert!(Formula::compile("(pose.x", &sigs).unwrap_err().message.contains("the end of the formula"));
        // A condition is still only a bool.
        assert!(Condition::compile("odom.speed", &sigs).is_err());
    }

    fn standard() -> Vals {
        Vals::default()
            .with("sonar.range", Value::F32s(vec![0.5, 0.25, 2.0].into()))
            .with("sonar.ok", Value::Bool(true))
            .with("barcode.id", Value::I64(3))
            .with("odom.speed", Value::F64(-0.75))
            .with("label", Value::Str(Arc::from("dock")))
            .with("raw", Value::Bytes(vec![1, 2, 3, 4, 5, 6].into()))
            .with("pose.x", Value::F64(1.5))
            .with("counts", Value::I64s(vec![7, 8, 9].into()))
            .with("gains", Value::F64s(vec![0.1, 0.2].into()))
            .with("flag", Value::Bool(false))
    }

    fn compile(src: &str) -> Result<Condition, ExprError> {
        Condition::compile(src, &Sigs(signals()))
    }

    fn eval_with(src: &str, vals: &Vals) -> Option<bool> {
        match compile(src) {
            Ok(c) => c.eval(vals),
            Err(e) => panic!("`{src}` does not compile: {e}\n{}", e.pointer(src)),
        }
    }

    fn eval(src: &str) -> Option<bool> {
        eval_with(src, &standard())
    }

    fn err(src: &str) -> ExprError {
        match compile(src) {
            Ok(_) => panic!("`{src}` compiled"),
            Err(e) => e,
        }
    }

    /// Asserts a compile error at `column` whose message contains every part.
    fn assert_err(src: &str, column: usize, parts: &[&str]) {
        let e = err(src);
        assert_eq!(e.column, column, "column of `{src}`: {e}\n{}", e.pointer(src));
        for p in parts {
            assert!(e.message.contains(p), "`{src}`: {e:?} should mention {p:?}");
        }
    }

    #[test]
    fn precedence_and_associativity() {
        for (src, want) in [
            ("1 + 2 * 3 == 7", true),
            ("(1 + 2) * 3 == 9", true),
            ("10 - 4 - 3 == 3", true),
            ("16 / 4 / 2 == 2", true),
            ("2 * 3 % 4 == 2", true),
            ("7 % 4 * 2 == 6", true),
            ("-2 * 3 == -6", true),
            ("- 2 - -3 == 1", true),
            ("--2 == 2", true),
            ("1 + 1 < 3", true),
            ("3 > 1 + 1", true),
            ("1 < 2 == true", true),
            ("true == 1 < 2", true),
            ("1 < 2 == 3 < 4", true),
            ("true || false && false", true),
            ("false && false || true", true),
            ("!false && false", false),
            ("!(false && false)", true),
            ("!true == false", true),
        ] {
            assert_eq!(eval(src), Some(want), "{src}");
        }
        assert_eq!(eval("-sonar.range[1] == -0.25"), Some(true));
        assert_eq!(eval("counts[0] + counts[1] * counts[2] == 79"), Some(true));
    }

    #[test]
    fn comparisons_do_not_chain() {
        assert_err("1 < 2 < 3", 7, &["`<`", "chain", "&&"]);
        assert_err("1 < 2 + 1 >= 3", 11, &["`>=`", "`<`"]);
        assert_err("true == false != true", 15, &["`!=`", "`==`"]);
        assert_err("1 == 1 == true", 8, &["chain"]);
        // Parentheses make them legal.
        assert_eq!(eval("(1 < 2) == (3 < 4)"), Some(true));
        assert_eq!(eval("(false == false) == true"), Some(true));
    }

    #[test]
    fn every_operator() {
        for (src, want) in [
            ("!true", false),
            ("!false", true),
            ("true && true", true),
            ("true && false", false),
            ("false || false", false),
            ("false || true", true),
            ("true == true", true),
            ("true != true", false),
            ("1 == 1", true),
            ("1 != 1", false),
            ("1 != 2", true),
            ("'a' == \"a\"", true),
            ("'a' != 'b'", true),
            ("'a' == 'b'", false),
            ("1 < 2", true),
            ("2 < 2", false),
            ("2 <= 2", true),
            ("3 <= 2", false),
            ("3 > 2", true),
            ("2 > 2", false),
            ("2 >= 2", true),
            ("1 >= 2", false),
            ("1 + 2 == 3", true),
            ("1 - 2 == -1", true),
            ("2 * 3 == 6", true),
            ("7 / 2 == 3.5", true),
            ("7 % 4 == 3", true),
            ("-7 % 4 == -3", true),
            ("-(1) == 0 - 1", true),
            ("1e-3 == 0.001", true),
            ("2.5E+2 == 250", true),
            ("-0 == 0", true),
        ] {
            assert_eq!(eval(src), Some(want), "{src}");
        }
    }

    #[test]
    fn functions() {
        for (src, want) in [
            ("abs(-3) == 3", true),
            ("abs(odom.speed) == 0.75", true),
            ("min(3, 1, 2) == 1", true),
            ("max(3, 1, 2) == 3", true),
            ("min(sonar.range[0], sonar.range[1]) == 0.25", true),
            ("max(barcode.id, 2) == 3", true),
            ("len(label) == 4", true),
            ("len('héllo') == 6", true), // bytes
            ("len(raw) == 6", true),
            ("len(sonar.range) == 3", true),
            ("len(counts) == 3", true),
            ("len(gains) == 2", true),
            ("abs(min(-1, -2)) == 2", true),
            ("max( 1 , 2 ) == 2", true),
            ("len (label) == 4", true),
        ] {
            assert_eq!(eval(src), Some(want), "{src}");
        }
        // NaN propagates through min/max (and then compares as missing).
        assert_eq!(eval("min(0 / 0, 1) < 2"), None);
        assert_eq!(eval("max(1, 0 / 0) < 2"), None);
        // A missing argument makes the whole call missing.
        assert_eq!(eval_with("min(1, odom.speed) < 2", &Vals::default()), None);
        assert_eq!(eval_with("len(label) == 0", &Vals::default()), None);
    }

    #[test]
    fn function_errors() {
        assert_err("foo(1) > 0", 1, &["unknown function `foo`", "abs", "min", "max", "len"]);
        assert_err("1 < lenn(label)", 5, &["`lenn`", "did you mean `len`"]);
        assert_err("sonar.range(1) > 0", 1, &["unknown function `sonar.range`"]);
        assert_err("abs(1, 2) > 0", 1, &["`abs` takes one number", "2 arguments"]);
        assert_err("abs() > 0", 1, &["`abs`", "0 arguments"]);
        assert_err("min(1) > 0", 1, &["`min` takes two or more", "1 argument"]);
        assert_err("max() > 0", 1, &["`max`", "0 arguments"]);
        assert_err("len(label, raw) > 0", 1, &["`len` takes one"]);
        assert_err("abs('x') > 0", 5, &["`abs` needs a number", "a string"]);
        assert_err("min(1, true) > 0", 8, &["`min` needs numbers", "a bool"]);
        assert_err("max(1, 2, label) > 0", 11, &["`max`", "a string"]);
        assert_err("len(3) > 0", 5, &["`len` needs an array", "a number"]);
        assert_err("len(sonar.ok) > 0", 5, &["`len`", "a bool"]);
        assert_err("abs(1 2) > 0", 7, &["expected `,` or `)`", "`abs`", "`2`"]);
        assert_err("abs(1", 6, &["expected `,` or `)`", "end of the condition"]);
        assert_err("abs(,) > 0", 5, &["expected a value", "`,`"]);
        assert_err("abs(1) == 1 && min(", 20, &["expected a value"]);
    }

    #[test]
    fn type_errors_name_operator_types_and_column() {
        assert_err("label < 3", 7, &["`<`", "two numbers", "a string and a number"]);
        assert_err("1 <= label", 3, &["`<=`", "a number and a string"]);
        assert_err("odom.speed > true", 12, &["`>`", "a number and a bool"]);
        assert_err("1 >= raw", 3, &["`>=`", "a number and bytes"]);
        assert_err("1 + true > 0", 3, &["`+`", "a number and a bool"]);
        assert_err("label - 1 > 0", 7, &["`-`", "a string and a number"]);
        assert_err("2 * sonar.range > 0", 3, &["`*`", "a number and an array"]);
        assert_err("2 / 'x' > 0", 3, &["`/`"]);
        assert_err("2 % 'x' > 0", 3, &["`%`"]);
        assert_err("label == 3", 7, &["`==`", "two bools, two numbers or two strings", "a string and a number"]);
        assert_err("true != 1", 6, &["`!=`", "a bool and a number"]);
        assert_err("sonar.range == sonar.range", 13, &["`==`", "an array and an array"]);
        assert_err("raw == raw", 5, &["`==`", "bytes and bytes"]);
        assert_err("sonar.ok && 1", 10, &["`&&`", "true or false", "a bool and a number"]);
        assert_err("label || true", 7, &["`||`", "a string and a bool"]);
        assert_err("!3", 1, &["`!`", "true or false", "a number"]);
        assert_err("true && !label", 9, &["`!`", "a string"]);
        assert_err("-true", 1, &["`-`", "a number", "a bool"]);
        assert_err("1 < -label", 5, &["`-`", "a string"]);
        // Columns count characters, not bytes.
        assert_err("'ééé' == 1", 7, &["`==`", "a string and a number"]);
    }

    #[test]
    fn the_condition_must_be_a_bool() {
        assert_err("1 + 2", 1, &["a monitor condition must be true or false, this is a number"]);
        assert_err("  label", 3, &["must be true or false, this is a string"]);
        assert_err("sonar.range", 1, &["this is an array"]);
        assert_err("raw", 1, &["this is bytes"]);
        assert_err("(1 + 2) * 3", 1, &["this is a number"]);
        assert_eq!(eval("sonar.ok"), Some(true));
        assert_eq!(eval("(flag)"), Some(false));
    }

    #[test]
    fn unknown_names_report_the_resolver_message_at_the_name() {
        assert_err("sonr.range[0] < 1", 1, &["unknown signal `sonr` — did you mean `sonar`?"]);
        let e = err("sonar.ok && barcod.id == 3");
        assert_eq!(e.column, 13);
        assert_eq!(e.message, "unknown signal `barcod` — did you mean `barcode`?");
        assert_err("1 < 2 && (abs(nothing_like_it) > 0)", 15, &["unknown signal `nothing_like_it`"]);
        // A keyword inside a dotted name is just part of the name.
        assert_err("true.x", 1, &["unknown signal `true`"]);
    }

    #[test]
    fn records_need_a_field() {
        let e = err("pose > 1");
        assert_eq!(e.column, 1);
        assert_eq!(e.message, "`pose` is a record; name one of its fields: x, y");
        assert_err("1 < 2 && pose", 10, &["`pose` is a record", "x, y"]);
        assert_err("empty", 1, &["`empty` is a record without fields"]);
        assert_eq!(eval("pose.x > 1"), Some(true));
    }

    #[test]
    fn indexing() {
        assert_eq!(eval("sonar.range[0] == 0.5"), Some(true));
        assert_eq!(eval("sonar.range[2] == 2"), Some(true));
        assert_eq!(eval("sonar.range[1 + 1] == 2"), Some(true));
        assert_eq!(eval("sonar.range[barcode.id - 1] == 2"), Some(true));
        assert_eq!(eval("sonar.range[len(sonar.range) - 1] == 2"), Some(true));
        assert_eq!(eval("counts[2] == 9"), Some(true));
        assert_eq!(eval("gains[1] == 0.2"), Some(true));
        assert_eq!(eval("(sonar.range)[0] == 0.5"), Some(true));
        // Runtime: out of range, negative, fractional, NaN and infinite indexes are missing.
        assert_eq!(eval("sonar.range[3] < 100"), None);
        assert_eq!(eval("sonar.range[1e300] < 100"), None);
        assert_eq!(eval("sonar.range[barcode.id] < 100"), None);
        assert_eq!(eval("sonar.range[odom.speed] < 100"), None);
        assert_eq!(eval("sonar.range[odom.speed + 0.75] == 0.5"), Some(true));
        assert_eq!(eval("sonar.range[-barcode.id] < 100"), None);
        assert_eq!(eval("sonar.range[odom.speed * 2] < 100"), None);
        assert_eq!(eval("sonar.range[0 / 0 + barcode.id] < 100"), None);
        assert_eq!(eval("sonar.range[1 / 0 + barcode.id] < 100"), None);
        let empty = Vals::default().with("sonar.range", Value::F32s(Vec::new().into()));
        assert_eq!(eval_with("sonar.range[0] < 1", &empty), None);
        assert_eq!(eval_with("len(sonar.range) == 0", &empty), Some(true));
        // Compile time: a constant index past the end of a fixed-length array.
        assert_err("counts[3] > 0", 8, &["index 3 is out of range", "`counts` has 3 elements (indexes 0 to 2)"]);
        assert!(compile("counts[2] > 0").is_ok());
        assert!(compile("gains[300] > 0").is_ok(), "a variable-length array is checked at run time");
        // Compile time: constant negative or fractional indexes.
        assert_err("sonar.range[-1] < 1", 13, &["negative", "-1"]);
        assert_err("sonar.range[1 - 2] < 1", 13, &["negative"]);
        assert_err("sonar.range[0.5] < 1", 13, &["whole number", "0.5"]);
        assert_err("sonar.range[(1 / 3)] < 1", 13, &["whole number"]);
        assert_err("sonar.range[0 / 0] < 1", 13, &["whole number", "NaN"]);
        assert_err("sonar.range[1 / 0] < 1", 13, &["whole number", "inf"]);
        // Types.
        assert_err("barcode.id[0] == 1", 11, &["`[]`", "array", "a number"]);
        assert_err("label[0] == 1", 6, &["`[]`", "a string"]);
        assert_err("sonar.range['a'] < 1", 13, &["`[]`", "index", "a string"]);
        assert_err("sonar.range[0][1] < 1", 15, &["`[]`", "a number"]);
        assert_err("sonar.range[0 < 1", 18, &["`]` to close the `[` at column 12"]);
    }

    #[test]
    fn missing_values_and_kleene_logic() {
        let none = Vals::default();
        let cases = [
            ("sonar.ok", None),
            ("!sonar.ok", None),
            ("sonar.ok || true", Some(true)),
            ("true || sonar.ok", Some(true)),
            ("sonar.ok || false", None),
            ("false || sonar.ok", None),
            ("sonar.ok && false", Some(false)),
            ("false && sonar.ok", Some(false)),
            ("sonar.ok && true", None),
            ("true && sonar.ok", None),
            ("sonar.ok || flag", None),
            ("sonar.ok == true", None),
            ("odom.speed < 1", None),
            ("odom.speed == odom.speed", None),
            ("odom.speed + 1 > 0", None),
            ("-odom.speed > 0", None),
            ("abs(odom.speed) > 0", None),
            ("label == 'x'", None),
            ("label != 'x'", None),
            ("sonar.range[0] < 1", None),
            ("len(raw) > 0", None),
            ("odom.speed < 1 || 1 < 2", Some(true)),
            ("!(odom.speed < 1 && 1 > 2)", Some(true)),
        ];
        for (src, want) in cases {
            assert_eq!(eval_with(src, &none), want, "{src}");
        }
        // NaN compares as missing, also for `==` and `!=`.
        let nan = Vals::default().with("odom.speed", Value::F64(f64::NAN));
        for src in
            ["odom.speed < 1", "odom.speed >= 1", "odom.speed == 1", "odom.speed != 1", "odom.speed == odom.speed"]
        {
            assert_eq!(eval_with(src, &nan), None, "{src}");
        }
        assert_eq!(eval_with("odom.speed < 1 || true", &nan), Some(true));
        // Division by zero follows IEEE and never panics.
        assert_eq!(eval("1 / 0 > 1e300"), Some(true));
        assert_eq!(eval("-1 / 0 < -1e300"), Some(true));
        assert_eq!(eval("0 / 0 == 0"), None);
        assert_eq!(eval("5 % 0 == 0"), None);
        assert_eq!(eval("barcode.id / 0 > 0"), Some(true));
        // A value of the wrong kind is missing.
        let wrong = Vals::default()
            .with("odom.speed", Value::Str(Arc::from("fast")))
            .with("sonar.ok", Value::I64(1))
            .with("label", Value::F64(1.0))
            .with("sonar.range", Value::Bytes(vec![1].into()))
            .with("raw", Value::F32s(vec![1.0].into()));
        for src in [
            "odom.speed > 0",
            "sonar.ok",
            "label == 'x'",
            "sonar.range[0] > 0",
            "len(sonar.range) > 0",
            "len(raw) > 0",
            "len(label) > 0",
        ] {
            assert_eq!(eval_with(src, &wrong), None, "{src}");
        }
        // i64 values convert to numbers.
        let big = Vals::default().with("barcode.id", Value::I64(1 << 53));
        assert_eq!(eval_with("barcode.id == 9007199254740992", &big), Some(true));
    }

    #[test]
    fn and_or_short_circuit() {
        let c = compile("false && sonar.ok").unwrap();
        let vals = standard();
        assert_eq!(c.eval(&vals), Some(false));
        assert_eq!(vals.reads.get(), 0);
        let c = compile("sonar.ok || odom.speed > 0 || barcode.id == 3").unwrap();
        let vals = standard();
        assert_eq!(c.eval(&vals), Some(true));
        assert_eq!(vals.reads.get(), 1);
        let c = compile("flag && odom.speed > 0").unwrap();
        let vals = standard();
        assert_eq!(c.eval(&vals), Some(false));
        assert_eq!(vals.reads.get(), 1);
    }

    #[test]
    fn literals_and_lexing() {
        assert_eq!(eval(r#"label == "dock""#), Some(true));
        assert_eq!(eval("label == 'dock'"), Some(true));
        assert_eq!(eval(r#"'it\'s' == "it's""#), Some(true));
        assert_eq!(eval(r#""say \"hi\"" == 'say "hi"'"#), Some(true));
        assert_eq!(eval(r#"len('a\\b') == 3"#), Some(true));
        assert_eq!(eval("len('') == 0"), Some(true));
        assert_eq!(eval("\tbarcode.id\n==\r\n3 "), Some(true));
        assert_eq!(eval("0.25 == 25e-2"), Some(true));
        assert_eq!(eval("007 == 7"), Some(true));
        assert_err(".5 < 1", 1, &["`0.5`, not `.5`"]);
        assert_err("3. < 1", 3, &["digits after the decimal point"]);
        assert_err("1e < 1", 3, &["exponent"]);
        assert_err("1e+ < 1", 4, &["exponent"]);
        assert_err("3abc < 1", 2, &["unexpected `a` right after a number"]);
        assert_err("1.2.3 < 1", 4, &["unexpected `.`"]);
        assert_err("1e999 < 1", 1, &["too large"]);
        assert_err("label == 'dock", 10, &["not closed"]);
        assert_err("label == 'dock\\", 10, &["not closed"]);
        assert_err(r"label == 'a\nb'", 12, &[r"unknown escape `\n`"]);
        assert_err("a = 1", 3, &["`=`", "`==`"]);
        assert_err("flag & flag", 6, &["`&&`"]);
        assert_err("flag | flag", 6, &["`||`"]);
        assert_err("flag # 1", 6, &["unexpected character `#`"]);
        assert_err("flag ∧ flag", 6, &["unexpected character `∧`"]);
        assert_err("sonar. range", 7, &["field name after `.`"]);
        assert_err("sonar.3", 7, &["field name after `.`"]);
        assert_err("", 1, &["empty"]);
        assert_err("   ", 1, &["empty"]);
        assert_err("flag flag", 6, &["expected an operator or the end", "`flag`"]);
        assert_err("(flag", 6, &["`)` to close the `(` at column 1", "end of the condition"]);
        assert_err("flag)", 5, &["expected an operator", "`)`"]);
        assert_err("flag &&", 8, &["expected a value", "end of the condition"]);
        assert_err("&& flag", 1, &["expected a value", "`&&`"]);
        assert_err("()", 2, &["expected a value", "`)`"]);
        assert_err("flag [", 6, &["`[]` indexes an array", "a bool"]);
        let long = format!("flag '{}'", "x".repeat(40));
        assert_err(&long, 6, &["…`"]);
    }

    #[test]
    fn limits() {
        // Source length.
        let ok = format!("{:<width$}", "flag", width = MAX_SOURCE_BYTES);
        assert_eq!(ok.len(), MAX_SOURCE_BYTES);
        assert!(compile(&ok).is_ok());
        let long = format!("{ok} ");
        assert_err(&long, 1, &["too long", "4097 bytes", "4096"]);
        assert!(compile(&"(".repeat(1_000_000)).is_err());

        // Nesting depth: parentheses.
        let nest = |n: usize| format!("{}flag{}", "(".repeat(n), ")".repeat(n));
        assert_eq!(eval(&nest(MAX_DEPTH)), Some(false));
        assert_err(&nest(MAX_DEPTH + 1), MAX_DEPTH + 1, &["nests too deeply", "64"]);
        assert_err(&"(".repeat(4000), MAX_DEPTH + 1, &["nests too deeply"]);
        // Unary operators, brackets and calls count too.
        let nots = |n: usize| format!("{}flag", "!".repeat(n));
        assert_eq!(eval(&nots(MAX_DEPTH)), Some(false));
        assert_err(&nots(MAX_DEPTH + 1), MAX_DEPTH + 1, &["nests too deeply"]);
        assert_err(&"-".repeat(4000), MAX_DEPTH + 1, &["nests too deeply"]);
        let calls = |n: usize| format!("{}1{} > 0", "abs(".repeat(n), ")".repeat(n));
        assert_eq!(eval(&calls(MAX_DEPTH)), Some(true));
        assert_err(&calls(MAX_DEPTH + 1), 4 * MAX_DEPTH + 4, &["nests too deeply"]);
        let index = |n: usize| format!("{}0{} >= 0", "counts[".repeat(n), "]".repeat(n));
        assert!(compile(&index(MAX_DEPTH)).is_ok());
        assert_err(&index(MAX_DEPTH + 1), 7 * MAX_DEPTH + 7, &["nests too deeply"]);
        // The deepest parser recursion: every precedence level at every nesting level.
        let mut worst = String::from("1");
        for _ in 0..MAX_DEPTH / 2 {
            worst = format!("flag || flag && flag == 1 < 1 + 1 * -({worst})");
        }
        assert!(compile(&worst).is_err());

        // Node count: `1 + 1 + … + 1 > 0` with k ones has 2k + 1 nodes.
        let sum = |k: usize| format!("{} > 0", vec!["1"; k].join(" + "));
        assert_eq!(eval(&sum(127)), Some(true));
        let e = err(&sum(128));
        assert!(e.message.contains("too large") && e.message.contains("256"), "{e}");
        assert_eq!(e.column, sum(128).find('>').unwrap() + 1);
        // Many nodes evaluate without trouble (a left-leaning chain of 255).
        let ors = format!("{} || true", vec!["flag"; 127].join(" || "));
        assert_eq!(eval(&ors), Some(true));
        assert_eq!(eval_with(&ors, &Vals::default()), Some(true));
    }

    #[test]
    fn deep_conditions_fit_a_small_stack() {
        // The deepest parser recursion the limits allow, on a 512 KiB stack
        // (a quarter of a default thread's), in debug builds too.
        let handle = std::thread::Builder::new()
            .stack_size(512 * 1024)
            .spawn(|| {
                let d = MAX_DEPTH;
                let parens = format!("{}flag{}", "(".repeat(d), ")".repeat(d));
                let calls = format!("{}1{} > 0", "abs(".repeat(d), ")".repeat(d));
                let mins = format!("{}1{} > 0", "min(1, ".repeat(d), ")".repeat(d));
                let index = format!("{}0{} >= 0", "counts[".repeat(d), "]".repeat(d));
                let mut chain = String::from("1");
                for _ in 0..d {
                    chain = format!("flag || flag && flag == 1 < 1 + 1 * ({chain})");
                }
                let mut right = String::from("flag");
                for _ in 0..d {
                    right = format!("flag && ({right})");
                }
                let mut results = Vec::new();
                for src in [&parens, &calls, &mins, &index, &chain, &right] {
                    results.push(compile(src).ok().and_then(|c| c.eval(&standard())));
                }
                results
            })
            .unwrap();
        let results = handle.join().unwrap();
        // `counts[counts[…]]` runs out of range (counts[0] is 7); the chain does not type-check.
        assert_eq!(results, [Some(false), Some(true), Some(true), None, None, Some(false)]);
    }

    #[test]
    fn refs_are_unique_in_first_use_order() {
        let c = compile("sonar.range[0] < 1 && barcode.id == 3 && sonar.range[1] < 2 || flag").unwrap();
        assert_eq!(c.refs(), &[id("sonar.range"), id("barcode.id"), id("flag")]);
        assert_eq!(c.ref_names(), &["sonar.range", "barcode.id", "flag"]);
        assert_eq!(c.source(), "sonar.range[0] < 1 && barcode.id == 3 && sonar.range[1] < 2 || flag");
        let c = compile("1 < 2").unwrap();
        assert!(c.refs().is_empty() && c.ref_names().is_empty());
        let c = compile("len(label) > 0 && min(pose.x, odom.speed, pose.x) < 1").unwrap();
        assert_eq!(c.ref_names(), &["label", "pose.x", "odom.speed"]);
        assert_eq!(c.refs(), &[id("label"), id("pose.x"), id("odom.speed")]);
        // A compiled condition clones.
        let d = c.clone();
        assert_eq!(d.eval(&standard()), c.eval(&standard()));
    }

    #[test]
    fn pointer_and_display() {
        let src = "label < 3";
        let e = err(src);
        assert_eq!(e.to_string(), "column 7: `<` needs two numbers, got a string and a number");
        assert_eq!(e.pointer(src), "label < 3\n      ^");
        let e = ExprError { column: 1, message: String::new() };
        assert_eq!(e.pointer("x"), "x\n^");
        // Past the end, e.g. "expected a value, found the end".
        let src = "flag &&";
        assert_eq!(err(src).pointer(src), "flag &&\n       ^");
        // Characters, tabs and line breaks keep the caret in place.
        let src = "'é'\t== 1";
        assert_eq!(err(src).pointer(src), "'é'\t== 1\n   \t^");
        let src = "flag &&\n3";
        assert_eq!(err(src).pointer(src), "flag && 3\n     ^");
    }

    /// Compiles `src` (which must not panic) and, if it compiles, evaluates it
    /// against several lookups; checks the error column is inside the source.
    fn exercise(src: &str) {
        match compile(src) {
            Ok(c) => {
                let bad = Vals::default()
                    .with("sonar.range", Value::Str(Arc::from("")))
                    .with("barcode.id", Value::F64(f64::NAN))
                    .with("odom.speed", Value::F64(f64::INFINITY))
                    .with("label", Value::I64(i64::MIN))
                    .with("counts", Value::I64s(Vec::new().into()))
                    .with("raw", Value::Bool(true))
                    .with("flag", Value::Record(Arc::default()));
                for vals in [standard(), Vals::default(), bad] {
                    let _ = c.eval(&vals);
                }
                assert!(c.refs().len() == c.ref_names().len());
            }
            Err(e) => {
                assert!(e.column >= 1 && e.column <= src.chars().count() + 1, "`{src}`: {e}");
                let _ = e.pointer(src);
            }
        }
    }

    const FRAGMENTS: &[&str] = &[
        "sonar.range",
        "sonar.ok",
        "barcode.id",
        "odom.speed",
        "label",
        "raw",
        "pose",
        "pose.x",
        "counts",
        "gains",
        "flag",
        "nope",
        "abs",
        "min",
        "max",
        "len",
        "true",
        "false",
        "0",
        "1",
        "-1",
        "2.5",
        "1e3",
        "1e400",
        ".5",
        "'s'",
        "\"t\"",
        "'\\''",
        "'",
        "\"",
        "\\",
        "(",
        ")",
        "[",
        "]",
        ",",
        "!",
        "-",
        "+",
        "*",
        "/",
        "%",
        "<",
        "<=",
        ">",
        ">=",
        "==",
        "!=",
        "=",
        "&&",
        "||",
        "&",
        "|",
        " ",
        "\t",
        "\n",
        ".",
        "é",
        "∧",
        "_",
        "x",
        "9",
    ];

    /// Deterministic garbling of valid conditions and random token soup.
    #[test]
    fn no_panic_on_garbled_inputs() {
        let seeds = [
            "sonar.range[0] < 0.25 && barcode.id == 3",
            "min(sonar.range[0], sonar.range[1], 2) < abs(odom.speed) || !sonar.ok",
            "len(label) > 2 && label != 'dock' && counts[barcode.id - 1] % 2 == 1",
            "(((gains[1] + 1) * 2 - 3 / (odom.speed)) >= max(1, 2, pose.x)) == flag",
        ];
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut rand = move |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n as u64) as usize
        };
        for _ in 0..3000 {
            let seed: Vec<char> = seeds[rand(seeds.len())].chars().collect();
            let mut chars = seed.clone();
            for _ in 0..=rand(4) {
                let at = rand(chars.len() + 1);
                match rand(3) {
                    0 if at < chars.len() => {
                        chars.remove(at);
                    }
                    1 => chars.insert(at, seed[rand(seed.len())]),
                    _ => {
                        let frag = FRAGMENTS[rand(FRAGMENTS.len())];
                        for (k, c) in frag.chars().enumerate() {
                            chars.insert(at + k, c);
                        }
                    }
                }
            }
            exercise(&chars.into_iter().collect::<String>());
            let soup: String = (0..rand(30)).map(|_| FRAGMENTS[rand(FRAGMENTS.len())]).collect();
            exercise(&soup);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]

        #[test]
        fn no_panic_on_arbitrary_strings(src in any::<String>()) {
            exercise(&src);
        }

        #[test]
        fn no_panic_on_token_soup(parts in prop::collection::vec(prop::sample::select(FRAGMENTS), 0..40)) {
            exercise(&parts.concat());
            exercise(&parts.join(" "));
        }

        #[test]
        fn arithmetic_matches_f64(a in -1e6f64..1e6, b in -1e6f64..1e6) {
            let src = format!("{a:e} + {b:e} * 2 - {a:e} / 4 > {b:e}");
            prop_assert_eq!(eval(&src), Some(a + b * 2.0 - a / 4.0 > b));
        }
    }
}
