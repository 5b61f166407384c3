//! The manager's side of the link: queryables for requests, publishers for
//! events and telemetry.
//!
//! Every thread of the link runs under [`situate_manager::supervise`]: one
//! that panics is reported (`worker_failed`) and restarted.
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

use crate::client_session::Sessions;
use crate::json::{self, Decoded};
use crate::session::LinkConfig;
use crate::LinkError;

/// How long the bridge waits for the manager before answering `unavailable`.
const MANAGER_TIMEOUT: Duration = Duration::from_secs(30);

struct Telemetry {
    signals: Vec<String>,
    rate_hz: f64,
}

/// The link's threads, by name. Each runs under
/// [`situate_manager::supervise`]: a panic is reported (`worker_failed`)
/// and the thread restarted, or the robot stopped if it keeps panicking.
pub const THREADS: [&str; 3] = [REQ_THREAD, EVENTS_THREAD, TELEMETRY_THREAD];
const REQ_THREAD: &str = "situate-link-req";
const EVENTS_THREAD: &str = "situate-link-events";
const TELEMETRY_THREAD: &str = "situate-link-telemetry";

/// Panics the tests ask for, by thread name (see [`Link::inject_panic`]).
#[derive(Default)]
struct Injected(Mutex<Vec<String>>);

impl Injected {
    /// Panics if a panic was asked of `thread`.
    fn check(&self, thread: &str) {
        let mut asked = self.0.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(k) = asked.iter().position(|t| t == thread) {
            asked.remove(k);
            drop(asked);
            panic!("a panic injected by a test");
        }
    }
}

/// A running link. Dropping it closes the session and ends its threads.
pub struct Link {
    session: Session,
    stop: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
    robot: String,
    injected: Arc<Injected>,
}

impl Link {
    /// Opens the manager's Zenoh session (before the manager is built, when
    /// remote skills need it).
    pub fn open(config: &LinkConfig) -> Result<Session, LinkError> {
        zenoh::open(config.zenoh_config()?).wait().map_err(|e| LinkError::Open(e.to_string()))
    }

    /// Serves `handle` for robot `robot` on `session`.
    pub fn serve(robot: &str, handle: Handle, session: Session, config: &LinkConfig) -> Result<Link, LinkError> {
        Link::serve_with(robot, handle, session, config, Verbs::default())
    }

    /// [`Link::serve`], answering `verbs` besides the protocol's (the
    /// program's own requests, such as `record`).
    pub fn serve_with(
        robot: &str,
        handle: Handle,
        session: Session,
        config: &LinkConfig,
        verbs: Verbs,
    ) -> Result<Link, LinkError> {
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

        let sessions = Sessions::watch(robot, &session, &handle)?;
        let injected = Arc::new(Injected::default());
        let mut threads = Vec::new();
        {
            let (handle, telemetry, robot) = (handle.clone(), Arc::clone(&telemetry), robot.to_string());
            let (prefix, injected, reporter) = (prefix.clone(), Arc::clone(&injected), handle.clone());
            let verbs = Arc::new(verbs);
            let ask = Asker { handle, sessions, telemetry, robot, verbs };
            threads.push(spawn(REQ_THREAD, reporter, move || bridge(&rx, &ask, &prefix, &injected))?);
        }
        {
            let (session, events, stop, robot) =
                (session.clone(), handle.events(), Arc::clone(&stop), robot.to_string());
            let injected = Arc::clone(&injected);
            threads.push(spawn(EVENTS_THREAD, handle.clone(), move || {
                publish_events(&session, &events, &stop, &robot, &injected)
            })?);
        }
        {
            let (session, stop, robot) = (session.clone(), Arc::clone(&stop), robot.to_string());
            let (injected, sampler) = (Arc::clone(&injected), handle.clone());
            threads.push(spawn(TELEMETRY_THREAD, handle, move || {
                publish_telemetry(&session, &sampler, &telemetry, &stop, &robot, &injected)
            })?);
        }
        Ok(Link { session, stop, threads, robot: robot.to_string(), injected })
    }

