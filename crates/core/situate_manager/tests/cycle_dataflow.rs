//! The data-flow cycle: readiness order, partial match, activation, params.

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{Control, ControlError, Event, Registry, Reply, Request};

/// A chain declared consumer-first still runs producer-first, each in the
/// same cycle as its producer.
#[test]
fn readiness_order_follows_data_dependencies_not_declaration_order() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(1.0)));
    reg.add(adder("add", 1.0, &log, "x"));
    let spec = simulated("chain")
        .skill(skill("c", "add").remap("x", "b_out").remap("y", "c_out"))
        .skill(skill("b", "add").remap("x", "a_out").remap("y", "b_out"))
        .skill(skill("a", "add").remap("x", "s").remap("y", "a_out"))
        .skill(skill("s", "src").remap("out", "s"));
    let mut m = build(&spec, &reg);
    m.step(2).unwrap();
    // Three adders ran in each of two cycles.
    assert_eq!(entries(&log), vec!["x@1", "x@1", "x@1", "x@2", "x@2", "x@2"]);
    assert_eq!(m.query("c_out").unwrap().value, Some(Value::F64(4.0)));
    assert_eq!(m.query("c_out").unwrap().cycle, 2);
    let timing = m.skill("a").unwrap().timing;
    assert_eq!(timing.runs, 2);
    // Several signals in one request: each as its own query gives it, in the order asked.
    let signals = vec!["c_out".to_string(), "a_out".to_string(), "s".to_string()];
    match m.request(Request::QuerySignals { signals: signals.clone() }).unwrap() {
        Reply::Signals(readings) => {
            let one_by_one: Vec<_> = signals.iter().map(|s| m.query(s).unwrap()).collect();
            assert_eq!(readings, one_by_one);
            assert_eq!(readings[1].value, Some(Value::F64(2.0)));
        }
        other => panic!("not the signals: {other:?}"),
    }
    let unknown = vec!["c_out".to_string(), "a_ot".to_string()];
    let err = m.request(Request::QuerySignals { signals: unknown }).unwrap_err();
    assert_eq!(err.to_string(), "unknown signal `a_ot` — did you mean `a_out`?");
}

#[test]
fn each_skill_in_a_chain_runs_after_its_producer() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    for tag in ["a", "b", "c"] {
        reg.add(adder(&format!("add_{tag}"), 1.0, &log, tag));
    }
    let spec = simulated("chain")
        .skill(skill("c", "add_c").remap("x", "b").remap("y", "c"))
        .skill(skill("b", "add_b").remap("x", "a").remap("y", "b"))
        .skill(skill("a", "add_a").remap("x", "s").remap("y", "a"))
        .skill(skill("s", "src").remap("out", "s"));
    let mut m = build(&spec, &reg);
    m.step(1).unwrap();
    assert_eq!(entries(&log), vec!["a@1", "b@1", "c@1"]);
}

/// Paper 3.2.1: a record input is ready once every field has been provided,
/// possibly by several producers.
#[test]
fn a_record_is_ready_only_when_all_its_fields_were_provided() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("px", "f64", Value::F64(1.5)));
    reg.add(constant("py", "f64", Value::F64(-2.0)));
    let l = log.clone();
    reg.add(fn_type(decl("use_pose", SkillKind::Sync, &[("pose", "{x: f64, y: f64}")], &[]), move |io, _| {
        l.lock().unwrap().push(format!("{}", io.inputs[0].as_ref().unwrap()));
        Ok(())
    }));
    let spec = simulated("partial")
        .skill(skill("x", "px").remap("out", "pose.x"))
        .skill(skill("y", "py").remap("out", "pose.y").active(false))
        .skill(skill("user", "use_pose"));
    let mut m = build(&spec, &reg);
    m.step(3).unwrap();
    assert!(entries(&log).is_empty(), "ran on a partial record: {:?}", entries(&log));
    assert_eq!(m.query("pose").unwrap().value, None);
    m.activate(&["y"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(entries(&log), vec!["{x: 1.5, y: -2}"]);
    let pose = m.query("pose").unwrap();
    assert_eq!(pose.ty.to_string(), "{x: f64, y: f64}");
    assert_eq!(pose.value.unwrap().to_string(), "{x: 1.5, y: -2}");
}

#[test]
fn inactive_skills_never_run_and_cost_nothing() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    reg.add(adder("add", 1.0, &log, "on"));
    let mut spec = simulated("idle").skill(skill("s", "src"));
    for i in 0..50 {
        spec = spec.skill(skill(&format!("a{i}"), "add").remap("x", "out").remap("y", &format!("y{i}")).active(false));
    }
    let mut m = build(&spec, &reg);
    m.step(10).unwrap();
    assert!(entries(&log).is_empty());
    assert!(m.skills().unwrap().iter().filter(|s| s.name != "s").all(|s| s.timing.runs == 0));
}

