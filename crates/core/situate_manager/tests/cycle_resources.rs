//! Resources and priority; faults.

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{Control, Event, Registry};

fn drive_writer(name: &str, priority: i32, v: f64) -> situate_core::SkillType {
    let d = with_priority(decl(name, SkillKind::Sync, &[], &[("drive", "{v: f64, w: f64}")]), priority);
    fn_type(d, move |io, _| {
        io.outputs[0] = Some(situate_core::record_value(vec![("v", Value::F64(v)), ("w", Value::F64(0.0))]));
        Ok(())
    })
}

fn drive_v(m: &mut situate_manager::Manager) -> Option<f64> {
    m.query("drive.v").unwrap().value.and_then(|v| v.as_f64())
}

#[test]
fn the_highest_priority_active_writer_wins_and_is_recorded() {
    let mut reg = Registry::new();
    reg.add(drive_writer("wander", 10, 0.2));
    reg.add(drive_writer("runaway", 20, -0.3));
    let spec = simulated("arb").skill(skill("wander", "wander")).skill(skill("runaway", "runaway"));
    let mut m = build(&spec, &reg);
    m.step(1).unwrap();
    assert_eq!(drive_v(&mut m), Some(-0.3));
    let winners = m.winners().unwrap();
    assert_eq!(winners.len(), 2, "drive.v and drive.w are both contested: {winners:?}");
    assert!(winners.iter().all(|w| w.winner.as_deref() == Some("runaway") && w.writers == ["wander", "runaway"]));
    m.deactivate(&["runaway"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(drive_v(&mut m), Some(0.2));
    assert_eq!(m.winners().unwrap()[0].winner.as_deref(), Some("wander"));
    assert_eq!(m.query("drive").unwrap().writer.as_deref(), Some("wander"));
    // The sequencer may raise a priority at run time.
    m.activate(&["runaway"]).unwrap();
    m.request(situate_manager::Request::SetPriority { skill: "wander".into(), priority: 30 }).unwrap();
    m.step(1).unwrap();
    assert_eq!(drive_v(&mut m), Some(0.2));
}

#[test]
fn equal_priorities_at_run_time_go_to_the_first_declared() {
    let mut reg = Registry::new();
    reg.add(drive_writer("first", 10, 1.0));
    reg.add(drive_writer("second", 20, 2.0));
    let spec = simulated("tie").skill(skill("a", "first")).skill(skill("b", "second"));
    let mut m = build(&spec, &reg);
    m.request(situate_manager::Request::SetPriority { skill: "b".into(), priority: 10 }).unwrap();
    m.step(1).unwrap();
    assert_eq!(drive_v(&mut m), Some(1.0));
}

/// A writer that writes only sometimes loses nothing when silent: the
/// other writer's value stands.
#[test]
fn a_silent_high_priority_writer_leaves_the_resource_to_others() {
    let mut reg = Registry::new();
    reg.add(drive_writer("wander", 10, 0.2));
    let d = with_priority(decl("runaway", SkillKind::Sync, &[], &[("drive", "{v: f64, w: f64}")]), 20);
    reg.add(fn_type(d, |io, _| {
        if io.cx.cycle() % 2 == 0 {
            io.outputs[0] = Some(situate_core::record_value(vec![("v", Value::F64(-1.0)), ("w", Value::F64(0.0))]));
        }
        Ok(())
    }));
    let mut m = build(&simulated("quiet").skill(skill("w", "wander")).skill(skill("r", "runaway")), &reg);
    let mut seen = Vec::new();
    for _ in 0..4 {
        m.step(1).unwrap();
        seen.push((drive_v(&mut m).unwrap(), m.winners().unwrap()[0].winner.clone().unwrap()));
    }
    assert_eq!(
        seen,
        vec![(0.2, "w".to_string()), (-1.0, "r".to_string()), (0.2, "w".to_string()), (-1.0, "r".to_string())]
    );
    // Every hand-over is counted (w, r, w, r: three), and every cycle it was held.
    let w = &m.winners().unwrap()[0];
    assert_eq!((w.switches, w.held_cycles), (3, 4));
    // A cycle nobody writes it in is no hand-over: r, nobody, r.
    m.deactivate(&["w"]).unwrap();
    for _ in 0..4 {
        m.step(1).unwrap();
    }
    let w = &m.winners().unwrap()[0];
    assert_eq!((w.switches, w.held_cycles), (3, 6), "{w:?}");
}

#[test]
fn a_failing_or_panicking_body_is_faulted_and_deactivated_while_the_rest_runs() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(1.0)));
    reg.add(adder("add", 1.0, &log, "ok"));
    reg.add(fn_type(decl("fails", SkillKind::Sync, &[("x", "f64")], &[]), |io, _| {
        if io.cx.cycle() == 2 {
            return Err("sensor model diverged".into());
        }
        Ok(())
    }));
    reg.add(fn_type(decl("panics", SkillKind::Sync, &[("x", "f64")], &[]), |io, _| {
        if io.cx.cycle() == 3 {
            panic!("index out of bounds");
        }
        Ok(())
    }));
    reg.add(fn_type(decl("liar", SkillKind::Sync, &[], &[("z", "f64")]), |io, _| {
        io.outputs[0] = Some(Value::Str("not a number".into()));
        Ok(())
    }));
    let spec = simulated("faults")
        .skill(skill("s", "src").remap("out", "x"))
        .skill(skill("a", "add"))
        .skill(skill("f", "fails"))
        .skill(skill("p", "panics"))
        .skill(skill("l", "liar"));
    let mut m = build(&spec, &reg);
    let events = m.events();
    m.step(5).unwrap();
    assert_eq!(entries(&log).len(), 5, "the healthy skill ran every cycle");
    let faults: Vec<(String, String, u64)> = events
        .try_iter()
        .filter_map(|e| match e {
            Event::SkillFaulted { skill, cause, cycle } => Some((skill, cause, cycle)),
            _ => None,
        })
        .collect();
    assert_eq!(
        faults,
        vec![
            ("l".into(), "output `z` expects f64, the body produced a string".into(), 1),
            ("f".into(), "sensor model diverged".into(), 2),
            ("p".into(), "panicked: index out of bounds".into(), 3),
        ]
    );
    let p = m.skill("p").unwrap();
    assert!(!p.active);
    assert_eq!(p.faulted.as_deref(), Some("panicked: index out of bounds"));
    assert_eq!(m.query("z").unwrap().value, None, "a wrongly typed output is never committed");
    // The sequencer may reactivate a faulted skill; that clears the fault.
    m.activate(&["f"]).unwrap();
    assert_eq!(m.skill("f").unwrap().faulted, None);
    m.step(1).unwrap();
    assert!(m.skill("f").unwrap().active);
}