    /// Makes link thread `thread` (one of [`THREADS`]) panic once, at its
    /// next turn: for tests of the supervision.
    #[doc(hidden)]
    pub fn inject_panic(&self, thread: &str) {
        self.injected.0.lock().unwrap_or_else(|p| p.into_inner()).push(thread.to_string());
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

fn spawn(name: &str, handle: Handle, f: impl FnMut() + Send + 'static) -> Result<JoinHandle<()>, LinkError> {
    situate_manager::supervise::supervise(name, handle, f).map_err(|e| LinkError::Open(e.to_string()))
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
    /// A `batch`: each request's answer, in order.
    Batch(Vec<Answer>),
}

impl Answer {
    /// The reply body: a manager's answer awaited (a batch's, one after another).
    fn resolve(self) -> Json {
        match self {
            Answer::Ready(body) => body,
            Answer::Manager(pending) => match pending.wait(MANAGER_TIMEOUT) {
                Ok(r) => json::ok(json::reply_to_json(&r)),
                Err(e) => json::control_error(&e),
            },
            Answer::Batch(answers) => json::ok(Json::Array(answers.into_iter().map(Answer::resolve).collect())),
        }
    }
}

/// What the bridge thread answers requests with.
struct Asker {
    handle: Handle,
    sessions: Sessions,
    telemetry: Arc<Mutex<Telemetry>>,
    robot: String,
    verbs: Arc<Verbs>,
}

fn bridge(rx: &Receiver<Query>, ask: &Asker, prefix: &str, injected: &Injected) {
    let mut burst: Vec<InFlight> = Vec::with_capacity(BURST);
    while let Ok(first) = rx.recv() {
        injected.check(REQ_THREAD);
        // Everything already waiting goes to the manager before any reply is
        // awaited; the order of the requests is kept.
        let mut next = Some(first);
        while let Some(query) = next {
            let answer = answer(&query, ask);
            burst.push(InFlight { reply_key: reply_key(&query, prefix), query, answer });
            next = if burst.len() < BURST { rx.try_recv().ok() } else { None };
        }
        for InFlight { query, reply_key, answer } in burst.drain(..) {
            reply_on(&query, &reply_key, &answer.resolve());
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

/// Decodes a query and answers it, or submits it to the manager (a `batch`: each of its
/// requests in order, as if each came alone).
fn answer(query: &Query, ask: &Asker) -> Answer {
    let verb = query.key_expr().as_str().rsplit('/').next().unwrap_or("");
    let payload = query.payload().map(|p| p.to_bytes().into_owned()).unwrap_or_default();
    if verb == json::BATCH {
        return match json::decode_batch(&payload) {
            Err(e) => Answer::Ready(json::wire_error(&e)),
            Ok(requests) => Answer::Batch(requests.iter().map(|(verb, args)| answer_one(verb, args, ask)).collect()),
        };
    }
    answer_one(verb, &payload, ask)
}

/// One request: answered here, or submitted to the manager.
fn answer_one(verb: &str, payload: &[u8], ask: &Asker) -> Answer {
    let Asker { handle, sessions, telemetry, robot, verbs } = ask;
    if let Some(f) = verbs.0.get(verb) {
        return Answer::Ready(match json::decode_args(verb, payload) {
            Err(e) => json::wire_error(&e),
            Ok(args) => match f(&args) {
                Ok(result) => json::ok(result),
                Err(e) => json::wire_error(&e),
            },
        });
    }
    Answer::Ready(match json::decode_request(verb, payload) {
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
        Ok(Decoded::Manager(request)) => match monitor_session(&request) {
            // Not about a monitor.
            None => {
                let step = matches!(request, Request::Step { .. });
                match handle.submit(request) {
                    // A step is answered before anything after it goes to the manager: on an
                    // external clock (ROS time) its cycles come with the clock's ticks, and what
                    // a client sends after a step must see them.
                    Ok(pending) if step => return Answer::Ready(Answer::Manager(pending).resolve()),
                    Ok(pending) => return Answer::Manager(pending),
                    Err(e) => json::control_error(&e),
                }
            }
            // A monitor belongs to a live session (crate::client_session).
            Some(Some(id)) => match sessions.submit_for(&id, request) {
                Ok(pending) => return Answer::Manager(pending),
                Err(Ok(refused)) => json::wire_error(&refused),
                Err(Err(e)) => json::control_error(&e),
            },
            Some(None) => json::wire_error(&json::WireError::bad_request(format!(
                "`{verb}`: missing argument `session` (the client's session secret: a monitor belongs to the \
                 session that added it; docs/protocol.md, \"Sessions\")"
            ))),
        },
    })
}

/// A request of the program's own (see [`Link::serve_with`]): its arguments
/// (a JSON object, `{}` when none came) to its result, or an error whose
/// kind the client sees (`bad_request`, `refused`, …).
pub type VerbFn = Arc<dyn Fn(&Json) -> Result<Json, json::WireError> + Send + Sync>;

/// For a request about a monitor, the session it names (`Some(None)`: none).
fn monitor_session(request: &Request) -> Option<Option<String>> {
    match request {
        Request::AddMonitor { session, .. } | Request::CancelMonitor { session, .. } => Some(session.clone()),
        _ => None,
    }
}

/// The program's own requests, by verb.
#[derive(Clone, Default)]
pub struct Verbs(pub std::collections::BTreeMap<String, VerbFn>);

fn publish_events(
    session: &Session,
    events: &Receiver<situate_manager::Event>,
    stop: &AtomicBool,
    robot: &str,
    injected: &Injected,
) {
    while !stop.load(Ordering::SeqCst) {
        injected.check(EVENTS_THREAD);
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
    handle: &Handle,
    telemetry: &Mutex<Telemetry>,
    stop: &AtomicBool,
    robot: &str,
    injected: &Injected,
) {
    let key = format!("situate/{robot}/telemetry");
    while !stop.load(Ordering::SeqCst) {
        injected.check(TELEMETRY_THREAD);
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
