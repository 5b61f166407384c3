//! The condition language of situate: a monitor's condition and a plotted
//! formula.
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
//! The same language, with a number as its result, is a [`Formula`]: a
//! derived series the GUI plots (`abs(drive.w) * 2`). The user documentation,
//! with examples checked against the manager, is `docs/conditions.md` in the
//! repository.
//!
//! # Pipeline
//!
//! A source goes lex → parse → check → program, each step in a file of its
//! own:
//!
//! - `lex.rs` cuts the text into tokens (numbers, strings, dotted names,
//!   operators), each with its byte offsets for the error's column;
//! - `parse.rs` reads the tokens by precedence (an operator stack for the
//!   binary operators; it recurses only into brackets, calls and unary
//!   operators) and enforces the limits below;
//! - `check.rs` types each part as the parser builds it (one pass, so an
//!   error is reported where it is written) and resolves names through the
//!   [`Resolver`];
//! - `program.rs` holds the result, a typed tree in one arena, and evaluates
//!   it every cycle through the [`Lookup`] without allocating.
//!
//! # Who uses it
//!
//! The skill manager's monitors (`situate_manager::monitor`; the manager
//! re-exports this crate as `situate_manager::expr`) compile conditions over
//! the robot's signals, parameters, `time` and `cycle`; the GUI's formulas
//! (`situate_gui::formula`) compile over the signal leaves. The language
//! itself knows no robot: names mean what the caller's [`Resolver`] says and
//! values come from the caller's [`Lookup`], so it is a crate of its own,
//! built and tested without the manager.
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

mod check;
mod lex;
mod parse;
mod program;

use parse::compile_program;
use program::{Program, Ty};
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
    /// local ids, made the evaluator's own: the manager's monitors).
    pub fn remap_refs(&mut self, map: impl Fn(usize) -> usize) {
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
