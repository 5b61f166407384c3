//! Skill declarations: what a skill says about itself.
//!
//! A skill author gives three things — inputs, outputs and a body — and
//! optionally typed parameters, a priority and a kind. The [`SkillDecl`] is
//! that declaration as data; the skill manager derives everything else
//! (wiring, scheduling, queries, display) from it.

use std::fmt;
use std::sync::Arc;

use crate::types::SignalType;
use crate::value::Value;

/// How a skill's body is run (paper 3.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SkillKind {
    /// Synchronous cskill: runs in the cycle when a complete new set of its
    /// required inputs has been produced in that cycle.
    Sync,
    /// Asynchronous cskill: runs continuously on its own thread on the latest
    /// inputs; the cycle takes its latest result and never waits for it.
    Async,
    /// dskill: wraps a device. The body does the device I/O on its own thread;
    /// inputs are buffered commands, outputs are the latest readings.
    Device,
}

impl SkillKind {
    pub fn name(self) -> &'static str {
        match self {
            SkillKind::Sync => "sync",
            SkillKind::Async => "async",
            SkillKind::Device => "device",
        }
    }

    pub fn parse(text: &str) -> Option<SkillKind> {
        match text {
            "sync" => Some(SkillKind::Sync),
            "async" => Some(SkillKind::Async),
            "device" | "dskill" => Some(SkillKind::Device),
            _ => None,
        }
    }

    pub fn is_threaded(self) -> bool {
        !matches!(self, SkillKind::Sync)
    }
}

impl fmt::Display for SkillKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// One input or output port.
#[derive(Debug, Clone, PartialEq)]
pub struct PortSpec {
    /// The port's name, unique among the skill's inputs (or outputs).
    pub name: String,
    /// The signal it connects to unless the robot file remaps it; a record
    /// field may be named with a path (`pose.x`).
    pub signal: String,
    pub ty: SignalType,
    /// An optional input does not hold its skill back: the body sees `None`
    /// when nobody produced it this cycle.
    pub optional: bool,
    pub doc: String,
}

impl PortSpec {
    pub fn new(name: &str, ty: SignalType) -> Self {
        PortSpec { name: name.into(), signal: name.into(), ty, optional: false, doc: String::new() }
    }

    pub fn optional(mut self) -> Self {
        self.optional = true;
        self
    }

    pub fn signal(mut self, signal: &str) -> Self {
        self.signal = signal.into();
        self
    }
}

/// The type of a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamType {
    Bool,
    I64,
    F64,
    Str,
}

impl ParamType {
    pub fn name(self) -> &'static str {
        match self {
            ParamType::Bool => "bool",
            ParamType::I64 => "i64",
            ParamType::F64 => "f64",
            ParamType::Str => "string",
        }
    }
}

/// A typed parameter with its default, range, unit and documentation.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    pub name: String,
    pub ty: ParamType,
    pub default: Value,
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub unit: String,
    pub doc: String,
}

/// Why a parameter value was refused. The message reads well after
/// "parameter `NAME` ".
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("expects {expected}, got {got}")]
pub struct ParamValueError {
    pub expected: String,
    pub got: String,
}

impl ParamSpec {
    pub fn new(name: &str, ty: ParamType, default: Value) -> Self {
        ParamSpec { name: name.into(), ty, default, min: None, max: None, unit: String::new(), doc: String::new() }
    }

    pub fn range(mut self, min: Option<f64>, max: Option<f64>) -> Self {
        self.min = min;
        self.max = max;
        self
    }

    /// What this parameter accepts, in words: "a number in [0.1, 3.0]".
    pub fn expectation(&self) -> String {
        let what = match self.ty {
            ParamType::Bool => return "a bool (true or false)".into(),
            ParamType::Str => return "a string".into(),
            ParamType::I64 => "an integer",
            ParamType::F64 => "a number",
        };
        // An integer's bounds read as integers (`[1, 100]`), a number's as numbers (`[0.0, 3.0]`).
        let bound = |x: f64| {
            if self.ty == ParamType::I64 && x.fract() == 0.0 && x.abs() < 9.2e18 {
                format!("{}", x as i64)
            } else {
                format!("{x:?}")
            }
        };
        match (self.min, self.max) {
            (Some(lo), Some(hi)) => format!("{what} in [{}, {}]", bound(lo), bound(hi)),
            (Some(lo), None) => format!("{what} ≥ {}", bound(lo)),
            (None, Some(hi)) => format!("{what} ≤ {}", bound(hi)),
            // Unbounded, a parameter still has its type's range.
            (None, None) if self.ty == ParamType::I64 => format!("{what} from {} to {}", i64::MIN, i64::MAX),
            (None, None) => "a finite number".to_string(),
        }
    }

