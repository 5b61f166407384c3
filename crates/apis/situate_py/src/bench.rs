//! Rust twins of the Python benchmark's skills (`bench/python/`), registered
//! in the in-process robot (`situate.LocalRobot`) only.
//!
//! - `bench.source` (sync): writes `x: f64` = the cycle number;
//! - `bench.double` (sync): reads `x: f64`, writes `y: f64` = 2·x — the
//!   trivial skill whose per-call cost the benchmark compares with the same
//!   skill in Python.

use situate_core::{FnSkill, PortSpec, SignalType, Skill, SkillDecl, SkillKind, SkillType, Value};
use situate_manager::Registry;

fn source() -> SkillType {
    let mut d = SkillDecl::new("bench.source", SkillKind::Sync);
    d.doc = "Writes x = the cycle number (benchmark).".into();
    d.outputs.push(PortSpec::new("x", SignalType::F64));
    let decl = d.clone();
    SkillType::new(d, move || {
        Ok(Box::new(FnSkill::new(&decl, |io, _| {
            io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
            Ok(())
        })) as Box<dyn Skill>)
    })
}

fn double() -> SkillType {
    let mut d = SkillDecl::new("bench.double", SkillKind::Sync);
    d.doc = "y = 2·x (benchmark: the trivial skill in Rust).".into();
    d.inputs.push(PortSpec::new("x", SignalType::F64));
    d.outputs.push(PortSpec::new("y", SignalType::F64));
    let decl = d.clone();
    SkillType::new(d, move || {
        Ok(Box::new(FnSkill::new(&decl, |io, _| {
            if let Some(Value::F64(x)) = io.inputs[0] {
                io.outputs[0] = Some(Value::F64(2.0 * x));
            }
            Ok(())
        })) as Box<dyn Skill>)
    })
}

/// Adds `bench.source` and `bench.double`.
pub fn register(registry: &mut Registry) {
    registry.add(source());
    registry.add(double());
}
