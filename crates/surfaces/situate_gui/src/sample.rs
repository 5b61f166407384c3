//! The server's threads that feed the tabs: the events forwarder, the telemetry sampler (one for
//! every tab, sampling only while a tab is connected) and the history's drain (the manager's tap
//! into the timeline).

use std::collections::{BTreeSet, HashSet};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use serde_json::{json, Value as Json};
use situate_link::json as wire;
use situate_manager::{ControlError, Reply, Request};

use crate::formula::Derived;
use crate::{ask, History, HistoryTap, Shared, WORLD_SIGNALS};

/// Forwards the manager's events to every tab (while one is connected) and notes each skill's
/// activation changes and faults (`Shared::activity`).
pub(crate) fn forward_events(shared: &Shared, events: &Receiver<situate_manager::Event>, stop: &AtomicBool) {
    while !stop.load(Ordering::SeqCst) {
        match events.recv_timeout(Duration::from_millis(100)) {
            Ok(e) => {
                shared.activity.lock().unwrap_or_else(|p| p.into_inner()).note(&e);
                if shared.clients.load(Ordering::SeqCst) == 0 {
                    continue;
                }
                let (_, body) = wire::event_to_json(&e);
                let _ = shared.events.send(json!({"type": "event", "event": body}).to_string().into());
            }
            Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
            Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
        }
    }
}

/// How often the history takes what the tap has queued (the tap holds
/// [`history::TAP_QUEUE`](crate::history::TAP_QUEUE) frames: 10 s at 100 Hz).
const HISTORY_POLL: Duration = Duration::from_millis(20);

/// Drains the manager's tap and events into the history until the server stops. When the manager
/// ends, the history stays (a finished run can still be looked back on). The tap's activation
/// changes go to `activity` too: the tap was made before the server subscribed to the events (a
/// skill deactivated before the server started is seen).
pub(crate) fn keep_history(
    history: &Mutex<History>,
    tap: HistoryTap,
    activity: &Mutex<crate::Activity>,
    stop: &AtomicBool,
) {
    use crossbeam_channel::TryRecvError;
    let lock = || history.lock().unwrap_or_else(|p| p.into_inner());
    let (mut frames_open, mut events_open) = (true, true);
    // Polled, not waited on: a reader blocked on the tap would be woken by
    // every cycle's send, a system call on the cycle's thread.
    while !stop.load(Ordering::SeqCst) && (frames_open || events_open) {
        if frames_open {
            let mut h = lock();
            loop {
                match tap.frames.try_recv() {
                    Ok(frame) => h.push_frame(frame),
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => {
                        frames_open = false;
                        break;
                    }
                }
            }
            h.set_dropped(tap.dropped());
        }
        if events_open {
            loop {
                match tap.events.try_recv() {
                    Ok(event) => {
                        lock().push_event(&event);
                        activity.lock().unwrap_or_else(|p| p.into_inner()).note_change(&event);
                    }
                    Err(TryRecvError::Empty) => break,
                    Err(TryRecvError::Disconnected) => {
                        events_open = false;
                        break;
                    }
                }
            }
        }
        std::thread::sleep(HISTORY_POLL);
    }
    if !stop.load(Ordering::SeqCst) {
        tracing::debug!("the history's sources ended: the GUI's history keeps what it holds");
    }
}

/// One sampler for every tab: samples only while someone is connected.
pub(crate) fn sample_loop(shared: &Shared, wake: &Receiver<()>, stop: &AtomicBool) {
    let period = Duration::from_secs_f64(1.0 / shared.sample_hz);
    let mut absent: HashSet<String> = HashSet::new();
    let mut next = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        if shared.clients.load(Ordering::SeqCst) == 0 {
            // Idle: no request reaches the manager until a browser connects.
            let _ = wake.recv_timeout(Duration::from_millis(500));
            next = Instant::now();
            continue;
        }
        let sample = take_sample(shared, &mut absent);
        let _ = shared.telemetry.send(sample.to_string().into());
        next += period;
        let now = Instant::now();
        if next < now {
            // Too slow for the rate: skip ahead rather than piling up requests.
            next = now + period;
        }
        let _ = wake.recv_timeout(next - now);
        while wake.try_recv().is_ok() {}
    }
}

fn reply_json(r: Result<Reply, ControlError>) -> Json {
    match r {
        Ok(reply) => wire::reply_to_json(&reply),
        Err(e) => wire::control_error(&e),
    }
}

