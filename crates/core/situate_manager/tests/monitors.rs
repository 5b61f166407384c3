//! Monitors: conditions over signals and parameters, in three modes.

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{
    CancelReason, Control, ControlError, Event, Manager, MonitorCondition, MonitorMode, Registry, Reply, Request,
    MAX_ANY_CONDITIONS,
};

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
    let ControlError::BadCondition { index, column, message, pointer } = &err else { panic!("{err:?}") };
    assert_eq!((*index, *column), (None, 26));
    assert!(err.to_string().starts_with("bad condition at column 26: "), "{err}");
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
            session: None,
            client: None,
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
            session: None,
            client: None,
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
            session: None,
            client: None,
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
    // Five sessions, each under its own cap, fill the robot's.
    let add = |m: &mut Manager, k: usize| {
        m.request(Request::AddMonitor {
            condition: "sonar.range[0] < 0.25".into(),
            mode: MonitorMode::Level,
            pause: false,
            report: Vec::new(),
            session: Some(format!("c{}", k % 5)),
            client: None,
        })
    };
    for k in 0..situate_manager::MAX_MONITORS {
        add(&mut m, k).expect("under the cap");
    }
    match add(&mut m, 5) {
        Err(ControlError::Invalid(message)) => {
            assert!(message.contains("the most it keeps (1000); cancel some first"), "{message}")
        }
        other => panic!("{other:?}"),
    }
    // Cancelling one makes room again.
    m.request(Request::CancelMonitor { monitor: 1, session: Some("c0".into()), force: false }).unwrap();
    add(&mut m, 0).expect("room again");
}

fn add_for(m: &mut Manager, session: Option<&str>, any: usize) -> Result<Reply, ControlError> {
    let conditions = vec!["sonar.range[0] < 0.25".to_string(); any];
    m.request(Request::AddMonitor {
        condition: MonitorCondition::Any(conditions),
        mode: MonitorMode::Level,
        pause: false,
        report: Vec::new(),
        session: session.map(str::to_string),
        client: Some("a-label".into()),
    })
}

#[test]
fn one_session_keeps_a_bounded_share_of_the_robots_monitors_and_is_told_so() {
    let mut m = robot(SCRIPT);
    let cap = situate_manager::MAX_MONITORS_PER_SESSION;
    for _ in 0..cap / 50 {
        add_for(&mut m, Some("leaky-session"), 50).expect("under the session's cap");
    }
    match add_for(&mut m, Some("leaky-session"), 1) {
        Err(ControlError::Invalid(message)) => assert_eq!(
            message,
            format!(
                "monitor_add: session `leaky-se` (client `a-label`) has {} monitors watching {cap} conditions; this \
                 one's 1 would be past the most one session keeps ({cap}); cancel some first",
                cap / 50
            )
        ),
        other => panic!("{other:?}"),
    }
    // Another session, whatever label its client gives, and the program itself still have theirs.
    add_for(&mut m, Some("other-session"), 64).expect("another session");
    for _ in 0..cap {
        add_for(&mut m, None, 1).expect("the program's own share one allowance");
    }
    match add_for(&mut m, None, 2) {
        Err(ControlError::Invalid(message)) => assert!(
            message.starts_with(&format!(
                "monitor_add: the program's own requests have {cap} monitors watching {cap} conditions; this \
                 one's 2 would be past the most one session keeps ({cap})"
            )),
            "{message}"
        ),
        other => panic!("{other:?}"),
    }
    let situate_manager::Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list.iter().filter(|i| i.session.as_deref() == Some("leaky-session")).count(), cap / 50);
    assert!(list.iter().all(|i| i.client.as_deref() == Some("a-label")), "the label is kept");
    // Cancelling one of its own makes room for that session again.
    let leaky = list.iter().find(|i| i.session.as_deref() == Some("leaky-session")).unwrap().monitor;
    m.request(Request::CancelMonitor { monitor: leaky, session: Some("leaky-session".into()), force: false }).unwrap();
    add_for(&mut m, Some("leaky-session"), 50).expect("room again");
}

/// Every `monitor_cancelled` event so far, as (monitor, session, reason).
fn cancelled(events: &crossbeam_channel::Receiver<Event>) -> Vec<(u64, Option<String>, CancelReason)> {
    events
        .try_iter()
        .filter_map(|e| match e {
            Event::MonitorCancelled { monitor, session, reason, .. } => Some((monitor, session, reason)),
            _ => None,
        })
        .collect()
}