/// Requests are handled between cycles and take effect from the next one.
#[test]
fn activation_applies_exactly_at_the_next_cycle_boundary() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    reg.add(adder("add", 1.0, &log, "a"));
    let spec = simulated("act").skill(skill("s", "src").remap("out", "x")).skill(skill("a", "add").active(false));
    let mut m = build(&spec, &reg);
    let events = m.events();
    m.step(3).unwrap();
    let changed = m.activate(&["a"]).unwrap();
    assert_eq!(changed, vec!["a"]);
    // Nothing ran between cycles.
    assert!(entries(&log).is_empty());
    m.step(2).unwrap();
    assert_eq!(entries(&log), vec!["a@4", "a@5"]);
    m.deactivate(&["a"]).unwrap();
    m.step(2).unwrap();
    assert_eq!(entries(&log), vec!["a@4", "a@5"]);
    let applied: Vec<Event> = events.try_iter().collect();
    assert_eq!(
        applied,
        vec![
            Event::ActivationApplied { activated: vec!["a".into()], deactivated: vec![], cycle: 4 },
            Event::ActivationApplied { activated: vec![], deactivated: vec!["a".into()], cycle: 6 },
        ]
    );
}

#[test]
fn off_and_on_again_before_a_cycle_is_reported_once_in_its_final_state() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    reg.add(adder("add", 1.0, &log, "a"));
    reg.add(adder("add2", 1.0, &log, "b"));
    let spec = simulated("act")
        .skill(skill("s", "src").remap("out", "x"))
        .skill(skill("a", "add"))
        .skill(skill("b", "add2").remap("y", "y2"));
    let mut m = build(&spec, &reg);
    let events = m.events();
    m.step(1).unwrap();
    let _ = events.try_iter().count();
    // `a` off then on again, `b` on (already) then off: one event, each skill once, in its final state.
    m.deactivate(&["a"]).unwrap();
    m.activate(&["a"]).unwrap();
    m.deactivate(&["b"]).unwrap();
    m.step(1).unwrap();
    let applied: Vec<Event> = events.try_iter().filter(|e| matches!(e, Event::ActivationApplied { .. })).collect();
    assert_eq!(
        applied,
        vec![Event::ActivationApplied { activated: vec!["a".into()], deactivated: vec!["b".into()], cycle: 2 }]
    );
}

#[test]
fn activating_a_skill_without_providers_names_the_missing_signals() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    reg.add(adder("add", 1.0, &log, "a"));
    let spec = simulated("prov")
        .skill(skill("s", "src").remap("out", "x").active(false))
        .skill(skill("a", "add").active(false))
        .skill(skill("b", "add").remap("x", "y").remap("y", "z").active(false));
    let mut m = build(&spec, &reg);
    let err = m.activate(&["b"]).unwrap_err();
    assert_eq!(
        err,
        ControlError::MissingProviders { skill: "b".into(), signals: vec!["y".into()], providers: vec!["a".into()] }
    );
    assert_eq!(
        err.to_string(),
        "cannot activate `b`: no active skill provides `y` (activate `a` too, or ask to activate providers)"
    );
    // Refused: nothing changed.
    assert!(m.stats().unwrap().active.is_empty());
    // With providers: b needs a, which needs s.
    let mut changed = m.activate_with(&["b"], true).unwrap();
    changed.sort();
    assert_eq!(changed, vec!["a", "b", "s"]);
    m.step(1).unwrap();
    assert_eq!(m.query("z").unwrap().value, Some(Value::F64(2.0)));
}

#[test]
fn unknown_names_are_refused_with_a_suggestion() {
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(0.0)));
    let mut m = build(&simulated("names").skill(skill("wander", "src")), &reg);
    assert_eq!(m.activate(&["wandr"]).unwrap_err().to_string(), "unknown skill `wandr` — did you mean `wander`?");
    assert_eq!(m.query("ot").unwrap_err().to_string(), "unknown signal `ot` — did you mean `out`?");
}

