//! One browser tab's WebSocket (`/ws`): the hello, the tab's requests and what it is sent
//! (replies, telemetry, events). A request is one of the link's verbs, decoded by the link's own
//! decoder and forwarded to the manager, or one of the GUI's own: `watch` (the signals the tab
//! plots), `history` and `history_frame` (the timeline).

use std::sync::atomic::Ordering;
use std::sync::Arc;

use axum::extract::ws::{Message, Utf8Bytes, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use serde_json::{json, Value as Json};
use situate_link::json as wire;
use situate_manager::{Reply, Request};
use tokio::sync::broadcast;

use crate::formula::Derived;
use crate::serve::{stopping, Keepalive};
use crate::{ask, HistoryError, Shared, MAX_MESSAGE, WORLD_SIGNALS};

/// The GUI's own verbs, besides the link's.
const GUI_VERBS: [&str; 5] = ["watch", "history", "history_frame", "history_series", "replay_events"];

/// A browser's WebSocket must come from a page of this server (no cross-site WebSocket): a
/// request with an `Origin` header is accepted only when its host is the request's `Host`
/// (which the server's middleware has checked is a host it answers to).
pub(crate) fn same_origin(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else { return true };
    let (Ok(origin), Some(Ok(host))) = (origin.to_str(), headers.get(header::HOST).map(|h| h.to_str())) else {
        return false;
    };
    origin.strip_prefix("http://").or_else(|| origin.strip_prefix("https://")) == Some(host)
}

pub(crate) async fn ws_upgrade(
    State(shared): State<Arc<Shared>>,
    headers: HeaderMap,
    ws: WebSocketUpgrade,
) -> Response {
    if !same_origin(&headers) {
        tracing::warn!("refused a WebSocket from another origin");
        return (StatusCode::FORBIDDEN, "cross-origin WebSocket refused").into_response();
    }
    ws.max_message_size(MAX_MESSAGE).on_upgrade(move |socket| session(shared, socket))
}

/// The first message of every connection: the run, the world's map, the verbs, and the run's
/// outcome when it is known already.
pub(crate) fn hello_message(shared: &Shared, client: u64) -> Json {
    json!({
        "type": "hello",
        "client": client,
        "session": tab_session(shared, client),
        "protocol": wire::PROTOCOL,
        "run": {"id": shared.run.id, "started_unix_s": shared.run.started_unix_s},
        "sample_hz": shared.sample_hz,
        "world": shared.world,
        "verbs": wire::VERBS.iter().filter(|v| **v != "telemetry").chain(GUI_VERBS.iter()).collect::<Vec<_>>(),
        "history": shared.history.as_ref().map(|h| {
            let h = h.lock().unwrap_or_else(|p| p.into_inner());
            json!({"frames": h.capacity(), "bytes": h.byte_budget()})
        }),
        "outcome": shared.outcome.lock().unwrap_or_else(|p| p.into_inner()).clone(),
        "replay": shared.replay.as_ref().map(|r| json!({
            "file": r.file, "summary": r.summary, "events": r.events.len(),
        })),
    })
}

/// Counts a connected tab for as long as it lives.
struct ClientGuard {
    shared: Arc<Shared>,
    id: u64,
}

impl Drop for ClientGuard {
    fn drop(&mut self) {
        self.shared.watched.lock().unwrap_or_else(|p| p.into_inner()).remove(&self.id);
        self.shared.clients.fetch_sub(1, Ordering::SeqCst);
        // The tab's monitors go with it (never waited for: the manager handles it between cycles).
        let end = Request::EndSession { session: tab_session(&self.shared, self.id) };
        if let Err(e) = self.shared.handle.submit(end) {
            tracing::debug!(error = %e, client = self.id, "could not end a GUI tab's session");
        }
    }
}

/// A tab's session (docs/protocol.md, "Sessions"): the monitors it adds are its own, only it (or,
/// with `force`, another tab after asking its user) cancels them, and they go when it closes. The
/// server knows when a tab goes, so a tab needs no secret or token.
fn tab_session(shared: &Shared, client: u64) -> String {
    format!("gui-{}-{client}", shared.run.id)
}

async fn session(shared: Arc<Shared>, mut socket: WebSocket) {
    let id = shared.next_client.fetch_add(1, Ordering::SeqCst);
    let mut telemetry = shared.telemetry.subscribe();
    let mut events = shared.events.subscribe();
    let mut shutdown = shared.shutdown.clone();
    shared.clients.fetch_add(1, Ordering::SeqCst);
    let _guard = ClientGuard { shared: Arc::clone(&shared), id };
    let _ = shared.wake.send(());
    tracing::debug!(client = id, "GUI tab connected");
    let mut keepalive = Keepalive::new(shared.ws_idle);
    let hello = hello_message(&shared, id);
    if !keepalive.send(&mut socket, Message::Text(hello.to_string().into())).await {
        return;
    }
    let (reply_tx, mut reply_rx) = tokio::sync::mpsc::unbounded_channel::<Utf8Bytes>();
    loop {
        tokio::select! {
            _ = stopping(&mut shutdown) => {
                keepalive.close(&mut socket).await;
                break;
            }
            beat = keepalive.beat() => {
                if !keepalive.answer(beat, &mut socket, &format!("GUI tab {id}")).await {
                    break;
                }
            }
            incoming = socket.recv() => {
                keepalive.heard_from(&incoming);
                match incoming {
                    Some(Ok(Message::Text(text))) => {
                        let shared = Arc::clone(&shared);
                        let tx = reply_tx.clone();
                        tokio::task::spawn_blocking(move || {
                            let reply = handle_message(&shared, id, text.as_str());
                            let _ = tx.send(reply.to_string().into());
                        });
                    }
                    Some(Ok(Message::Binary(_))) => {
                        let e = json!({"type": "reply", "id": null,
                            "error": {"kind": "bad_request", "message": "send JSON text frames, not binary"}});
                        if !keepalive.send(&mut socket, Message::Text(e.to_string().into())).await {
                            break;
                        }
                    }
                    Some(Ok(_)) => {}
                    Some(Err(_)) | None => break,
                }
            }
            Some(reply) = reply_rx.recv() => {
                if !keepalive.send(&mut socket, Message::Text(reply)).await {
                    break;
                }
            }
            t = telemetry.recv() => match t {
                Ok(text) => {
                    if !keepalive.send(&mut socket, Message::Text(text)).await {
                        break;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(_)) => {}
                Err(broadcast::error::RecvError::Closed) => break,
            },
            e = events.recv() => match e {
                Ok(text) => {
                    if !keepalive.send(&mut socket, Message::Text(text)).await {
                        break;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    let note = json!({"type": "lagged", "missed": n});
                    if !keepalive.send(&mut socket, Message::Text(note.to_string().into())).await {
                        break;
                    }
                }
                Err(broadcast::error::RecvError::Closed) => break,
            },
        }
    }
    tracing::debug!(client = id, "GUI tab disconnected");
}

/// Answers one browser message (blocking: it may wait for the manager).
pub(crate) fn handle_message(shared: &Shared, client: u64, text: &str) -> Json {
    let parsed: Json = match serde_json::from_str(text) {
        Ok(j) => j,
        Err(e) => return error_reply(&Json::Null, "bad_request", &format!("the message is not JSON: {e}")),
    };
    let id = parsed.get("id").cloned().unwrap_or(Json::Null);
    let Some(verb) = parsed.get("verb").and_then(Json::as_str) else {
        return error_reply(&id, "bad_request", "the message needs a `verb` (a string)");
    };
    let args = parsed.get("args").cloned().unwrap_or_else(|| json!({}));
    if verb == "watch" {
        return watch_signals(shared, client, &id, &args);
    }
    if verb == "history" || verb == "history_frame" || verb == "history_series" {
        return history_request(shared, verb, &id, &args);
    }
    if verb == "telemetry" {
        return error_reply(&id, "bad_request", "the GUI samples telemetry itself: use `watch` to choose signals");
    }
    if verb == "replay_events" {
        return replay_events(shared, &id);
    }
    if let Some(replay) = &shared.replay {
        if crate::CHANGING_VERBS.contains(&verb) {
            return error_reply(
                &id,
                "unavailable",
                &format!(
                    "`{verb}`: this is a replay of {}: its robot ran the recording to the end and nothing on it \
                     can be changed. Play the recording on the timeline; to run it with another parameter or \
                     skill, replay it again (`situate replay FILE --set …` or `--robot …`)",
                    replay.file
                ),
            );
        }
    }
    // A tab's monitors belong to its own session, whatever it says; `force` (cancel another
    // session's monitor) is the GUI's own argument, sent once the page asked its user.
    let mut args = args;
    let mut force = false;
    if matches!(verb, "monitor_add" | "monitor_cancel") {
        if let Some(obj) = args.as_object_mut() {
            obj.remove("session");
            if verb == "monitor_cancel" {
                match obj.remove("force") {
                    None | Some(Json::Bool(false)) => {}
                    Some(Json::Bool(true)) => force = true,
                    Some(other) => {
                        return error_reply(
                            &id,
                            "bad_request",
                            &format!("`monitor_cancel`: argument `force` must be true or false, got {other}"),
                        )
                    }
                }
            } else if !obj.contains_key("client") {
                obj.insert("client".into(), json!(format!("GUI tab {client}")));
            }
        }
    }
    let payload = args.to_string();
    match wire::decode_request(verb, payload.as_bytes()) {
        Err(e) => json!({"type": "reply", "id": id, "error": {"kind": e.kind, "message": e.message}}),
        Ok(wire::Decoded::Hello) => match ask(&shared.handle, Request::QueryStats) {
            Ok(Reply::Stats(s)) => json!({"type": "reply", "id": id, "ok": {
                "robot": s.robot, "protocol": wire::PROTOCOL, "verbs": wire::VERBS}}),
            Ok(other) => error_reply(&id, "invalid", &format!("unexpected reply {other:?}")),
            Err(e) => with_id(wire::control_error(&e), &id),
        },
        Ok(wire::Decoded::Telemetry { .. }) => error_reply(&id, "bad_request", "use `watch`"),
        Ok(wire::Decoded::Manager(mut request)) => {
            match &mut request {
                Request::AddMonitor { session, .. } => *session = Some(tab_session(shared, client)),
                Request::CancelMonitor { session, force: f, .. } => {
                    *session = Some(tab_session(shared, client));
                    *f = force;
                }
                _ => {}
            }
            tracing::debug!(?request, client, "GUI request");
            match ask(&shared.handle, request) {
                Ok(reply) => json!({"type": "reply", "id": id, "ok": wire::reply_to_json(&reply)}),
                Err(e) => with_id(wire::control_error(&e), &id),
            }
        }
    }
}

fn with_id(mut body: Json, id: &Json) -> Json {
    body["type"] = json!("reply");
    body["id"] = id.clone();
    body
}

fn error_reply(id: &Json, kind: &str, message: &str) -> Json {
    json!({"type": "reply", "id": id, "error": {"kind": kind, "message": message}})
}

/// `history` and `history_frame {cycle}`: the timeline's span and marks, and the state at a cycle.
fn history_request(shared: &Shared, verb: &str, id: &Json, args: &Json) -> Json {
    let Some(history) = &shared.history else {
        return error_reply(
            id,
            "unavailable",
            "this GUI keeps no history (the program that serves it did not tap the manager's cycle for it)",
        );
    };
    if verb == "history" {
        let summary = history.lock().unwrap_or_else(|p| p.into_inner()).summary_json();
        return json!({"type": "reply", "id": id, "ok": summary});
    }
    if verb == "history_series" {
        return history_series(shared, history, id, args);
    }
    let Some(cycle) = args.get("cycle").and_then(Json::as_u64) else {
        return error_reply(id, "bad_request", "`history_frame`: argument `cycle` must be a whole number ≥ 0");
    };
    let frame = history.lock().unwrap_or_else(|p| p.into_inner()).frame_json(cycle, &WORLD_SIGNALS);
    match frame {
        Ok(frame) => json!({"type": "reply", "id": id, "ok": frame}),
        Err(e @ HistoryError::Empty) => error_reply(id, "unavailable", &e.to_string()),
        Err(e @ (HistoryError::NotHeld { .. } | HistoryError::UnknownSignal(_))) => {
            error_reply(id, "bad_request", &e.to_string())
        }
    }
}

/// `replay_events`: a replay's recorded events (the newest [`crate::REPLAY_EVENTS`]), each the
/// link's JSON of it; `unavailable` when the robot is not a replay.
fn replay_events(shared: &Shared, id: &Json) -> Json {
    let Some(replay) = &shared.replay else {
        return error_reply(id, "unavailable", "`replay_events`: the robot is not a replay of a recording");
    };
    let skip = replay.events.len().saturating_sub(crate::REPLAY_EVENTS);
    json!({"type": "reply", "id": id, "ok": {
        "events": &replay.events[skip..], "total": replay.events.len(),
    }})
}

/// The most signals one `history_series` asks for, and the most points it may ask for.
const SERIES_SIGNALS: usize = 32;
const SERIES_POINTS: u64 = 20_000;

/// `history_series {signals, formulas, max_points}`: signals (and derived series) over the whole
/// timeline (robot time).
fn history_series(shared: &Shared, history: &std::sync::Mutex<crate::History>, id: &Json, args: &Json) -> Json {
    let usage = "`history_series`: argument `signals` must be a list of at most 32 signal names, `formulas` one \
                 of at most 8 formulas, and one of them not empty";
    let signals: Option<Vec<String>> = match args.get("signals") {
        None => Some(Vec::new()),
        Some(list) => list.as_array().and_then(|list| {
            list.iter().map(|s| s.as_str().filter(|n| !n.is_empty() && n.len() <= 200).map(String::from)).collect()
        }),
    };
    let Some(signals) = signals.filter(|s| s.len() <= SERIES_SIGNALS) else {
        return error_reply(id, "bad_request", usage);
    };
    let formulas = match formulas_arg(shared, args, "history_series") {
        Ok(f) => f,
        Err(message) => return error_reply(id, "bad_request", &message),
    };
    if signals.is_empty() && formulas.is_empty() {
        return error_reply(id, "bad_request", usage);
    }
    let max_points = match args.get("max_points") {
        None => 2000,
        Some(m) => match m.as_u64().filter(|m| (2..=SERIES_POINTS).contains(m)) {
            Some(m) => m as usize,
            None => {
                return error_reply(
                    id,
                    "bad_request",
                    &format!(
                    "`history_series`: argument `max_points` must be a whole number in 2..={SERIES_POINTS}, got {m}"
                ),
                )
            }
        },
    };
    let series = history.lock().unwrap_or_else(|p| p.into_inner()).series_json(&signals, &formulas, max_points);
    match series {
        Ok(s) => json!({"type": "reply", "id": id, "ok": s}),
        Err(e @ HistoryError::Empty) => error_reply(id, "unavailable", &e.to_string()),
        Err(e) => error_reply(id, "bad_request", &e.to_string()),
    }
}

/// The `formulas` argument of `verb` (absent: none), each compiled against the robot's wiring: at
/// most [`crate::formula::MAX_FORMULAS`]; the first that does not compile is the error.
fn formulas_arg(shared: &Shared, args: &Json, verb: &str) -> Result<Vec<Arc<Derived>>, String> {
    let Some(list) = args.get("formulas") else { return Ok(Vec::new()) };
    let list = list.as_array().ok_or_else(|| format!("`{verb}`: argument `formulas` must be a list of strings"))?;
    if list.len() > crate::formula::MAX_FORMULAS {
        return Err(format!("`{verb}`: at most {} formulas, got {}", crate::formula::MAX_FORMULAS, list.len()));
    }
    list.iter()
        .map(|f| {
            let source = f.as_str().filter(|s| !s.trim().is_empty());
            let source = source.ok_or_else(|| format!("`{verb}`: every formula must be a non-empty string"))?;
            Derived::compile(source, shared.handle.graph()).map(Arc::new)
        })
        .collect()
}

/// `watch`: the signals this tab plots (a list of signal names, at most 32), and its derived series
/// (`formulas`, at most 8, each sent in the telemetry's `signals` under its own text).
fn watch_signals(shared: &Shared, client: u64, id: &Json, args: &Json) -> Json {
    let empty = Vec::new();
    let list = match args.get("signals") {
        None => &empty,
        Some(list) => match list.as_array() {
            Some(list) => list,
            None => return error_reply(id, "bad_request", "`watch`: argument `signals` must be a list of strings"),
        },
    };
    let mut signals = Vec::new();
    for s in list {
        match s.as_str() {
            Some(name) if !name.is_empty() && name.len() <= 200 => signals.push(name.to_string()),
            _ => return error_reply(id, "bad_request", "`watch`: every signal must be a non-empty string"),
        }
    }
    if signals.len() > 32 {
        return error_reply(id, "bad_request", "`watch`: at most 32 signals per tab");
    }
    for name in &signals {
        if let Err(e) = ask(&shared.handle, Request::QuerySignal { signal: name.clone() }) {
            return with_id(wire::control_error(&e), id);
        }
    }
    let formulas = match formulas_arg(shared, args, "watch") {
        Ok(f) => f,
        Err(message) => return error_reply(id, "bad_request", &message),
    };
    let sources: Vec<&str> = formulas.iter().map(|f| f.source()).collect();
    let reply = json!({"type": "reply", "id": id, "ok": {"signals": signals, "formulas": sources}});
    let watched = crate::Watched { signals, formulas };
    shared.watched.lock().unwrap_or_else(|p| p.into_inner()).insert(client, watched);
    reply
}

#[cfg(test)]
mod tests {
    use std::time::{Duration, Instant};

    use situate::manager::{Control, Manager, RobotSpec, SkillSpec};
    use situate_manager::Request;

    use super::*;
    use crate::tests::{robot, shared};
    use crate::{serve_with_history, GuiConfig, HistoryTap};

    #[test]
    fn a_tabs_monitors_are_its_own_another_tab_cancels_them_only_by_force_and_they_go_with_it() {
        let (mut handle, join) = robot();
        let events = handle.events();
        let s = Arc::new(shared(handle.clone()));
        let add = handle_message(
            &s,
            1,
            r#"{"id": 1, "verb": "monitor_add", "args": {"condition": "cycle < 0", "session": "a-claimed-one"}}"#,
        );
        let monitor = add["ok"]["monitor"].as_u64().unwrap_or_else(|| panic!("{add}"));
        let list = handle_message(&s, 1, r#"{"id": 2, "verb": "monitor_list"}"#);
        assert_eq!(list["ok"][0]["session"], json!(tab_session(&s, 1)), "the tab's session, whatever it claimed");
        assert_eq!(list["ok"][0]["client"], "GUI tab 1");
        // Another tab: refused, unless it says its user confirmed.
        let cancel = format!(r#"{{"id": 3, "verb": "monitor_cancel", "args": {{"monitor": {monitor}}}}}"#);
        let r = handle_message(&s, 2, &cancel);
        assert_eq!(r["error"]["kind"], "not_owner", "{r}");
        let forced =
            format!(r#"{{"id": 4, "verb": "monitor_cancel", "args": {{"monitor": {monitor}, "force": true}}}}"#);
        let r = handle_message(&s, 2, &forced);
        assert!(r.get("error").is_none(), "{r}");
        let told = std::iter::from_fn(|| events.recv_timeout(Duration::from_secs(60)).ok()).find_map(|e| match e {
            situate_manager::Event::MonitorCancelled { monitor: m, reason, .. } if m == monitor => Some(reason),
            _ => None,
        });
        assert_eq!(told, Some(situate_manager::CancelReason::Forced), "the owner is told it was forced");
        let r = handle_message(&s, 2, r#"{"id": 5, "verb": "monitor_cancel", "args": {"monitor": 1, "force": 1}}"#);
        assert_eq!(r["error"]["kind"], "bad_request", "{r}");
        // A tab that closes takes its monitors with it.
        let add = handle_message(&s, 3, r#"{"id": 6, "verb": "monitor_add", "args": {"condition": "cycle < 0"}}"#);
        assert!(add["ok"]["monitor"].is_u64(), "{add}");
        s.clients.fetch_add(1, Ordering::SeqCst);
        drop(ClientGuard { shared: Arc::clone(&s), id: 3 });
        let deadline = Instant::now() + Duration::from_secs(60);
        loop {
            let list = handle_message(&s, 1, r#"{"id": 7, "verb": "monitor_list"}"#);
            if list["ok"].as_array().is_some_and(|l| l.is_empty()) {
                break;
            }
            assert!(Instant::now() < deadline, "the closed tab's monitor stayed: {list}");
            std::thread::sleep(Duration::from_millis(10));
        }
        handle.request(Request::Shutdown).unwrap();
        join.join().unwrap();
    }

    #[test]
    fn requests_go_through_the_links_decoder_and_the_control_api() {
        let (mut handle, join) = robot();
        let s = shared(handle.clone());
        let r = handle_message(&s, 1, r#"{"id": 1, "verb": "activate", "args": {"skills": ["wander"]}}"#);
        assert_eq!(r["id"], 1);
        assert_eq!(r["ok"]["changed"], json!(["wander"]));
        let r = handle_message(
            &s,
            1,
            r#"{"id": 2, "verb": "set_param", "args": {"skill": "runaway", "param": "safe_distance", "value": 9}}"#,
        );
        assert_eq!(r["error"]["kind"], "bad_param");
        assert!(r["error"]["message"].as_str().unwrap_or("").contains("[0.1, 3.0]"), "{r}");
        assert_eq!(handle.get_param("runaway", "safe_distance"), Ok(situate_core::Value::F64(0.5)));
        let r = handle_message(&s, 1, r#"{"id": 3, "verb": "shutdown"}"#);
        assert_eq!(r["error"]["kind"], "unknown_verb", "{r}");
        let r = handle_message(&s, 1, r#"{"id": 4, "verb": "telemetry", "args": {"signals": ["odom"]}}"#);
        assert_eq!(r["error"]["kind"], "bad_request");
        let r = handle_message(&s, 1, "not json");
        assert_eq!(r["error"]["kind"], "bad_request");
        assert_eq!(r["id"], Json::Null);
        let r = handle_message(&s, 1, r#"{"id": 5, "verb": "step", "args": {"cycles": "x"}}"#);
        assert!(r["error"]["message"].as_str().unwrap_or("").contains("cycles"), "{r}");
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn the_timeline_holds_the_robots_last_cycles_and_its_events() {
        let spec = RobotSpec::new("guitest")
            .skill(SkillSpec::new("sonar", "toy.sonar"))
            .skill(SkillSpec::new("wheels", "toy.wheels"))
            .skill(SkillSpec::new("runaway", "toy.runaway"))
            .skill(SkillSpec::new("wander", "toy.wander").active(false));
        let mut manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        let tap = HistoryTap::new(&mut manager);
        let (mut handle, join) = manager.spawn(false);
        let gui =
            serve_with_history(handle.clone(), GuiConfig { history_frames: 50, ..GuiConfig::default() }, Some(tap))
                .expect("serve");
        assert_eq!(hello_message(&gui.shared, 1)["history"]["frames"], 50);
        handle.step(10).expect("step");
        handle.request(Request::Activate { skills: vec!["wander".into()], with_providers: false }).expect("activate");
        handle.step(20).expect("step");
        let history_until = |ok: &dyn Fn(&Json) -> bool| {
            let deadline = Instant::now() + Duration::from_secs(60);
            loop {
                let r = handle_message(&gui.shared, 1, r#"{"id": 1, "verb": "history"}"#);
                if ok(&r["ok"]) {
                    return r["ok"].clone();
                }
                assert!(Instant::now() < deadline, "the history never caught up: {r}");
                std::thread::sleep(Duration::from_millis(20));
            }
        };
        let summary = history_until(&|ok| {
            ok["last_cycle"].as_u64() >= Some(30) && ok["marks"].as_array().is_some_and(|m| !m.is_empty())
        });
        assert_eq!(summary["marks"][0]["kind"], "activation", "{summary}");
        assert_eq!(summary["marks"][0]["text"], "activated wander", "{summary}");
        let activated = summary["marks"][0]["cycle"].as_u64().unwrap_or(0);
        assert!((10..=12).contains(&activated), "activated between the steps: {summary}");
        let at = |cycle: u64| {
            let r = handle_message(
                &gui.shared,
                1,
                &format!(r#"{{"id": 2, "verb": "history_frame", "args": {{"cycle": {cycle}}}}}"#),
            );
            let wander = r["ok"]["skills"].as_array().and_then(|s| s.iter().find(|s| s["name"] == "wander")).cloned();
            (r, wander.map(|w| w["active"].clone()))
        };
        assert_eq!(at(activated).1, Some(json!(true)), "{}", at(activated).0);
        assert_eq!(at(activated - 1).1, Some(json!(false)), "{}", at(activated - 1).0);
        handle.step(100).expect("step");
        let summary = history_until(&|ok| ok["last_cycle"].as_u64() >= Some(130));
        assert_eq!(summary["frames"], 50, "bounded: {summary}");
        assert_eq!(summary["marks"], json!([]), "the mark left with its cycle: {summary}");
        let (first, last) = (summary["first_cycle"].as_u64().unwrap_or(0), summary["last_cycle"].as_u64().unwrap_or(0));
        assert_eq!(last - first + 1, 50);
        // The activation fell out of the window: wander's state as of the window is its last change.
        let r = handle_message(
            &gui.shared,
            1,
            &format!(r#"{{"id": 2, "verb": "history_frame", "args": {{"cycle": {last}}}}}"#),
        );
        let frame = &r["ok"];
        assert_eq!(frame["cycle"], last, "{r}");
        let wander = frame["skills"].as_array().and_then(|s| s.iter().find(|s| s["name"] == "wander")).expect("wander");
        assert_eq!(wander["active"], true, "{frame}");
        assert_eq!(frame["activity"]["changed"]["wander"], activated);
        assert!(
            frame["signals"]["odom"]["value"].is_object() || frame["signals"]["odom.x"]["value"].is_number(),
            "{frame}"
        );
        let r = handle_message(&gui.shared, 1, r#"{"id": 3, "verb": "history_frame", "args": {"cycle": 0}}"#);
        assert_eq!(r["error"]["kind"], "bad_request", "{r}");
        assert!(r["error"]["message"].as_str().unwrap_or("").contains("not in the history"), "{r}");
        let r = handle_message(&gui.shared, 1, r#"{"id": 4, "verb": "history_frame", "args": {"cycle": -1}}"#);
        assert_eq!(r["error"]["kind"], "bad_request", "{r}");
        gui.stop();
        // Without a tap, the verbs say why there is no timeline.
        let plain = shared(handle.clone());
        let r = handle_message(&plain, 1, r#"{"id": 5, "verb": "history"}"#);
        assert_eq!(r["error"]["kind"], "unavailable", "{r}");
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn a_replays_gui_says_so_refuses_every_change_and_marks_the_recordings_events() {
        let spec = RobotSpec::new("guitest")
            .skill(SkillSpec::new("sonar", "toy.sonar"))
            .skill(SkillSpec::new("wander", "toy.wander").active(false));
        let mut manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        let tap = HistoryTap::new(&mut manager);
        let (mut handle, join) = manager.spawn(false);
        let recorded = vec![
            json!({"kind": "activation_applied", "activated": ["wander"], "deactivated": [], "cycle": 3}),
            json!({"kind": "monitor_fired", "monitor": 7, "condition": "sonar.front < 0.25", "cycle": 5,
                   "time_s": 0.25, "values": {}, "held": 1}),
            json!({"kind": "print", "skill": "wander", "line": "hi", "cycle": 5}),
        ];
        let replay = crate::ReplayInfo {
            file: "run.mcap".into(),
            summary: "identical: every cycle matches the recording".into(),
            events: recorded.clone(),
        };
        let config = GuiConfig { replay: Some(replay), ..GuiConfig::default() };
        let gui = serve_with_history(handle.clone(), config, Some(tap)).expect("serve");
        handle.step(8).expect("step");
        // The replayed robot's own activation is not marked: the recording's is.
        handle.request(Request::Activate { skills: vec!["wander".into()], with_providers: false }).expect("activate");
        handle.step(2).expect("step");
        let hello = hello_message(&gui.shared, 1);
        assert_eq!(hello["replay"]["file"], "run.mcap", "{hello}");
        assert_eq!(hello["replay"]["events"], 3, "{hello}");
        assert!(hello["verbs"].as_array().is_some_and(|v| v.contains(&json!("replay_events"))), "{hello}");
        let deadline = Instant::now() + Duration::from_secs(60);
        let summary = loop {
            let r = handle_message(&gui.shared, 1, r#"{"id": 1, "verb": "history"}"#);
            if r["ok"]["last_cycle"].as_u64() >= Some(10) {
                break r["ok"].clone();
            }
            assert!(Instant::now() < deadline, "the history never caught up: {r}");
            std::thread::sleep(Duration::from_millis(20));
        };
        let marks: Vec<_> = summary["marks"]
            .as_array()
            .expect("marks")
            .iter()
            .map(|m| (m["cycle"].as_u64().unwrap_or(0), m["text"].as_str().unwrap_or("").to_string()))
            .collect();
        assert_eq!(
            marks,
            vec![(3, "activated wander".to_string()), (5, "monitor 7 fired: sonar.front < 0.25".to_string())],
            "{summary}"
        );
        let events = handle_message(&gui.shared, 1, r#"{"id": 2, "verb": "replay_events"}"#);
        assert_eq!(events["ok"]["events"], json!(recorded), "{events}");
        for (verb, args) in [
            ("run", "{}"),
            ("step", r#"{"cycles": 1}"#),
            ("activate", r#"{"skills": ["wander"]}"#),
            ("set_param", r#"{"skill": "wander", "param": "speed", "value": 1.0}"#),
            ("monitor_add", r#"{"condition": "cycle > 1"}"#),
        ] {
            let r = handle_message(&gui.shared, 1, &format!(r#"{{"id": 3, "verb": "{verb}", "args": {args}}}"#));
            assert_eq!(r["error"]["kind"], "unavailable", "{verb}: {r}");
            let message = r["error"]["message"].as_str().unwrap_or("");
            assert!(message.contains("a replay of run.mcap"), "{verb}: {message}");
        }
        let stats = match handle.request(Request::QueryStats).expect("stats") {
            situate_manager::Reply::Stats(s) => s,
            other => panic!("{other:?}"),
        };
        assert_eq!(stats.cycle, 10, "no refused request reached the robot");
        let r = handle_message(&gui.shared, 1, r#"{"id": 4, "verb": "query", "args": {"signal": "cycle"}}"#);
        assert!(r.get("error").is_none() || r["error"]["kind"] != "unavailable", "queries are answered: {r}");
        // A live robot's GUI has no recording to give.
        let plain = shared(handle.clone());
        let r = handle_message(&plain, 1, r#"{"id": 5, "verb": "replay_events"}"#);
        assert_eq!(r["error"]["kind"], "unavailable", "{r}");
        drop(gui);
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }
}