#[test]
fn only_its_session_cancels_a_monitor_unless_forced_and_the_owner_is_told() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let id = |r: Reply| match r {
        Reply::MonitorAdded(id) => id,
        other => panic!("{other:?}"),
    };
    let a = id(add_for(&mut m, Some("session-a"), 1).unwrap());
    let own = id(add_for(&mut m, None, 1).unwrap());
    let cancel = |m: &mut Manager, monitor: u64, session: Option<&str>, force: bool| {
        m.request(Request::CancelMonitor { monitor, session: session.map(str::to_string), force })
    };
    match cancel(&mut m, a, Some("session-b"), false) {
        Err(ControlError::NotOwner(message)) => assert_eq!(
            message,
            format!("monitor_cancel: monitor {a} belongs to session `session-`; only its session cancels it")
        ),
        other => panic!("{other:?}"),
    }
    match cancel(&mut m, a, None, false) {
        Err(ControlError::NotOwner(_)) => {}
        other => panic!("the program is not the session either: {other:?}"),
    }
    match cancel(&mut m, own, Some("session-a"), false) {
        Err(ControlError::NotOwner(message)) => {
            assert!(message.ends_with("belongs to the program running the robot; only its session cancels it"))
        }
        other => panic!("{other:?}"),
    }
    assert!(cancelled(&events).is_empty(), "a refused cancel changes nothing");
    let Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list.len(), 2);
    // Forced (the GUI, after asking): gone, and its owner is told it was not its own doing.
    cancel(&mut m, a, Some("gui-1"), true).unwrap();
    assert_eq!(cancelled(&events), vec![(a, Some("session-a".to_string()), CancelReason::Forced)]);
    cancel(&mut m, own, None, false).unwrap();
    assert_eq!(cancelled(&events), vec![(own, None, CancelReason::Owner)]);
    assert_eq!(cancel(&mut m, own, None, false), Err(ControlError::UnknownMonitor(own)));
}

#[test]
fn a_sessions_monitors_go_when_it_ends_and_free_its_allowance() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let cap = situate_manager::MAX_MONITORS_PER_SESSION;
    // A sequencer that fills its allowance and crashes…
    for _ in 0..cap / 50 {
        add_for(&mut m, Some("crashed"), 50).unwrap();
    }
    add_for(&mut m, Some("survivor"), 3).unwrap();
    assert!(add_for(&mut m, Some("crashed"), 1).is_err());
    let Reply::MonitorsCancelled(gone) = m.request(Request::EndSession { session: "crashed".into() }).unwrap() else {
        panic!()
    };
    assert_eq!(gone.len(), cap / 50);
    let told = cancelled(&events);
    assert_eq!(told.len(), gone.len());
    assert!(told.iter().all(|(_, s, r)| s.as_deref() == Some("crashed") && *r == CancelReason::SessionEnded));
    // …leaves nothing behind; the other session's are untouched.
    let Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list.iter().map(|i| i.session.as_deref()).collect::<Vec<_>>(), vec![Some("survivor")]);
    // A restarted sequencer (a new session) has its whole allowance, however often it crashed before.
    for restart in 0..5 {
        let session = format!("restart-{restart}");
        for _ in 0..cap / 50 {
            add_for(&mut m, Some(&session), 50).expect("a fresh allowance");
        }
        m.request(Request::EndSession { session }).unwrap();
    }
    let Reply::MonitorsCancelled(none) = m.request(Request::EndSession { session: "unknown".into() }).unwrap() else {
        panic!()
    };
    assert!(none.is_empty());
}

// ----- any: one monitor on several conditions ----------------------------

/// Every `monitor_fired` event so far, as (monitor, cycle, held).
fn fired_held(events: &crossbeam_channel::Receiver<Event>) -> Vec<(u64, u64, Vec<usize>)> {
    events
        .try_iter()
        .filter_map(|e| match e {
            Event::MonitorFired { monitor, cycle, held, .. } => Some((monitor, cycle, held)),
            _ => None,
        })
        .collect()
}