/// The skills with their inputs' values: the manager's [`Request::QuerySkills`], and, asked right
/// after it (mostly answered in the same pause between two cycles), the latest value of every signal a skill reads. An active skill's input the manager gives no
/// value for (not written in the manager's latest cycle: a device's reading that came a cycle
/// late, or a record input, which the running manager does not keep once the body has read it)
/// is given the signal's latest value and `written`, the cycle that wrote it. Without this an input
/// written every cycle read null now and then (issue 38).
fn skills_with_inputs(h: &situate_manager::Handle) -> Json {
    let skills = match ask(h, Request::QuerySkills) {
        Ok(Reply::Skills(list)) => list,
        other => return reply_json(other),
    };
    let mut signals: Vec<String> =
        skills.iter().filter(|s| s.active).flat_map(|s| s.inputs.iter().map(|p| p.signal.clone())).collect();
    signals.sort_unstable();
    signals.dedup();
    let latest = if signals.is_empty() {
        Vec::new()
    } else {
        match ask(h, Request::QuerySignals { signals }) {
            Ok(Reply::Signals(readings)) => readings,
            _ => Vec::new(),
        }
    };
    let reply = Reply::Skills(skills);
    let mut out = wire::reply_to_json(&reply);
    let Reply::Skills(skills) = reply else { return out };
    let Some(list) = out.as_array_mut() else { return out };
    for (info, json) in skills.iter().zip(list.iter_mut()) {
        if !info.active {
            continue;
        }
        let Some(ports) = json.get_mut("inputs").and_then(Json::as_array_mut) else { continue };
        for (port, pj) in info.inputs.iter().zip(ports.iter_mut()) {
            if port.value.is_some() {
                continue;
            }
            if let Some(r) = latest.iter().find(|r| r.signal == port.signal && r.value.is_some()) {
                pj["value"] = wire::opt_value_to_json(&r.value);
                pj["written"] = json!(r.cycle);
            }
        }
    }
    out
}

fn take_sample(shared: &Shared, absent: &mut HashSet<String>) -> Json {
    let h = &shared.handle;
    let stats = reply_json(ask(h, Request::QueryStats));
    let skills = skills_with_inputs(h);
    let winners = reply_json(ask(h, Request::QueryWinners));
    let (mut wanted, formulas) = {
        let watched = shared.watched.lock().unwrap_or_else(|p| p.into_inner());
        let signals: BTreeSet<String> = watched.values().flat_map(|w| w.signals.iter().cloned()).collect();
        let mut formulas: Vec<Arc<Derived>> = watched.values().flat_map(|w| w.formulas.iter().cloned()).collect();
        formulas.sort_by(|a, b| a.source().cmp(b.source()));
        formulas.dedup_by(|a, b| a.source() == b.source());
        (signals, formulas)
    };
    wanted.extend(WORLD_SIGNALS.iter().map(|s| s.to_string()));
    let mut signals = serde_json::Map::new();
    for name in wanted {
        if absent.contains(&name) {
            continue;
        }
        match ask(h, Request::QuerySignal { signal: name.clone() }) {
            Ok(reply) => {
                signals.insert(name, wire::reply_to_json(&reply));
            }
            Err(e @ ControlError::UnknownSignal { .. }) => {
                // The wiring never changes while running: don't ask again.
                if !WORLD_SIGNALS.contains(&name.as_str()) {
                    signals.insert(name.clone(), wire::control_error(&e));
                }
                absent.insert(name);
            }
            Err(e) => {
                signals.insert(name, wire::control_error(&e));
            }
        }
    }
    derive(h, &formulas, &mut signals);
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default().as_secs_f64();
    let activity = shared.activity.lock().unwrap_or_else(|p| p.into_inner()).to_json();
    json!({"type": "telemetry", "wall_s": now, "run": shared.run.id, "stats": stats, "skills": skills,
        "winners": winners, "signals": signals, "activity": activity})
}