    /// Checks a candidate value and returns it in the parameter's own type
    /// (an integer given for an `f64` parameter becomes a float).
    pub fn check(&self, value: &Value) -> Result<Value, ParamValueError> {
        let refuse = || ParamValueError {
            expected: self.expectation(),
            got: match (self.ty, value) {
                // A float refused where an integer is due reads as one (`2.0`,
                // not `2`), and a large one exactly (`9223372036854775808`).
                (ParamType::I64, Value::F64(x)) if x.fract() == 0.0 && x.abs() < 1e16 => format!("{x:.1}"),
                (ParamType::I64, Value::F64(x)) if x.abs() < 1e20 => format!("{x:.0}"),
                (ParamType::I64, Value::F64(x)) if x.is_finite() => format!("{x:e}"),
                _ => describe(value),
            },
        };
        let v = match (self.ty, value) {
            (ParamType::Bool, Value::Bool(_)) => value.clone(),
            (ParamType::Str, Value::Str(_)) => value.clone(),
            (ParamType::I64, Value::I64(_)) => value.clone(),
            (ParamType::F64, Value::F64(x)) if x.is_finite() => value.clone(),
            (ParamType::F64, Value::I64(x)) => Value::F64(*x as f64),
            _ => return Err(refuse()),
        };
        if let Some(x) = v.as_f64().filter(|_| matches!(self.ty, ParamType::I64 | ParamType::F64)) {
            if self.min.is_some_and(|lo| x < lo) || self.max.is_some_and(|hi| x > hi) {
                return Err(refuse());
            }
        }
        Ok(v)
    }
}

fn describe(value: &Value) -> String {
    match value {
        Value::Str(s) => format!("{s:?}"),
        Value::F32s(_) | Value::F64s(_) | Value::I64s(_) => "a list of numbers".to_string(),
        Value::Record(_) => "a record".to_string(),
        Value::Bytes(_) => "bytes".to_string(),
        other => other.to_string(),
    }
}

/// A Rust type usable as a parameter field: `bool`, `i64`, `f64`, `String`.
pub trait ParamValue: Sized {
    fn param_type() -> ParamType;
    fn from_param(value: &Value) -> Option<Self>;
    fn into_param(self) -> Value;
}

impl ParamValue for bool {
    fn param_type() -> ParamType {
        ParamType::Bool
    }
    fn from_param(value: &Value) -> Option<Self> {
        match value {
            Value::Bool(b) => Some(*b),
            _ => None,
        }
    }
    fn into_param(self) -> Value {
        Value::Bool(self)
    }
}

impl ParamValue for i64 {
    fn param_type() -> ParamType {
        ParamType::I64
    }
    fn from_param(value: &Value) -> Option<Self> {
        match value {
            Value::I64(x) => Some(*x),
            _ => None,
        }
    }
    fn into_param(self) -> Value {
        Value::I64(self)
    }
}

impl ParamValue for f64 {
    fn param_type() -> ParamType {
        ParamType::F64
    }
    fn from_param(value: &Value) -> Option<Self> {
        value.as_f64().filter(|_| !matches!(value, Value::Bool(_)))
    }
    fn into_param(self) -> Value {
        Value::F64(self)
    }
}

impl ParamValue for String {
    fn param_type() -> ParamType {
        ParamType::Str
    }
    fn from_param(value: &Value) -> Option<Self> {
        match value {
            Value::Str(s) => Some(s.to_string()),
            _ => None,
        }
    }
    fn into_param(self) -> Value {
        Value::Str(Arc::from(self))
    }
}

