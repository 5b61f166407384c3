//! Steps run the short way (`plan::Fast`): a sync cskill with one required
//! plain input, and one output of its type by construction on a leaf no
//! other skill writes, run back to back untimed outside the sampled cycles.
//! They must compute what the usual way computes, and keep its promises:
//! a print or an error goes the usual way, a body late in such a stretch
//! is faulted from the next cycle on, a stuck one is left behind. Each
//! holds too for a body that writes its output straight into its slot
//! (`plan::Fast::in_slot`: it says so by `Skill::writes_output`).
//!
//! No timing is asserted: a slow body sleeps far past its budget, a stuck
//! one waits at a gate the test holds closed, and every wait is for a
//! condition with a generous bound.

mod common;

use std::time::Duration;

use common::*;
use situate_core::{SkillKind, SkillType, Value};
use situate_manager::manager::SAMPLED_STEPS;
use situate_manager::{ClockKind, Control, Manager, Registry, Reply, Request, RobotSpec, SignalReading};

/// `x + 1` to `y`; with parameter `mode` 1 it prints, 2 it fails, 3 it
/// sleeps 400 ms, 4 it waits at `gate`.
fn plus_one(name: &str, way: Way, gate: &Gate) -> SkillType {
    let d = with_param(decl(name, SkillKind::Sync, &[("x", "f64")], &[("y", "f64")]), "mode", 0.0, 0.0, 4.0);
    let gate = gate.clone();
    body_type(d, way, move |io, params| {
        match params[0].as_f64() {
            Some(1.0) => io.cx.print(format!("x is {:?}", io.inputs[0])),
            Some(2.0) => return Err("no can do".into()),
            Some(3.0) => std::thread::sleep(Duration::from_millis(400)),
            Some(4.0) => gate.pass(),
            _ => {}
        }
        let x = io.inputs[0].as_ref().and_then(Value::as_f64).ok_or("no x")?;
        io.outputs[0] = Some(Value::F64(x + 1.0));
        Ok(())
    })
}

/// The cycle number to `out` (a source: typed, it runs the short way too).
fn counter(way: Way) -> SkillType {
    body_type(decl("count", SkillKind::Sync, &[], &[("out", "f64")]), way, |io, _| {
        io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        Ok(())
    })
}

/// A chain `count → s1 → … → sN` of [`plus_one`] on `x0, x1, …`, every
/// skill on a budget of `budget_ms` (the source's too: a stretch is late
/// past the shortest budget in it).
fn chain(spec: RobotSpec, n: usize, budget_ms: f64) -> RobotSpec {
    let mut spec = spec.skill(skill("count", "count").remap("out", "x0").budget_ms(budget_ms));
    for k in 1..=n {
        let s = skill(&format!("s{k}"), "plus_one").remap("x", &format!("x{}", k - 1)).remap("y", &format!("x{k}"));
        spec = spec.skill(s.budget_ms(budget_ms));
    }
    spec
}

fn registry(way: Way, gate: &Gate) -> Registry {
    let mut reg = Registry::new();
    reg.add(counter(way));
    reg.add(plus_one("plus_one", way, gate));
    reg
}

fn value(m: &mut impl Control, path: &str) -> Option<Value> {
    m.query(path).unwrap().value
}

#[test]
fn a_chain_run_the_short_way_computes_what_the_usual_way_does_in_every_cycle() {
    for way in [Way::Fast, Way::InSlot] {
        a_chain_computes_what_the_usual_way_does(way);
    }
}

fn a_chain_computes_what_the_usual_way_does(way: Way) {
    let gate = Gate::default();
    let mut fast = build(&chain(simulated("fast"), 6, 500.0), &registry(way, &gate));
    let mut usual = build(&chain(simulated("usual"), 6, 500.0), &registry(Way::Usual, &gate));
    // From the first cycle, sampled (run the usual way in both), on.
    for cycle in 1..=70u64 {
        fast.step(1).unwrap();
        usual.step(1).unwrap();
        for k in 0..=6 {
            let x = format!("x{k}");
            assert_eq!(value(&mut fast, &x), value(&mut usual, &x), "{way:?}: {x} in cycle {cycle}");
            assert_eq!(value(&mut fast, &x), Some(Value::F64((cycle + k) as f64)), "{way:?}: {x} in cycle {cycle}");
        }
    }
    // Switched off and on again: the short way's slot is written afresh.
    fast.deactivate(&["s3"]).unwrap();
    fast.step(2).unwrap();
    assert_eq!(value(&mut fast, "x4"), Some(Value::F64(70.0 + 4.0)), "x4 keeps its value of cycle 70");
    fast.activate(&["s3"]).unwrap();
    fast.step(1).unwrap();
    assert_eq!(value(&mut fast, "x6"), Some(Value::F64(73.0 + 6.0)));
}

