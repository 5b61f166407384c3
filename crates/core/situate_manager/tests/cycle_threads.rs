//! Threaded bodies: a hung device or a slow async computation never delays
//! the cycle. No timing is asserted: a blocked body is blocked on a gate the
//! test holds closed, and the test checks the cycle went on regardless (a
//! watchdog turns a hang into a failure).

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{ClockKind, Control, Event, Registry, Reply, Request, RobotSpec};

fn wall(robot: &str) -> RobotSpec {
    RobotSpec::new(robot).clock(ClockKind::Wall).period_s(0.002)
}

#[test]
fn a_dskill_whose_device_hangs_does_not_delay_the_cycle() {
    let gate = Gate::default();
    let g = gate.clone();
    let mut reg = Registry::new();
    reg.add(fn_type(decl("dev", SkillKind::Device, &[("cmd", "f64?")], &[("reading", "f64")]), move |io, _| {
        g.pass();
        io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        Ok(())
    }));
    reg.add(constant("src", "f64", Value::F64(1.0)));
    // Its liveness deadline is far away: this test is about the cycle not
    // waiting, not about the deadline (tests/cycle_faults.rs).
    let spec =
        wall("hang").liveness_ms(3_600_000.0).skill(skill("d", "dev")).skill(skill("s", "src").remap("out", "cmd"));
    let mut m = build(&spec, &reg);
    let mut m = within_bound(move || {
        m.run_cycles(30);
        m
    });
    assert_eq!(m.stats().unwrap().cycle, 30);
    assert_eq!(m.skill("d").unwrap().timing.runs, 0, "the device never finished an exchange");
    assert_eq!(m.query("reading").unwrap().value, None);
    assert_eq!(m.skill("s").unwrap().timing.runs, 30, "the rest of the cycle ran every time");
    gate.open();
    // Once the device answers, its readings reach the cycle.
    let m = within_bound(move || {
        while m.query("reading").unwrap().value.is_none() {
            m.run_cycles(1);
        }
        m
    });
    drop(m);
}

#[test]
fn a_slow_async_cskill_does_not_delay_the_cycle_and_its_latest_result_is_taken() {
    let gate = Gate::default();
    let g = gate.clone();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(2.0)));
    reg.add(fn_type(decl("slow", SkillKind::Async, &[("x", "f64")], &[("y", "f64")]), move |io, _| {
        g.pass();
        let x = io.inputs[0].as_ref().and_then(Value::as_f64).ok_or("no x")?;
        io.outputs[0] = Some(Value::F64(x * 10.0));
        Ok(())
    }));
    let log = log();
    reg.add(adder("add", 1.0, &log, "after"));
    let spec = wall("async")
        .liveness_ms(3_600_000.0)
        .skill(skill("s", "src").remap("out", "x"))
        .skill(skill("slow", "slow"))
        .skill(skill("a", "add").remap("x", "y").remap("y", "z"));
    let mut m = build(&spec, &reg);
    let mut m = within_bound(move || {
        m.run_cycles(20);
        m
    });
    assert_eq!(m.stats().unwrap().cycle, 20);
    assert_eq!(m.query("y").unwrap().value, None, "no result yet");
    assert!(entries(&log).is_empty(), "its consumer waits for a first result");
    gate.open();
    let mut m = within_bound(move || {
        while m.query("z").unwrap().value.is_none() {
            m.run_cycles(1);
        }
        m
    });
    assert_eq!(m.query("y").unwrap().value, Some(Value::F64(20.0)));
    assert_eq!(m.query("z").unwrap().value, Some(Value::F64(21.0)));
    // From then on the consumer runs on each new result, and only then: an
    // async skill's output is fresh in the cycle it is taken in.
    let (runs, n) = (m.skill("slow").unwrap().timing.runs, entries(&log).len());
    let mut m = within_bound(move || {
        while entries(&log).len() < n + 3 {
            m.run_cycles(1);
        }
        m
    });
    let new_results = m.skill("slow").unwrap().timing.runs - runs;
    assert!(new_results >= 3, "3 consumer runs need 3 new results, got {new_results}");
}

#[test]
fn a_device_gets_each_command_once_and_a_faulting_device_is_reported() {
    let mut reg = Registry::new();
    let seen = log();
    let s2 = seen.clone();
    reg.add(fn_type(decl("dev", SkillKind::Device, &[("cmd", "f64?")], &[("n", "i64")]), move |io, _| {
        if let Some(v) = &io.inputs[0] {
            s2.lock().unwrap().push(v.to_string());
            if v.as_f64() == Some(3.0) {
                return Err("motor driver over-current".into());
            }
        }
        io.outputs[0] = Some(Value::I64(1));
        Ok(())
    }));
    reg.add(fn_type(decl("counter", SkillKind::Sync, &[], &[("cmd", "f64")]), |io, _| {
        io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        Ok(())
    }));
    // Lockstep (simulated clock): the device exchanges once per cycle, in order.
    let spec = simulated("dev").skill(skill("d", "dev")).skill(skill("c", "counter"));
    let mut m = build(&spec, &reg);
    let events = m.events();
    m.step(5).unwrap();
    assert_eq!(entries(&seen), vec!["1", "2", "3"]);
    assert!(!m.skill("d").unwrap().active);
    assert!(events.try_iter().any(|e| matches!(e, Event::SkillFaulted { skill, cause, cycle: 3 } if skill == "d" && cause == "motor driver over-current")));
}