/// Everything a skill type declares about itself.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillDecl {
    /// The name robot files use for this type (`runaway`, `toy.sonar`).
    pub type_name: String,
    pub doc: String,
    pub kind: SkillKind,
    pub inputs: Vec<PortSpec>,
    pub outputs: Vec<PortSpec>,
    pub params: Vec<ParamSpec>,
    /// Priority for contention over a resource; higher wins.
    pub priority: i32,
    /// Names of things this skill uses exclusively (a non-reentrant library,
    /// an interpreter lock): skills sharing a claim never run at the same time.
    pub claims: Vec<String>,
}

impl SkillDecl {
    pub fn new(type_name: &str, kind: SkillKind) -> Self {
        SkillDecl {
            type_name: type_name.into(),
            doc: String::new(),
            kind,
            inputs: Vec::new(),
            outputs: Vec::new(),
            params: Vec::new(),
            priority: 0,
            claims: Vec::new(),
        }
    }

    pub fn param(&self, name: &str) -> Option<(usize, &ParamSpec)> {
        self.params.iter().enumerate().find(|(_, p)| p.name == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_integers_bounds_read_as_integers_and_a_numbers_as_numbers() {
        let int = |lo, hi| ParamSpec::new("n", ParamType::I64, Value::I64(3)).range(lo, hi).expectation();
        assert_eq!(int(Some(1.0), Some(100.0)), "an integer in [1, 100]");
        assert_eq!(int(Some(-5.0), None), "an integer ≥ -5");
        assert_eq!(int(None, Some(7.0)), "an integer ≤ 7");
        // A bound that is not a whole number (a hand-written manifest's) is shown as it is.
        assert_eq!(int(Some(0.5), None), "an integer ≥ 0.5");
        let num = ParamSpec::new("x", ParamType::F64, Value::F64(1.0)).range(Some(0.0), Some(3.0));
        assert_eq!(num.expectation(), "a number in [0.0, 3.0]");
    }

    #[test]
    fn a_number_out_of_range_is_refused_with_the_range_named() {
        let p = ParamSpec::new("safe_distance", ParamType::F64, Value::F64(0.5)).range(Some(0.1), Some(3.0));
        assert_eq!(p.check(&Value::F64(0.3)), Ok(Value::F64(0.3)));
        assert_eq!(p.check(&Value::I64(2)), Ok(Value::F64(2.0)));
        let e = p.check(&Value::F64(7.0)).unwrap_err();
        assert_eq!(e.to_string(), "expects a number in [0.1, 3.0], got 7");
        let e = p.check(&Value::Str("far".into())).unwrap_err();
        assert_eq!(e.to_string(), "expects a number in [0.1, 3.0], got \"far\"");
        assert!(p.check(&Value::F64(f64::NAN)).is_err());
    }

    #[test]
    fn integers_are_not_silently_truncated() {
        let p = ParamSpec::new("n", ParamType::I64, Value::I64(1)).range(Some(0.0), None);
        assert!(p.check(&Value::F64(1.5)).is_err());
        assert!(p.check(&Value::I64(-1)).is_err());
        assert_eq!(p.check(&Value::I64(4)), Ok(Value::I64(4)));
    }

    #[test]
    fn an_unbounded_parameter_names_its_type_range() {
        let n = ParamSpec::new("seed", ParamType::I64, Value::I64(1));
        assert_eq!(
            n.check(&Value::F64(9_223_372_036_854_775_808.0)).unwrap_err().to_string(),
            "expects an integer from -9223372036854775808 to 9223372036854775807, got 9223372036854775808"
        );
        // A whole float where an integer is due reads as a float.
        assert_eq!(
            n.check(&Value::F64(2.0)).unwrap_err().to_string(),
            "expects an integer from -9223372036854775808 to 9223372036854775807, got 2.0"
        );
        assert_eq!(
            n.check(&Value::F64(-1e300)).unwrap_err().to_string(),
            "expects an integer from -9223372036854775808 to 9223372036854775807, got -1e300"
        );
        let x = ParamSpec::new("gain", ParamType::F64, Value::F64(1.0));
        assert_eq!(x.check(&Value::F64(f64::INFINITY)).unwrap_err().to_string(), "expects a finite number, got inf");
        assert_eq!(x.check(&Value::F64(-1e300)), Ok(Value::F64(-1e300)));
    }
}