fn add_any(m: &mut Manager, any: &[&str], mode: MonitorMode, report: &[&str]) -> Result<u64, ControlError> {
    match m.request(Request::AddMonitor {
        condition: MonitorCondition::Any(any.iter().map(|c| c.to_string()).collect()),
        mode,
        pause: false,
        report: report.iter().map(|r| r.to_string()).collect(),
        session: None,
        client: None,
    })? {
        Reply::MonitorAdded(id) => Ok(id),
        other => panic!("{other:?}"),
    }
}

#[test]
fn an_any_monitor_says_exactly_which_conditions_held_each_cycle() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    // Range < 0.25 at cycles 2, 3, 5; barcode seen from 4; cycle 5; never > 100.
    let any = ["sonar.range[0] < 0.25", "barcode.visible", "cycle == 5", "sonar.range[0] > 100"];
    let id = add_any(&mut m, &any, MonitorMode::Level, &[]).unwrap();
    m.step(6).unwrap();
    assert_eq!(
        fired_held(&events),
        vec![(id, 2, vec![0]), (id, 3, vec![0]), (id, 4, vec![1]), (id, 5, vec![0, 1, 2]), (id, 6, vec![1]),]
    );
    // The list shows the conditions as given, and the disjunction they make.
    let Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list[0].any.as_deref(), Some(&any.map(String::from)[..]));
    assert_eq!(
        list[0].condition,
        "(sonar.range[0] < 0.25) || (barcode.visible) || (cycle == 5) || (sonar.range[0] > 100)"
    );
    assert!(list[0].holds);
    assert_eq!(list[0].fired, 5);
}

#[test]
fn modes_apply_to_the_disjunction_and_a_lone_condition_held_is_zero() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let any = ["sonar.range[0] < 0.25", "barcode.visible"];
    // The disjunction holds from cycle 2 on without a break: one rising edge.
    let edge = add_any(&mut m, &any, MonitorMode::Edge, &[]).unwrap();
    let once = add_any(&mut m, &any, MonitorMode::Once, &[]).unwrap();
    let plain = m.add_monitor("barcode.visible", MonitorMode::Once).unwrap();
    m.step(8).unwrap();
    assert_eq!(fired_held(&events), vec![(edge, 2, vec![0]), (once, 2, vec![0]), (plain, 4, vec![0])]);
    let Reply::Monitors(list) = m.request(Request::ListMonitors).unwrap() else { panic!() };
    assert_eq!(list.iter().map(|i| (i.monitor, i.any.is_some())).collect::<Vec<_>>(), [(edge, true)]);
}

#[test]
fn an_any_monitor_carries_the_values_of_every_name_its_conditions_read() {
    let mut m = robot(SCRIPT);
    let events = m.events();
    let any = ["sonar.range[0] < 0.25", "barcode.id == 3 && sonar.range[0] > 100", "runaway.safe_distance > 2"];
    let id = add_any(&mut m, &any, MonitorMode::Once, &["cycle"]).unwrap();
    m.step(3).unwrap();
    let (condition, values, held) = events
        .try_iter()
        .find_map(|e| match e {
            Event::MonitorFired { monitor, condition, values, held, .. } if monitor == id => {
                Some((condition, values, held))
            }
            _ => None,
        })
        .expect("the monitor fired");
    assert_eq!(held, [0]);
    assert_eq!(
        condition,
        "(sonar.range[0] < 0.25) || (barcode.id == 3 && sonar.range[0] > 100) || (runaway.safe_distance > 2)"
    );
    // Each name once, in first-use order across the conditions, then `report`.
    let names: Vec<&str> = values.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["sonar.range", "barcode.id", "runaway.safe_distance", "cycle"]);
    assert_eq!(values[1].1, Some(Value::I64(0)));
    assert_eq!(values[2].1, Some(Value::F64(0.5)));
    assert_eq!(values[3].1, Some(Value::I64(2)));
}