#[test]
fn a_rejected_parameter_leaves_the_old_value() {
    let log = log();
    let mut reg = Registry::new();
    let l = log.clone();
    reg.add(fn_type(
        with_param(decl("p", SkillKind::Sync, &[], &[]), "safe_distance", 0.5, 0.1, 3.0),
        move |_, params| {
            l.lock().unwrap().push(format!("{}", params[0]));
            Ok(())
        },
    ));
    let mut m = build(&simulated("params").skill(skill("runaway", "p")), &reg);
    let events = m.events();
    m.step(1).unwrap();
    let err = m.set_param("runaway", "safe_distance", Value::F64(7.0)).unwrap_err();
    assert_eq!(err.to_string(), "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got 7");
    let err = m.set_param("runaway", "safe_distance", Value::Str("far".into())).unwrap_err();
    assert_eq!(
        err.to_string(),
        "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got \"far\""
    );
    let err = m.set_param("runaway", "safe_distnce", Value::F64(1.0)).unwrap_err();
    assert_eq!(err.to_string(), "skill `runaway`: unknown parameter `safe_distnce` — did you mean `safe_distance`?");
    assert_eq!(m.get_param("runaway", "safe_distance").unwrap(), Value::F64(0.5));
    m.step(1).unwrap();
    m.set_param("runaway", "safe_distance", Value::F64(0.25)).unwrap();
    assert_eq!(m.get_param("runaway", "safe_distance").unwrap(), Value::F64(0.25));
    m.step(1).unwrap();
    assert_eq!(entries(&log), vec!["0.5", "0.5", "0.25"]);
    let changes: Vec<Event> = events.try_iter().collect();
    assert_eq!(
        changes,
        vec![Event::ParamChanged {
            skill: "runaway".into(),
            param: "safe_distance".into(),
            value: Value::F64(0.25),
            cycle: 3
        }]
    );
}

#[test]
fn a_sequencers_phase_is_an_event_from_the_next_cycle_and_a_text_that_is_not_one_line_is_refused() {
    let reg = Registry::new();
    let mut m = build(&simulated("phases"), &reg);
    let events = m.events();
    m.step(3).unwrap();
    let phase = |text: &str| Request::Phase { text: text.into(), client: Some("deliver".into()) };
    assert_eq!(m.request(phase("leaving the lab")).unwrap(), Reply::Done);
    let phases: Vec<Event> = events.try_iter().filter(|e| matches!(e, Event::Phase { .. })).collect();
    assert_eq!(phases, vec![Event::Phase { text: "leaving the lab".into(), client: Some("deliver".into()), cycle: 4 }]);
    for (text, says) in [
        ("", "1 to 200 characters, got 0"),
        (&"x".repeat(201) as &str, "1 to 200 characters, got 201"),
        ("two\nlines", "control characters, got '\\n'"),
    ] {
        let err = m.request(phase(text)).unwrap_err();
        assert!(matches!(err, ControlError::Invalid(_)), "{err:?}");
        assert!(err.to_string().contains(says), "{text:?}: {err}");
    }
    assert_eq!(
        events.try_iter().filter(|e| matches!(e, Event::Phase { .. })).count(),
        0,
        "a refused phase is no event"
    );
}

#[test]
fn skill_queries_show_inputs_outputs_parameters_and_timing() {
    let log = log();
    let mut reg = Registry::new();
    reg.add(constant("src", "f64", Value::F64(2.0)));
    reg.add(adder("add", 1.0, &log, "a"));
    let mut m = build(&simulated("q").skill(skill("s", "src").remap("out", "x")).skill(skill("a", "add")), &reg);
    m.step(2).unwrap();
    let info = m.skill("a").unwrap();
    assert!(info.active);
    assert_eq!(info.inputs[0].value, Some(Value::F64(2.0)));
    assert_eq!(info.outputs[0].value, Some(Value::F64(3.0)));
    assert_eq!(info.outputs[0].signal, "y");
    assert_eq!(info.timing.runs, 2);
    let stats = m.stats().unwrap();
    assert_eq!(stats.cycle, 2);
    assert_eq!(stats.active, vec!["s", "a"]);
    assert!((stats.time_s - 0.02).abs() < 1e-12, "simulated time advances by the period");
}

/// A running (spawned) manager hands bodies copies of their inputs and drops them after the
/// run; what a skill read in the last cycle is still shown, a record input as a record (it read
/// null for every record input).
#[test]
fn a_running_robot_shows_what_each_input_read_a_record_too() {
    use situate_core::record_value;
    let pose = record_value(vec![("x", Value::F64(1.5)), ("y", Value::F64(-2.0))]);
    let mut reg = Registry::new();
    reg.add(constant("pose_src", "{x: f64, y: f64}", pose.clone()));
    reg.add(constant("num_src", "f64", Value::F64(7.0)));
    reg.add(fn_type(
        decl("reader", SkillKind::Sync, &[("pose", "{x: f64, y: f64}"), ("n", "f64")], &[]),
        |_, _| Ok(()),
    ));
    let spec = simulated("reads")
        .skill(skill("p", "pose_src").remap("out", "pose"))
        .skill(skill("n", "num_src").remap("out", "n"))
        .skill(skill("r", "reader"));
    let (mut handle, join) = build(&spec, &reg).spawn(false);
    handle.step(3).unwrap();
    let inputs = handle.skill("r").unwrap().inputs;
    let read: Vec<_> = inputs.iter().map(|p| (p.name.as_str(), p.value.clone())).collect();
    assert_eq!(read, vec![("pose", Some(pose)), ("n", Some(Value::F64(7.0)))]);
    handle.request(situate_manager::Request::Shutdown).unwrap();
    join.join_timeout(BOUND).ok().expect("the manager ended").unwrap();
}
