//! A body left behind on a spawned manager's cycle thread: it runs where it
//! is, with the manager's lock held, reading its input in its slot or its
//! inputs lent from their slots. Once the watchdog has left it behind, the
//! next cycles must neither change what it reads nor lose what it was lent.
//!
//! No timing is asserted: the stuck body waits at a gate the test holds
//! closed, and every wait is for a condition with a generous bound.

mod common;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{ClockKind, Control, Registry, Request, RobotSpec};

/// A source writing the cycle number to `out` in cycles up to `last`.
fn counter(name: &str, last: u64) -> situate_core::SkillType {
    fn_type(decl(name, SkillKind::Sync, &[], &[("out", "f64")]), move |io, _| {
        if io.cx.cycle() <= last {
            io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        }
        Ok(())
    })
}

fn wall(robot: &str) -> RobotSpec {
    RobotSpec::new(robot).clock(ClockKind::Wall).period_s(0.002)
}

#[test]
fn a_body_left_behind_reads_its_input_unchanged_while_later_cycles_write_its_slot() {
    let gate = Gate::default();
    let seen: Arc<Mutex<Vec<f64>>> = Arc::default();
    let mut reg = Registry::new();
    reg.add(counter("count", u64::MAX));
    let (g, s) = (gate.clone(), seen.clone());
    // One plain input: read where it is, in its slot.
    reg.add(fn_type(decl("reader", SkillKind::Sync, &[("x", "f64")], &[]), move |io, _| {
        let read = |io: &situate_core::Io<'_>| io.inputs[0].as_ref().and_then(Value::as_f64).unwrap_or(-1.0);
        if io.cx.cycle() == 5 {
            s.lock().unwrap().push(read(io));
            g.pass();
            s.lock().unwrap().push(read(io));
        }
        Ok(())
    }));
    let spec =
        wall("in-place").skill(skill("c", "count").remap("out", "x")).skill(skill("r", "reader").budget_ms(50.0));
    let m = build(&spec, &reg);
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    assert!(fault_of(&events, "r").contains("left behind"));
    // Later cycles write the slot it read many times over.
    until("cycles after the fault", || handle.query("x").unwrap().cycle > 20);
    gate.open();
    until("the body's second reading", || seen.lock().unwrap().len() == 2);
    assert_eq!(*seen.lock().unwrap(), [5.0, 5.0], "what the body read changed under it");
    handle.request(Request::Shutdown).unwrap();
    assert!(join.join_timeout(BOUND).is_ok());
}

#[test]
fn inputs_lent_to_a_body_left_behind_stay_in_their_slots() {
    let gate = Gate::default();
    let mut reg = Registry::new();
    // Both written for the last time in cycle 5, the cycle the body gets stuck in.
    reg.add(counter("count", 5));
    let g = gate.clone();
    // Two plain inputs: lent to the body for its run.
    reg.add(fn_type(decl("pair", SkillKind::Sync, &[("a", "f64"), ("b", "f64")], &[]), move |io, _| {
        if io.cx.cycle() == 5 {
            g.pass();
        }
        Ok(())
    }));
    let spec = wall("lent")
        .skill(skill("ca", "count").remap("out", "a"))
        .skill(skill("cb", "count").remap("out", "b"))
        .skill(skill("p", "pair").budget_ms(50.0));
    let m = build(&spec, &reg);
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    assert!(fault_of(&events, "p").contains("left behind"));
    let at = handle.stats().unwrap().cycle;
    until("cycles after the fault", || handle.stats().unwrap().cycle > at + 10);
    for signal in ["a", "b"] {
        let q = handle.query(signal).unwrap();
        assert_eq!((q.value, q.cycle), (Some(Value::F64(5.0)), 5), "`{signal}` lost with the body left behind");
    }
    gate.open();
    // The body returns and its thread drops what it held; the manager is unharmed.
    until("the skill can be activated again", || handle.activate(&["p"]).is_ok());
    let now = handle.stats().unwrap().cycle;
    until("cycles after the body returned", || handle.stats().unwrap().cycle > now + 10);
    assert_eq!(handle.query("a").unwrap().value, Some(Value::F64(5.0)));
    handle.request(Request::Shutdown).unwrap();
    assert!(join.join_timeout(BOUND).is_ok());
}

#[test]
fn a_body_stuck_in_a_parallel_batch_is_left_behind_and_the_cycle_goes_on() {
    let gate = Gate::default();
    let mut reg = Registry::new();
    let g = gate.clone();
    // Long enough to be worth the pool: the two run as one batch, with the lock let go.
    let d = with_param(decl("spinner", SkillKind::Sync, &[], &[("out", "f64")]), "mode", 0.0, 0.0, 1.0);
    reg.add(fn_type(d, move |io, params| {
        let until = Instant::now() + Duration::from_micros(200);
        while Instant::now() < until {
            std::hint::spin_loop();
        }
        if params[0].as_f64() == Some(1.0) {
            g.pass();
        }
        io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        Ok(())
    }));
    let spec = RobotSpec::new("batch")
        .clock(ClockKind::Wall)
        .period_s(0.005)
        .executor(situate_manager::ExecutorKind::Parallel, Some(2))
        .skill(skill("a", "spinner").remap("out", "ya").budget_ms(100.0))
        .skill(skill("b", "spinner").remap("out", "yb"));
    let m = build(&spec, &reg);
    assert_eq!(m.executor(), situate_manager::ExecutorKind::Parallel);
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    until("a few cycles", || handle.query("yb").unwrap().cycle > 5);
    handle.set_param("a", "mode", Value::F64(1.0)).unwrap();
    assert!(fault_of(&events, "a").contains("left behind"));
    let at = handle.query("yb").unwrap().cycle;
    until("cycles after the fault", || handle.query("yb").unwrap().cycle > at + 10);
    handle.set_param("a", "mode", Value::F64(0.0)).unwrap();
    gate.open();
    until("the skill can be activated again", || handle.activate(&["a"]).is_ok());
    let now = handle.stats().unwrap().cycle;
    until("the fresh body's output", || handle.query("ya").unwrap().cycle > now);
    handle.request(Request::Shutdown).unwrap();
    assert!(join.join_timeout(BOUND).is_ok());
}