#[test]
fn a_bad_condition_of_an_any_is_named_by_its_index_and_column() {
    let mut m = robot(SCRIPT);
    let any = ["cycle > 1", "barcode.visible", "sonar.range[0] < 0.25 && barcde.id == 3"];
    let err = add_any(&mut m, &any, MonitorMode::Once, &[]).unwrap_err();
    let ControlError::BadCondition { index, column, message, pointer } = &err else { panic!("{err:?}") };
    assert_eq!((*index, *column), (Some(2), 26));
    assert!(message.contains("did you mean `barcode.id`?"), "{message}");
    // The pointer shows that condition alone, with the caret in it.
    assert_eq!(pointer, "sonar.range[0] < 0.25 && barcde.id == 3\n                         ^");
    assert!(err.to_string().starts_with("any[2]: bad condition at column 26: unknown signal `barcde.id`"), "{err}");
    let err = add_any(&mut m, &["cycle > 1", "sonar.range[0] + 1"], MonitorMode::Once, &[]).unwrap_err();
    assert!(matches!(err, ControlError::BadCondition { index: Some(1), column: 1, .. }), "{err:?}");
    // Nothing was added.
    assert_eq!(m.request(Request::ListMonitors).unwrap(), Reply::Monitors(vec![]));
}

#[test]
fn an_any_monitor_takes_one_to_64_conditions_and_each_counts_toward_the_cap() {
    let mut m = robot(SCRIPT);
    let many: Vec<String> = (0..=MAX_ANY_CONDITIONS).map(|i| format!("cycle == {i}")).collect();
    let many: Vec<&str> = many.iter().map(String::as_str).collect();
    for refused in [&many[..], &[]] {
        match add_any(&mut m, refused, MonitorMode::Level, &[]) {
            Err(ControlError::Invalid(message)) => {
                assert_eq!(message, format!("monitor_add: `any` has {} conditions, it takes 1 to 64", refused.len()))
            }
            other => panic!("{other:?}"),
        }
    }
    // 64 are fine, down to the last one holding.
    let events = m.events();
    let first = add_any(&mut m, &many[..MAX_ANY_CONDITIONS], MonitorMode::Once, &[]).unwrap();
    let mut only_last = vec!["cycle < 0"; MAX_ANY_CONDITIONS - 1];
    only_last.push("cycle == 64");
    let last = add_any(&mut m, &only_last, MonitorMode::Once, &[]).unwrap();
    m.step(70).unwrap();
    assert_eq!(fired_held(&events), vec![(first, 1, vec![1]), (last, 64, vec![63])]);
    let id = add_any(&mut m, &many[1..], MonitorMode::Level, &[]).unwrap();
    // Every condition is evaluated every cycle: the robot's cap counts conditions.
    for k in 0..situate_manager::MAX_MONITORS - MAX_ANY_CONDITIONS {
        // Spread over sessions, each under its own cap.
        m.request(Request::AddMonitor {
            condition: "cycle > 0".into(),
            mode: MonitorMode::Level,
            pause: false,
            report: Vec::new(),
            session: Some(format!("c{}", k % 5)),
            client: None,
        })
        .expect("under the cap");
    }
    match add_any(&mut m, &["cycle > 0", "cycle > 1"], MonitorMode::Level, &[]) {
        Err(ControlError::Invalid(message)) => assert_eq!(
            message,
            "monitor_add: this robot has 937 monitors watching 1000 conditions; this one's 2 would be past \
             the most it keeps (1000); cancel some first"
        ),
        other => panic!("{other:?}"),
    }
    m.cancel_monitor(id).unwrap();
    add_any(&mut m, &["cycle > 0", "cycle > 1"], MonitorMode::Level, &[]).expect("room again");
}

// ----- evaluated only when something read changed ------------------------

/// A door whose `open` is written only in cycles 3 (true) and 7 (false), a
/// sonar written every cycle, and a skill with a parameter.
fn door_robot() -> Manager {
    let mut reg = Registry::new();
    reg.add(fn_type(decl("door", SkillKind::Sync, &[], &[("door", "{open: bool}")]), |io, _| {
        match io.cx.cycle() {
            3 => io.outputs[0] = Some(situate_core::record_value(vec![("open", Value::Bool(true))])),
            7 => io.outputs[0] = Some(situate_core::record_value(vec![("open", Value::Bool(false))])),
            _ => {}
        }
        Ok(())
    }));
    reg.add(fn_type(decl("sonar", SkillKind::Sync, &[], &[("sonar", "{range: f32[]}")]), |io, _| {
        let range: std::sync::Arc<[f32]> = vec![1.0, 5.0].into();
        io.outputs[0] = Some(situate_core::record_value(vec![("range", Value::F32s(range))]));
        Ok(())
    }));
    reg.add(fn_type(with_param(decl("runaway", SkillKind::Sync, &[], &[]), "safe_distance", 0.5, 0.1, 3.0), |_, _| {
        Ok(())
    }));
    let spec = simulated("door")
        .skill(skill("door", "door"))
        .skill(skill("sonar", "sonar"))
        .skill(skill("runaway", "runaway"));
    build(&spec, &reg)
}