/// One skill whose two outputs write the same signal: the first wins while
/// it writes; in a cycle it is silent, the second's value is committed, and
/// the skill's last outputs show that value (a port's last output is read
/// from its slot while its skill holds it), not the one the second output
/// lost with before.
#[test]
fn a_skill_with_two_outputs_on_one_signal_reports_what_each_last_wrote() {
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::Arc;
    let runs = Arc::new(AtomicU64::new(0));
    let counter = Arc::clone(&runs);
    let d = decl("twice", SkillKind::Sync, &[], &[("a", "f64"), ("b", "f64")]);
    let mut reg = Registry::new();
    reg.add(fn_type(d, move |io, _| {
        let n = counter.fetch_add(1, Ordering::Relaxed) + 1;
        // `a` is silent in the third run only; `b` always writes.
        io.outputs[0] = (n != 3).then_some(Value::F64(n as f64));
        io.outputs[1] = Some(Value::F64(100.0 + n as f64));
        Ok(())
    }));
    let spec = simulated("twice").skill(skill("t", "twice").remap("a", "s").remap("b", "s"));
    let mut m = build(&spec, &reg);
    let last = |m: &mut situate_manager::Manager| -> Vec<Option<f64>> {
        m.skill("t").unwrap().outputs.iter().map(|p| p.value.as_ref().and_then(Value::as_f64)).collect()
    };
    m.step(2).unwrap();
    assert_eq!(m.query("s").unwrap().value.and_then(|v| v.as_f64()), Some(2.0), "the first output wins");
    assert_eq!(last(&mut m), vec![Some(2.0), Some(102.0)]);
    m.step(1).unwrap();
    assert_eq!(m.query("s").unwrap().value.and_then(|v| v.as_f64()), Some(103.0), "`a` was silent");
    assert_eq!(last(&mut m), vec![Some(103.0), Some(103.0)]);
    m.step(1).unwrap();
    assert_eq!(m.query("s").unwrap().value.and_then(|v| v.as_f64()), Some(4.0));
    assert_eq!(last(&mut m), vec![Some(4.0), Some(104.0)]);
}