/// The derived series watched, each under its own text in the sample's `signals`: `{signal,
/// value, cycle, formula: true}`, the value from the leaves' latest values (null when one has
/// none), the cycle the oldest of them was written in. One query reads every leaf they need.
fn derive(h: &situate_manager::Handle, formulas: &[Arc<Derived>], signals: &mut serde_json::Map<String, Json>) {
    if formulas.is_empty() {
        return;
    }
    let mut leaves: Vec<String> = formulas.iter().flat_map(|f| f.leaves().iter().cloned()).collect();
    leaves.sort_unstable();
    leaves.dedup();
    let readings = match ask(h, Request::QuerySignals { signals: leaves.clone() }) {
        Ok(Reply::Signals(r)) => r,
        Ok(_) => return,
        Err(e) => {
            for f in formulas {
                signals.insert(f.source().to_string(), wire::control_error(&e));
            }
            return;
        }
    };
    for f in formulas {
        let values: Vec<Option<(u64, &situate_core::Value)>> = f
            .leaves()
            .iter()
            .map(|l| {
                let k = leaves.binary_search(l).ok()?;
                let r = readings.get(k)?;
                r.value.as_ref().map(|v| (r.cycle, v))
            })
            .collect();
        let (cycle, value) = match f.eval(&values) {
            Some((c, v)) => (json!(c), json!(v)),
            None => (Json::Null, Json::Null),
        };
        signals.insert(
            f.source().to_string(),
            json!({"signal": f.source(), "value": value, "cycle": cycle, "formula": true}),
        );
    }
}

#[cfg(test)]
mod tests {
    use situate::manager::Control;
    use situate_manager::{Handle, Request};

    use super::*;
    use crate::session::handle_message;
    use crate::tests::{robot, shared};
    use crate::{history, serve, serve_with_history, GuiConfig, Layout};