#[test]
fn a_condition_is_evaluated_only_in_cycles_where_a_name_it_reads_changed() {
    let mut m = door_robot();
    let events = m.events();
    let level = m.add_monitor("door.open", MonitorMode::Level).unwrap();
    let param = m.add_monitor("runaway.safe_distance > 1", MonitorMode::Edge).unwrap();
    let start = m.monitor_evaluations();
    m.step(10).unwrap();
    // `door.open`: at its first evaluation (cycle 1), then when written (3 and 7); the parameter
    // only at its first. Ten cycles of the old way were twenty evaluations.
    assert_eq!(m.monitor_evaluations() - start, 3 + 1);
    // A level monitor still fires in every cycle it holds, evaluated or not.
    assert_eq!(fired(&events), vec![(level, 3), (level, 4), (level, 5), (level, 6)]);

    // A parameter set is a change: evaluated once more, and the edge fires at once.
    let start = m.monitor_evaluations();
    m.set_param("runaway", "safe_distance", Value::F64(2.0)).unwrap();
    m.step(3).unwrap();
    assert_eq!(m.monitor_evaluations() - start, 1);
    assert_eq!(fired(&events), vec![(param, 11)]);
    m.cancel_monitor(level).unwrap();
    m.cancel_monitor(param).unwrap();

    // A signal written every cycle, `time` and `cycle` change every cycle.
    let each = [
        m.add_monitor("sonar.range[0] > 100", MonitorMode::Level).unwrap(),
        m.add_monitor("time > 1000", MonitorMode::Level).unwrap(),
        m.add_monitor("cycle < 0", MonitorMode::Level).unwrap(),
    ];
    let start = m.monitor_evaluations();
    m.step(5).unwrap();
    assert_eq!(m.monitor_evaluations() - start, 3 * 5);
    for id in each {
        m.cancel_monitor(id).unwrap();
    }
}

#[test]
fn an_any_monitor_keeps_what_its_unchanged_conditions_held_and_fires_the_moment_one_holds() {
    let mut m = door_robot();
    let events = m.events();
    let id = m.add_monitor_any(&["door.open", "cycle == 5", "runaway.safe_distance > 1"], MonitorMode::Level).unwrap();
    m.step(8).unwrap();
    // `door.open` held from cycle 3 (written) to 6, not evaluated in 4..6; `cycle == 5` in 5.
    assert_eq!(fired_held(&events), vec![(id, 3, vec![0]), (id, 4, vec![0]), (id, 5, vec![0, 1]), (id, 6, vec![0])]);
    // An edge on a condition that holds from its first evaluation fires then, as ever.
    let edge = m.add_monitor("door.open == false", MonitorMode::Edge).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired_held(&events), vec![(edge, 9, vec![0])]);
}

#[test]
fn a_restarted_skills_old_result_is_missing_until_it_writes_again() {
    let mut m = door_robot();
    let events = m.events();
    m.step(4).unwrap();
    // `door.open` is true, written in cycle 3. Off, it keeps that value for conditions.
    m.deactivate(&["door"]).unwrap();
    let off = m.add_monitor("door.open", MonitorMode::Once).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![(off, 5)]);
    // On again: it runs in cycle 6 but writes nothing until 7. Its old `true` is no result of
    // this activation: neither the condition nor its negation holds before it writes again.
    m.activate(&["door"]).unwrap();
    let on = m.add_monitor("door.open", MonitorMode::Level).unwrap();
    let not = m.add_monitor("!door.open", MonitorMode::Level).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![]);
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![(not, 7)]);
    // A monitor added before the restart lets go of the old value the cycle it goes missing.
    m.step(1).unwrap();
    m.cancel_monitor(not).unwrap();
    let _ = fired(&events);
    m.cancel_monitor(on).unwrap();
    let after = m.add_monitor("!door.open", MonitorMode::Level).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![(after, 9)]);
    m.deactivate(&["door"]).unwrap();
    m.step(1).unwrap();
    m.activate(&["door"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(fired(&events), vec![(after, 10)], "cycle 11: the old `false` is missing");
}
