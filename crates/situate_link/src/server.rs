//! The manager's side of the link: queryables for requests, publishers for
//! events and telemetry.
//!
//! Zenoh delivers queries on its own threads; they are handed to one bridge
//! thread that decodes them, asks the manager through its [`Handle`] and
//! replies. A malformed request is answered by the bridge without the
//! manager ever seeing it, so no payload can disturb the cycle; a
//! well-formed one is handled between two cycles like any in-process
//! request.
//!
//! Requests are handled in the order they arrive. The bridge takes every
//! query already waiting and submits them to the manager together before
//! waiting for the first reply: a sequencer that sends several requests
//! without awaiting each (a burst of changes, then a query) costs one wake-up
//! of each thread on the way, not one per request.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use crossbeam_channel::{Receiver, RecvTimeoutError};
use serde_json::{json, Map, Value as Json};
use situate_manager::{Handle, Pending, Reply, Request};
use zenoh::query::Query;
use zenoh::{Session, Wait};

use crate::json::{self, Decoded};
use crate::session::LinkConfig;
use crate::LinkError;

/// How long the bridge waits for the manager before answering `unavailable`.
const MANAGER_TIMEOUT: Duration = Duration::from_secs(30);

struct Telemetry {
    signals: Vec<String>,
    rate_hz: f64,
}

/// A running link. Dropping it closes the session and ends its threads.
pub struct Link {
    session: Session,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
    robot: String,
}

impl Link {
    /// Opens the manager's Zenoh session (before the manager is built, when
    /// remote skills need it).
    pub fn open(config: &LinkConfig) -> Result<Session, LinkError> {
        zenoh::open(config.zenoh_config()?).wait().map_err(|e| LinkError::Open(e.to_string()))
    }

    /// Serves `handle` for robot `robot` on `session`.
    pub fn serve(robot: &str, handle: Handle, session: Session, config: &LinkConfig) -> Result<Link, LinkError> {
        let stop = Arc::new(AtomicBool::new(false));
        let telemetry = Arc::new(Mutex::new(Telemetry { signals: Vec::new(), rate_hz: config.telemetry_hz }));
        let (tx, rx) = crossbeam_channel::bounded::<Query>(1024);
        let prefix = format!("situate/{robot}/req/");
        session
            .declare_queryable(format!("{prefix}*"))
            .callback(move |query| {
                // A full queue means someone floods the link: refuse at once
                // rather than queue without bound.
                if let Err(crossbeam_channel::TrySendError::Full(q)) = tx.try_send(query) {
                    reply(
                        &q,
                        &json::wire_error(&json::WireError {
                            kind: "unavailable",
                            message: "the link is busy; try again".into(),
                        }),
                    );
                }
            })
            .background()
            .wait()
            .map_err(|e| LinkError::Open(e.to_string()))?;

        let mut threads = Vec::new();
        {
            let (handle, telemetry, robot) = (handle.clone(), Arc::clone(&telemetry), robot.to_string());
            let prefix = prefix.clone();
            threads.push(spawn("situate-link-req", move || bridge(rx, handle, telemetry, &robot, &prefix))?);
        }
        {
            let (session, events, stop, robot) =
                (session.clone(), handle.events(), Arc::clone(&stop), robot.to_string());
            threads.push(spawn("situate-link-events", move || publish_events(&session, events, &stop, &robot))?);
        }
        {
            let (session, stop, robot) = (session.clone(), Arc::clone(&stop), robot.to_string());
            threads.push(spawn("situate-link-telemetry", move || {
                publish_telemetry(&session, handle, telemetry, &stop, &robot)
            })?);
        }
        Ok(Link { session, stop, threads, robot: robot.to_string() })
    }

    pub fn session(&self) -> &Session {
        &self.session
    }