    /// Steps the robot one cycle at a time until a sample passes `ok`; a
    /// minute without one fails the test (a hang, not a slow machine).
    fn step_until(handle: &mut Handle, s: &Shared, ok: impl Fn(&Json) -> bool) -> Json {
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            handle.step(1).expect("step");
            let sample = take_sample(s, &mut HashSet::new());
            if ok(&sample) {
                return sample;
            }
            assert!(Instant::now() < deadline, "no such sample within a minute; the last: {sample}");
            std::thread::sleep(Duration::from_millis(5));
        }
    }

    #[test]
    fn watch_checks_signals_and_the_sample_carries_them() {
        let (mut handle, join) = robot();
        let s = shared(handle.clone());
        let r = handle_message(&s, 7, r#"{"id": 1, "verb": "watch", "args": {"signals": ["odom", "sonar.rang"]}}"#);
        assert_eq!(r["error"]["kind"], "unknown_signal", "{r}");
        assert!(r["error"]["message"].as_str().unwrap_or("").contains("sonar.range"), "suggests the name: {r}");
        let r = handle_message(&s, 7, r#"{"id": 2, "verb": "watch", "args": {"signals": ["odom"]}}"#);
        assert_eq!(r["ok"]["signals"], json!(["odom"]));
        // The toy sonar reads on its own thread (wall clock): how many cycles
        // its first reading takes depends on the machine's load, so step
        // until it is there (a minute at most) rather than a fixed count.
        let sample = step_until(&mut handle, &s, |sample| sample["signals"]["sonar.range"]["value"].is_array());
        assert_eq!(sample["type"], "telemetry");
        assert_eq!(sample["stats"]["robot"], "guitest");
        assert_eq!(sample["skills"].as_array().map(Vec::len), Some(4));
        assert_eq!(sample["signals"]["odom"]["signal"], "odom");
        assert!(sample["signals"]["sonar.range"]["value"].is_array(), "the world view's sonar: {sample}");
        assert!(sample["signals"].get("truth.pose").is_none(), "absent world signals are left out");
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn a_sample_says_since_which_cycle_a_skill_is_inactive() {
        let (mut handle, join) = robot();
        let events = handle.events();
        let gui = serve(handle.clone(), GuiConfig::default()).expect("serve");
        let sample = take_sample(&gui.shared, &mut HashSet::new());
        assert!(sample["activity"]["observed_from"].is_u64(), "{sample}");
        assert_eq!(sample["activity"]["changed"], json!({}), "no change seen yet: {sample}");
        assert_eq!(sample["run"], gui.run_id());
        handle.request(Request::Deactivate { skills: vec!["runaway".into()] }).expect("deactivate");
        let deadline = Instant::now() + Duration::from_secs(60);
        let applied_at = loop {
            match events.recv_timeout(Duration::from_secs(1)) {
                Ok(situate_manager::Event::ActivationApplied { deactivated, cycle, .. })
                    if deactivated.contains(&"runaway".to_string()) =>
                {
                    break cycle
                }
                _ => assert!(Instant::now() < deadline, "no activation_applied for runaway within a minute"),
            }
        };
        let sample = loop {
            let sample = take_sample(&gui.shared, &mut HashSet::new());
            if sample["activity"]["changed"]["runaway"].is_u64() {
                break sample;
            }
            assert!(Instant::now() < deadline, "the change never reached the sample: {sample}");
            std::thread::sleep(Duration::from_millis(10));
        };
        assert_eq!(sample["activity"]["changed"]["runaway"], applied_at, "{sample}");
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    /// With a tap made before the manager ran, the activity holds from cycle 0: a skill never
    /// changed is inactive since cycle 0, and a change made before the server started is seen.
    #[test]
    fn with_a_tap_the_activity_holds_from_the_tap_on() {
        use situate::manager::{Manager, RobotSpec, SkillSpec};
        let spec = RobotSpec::new("guitest")
            .skill(SkillSpec::new("sonar", "toy.sonar"))
            .skill(SkillSpec::new("wheels", "toy.wheels"))
            .skill(SkillSpec::new("runaway", "toy.runaway"))
            .skill(SkillSpec::new("wander", "toy.wander").active(false));
        let mut manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        let tap = HistoryTap::new(&mut manager);
        let (mut handle, join) = manager.spawn(false);
        handle.step(3).expect("step");
        handle.request(Request::Deactivate { skills: vec!["runaway".into()] }).expect("deactivate");
        handle.step(3).expect("step");
        let deactivated_at = match handle.request(Request::QueryStats) {
            Ok(situate_manager::Reply::Stats(s)) => s.cycle,
            other => panic!("stats: {other:?}"),
        };
        assert!(deactivated_at > 0);
        // The server starts after the change (its own events never saw it).
        let gui = serve_with_history(handle.clone(), GuiConfig::default(), Some(tap)).expect("serve");
        let deadline = Instant::now() + Duration::from_secs(60);
        let sample = loop {
            let sample = take_sample(&gui.shared, &mut HashSet::new());
            if sample["activity"]["changed"]["runaway"].is_u64() {
                break sample;
            }
            assert!(Instant::now() < deadline, "the change before the server never reached the sample: {sample}");
            std::thread::sleep(Duration::from_millis(10));
        };
        assert_eq!(sample["activity"]["observed_from"], 0, "{sample}");
        let at = sample["activity"]["changed"]["runaway"].as_u64().unwrap_or(0);
        assert!(at > 3 && at <= deactivated_at, "runaway deactivated in cycle {at}: {sample}");
        assert!(sample["activity"]["changed"].get("wander").is_none(), "wander never changed: {sample}");
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn a_watched_formula_is_in_the_sample_under_its_text_from_the_values_of_that_cycle() {
        let (mut handle, join) = robot();
        let s = shared(handle.clone());
        // Refused, each with its reason: a name the robot lacks (the column), a string, too many.
        let r = handle_message(
            &s,
            7,
            r#"{"id": 1, "verb": "watch", "args": {"signals": [], "formulas": ["abs(odom.q) + 1"]}}"#,
        );
        let message = r["error"]["message"].as_str().unwrap_or_default();
        assert!(
            r["error"]["kind"] == "bad_request"
                && message.contains("formula `abs(odom.q) + 1`: column 5: unknown signal `odom.q`"),
            "{r}"
        );
        let many = json!({"id": 2, "verb": "watch", "args": {"formulas": vec!["odom.x"; 9]}}).to_string();
        let r = handle_message(&s, 7, &many);
        assert!(r["error"]["message"].as_str().unwrap_or_default().contains("at most 8 formulas"), "{r}");
        let r = handle_message(
            &s,
            7,
            r#"{"id": 3, "verb": "watch", "args": {"signals": ["odom"], "formulas": ["abs(odom.x) + 1", "odom.x > odom.y"]}}"#,
        );
        assert_eq!(r["ok"]["formulas"], json!(["abs(odom.x) + 1", "odom.x > odom.y"]), "{r}");
        let sample = step_until(&mut handle, &s, |sample| sample["signals"]["abs(odom.x) + 1"]["value"].is_number());
        let odom = &sample["signals"]["odom"];
        let (x, y) = (odom["value"]["x"].as_f64().expect("x"), odom["value"]["y"].as_f64().expect("y"));
        let f = &sample["signals"]["abs(odom.x) + 1"];
        assert_eq!(
            (f["value"].as_f64(), &f["cycle"], &f["formula"]),
            (Some(x.abs() + 1.0), &odom["cycle"], &json!(true)),
            "{sample}"
        );
        assert_eq!(
            sample["signals"]["odom.x > odom.y"]["value"].as_f64(),
            Some(if x > y { 1.0 } else { 0.0 }),
            "{sample}"
        );
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn a_formula_over_the_timeline_is_its_value_at_each_cycle() {
        let (mut handle, join) = robot();
        let layout = Layout::of(handle.graph());
        let x = handle.graph().leaf_index["odom.x"];
        let (frames_tx, frames) = crossbeam_channel::bounded(4);
        let (_events_tx, events) = crossbeam_channel::bounded(4);
        let tap = HistoryTap::from_channels(layout, frames, events, 0);
        let gui = serve_with_history(handle.clone(), GuiConfig::default(), Some(tap)).expect("serve");
        for cycle in 1..=10u64 {
            // odom.x written every other cycle: the formula's value then is the one of the cycle before.
            let values = if cycle % 2 == 1 { vec![(x, situate_core::Value::F64(cycle as f64))] } else { vec![] };
            let frame = situate_manager::Frame {
                cycle,
                time_s: cycle as f64 / 10.0,
                values: values.into(),
                prints: vec![],
                winners: vec![],
            };
            frames_tx.send(frame).expect("the history takes frames");
        }
        let ask = r#"{"id": 1, "verb": "history_series", "args": {"formulas": ["odom.x * 2"], "max_points": 100}}"#;
        let deadline = Instant::now() + Duration::from_secs(60);
        let r = loop {
            let r = handle_message(&gui.shared, 1, ask);
            if r["ok"]["cycles"].as_array().is_some_and(|c| c.len() == 10) {
                break r;
            }
            assert!(Instant::now() < deadline, "the frames never arrived: {r}");
            std::thread::sleep(Duration::from_millis(10));
        };
        let series = &r["ok"]["signals"]["odom.x * 2"];
        assert_eq!(series["values"], json!([2.0, 2.0, 6.0, 6.0, 10.0, 10.0, 14.0, 14.0, 18.0, 18.0]), "{r}");
        assert_eq!(series["written"], json!([1, 1, 3, 3, 5, 5, 7, 7, 9, 9]), "{r}");
        let bad = r#"{"id": 2, "verb": "history_series", "args": {"formulas": ["odom.x *"]}}"#;
        let r = handle_message(&gui.shared, 1, bad);
        assert_eq!(r["error"]["kind"], "bad_request", "{r}");
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn a_history_can_be_fed_from_any_source() {
        let (mut handle, join) = robot();
        let layout =
            Layout { leaves: vec![history::LeafLayout { path: "recorded.x".into(), writers: vec![] }], skills: vec![] };
        let (frames_tx, frames) = crossbeam_channel::bounded(4);
        let (events_tx, events) = crossbeam_channel::bounded(4);
        let tap = HistoryTap::from_channels(layout, frames, events, 0);
        let gui = serve_with_history(handle.clone(), GuiConfig::default(), Some(tap)).expect("serve");
        for cycle in 1..=20u64 {
            let frame = situate_manager::Frame {
                cycle,
                time_s: cycle as f64 / 10.0,
                values: vec![(0, situate_core::Value::F64(cycle as f64 * 2.0))].into(),
                prints: vec![],
                winners: vec![],
            };
            frames_tx.send(frame).expect("the history takes frames");
        }
        events_tx.send(situate_manager::Event::ManagerStopped { cycle: 20 }).expect("and events");
        drop((frames_tx, events_tx));
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let r = handle_message(&gui.shared, 1, r#"{"id": 1, "verb": "history"}"#);
            if r["ok"]["last_cycle"] == 20 && r["ok"]["marks"].as_array().is_some_and(|m| m.len() == 1) {
                break;
            }
            assert!(Instant::now() < deadline, "the frames never arrived: {r}");
            std::thread::sleep(Duration::from_millis(10));
        }
        let r = handle_message(&gui.shared, 1, r#"{"id": 2, "verb": "history_frame", "args": {"cycle": 7}}"#);
        assert_eq!(r["ok"]["signals"]["recorded.x"]["value"], 14.0, "{r}");
        assert_eq!(r["ok"]["time_s"], 0.7, "{r}");
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }
}
