//! Monitors: conditions over signals and parameters, in three modes.

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{Control, ControlError, Event, Manager, MonitorMode, Registry, Request};

/// A sonar whose front range follows a script, one value per cycle, and a
/// barcode reader that sees barcode 3 from cycle 4 on.
fn robot(front: &'static [f32]) -> Manager {
    let mut reg = Registry::new();
    reg.add(fn_type(decl("sonar", SkillKind::Sync, &[], &[("sonar", "{range: f32[]}")]), move |io, _| {
        let c = io.cx.cycle() as usize;
        let r = front.get(c - 1).copied().unwrap_or(9.0);
        let range: std::sync::Arc<[f32]> = vec![r, 5.0, 5.0].into();
        io.outputs[0] = Some(situate_core::record_value(vec![("range", Value::F32s(range))]));
        Ok(())
    }));
    reg.add(fn_type(decl("barcode", SkillKind::Sync, &[], &[("barcode", "{id: i64, visible: bool}")]), |io, _| {
        let seen = io.cx.cycle() >= 4;
        io.outputs[0] = Some(situate_core::record_value(vec![
            ("id", Value::I64(if seen { 3 } else { 0 })),
            ("visible", Value::Bool(seen)),
        ]));
        Ok(())
    }));
    reg.add(fn_type(with_param(decl("runaway", SkillKind::Sync, &[], &[]), "safe_distance", 0.5, 0.1, 3.0), |_, _| {
        Ok(())
    }));
    let spec = simulated("mon")
        .skill(skill("sonar", "sonar"))
        .skill(skill("barcode", "barcode"))
        .skill(skill("runaway", "runaway"));
    build(&spec, &reg)
}

fn fired(events: &crossbeam_channel::Receiver<Event>) -> Vec<(u64, u64)> {
    events
        .try_iter()
        .filter_map(|e| match e {
            Event::MonitorFired { monitor, cycle, .. } => Some((monitor, cycle)),
            _ => None,
        })
        .collect()
}

const SCRIPT: &[f32] = &[1.0, 0.2, 0.2, 1.0, 0.1, 1.0];

#[test]
fn once_fires_the_first_cycle_it_holds_then_is_gone() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m.add_monitor("sonar.range[0] < 0.25", MonitorMode::Once).unwrap();
    m.step(6).unwrap();
    assert_eq!(fired(&events), vec![(id, 2)]);
    assert_eq!(m.request(Request::ListMonitors).unwrap(), situate_manager::Reply::Monitors(vec![]));
}

#[test]
fn edge_fires_on_every_rising_edge() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m.add_monitor("sonar.range[0] < 0.25", MonitorMode::Edge).unwrap();
    m.step(6).unwrap();
    assert_eq!(fired(&events), vec![(id, 2), (id, 5)]);
}

#[test]
fn level_fires_every_cycle_while_it_holds() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m.add_monitor("sonar.range[0] < 0.25", MonitorMode::Level).unwrap();
    m.step(6).unwrap();
    assert_eq!(fired(&events), vec![(id, 2), (id, 3), (id, 5)]);
}

#[test]
fn conditions_combine_signals_records_and_parameters() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m
        .add_monitor("barcode.visible && barcode.id == 3 && sonar.range[0] < runaway.safe_distance", MonitorMode::Edge)
        .unwrap();
    m.step(6).unwrap();
    // Barcode seen from cycle 4; range 0.1 < 0.5 at cycle 5.
    let all: Vec<Event> = events.try_iter().collect();
    let Some(Event::MonitorFired { monitor, cycle, values, condition, .. }) = all.first() else {
        panic!("no event: {all:?}")
    };
    assert_eq!((*monitor, *cycle), (id, 5));
    assert_eq!(condition, "barcode.visible && barcode.id == 3 && sonar.range[0] < runaway.safe_distance");
    let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["barcode.visible", "barcode.id", "sonar.range", "runaway.safe_distance"]);
    assert_eq!(values[3].1, Some(Value::F64(0.5)));
    // A parameter change moves the threshold at once.
    let id2 = m.add_monitor("abs(sonar.range[0] - 9) < 0.01 && runaway.safe_distance > 2", MonitorMode::Once).unwrap();
    m.set_param("runaway", "safe_distance", Value::F64(2.5)).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![(id2, 7)]);
}