    pub fn robot(&self) -> &str {
        &self.robot
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        let _ = self.session.close().wait();
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

fn spawn(name: &str, f: impl FnOnce() + Send + 'static) -> Result<JoinHandle<()>, LinkError> {
    std::thread::Builder::new().name(name.into()).spawn(f).map_err(|e| LinkError::Open(e.to_string()))
}

/// Replies on a concrete key: a query may come with wildcards
/// (`situate/*/req/hello` finds every robot).
fn reply_on(query: &Query, key: &str, body: &Json) {
    if let Err(e) = query.reply(key, body.to_string()).wait() {
        tracing::debug!(error = %e, "could not reply");
    }
}

fn reply(query: &Query, body: &Json) {
    if let Err(e) = query.reply(query.key_expr().clone(), body.to_string()).wait() {
        tracing::debug!(error = %e, "could not reply");
    }
}

/// At most this many waiting queries are taken together.
const BURST: usize = 64;

/// A query being answered: its reply key and the answer, ready or to come.
struct InFlight {
    query: Query,
    reply_key: String,
    answer: Answer,
}

enum Answer {
    Ready(Json),
    Manager(Pending),
}

fn bridge(rx: Receiver<Query>, handle: Handle, telemetry: Arc<Mutex<Telemetry>>, robot: &str, prefix: &str) {
    let mut burst: Vec<InFlight> = Vec::with_capacity(BURST);
    while let Ok(first) = rx.recv() {
        // Everything already waiting goes to the manager before any reply is
        // awaited; the order of the requests is kept.
        let mut next = Some(first);
        while let Some(query) = next {
            let answer = answer(&query, &handle, &telemetry, robot);
            burst.push(InFlight { reply_key: reply_key(&query, prefix), query, answer });
            next = if burst.len() < BURST { rx.try_recv().ok() } else { None };
        }
        for InFlight { query, reply_key, answer } in burst.drain(..) {
            let body = match answer {
                Answer::Ready(body) => body,
                Answer::Manager(pending) => match pending.wait(MANAGER_TIMEOUT) {
                    Ok(r) => json::ok(json::reply_to_json(&r)),
                    Err(e) => json::control_error(&e),
                },
            };
            reply_on(&query, &reply_key, &body);
        }
    }
}

/// The key a query is answered on: the last chunk names the verb; a wildcard
/// there names none.
fn reply_key(query: &Query, prefix: &str) -> String {
    let verb = query.key_expr().as_str().rsplit('/').next().unwrap_or("");
    let concrete = if verb.contains(['*', '$']) { "unknown" } else { verb };
    format!("{prefix}{concrete}")
}

/// Decodes a query and answers it, or submits it to the manager.
fn answer(query: &Query, handle: &Handle, telemetry: &Mutex<Telemetry>, robot: &str) -> Answer {
    let verb = query.key_expr().as_str().rsplit('/').next().unwrap_or("");
    let payload = query.payload().map(|p| p.to_bytes().into_owned()).unwrap_or_default();
    Answer::Ready(match json::decode_request(verb, &payload) {
        Err(e) => json::wire_error(&e),
        Ok(Decoded::Hello) => {
            json::ok(json!({"protocol": json::PROTOCOL, "robot": robot, "version": env!("CARGO_PKG_VERSION")}))
        }
        Ok(Decoded::Telemetry { signals, rate_hz }) => {
            let mut t = telemetry.lock().unwrap_or_else(|p| p.into_inner());
            t.signals = signals;
            if let Some(r) = rate_hz {
                t.rate_hz = r;
            }
            json::ok(Json::Null)
        }
        Ok(Decoded::Manager(Request::Shutdown)) => {
            json::wire_error(&json::WireError::bad_request("shutdown is not a link request"))
        }
        Ok(Decoded::Manager(request)) => match handle.submit(request) {
            Ok(pending) => return Answer::Manager(pending),
            Err(e) => json::control_error(&e),
        },
    })
}

fn publish_events(session: &Session, events: Receiver<situate_manager::Event>, stop: &AtomicBool, robot: &str) {
    while !stop.load(Ordering::SeqCst) {
        match events.recv_timeout(Duration::from_millis(100)) {
            Ok(event) => {
                let (kind, body) = json::event_to_json(&event);
                if let Err(e) = session.put(format!("situate/{robot}/events/{kind}"), body.to_string()).wait() {
                    tracing::debug!(error = %e, "could not publish an event");
                }
            }
            Err(RecvTimeoutError::Timeout) => {}
            Err(RecvTimeoutError::Disconnected) => return,
        }
    }
}

fn publish_telemetry(
    session: &Session,
    handle: Handle,
    telemetry: Arc<Mutex<Telemetry>>,
    stop: &AtomicBool,
    robot: &str,
) {
    let key = format!("situate/{robot}/telemetry");
    while !stop.load(Ordering::SeqCst) {
        let (signals, rate_hz) = {
            let t = telemetry.lock().unwrap_or_else(|p| p.into_inner());
            (t.signals.clone(), t.rate_hz)
        };
        // Rates are checked where they enter (MIN..=MAX_TELEMETRY_HZ); clamped again so that no
        // value can make the period unrepresentable. Slept in slices: a stop is noticed within
        // 50 ms whatever the rate (a 0.01 Hz sampler once held shutdown for 100 s).
        let period = Duration::from_secs_f64(1.0 / rate_hz.clamp(json::MIN_TELEMETRY_HZ, json::MAX_TELEMETRY_HZ));
        let until = std::time::Instant::now() + period;
        loop {
            let now = std::time::Instant::now();
            if now >= until || stop.load(Ordering::SeqCst) {
                break;
            }
            std::thread::sleep((until - now).min(Duration::from_millis(50)));
        }
        if stop.load(Ordering::SeqCst) {
            break;
        }
        // Sampled between cycles through the handle: never on the cycle's thread.
        let Ok(Reply::Stats(stats)) = handle.request_timeout(Request::QueryStats, Duration::from_secs(1)) else {
            continue;
        };
        let mut values = Map::new();
        for s in &signals {
            let v = match handle.request_timeout(Request::QuerySignal { signal: s.clone() }, Duration::from_secs(1)) {
                Ok(Reply::Signal(r)) => json::opt_value_to_json(&r.value),
                _ => Json::Null,
            };
            values.insert(s.clone(), v);
        }
        let mut body = json::stats_to_json(&stats);
        body["signals"] = Json::Object(values);
        if let Err(e) = session.put(key.as_str(), body.to_string()).wait() {
            tracing::debug!(error = %e, "could not publish telemetry");
        }
    }
}