#[test]
fn a_managed_thread_serves_requests_while_it_cycles() {
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(4.0)));
    let log = log();
    reg.add(adder("add", 1.0, &log, "a"));
    let spec = RobotSpec::new("served")
        .clock(ClockKind::Wall)
        .period_s(0.001)
        .skill(skill("s", "src").remap("out", "x"))
        .skill(skill("a", "add").active(false));
    let m = build(&spec, &reg);
    let (mut handle, join) = m.spawn(true);
    let events = handle.events();
    handle.activate(&["a"]).unwrap();
    // Wait, by events, for the activation to be applied.
    let applied =
        events.iter().find(|e| matches!(e, Event::ActivationApplied { activated, .. } if activated == &["a"])).unwrap();
    let Event::ActivationApplied { cycle, .. } = applied else { unreachable!() };
    assert!(cycle >= 1);
    handle.request(situate_manager::Request::Stop).unwrap();
    let stopped_at = handle.stats().unwrap().cycle;
    handle.step(3).unwrap();
    assert_eq!(handle.stats().unwrap().cycle, stopped_at + 3);
    assert_eq!(handle.query("y").unwrap().value, Some(Value::F64(5.0)));
    handle.request(situate_manager::Request::Shutdown).unwrap();
    let mut m = join.join().unwrap();
    assert_eq!(m.stats().unwrap().cycle, stopped_at + 3, "stopped means no more cycles");
    assert!(handle.query("y").is_err(), "the handle reports the manager gone");
}

/// An external clock (ROS time, `situate_ros2`) runs cycles only with `Tick`s, only while the
/// manager runs (or a step asks for them); the manager's own clock never does. `stop_after`
/// (`--cycles N`) holds there too.
#[test]
fn an_external_clock_ticks_the_cycle_while_it_runs_and_stops_where_it_is_told() {
    let mut reg = Registry::new();
    reg.add(fn_type(decl("tick", SkillKind::Sync, &[], &[("out", "i64")]), |io, _| {
        io.outputs[0] = Some(Value::I64(io.cx.cycle() as i64));
        Ok(())
    }));
    let mut m = build(&simulated("ext").skill(skill("t", "tick")), &reg);
    m.stop_after(Some(5));
    let refused = m.request(Request::Tick { until: 1 });
    assert!(refused.is_err(), "no tick without an external clock: {refused:?}");
    let (mut h, join) = m.spawn(false);
    h.request(Request::ExternalClock { on: true }).unwrap();
    // Stopped: a tick runs nothing.
    assert_eq!(h.request(Request::Tick { until: 3 }).unwrap(), Reply::Ticked { ran: 0, cycle: 0 });
    // Running: the manager's own clock runs no cycle (stats are answered between ticks only).
    h.request(Request::Run).unwrap();
    for _ in 0..20 {
        assert_eq!(h.stats().unwrap().cycle, 0, "no cycle of its own");
    }
    assert_eq!(h.request(Request::Tick { until: 3 }).unwrap(), Reply::Ticked { ran: 3, cycle: 3 });
    // `stop_after(5)`: a tick to 9 stops at 5, and the manager is stopped.
    assert_eq!(h.request(Request::Tick { until: 9 }).unwrap(), Reply::Ticked { ran: 2, cycle: 5 });
    assert!(!h.stats().unwrap().running);
    // A step runs the next cycles the clock gives, stopped as the manager is: its reply waits
    // for them.
    let stepper = {
        let mut h = h.clone();
        std::thread::spawn(move || h.request(Request::Step { cycles: 2 }))
    };
    let ticked = |h: &mut situate_manager::Handle, until: u64| match h.request(Request::Tick { until }).unwrap() {
        Reply::Ticked { ran, cycle } => (ran, cycle),
        other => panic!("{other:?}"),
    };
    wait_until("the step under way", || ticked(&mut h, 6) == (1, 6));
    assert!(!stepper.is_finished(), "a step of 2 waits for its second cycle");
    // One tick to 9 runs its second cycle, and no more: the manager is stopped.
    assert_eq!(ticked(&mut h, 9), (1, 7));
    assert_eq!(stepper.join().unwrap().unwrap(), Reply::Done);
    assert_eq!(ticked(&mut h, 9), (0, 7));
    // A stop ends a step where it is.
    let stepper = {
        let mut h = h.clone();
        std::thread::spawn(move || h.request(Request::Step { cycles: 5 }))
    };
    wait_until("the second step under way", || ticked(&mut h, 8) == (1, 8));
    h.request(Request::Stop).unwrap();
    assert_eq!(stepper.join().unwrap().unwrap(), Reply::Done);
    assert_eq!(ticked(&mut h, 20), (0, 8));
    assert_eq!(h.stats().unwrap().cycle, 8);
    h.request(Request::Shutdown).unwrap();
    join.join().expect("the manager ends");
}

/// Calls `ok` until it holds, for at most a generous bound (a loaded machine).
fn wait_until(what: &str, mut ok: impl FnMut() -> bool) {
    let end = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while !ok() {
        assert!(std::time::Instant::now() < end, "{what}: not within 60 s");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}