#[test]
fn a_monitor_on_a_value_not_yet_produced_does_not_hold() {
    let mut m = robot(SCRIPT);
    m.deactivate(&["sonar"]).unwrap();
    let events = m.events();
    m.add_monitor("sonar.range[0] < 100 || !(sonar.range[0] < 100)", MonitorMode::Level).unwrap();
    m.step(3).unwrap();
    assert!(fired(&events).is_empty());
}

#[test]
fn bad_conditions_are_refused_with_the_column_and_change_nothing() {
    let mut m = robot(SCRIPT);
    let err = m.add_monitor("sonar.range[0] < 0.25 && barcde.id == 3", MonitorMode::Once).unwrap_err();
    let ControlError::BadCondition { column, message, pointer } = &err else { panic!("{err:?}") };
    assert_eq!(*column, 26);
    assert!(message.contains("barcde") && message.contains("did you mean `barcode.id`?"), "{message}");
    assert!(pointer.ends_with("                         ^"), "{pointer:?}");
    // `sonar` is both a skill and a record signal: a typo in the field is a signal typo.
    let err = m.add_monitor("sonar.rang[0] < 1", MonitorMode::Once).unwrap_err();
    assert!(err.to_string().contains("unknown signal `sonar.rang` — did you mean `sonar.range`?"), "{err}");
    let err = m.add_monitor("runaway.safe_distanse > 1", MonitorMode::Once).unwrap_err();
    assert!(err.to_string().contains("did you mean `safe_distance`?"), "{err}");
    let err = m.add_monitor("sonar.range[0] + 1", MonitorMode::Once).unwrap_err();
    assert!(matches!(err, ControlError::BadCondition { column: 1, .. }), "{err:?}");
    assert_eq!(m.request(Request::ListMonitors).unwrap(), situate_manager::Reply::Monitors(vec![]));
}

#[test]
fn a_cancelled_monitor_stops_firing() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m.add_monitor("sonar.range[0] < 0.25", MonitorMode::Level).unwrap();
    m.step(2).unwrap();
    m.cancel_monitor(id).unwrap();
    m.step(4).unwrap();
    assert_eq!(fired(&events), vec![(id, 2)]);
    assert_eq!(m.cancel_monitor(id).unwrap_err(), ControlError::UnknownMonitor(id));
}

#[test]
fn time_and_cycle_are_names_every_condition_can_use() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = m.add_monitor("cycle == 3 && time > 0", MonitorMode::Edge).unwrap();
    m.step(6).unwrap();
    assert_eq!(fired(&events), vec![(id, 3)]);
}

#[test]
fn a_pausing_monitor_stops_the_cycle_at_the_cycle_it_fires_in() {
    let m = robot(SCRIPT);
    let events = m.events();
    let (mut handle, join) = m.spawn(false);
    let reply = handle
        .request(Request::AddMonitor {
            condition: "sonar.range[0] < 0.25".into(),
            mode: MonitorMode::Edge,
            pause: true,
            report: Vec::new(),
        })
        .unwrap();
    let situate_manager::Reply::MonitorAdded(id) = reply else { panic!("{reply:?}") };
    let wait_stopped = || loop {
        match events.recv_timeout(std::time::Duration::from_secs(60)).expect("the manager stops") {
            Event::ManagerStopped { cycle } => return cycle,
            _ => continue,
        }
    };
    handle.request(Request::Run).unwrap();
    // However fast the cycle runs, it stops where the condition first held…
    assert_eq!(wait_stopped(), 2);
    assert_eq!(handle.stats().unwrap().cycle, 2);
    // …and again at the next rising edge once resumed.
    handle.request(Request::Run).unwrap();
    assert_eq!(wait_stopped(), 5);
    let situate_manager::Reply::Monitors(list) = handle.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!((list[0].monitor, list[0].fired, list[0].pause), (id, 2, true));
    handle.request(Request::Shutdown).unwrap();
    join.join().unwrap();
}