#[test]
fn a_print_and_an_error_of_a_step_run_the_short_way_go_the_usual_way() {
    for way in [Way::Fast, Way::InSlot] {
        a_print_and_an_error_go_the_usual_way(way);
    }
}

fn a_print_and_an_error_go_the_usual_way(way: Way) {
    let gate = Gate::default();
    let mut m = build(&chain(simulated("prints"), 2, 500.0), &registry(way, &gate));
    let events = m.events();
    m.step(2).unwrap();
    m.set_param("s1", "mode", Value::F64(1.0)).unwrap();
    m.step(1).unwrap();
    let prints = m.skill("s1").unwrap().prints;
    assert!(prints.iter().any(|(_, p)| p.contains("x is Some(F64(3.0))")), "{way:?}: the print is kept: {prints:?}");
    assert_eq!(value(&mut m, "x2"), Some(Value::F64(5.0)), "{way:?}: a run that printed is committed");
    assert_eq!(m.query("x1").unwrap().cycle, 3, "{way:?}: in its cycle");
    m.set_param("s1", "mode", Value::F64(2.0)).unwrap();
    m.step(1).unwrap();
    assert!(fault_of(&events, "s1").contains("no can do"), "{way:?}");
    assert_eq!(value(&mut m, "x1"), Some(Value::F64(4.0)), "{way:?}: a failed run commits nothing");
    assert_eq!(m.query("x1").unwrap().cycle, 3, "{way:?}: nor stamps its slot");
}

#[test]
fn a_body_late_in_a_stretch_run_the_short_way_is_faulted_by_the_next_cycle() {
    for way in [Way::Fast, Way::InSlot] {
        a_late_body_is_faulted_by_the_next_cycle(way);
    }
}

fn a_late_body_is_faulted_by_the_next_cycle(way: Way) {
    // In a plan of more steps than a sampled cycle times (`SAMPLED_STEPS`)
    // too, the late body far out of the first cycle's window.
    for (n, late) in [(3, 2), (3 * SAMPLED_STEPS + 10, 2 * SAMPLED_STEPS + 5)] {
        let gate = Gate::default();
        // Budgets above the exact-timing bound (100 ms): these bodies run the short way.
        let mut m = build(&chain(simulated("late"), n, 150.0), &registry(way, &gate));
        let events = m.events();
        let late = format!("s{late}");
        m.step(2).unwrap();
        m.set_param(&late, "mode", Value::F64(3.0)).unwrap();
        // Cycle 3 runs it untimed (400 ms): the stretch ran past the shortest budget, so cycle 4
        // times every body and finds it late (the next sampled cycle would be the 33rd).
        m.step(2).unwrap();
        let cause = fault_of(&events, &late);
        assert!(cause.contains("over its execution budget"), "{way:?}, {n} steps: {cause}");
    }
}

#[test]
fn a_body_stuck_in_a_stretch_run_the_short_way_is_left_behind_and_the_cycle_goes_on() {
    for way in [Way::Fast, Way::InSlot] {
        a_stuck_body_is_left_behind_and_the_cycle_goes_on(way);
    }
}

fn a_stuck_body_is_left_behind_and_the_cycle_goes_on(way: Way) {
    let gate = Gate::default();
    let spec = chain(RobotSpec::new("stuck").clock(ClockKind::Wall).period_s(0.002), 3, 150.0);
    let mut m = build(&spec, &registry(way, &gate));
    m.set_param("s2", "mode", Value::F64(4.0)).unwrap();
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    let cause = fault_of(&events, "s2");
    assert!(cause.contains("left behind"), "{way:?}: {cause}");
    // The cycle goes on without it: its source still counts, the skills before it still run.
    let at = handle.stats().unwrap().cycle;
    until("cycles after the fault", || handle.query("x1").unwrap().cycle > at + 10);
    gate.open();
    // The body returns and its thread drops what it held; the manager is unharmed.
    until("the skill can be activated again", || handle.activate(&["s2"]).is_ok());
    handle.set_param("s2", "mode", Value::F64(0.0)).unwrap();
    let now = handle.stats().unwrap().cycle;
    // Both read at the end of one cycle (one request): the chain's end is its start plus 3.
    until("the chain whole again", || {
        let reply = handle.request(Request::QuerySignals { signals: vec!["x0".into(), "x3".into()] }).unwrap();
        let Reply::Signals(r) = reply else { panic!("not the signals' readings: {reply:?}") };
        let start = r[0].value.as_ref().and_then(Value::as_f64);
        r[1].cycle > now + 5 && r[1].value == start.map(|x| Value::F64(x + 3.0))
    });
    handle.request(Request::Shutdown).unwrap();
    assert!(join.join_timeout(BOUND).is_ok());
}

