//! No worker thread of a skill dies silently (issue 17): a panic outside the
//! body — in the skill's own `set_param`, run on its worker thread or, for a
//! cskill run in the cycle, on the cycle's thread — faults the skill with the
//! cause, and activating it again makes a fresh body (and thread).

mod common;

use common::*;
use situate_core::{Io, Skill, SkillError, SkillKind, SkillType, Value};
use situate_manager::{ClockKind, Control, Event, Manager, Registry, RobotSpec};

/// Writes `y = gain` every run; `set_param` panics on a gain over 5.
struct Touchy {
    gain: f64,
}

impl Skill for Touchy {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        io.outputs[0] = Some(Value::F64(self.gain));
        Ok(())
    }

    fn set_param(&mut self, _index: usize, value: &Value) {
        let gain = value.as_f64().unwrap_or(0.0);
        assert!(gain <= 5.0, "gain {gain} is more than this skill can take");
        self.gain = gain;
    }
}

fn touchy(kind: SkillKind) -> SkillType {
    let d = with_param(decl("touchy", kind, &[("x", "f64")], &[("y", "f64")]), "gain", 1.0, 0.0, 10.0);
    SkillType::new(d, || Ok(Box::new(Touchy { gain: 1.0 }) as Box<dyn Skill>))
}

fn robot(kind: SkillKind) -> Manager {
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(2.0)));
    reg.add(touchy(kind));
    let spec = RobotSpec::new("touchy")
        .clock(ClockKind::Wall)
        .period_s(0.005)
        .skill(skill("s", "src").remap("out", "x"))
        .skill(skill("t", "touchy"));
    build(&spec, &reg)
}

/// Runs cycles until `done` holds (at most [`BOUND`]).
fn cycles_until(m: Manager, done: impl Fn(&mut Manager) -> bool + Send + 'static) -> Manager {
    within_bound(move || {
        let mut m = m;
        while !done(&mut m) {
            m.run_cycles(1);
        }
        m
    })
}

fn faulted(m: &mut Manager) -> Option<String> {
    m.skill("t").unwrap().faulted
}

fn check(kind: SkillKind, cause: &str) {
    let mut m = robot(kind);
    let events = m.events();
    m.set_param("t", "gain", Value::F64(3.0)).unwrap();
    let mut m = cycles_until(m, |m| m.query("y").unwrap().value == Some(Value::F64(3.0)));
    m.set_param("t", "gain", Value::F64(9.0)).unwrap();
    let mut m = cycles_until(m, |m| faulted(m).is_some());
    let fault = faulted(&mut m).unwrap();
    assert!(fault.starts_with(cause), "{fault}");
    assert!(fault.contains("gain 9 is more than this skill can take"), "{fault}");
    assert!(!m.skill("t").unwrap().active);
    assert!(
        events
            .try_iter()
            .any(|e| matches!(&e, Event::SkillFaulted { skill, cause, .. } if skill == "t" && *cause == fault)),
        "reported as skill_faulted"
    );
    // Activated again: a fresh body (and thread), with the parameters it has now (9 is kept,
    // a fresh body is given it again: lower it first).
    m.set_param("t", "gain", Value::F64(4.0)).unwrap();
    m.activate(&["t"]).unwrap();
    let mut m = cycles_until(m, |m| m.query("y").unwrap().value == Some(Value::F64(4.0)));
    assert_eq!(faulted(&mut m), None);
}

#[test]
fn a_panic_in_set_param_on_an_async_skills_thread_faults_it_and_reactivation_makes_a_fresh_one() {
    check(SkillKind::Async, "its thread ended: panicked: ");
}

#[test]
fn a_panic_in_set_param_of_a_sync_skill_faults_it_instead_of_unwinding_the_cycle() {
    check(SkillKind::Sync, "panicked in set_param (`gain`): ");
}