#[test]
fn a_pausing_monitor_also_ends_a_step_where_it_fires() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let reply = m
        .request(Request::AddMonitor {
            condition: "sonar.range[0] < 0.25".into(),
            mode: MonitorMode::Edge,
            pause: true,
            report: Vec::new(),
        })
        .unwrap();
    let situate_manager::Reply::MonitorAdded(id) = reply else { panic!("{reply:?}") };
    m.request(Request::Step { cycles: 6 }).unwrap();
    assert_eq!(fired(&events), vec![(id, 2)]);
    assert_eq!(m.stats().unwrap().cycle, 2);
    // The next step goes on from there to the next rising edge.
    m.request(Request::Step { cycles: 6 }).unwrap();
    assert_eq!(fired(&events), vec![(id, 5)]);
    assert_eq!(m.stats().unwrap().cycle, 5);
}

#[test]
fn a_monitor_reports_the_values_it_was_asked_for_as_of_the_cycle_it_fires_in() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let add = |m: &mut Manager, report: &[&str]| {
        m.request(Request::AddMonitor {
            condition: "sonar.range[0] < 0.25".into(),
            mode: MonitorMode::Once,
            pause: false,
            report: report.iter().map(|s| s.to_string()).collect(),
        })
    };
    // A whole record is reported as its leaves; parameters, time and cycle too.
    let reply = add(&mut m, &["barcode", "runaway.safe_distance", "cycle"]).unwrap();
    let situate_manager::Reply::MonitorAdded(id) = reply else { panic!("{reply:?}") };
    let situate_manager::Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list[0].report, vec!["barcode", "runaway.safe_distance", "cycle"]);
    m.step(6).unwrap();
    let values = events
        .try_iter()
        .find_map(|e| match e {
            Event::MonitorFired { monitor, values, .. } if monitor == id => Some(values),
            _ => None,
        })
        .expect("the monitor fired");
    let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["sonar.range", "barcode.id", "barcode.visible", "runaway.safe_distance", "cycle"]);
    // As of cycle 2: the barcode is not seen yet (it is from cycle 4 on).
    assert_eq!(values[2].1, Some(Value::Bool(false)));
    assert_eq!(values[3].1, Some(Value::F64(0.5)));
    assert_eq!(values[4].1, Some(Value::I64(2)));

    // An unknown name is refused with a suggestion, and nothing is added.
    let err = add(&mut m, &["barcod"]).unwrap_err();
    assert!(matches!(&err, ControlError::BadReport(msg) if msg.contains("did you mean `barcode`")), "{err}");
    let situate_manager::Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert!(list.is_empty());
}

#[test]
fn a_robot_keeps_a_bounded_number_of_monitors_and_says_so() {
    // 60,000 monitors once took a cycle from 45 µs to 75 ms.
    let mut m = robot(SCRIPT);
    let add = |m: &mut Manager| {
        m.request(Request::AddMonitor {
            condition: "sonar.range[0] < 0.25".into(),
            mode: MonitorMode::Level,
            pause: false,
            report: Vec::new(),
        })
    };
    for _ in 0..situate_manager::MAX_MONITORS {
        add(&mut m).expect("under the cap");
    }
    match add(&mut m) {
        Err(ControlError::Invalid(message)) => {
            assert!(message.contains("the most it keeps (1000); cancel some first"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    // Cancelling one makes room again.
    m.request(Request::CancelMonitor { monitor: 1 }).unwrap();
    add(&mut m).expect("room again");
}