#[test]
fn a_body_left_behind_in_a_stretch_leaves_its_output_its_last_value() {
    let gate = Gate::default();
    let spec = chain(RobotSpec::new("kept").clock(ClockKind::Wall).period_s(0.002), 3, 150.0);
    let m = build(&spec, &registry(Way::InSlot, &gate));
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    // Written by a whole chain in its cycle: `x2` is its cycle plus 2.
    let whole = |r: &SignalReading| r.value == Some(Value::F64(r.cycle as f64 + 2.0));
    until("x2 written a few times", || handle.query("x2").unwrap().cycle > 5);
    handle.set_param("s2", "mode", Value::F64(4.0)).unwrap();
    let cause = fault_of(&events, "s2");
    assert!(cause.contains("left behind"), "{cause}");
    let kept = handle.query("x2").unwrap();
    assert!(whole(&kept), "the last value, whole: {kept:?}");
    let at = handle.stats().unwrap().cycle;
    until("cycles after the fault", || handle.query("x1").unwrap().cycle > at + 10);
    let later = handle.query("x2").unwrap();
    assert_eq!((&later.value, later.cycle), (&kept.value, kept.cycle), "kept while the body is stuck");
    // The body returns (its output goes nowhere); then it runs again and writes anew.
    gate.open();
    until("the skill can be activated again", || handle.activate(&["s2"]).is_ok());
    until("x2 written again", || handle.query("x2").unwrap().cycle > kept.cycle);
    let again = handle.query("x2").unwrap();
    assert!(whole(&again), "{again:?}");
    handle.request(Request::Shutdown).unwrap();
    assert!(join.join_timeout(BOUND).is_ok());
}

/// The resolution of the kernel's coarse monotonic clock, which paces the
/// sampled cycles (1 ns where there is none to ask).
fn coarse_tick_ns() -> u64 {
    #[cfg(target_os = "linux")]
    {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
        if unsafe { libc::clock_getres(libc::CLOCK_MONOTONIC_COARSE, &mut ts) } == 0 {
            return (ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64).max(1);
        }
    }
    1
}

#[test]
fn cycles_back_to_back_are_sampled_at_most_once_a_tick_of_the_coarse_clock() {
    let gate = Gate::default();
    // Budgets no stall of a loaded machine reaches: no stretch makes the next cycle sampled.
    let mut m = build(&chain(simulated("sampling"), 2, 10_000.0), &registry(Way::InSlot, &gate));
    let cycles = 3200;
    let started = std::time::Instant::now();
    m.step(cycles).unwrap();
    let elapsed_ns = started.elapsed().as_nanos() as u64;
    let timing = m.skill("s1").unwrap().timing;
    assert_eq!(timing.runs, cycles, "every run is counted, timed or not");
    // By number alone, one cycle in TIMING_SAMPLE would be (100 here); sampled
    // cycles start a tick apart on the coarse clock, which lags by less than a
    // tick: at most two more than the ticks the cycles took.
    let by_number = cycles.div_ceil(situate_manager::manager::TIMING_SAMPLE);
    let by_ticks = elapsed_ns / coarse_tick_ns() + 2;
    assert!(timing.timed_runs >= 1, "the first cycle is sampled");
    assert!(
        timing.timed_runs <= by_number.min(by_ticks),
        "{} runs timed in {cycles} cycles over {elapsed_ns} ns (ticks of {} ns)",
        timing.timed_runs,
        coarse_tick_ns()
    );
}

#[test]
fn a_sampled_cycle_of_a_large_plan_times_a_window_of_its_steps_and_every_step_in_turn() {
    let gate = Gate::default();
    let n = 3 * SAMPLED_STEPS + 10;
    // Budgets no stall of a loaded machine reaches: no stretch makes the next cycle sampled.
    let mut m = build(&chain(simulated("window"), n, 10_000.0), &registry(Way::InSlot, &gate));
    let names: Vec<String> = (1..=n).map(|k| format!("s{k}")).collect();
    let timed = |m: &mut Manager| -> Vec<u64> { names.iter().map(|s| m.skill(s).unwrap().timing.timed_runs).collect() };
    let mut last = timed(&mut m);
    let mut sampled = 0;
    // One cycle at a time, a few ms apart: each one due by its number is sampled.
    until("every step timed exactly", || {
        m.step(1).unwrap();
        let now = timed(&mut m);
        let newly = now.iter().zip(&last).filter(|(a, b)| a > b).count();
        assert!(newly <= SAMPLED_STEPS, "{newly} steps timed exactly in cycle {}", m.cycle_count());
        sampled += usize::from(newly > 0);
        last = now;
        last.iter().all(|&t| t > 0)
    });
    assert!(sampled >= n.div_ceil(SAMPLED_STEPS), "{sampled} sampled cycles timed all {n} steps");
}
