//! The condition language through its public API: what compiles, what is
//! refused and with which message and column, what evaluates to what, and
//! that no input makes it panic or overflow the stack. The signals and values
//! the tests know are here; the tests are grouped by concern in the modules.

mod checks;
mod eval;
mod limits;
mod syntax;

use proptest::prelude::*;
use situate_core::{ElemType, SignalType, Value};
use situate_expr::{Condition, ExprError, Formula, Lookup, Resolver, MAX_DEPTH, MAX_SOURCE_BYTES};
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
