//! The debugging GUI in the browser (paper sections 4–5): a small web server
//! beside a running skill manager that serves the built web app (`web/dist`,
//! embedded at compile time) and speaks to it over one WebSocket per tab.
//!
//! Everything the GUI does goes through the manager's control API: a browser
//! request is decoded by the sequencer link's own decoder
//! ([`situate_link::json::decode_request`]) into a [`Request`] and sent through
//! the [`Handle`], and replies, errors and events use the link's JSON forms
//! (docs/protocol.md). So the GUI can never do what the link refuses.
//!
//! Telemetry (manager stats, every skill's state, resource winners, the
//! signals some tab watches and the world view's signals) is sampled by one
//! thread, off the cycle's thread, at [`GuiConfig::sample_hz`], and only while
//! at least one browser is connected; each sample is broadcast to every tab.
//! Events from [`Handle::events`] are forwarded live.
//!
//! ## Messages (JSON text frames)
//! Browser → server: `{"id": 7, "verb": "activate", "args": {"skills": ["wander"]}}` with any verb of
//! the link's protocol except `telemetry`, plus the GUI's own `{"id": 8, "verb": "watch", "args":
//! {"signals": ["odom", "sonar.range"]}}` (the signals this tab plots), `history` and
//! `history_frame` (the timeline, below).
//! Server → browser: `{"type": "hello", …}` once, `{"type": "reply", "id": 7, "ok": …}` or
//! `{"type": "reply", "id": 7, "error": {"kind", "message"}}`, `{"type": "telemetry", …}` at the
//! sampling rate, `{"type": "event", "event": {…}}` as they happen and `{"type": "outcome", …}`
//! when the program says how its run ended ([`GuiServer::set_outcome`]).
//!
//! ## Time
//! A page must never show the past as the present. The hello names the run (`run: {id,
//! started_unix_s}`, new for every server), so a page that reconnects to a restarted robot on the
//! same port knows its plots, trails and events belong to the old run. Each telemetry sample carries
//! `activity`: per skill, the cycle of the last activation change the server saw
//! (`activation_applied`, `skill_faulted`), and `observed_from`, the cycle the server started
//! watching at, so an inactive skill's outputs can be shown as "inactive since cycle N". With a
//! [`HistoryTap`] the server has seen every change since the tap was made (before the manager
//! ran: `observed_from` 0), the ones before the server started included.
//!
//! ## Timeline
//! Given a [`HistoryTap`] ([`serve_with_history`]), the server keeps the robot's last
//! [`GuiConfig::history_frames`] cycles and its events in a [`History`], drained from the manager's
//! tap on a thread of its own (the cycle never waits for it), and answers the GUI's verbs
//! `history` (the span held and the events as marks) and `history_frame` (the state at a cycle).
//!
//! ## Foxglove
//! `/foxglove` speaks the Foxglove WebSocket protocol: the history's signals live and the skills'
//! parameters ([`foxglove`], docs/foxglove.md).
//!
//! ## Metrics
//! `GET /metrics` answers in Prometheus' text format: cycle time, overruns, per-skill time and
//! faults ([`metrics`]).
//!
//! ## Who may connect
//! Every route answers only requests whose `Host` names this server: `localhost`, a loopback
//! address, the bound address, or a name in [`GuiConfig::allowed_hosts`] (a guard against DNS
//! rebinding: see `hosts.rs`); others get `403`. At most [`GuiConfig::max_connections`]
//! connections are served at once (past it: `503` and closed); a connection that sends no whole
//! request head within [`GuiConfig::header_timeout`], and a WebSocket that sends nothing and
//! answers no ping for [`GuiConfig::ws_idle_timeout`], are closed (docs/gui.md).

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use axum::extract::ws::Utf8Bytes;
use axum::routing::get;
use axum::Router;
use crossbeam_channel::Sender;
use serde_json::{json, Value as Json};
use situate_manager::{ControlError, Handle, Reply, Request};
use tokio::sync::{broadcast, watch};

mod activity;
mod config;
pub mod formula;
pub mod foxglove;
pub mod history;
mod hosts;
mod http;
pub mod metrics;
mod sample;
mod serve;
mod session;
#[cfg(test)]
pub(crate) mod tests;

use activity::Activity;
pub use config::{
    GuiConfig, GuiError, ReplayInfo, DEFAULT_HEADER_TIMEOUT, DEFAULT_MAX_CONNECTIONS, DEFAULT_WS_IDLE_TIMEOUT,
};
pub use history::{History, HistoryError, HistoryTap, Layout};
pub use http::{has_web_app, PLACEHOLDER};
use http::{metrics_page, static_file, world};

/// How long a browser's request may wait for the manager.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// The largest message a browser may send.
const MAX_MESSAGE: usize = 64 * 1024;

/// The signals the world view draws, when they exist (`floor`: the robot's floor when its
/// `truth.pose` has none, as a ROS 2 ground-truth Odometry mapped onto it).
const WORLD_SIGNALS: [&str; 5] = ["truth.pose", "floor", "sonar.range", "truth.cars", "truth.people"];

/// The verbs a replay's GUI refuses: each would change the robot, and a replay's robot has run
/// its recording to the end.
const CHANGING_VERBS: [&str; 9] =
    ["activate", "deactivate", "set_param", "set_priority", "set_verbose", "monitor_add", "run", "stop", "step"];
/// The most recorded events one `replay_events` reply carries (the newest).
const REPLAY_EVENTS: usize = 2000;

/// A running GUI server. Dropping it stops it, like [`GuiServer::stop`].
pub struct GuiServer {
    addr: SocketAddr,
    shutdown: watch::Sender<bool>,
    stop: Arc<AtomicBool>,
    wake: Sender<()>,
    threads: Vec<JoinHandle<()>>,
    shared: Arc<Shared>,
}

/// How a program's run ended, shown on every page (e.g. the demo's mission: delivered or not).
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Whether the run did what it was for.
    pub ok: bool,
    /// One line for a person: `message delivered at t = 212.4 s`, or why not.
    pub summary: String,
}

impl GuiServer {
    /// Tells every page (those open now and those opened later) how the run ended.
    pub fn set_outcome(&self, outcome: Outcome) {
        let body = json!({"type": "outcome", "ok": outcome.ok, "summary": outcome.summary});
        *self.shared.outcome.lock().unwrap_or_else(|p| p.into_inner()) = Some(body.clone());
        let _ = self.shared.events.send(body.to_string().into());
    }

    /// This server's run id (in the hello): new for every server, so a page tells runs apart.
    pub fn run_id(&self) -> &str {
        &self.shared.run.id
    }

    /// The address actually bound (with the port picked when 0 was asked).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The URL a browser opens.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// How many browser tabs are connected now.
    pub fn clients(&self) -> usize {
        self.shared.clients.load(Ordering::SeqCst)
    }

    /// Stops serving: closes every socket, ends the sampler and the server's threads, and waits
    /// for them.
    pub fn stop(mut self) {
        self.stop_inner();
    }

    fn stop_inner(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        let _ = self.shutdown.send(true);
        let _ = self.wake.send(());
        for t in self.threads.drain(..) {
            if t.join().is_err() {
                tracing::warn!("a GUI thread panicked");
            }
        }
    }
}

impl Drop for GuiServer {
    fn drop(&mut self) {
        self.stop_inner();
    }
}

/// One run of a server: pages compare ids to tell a restarted robot from a reconnection.
struct RunInfo {
    id: String,
    started_unix_s: f64,
}

impl RunInfo {
    fn new() -> Self {
        use std::hash::{BuildHasher, Hasher};
        let started = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
        // RandomState is seeded afresh per process and per instance: two servers, even started in
        // the same nanosecond, get different ids.
        let mut h = std::collections::hash_map::RandomState::new().build_hasher();
        h.write_u128(started.as_nanos());
        h.write_u32(std::process::id());
        RunInfo { id: format!("{:012x}", h.finish() & 0xffff_ffff_ffff), started_unix_s: started.as_secs_f64() }
    }
}

/// What every connection shares.
/// What one tab plots: signals by name, and derived series (formulas).
#[derive(Debug, Clone, Default)]
pub(crate) struct Watched {
    signals: Vec<String>,
    formulas: Vec<Arc<formula::Derived>>,
}

struct Shared {
    handle: Handle,
    run: RunInfo,
    activity: Mutex<Activity>,
    /// The run's outcome once the program has set it (sent in every later hello too).
    outcome: Mutex<Option<Json>>,
    world: Option<Json>,
    sample_hz: f64,
    /// [`GuiConfig::ws_idle_timeout`].
    ws_idle: Duration,
    clients: AtomicUsize,
    next_client: AtomicU64,
    /// Per connected tab, the signals and formulas it watches.
    watched: Mutex<HashMap<u64, Watched>>,
    /// The robot's recent past, when the server was given a tap.
    history: Option<Arc<Mutex<History>>>,
    /// The recording replayed, when the robot is a replay ([`GuiConfig::replay`]).
    replay: Option<ReplayInfo>,
    /// The Foxglove clients (`/foxglove`).
    foxglove: foxglove::Hub,
    telemetry: broadcast::Sender<Utf8Bytes>,
    events: broadcast::Sender<Utf8Bytes>,
    wake: Sender<()>,
    shutdown: watch::Receiver<bool>,
}

/// Serves the GUI for the manager behind `handle`: binds `config.listen` now (so a busy port is
/// reported here), then serves on its own threads until [`GuiServer::stop`]. Without a timeline:
/// see [`serve_with_history`].
pub fn serve(handle: Handle, config: GuiConfig) -> Result<GuiServer, GuiError> {
    serve_with_history(handle, config, None)
}

/// Like [`serve`], keeping the robot's recent past for the timeline from `tap` (made with
/// [`HistoryTap::new`] before the manager was spawned); `None`: no timeline (the `history` verbs
/// answer `unavailable`).
pub fn serve_with_history(handle: Handle, config: GuiConfig, tap: Option<HistoryTap>) -> Result<GuiServer, GuiError> {
    if !(config.sample_hz.is_finite() && config.sample_hz > 0.0 && config.sample_hz <= 100.0) {
        return Err(GuiError::Config(format!("sample_hz must be in (0, 100], got {}", config.sample_hz)));
    }
    if config.history_frames == 0 || config.history_frames > history::MAX_FRAMES {
        return Err(GuiError::Config(format!(
            "history_frames must be in [1, {}], got {}",
            history::MAX_FRAMES,
            config.history_frames
        )));
    }
    if config.max_connections == 0 {
        return Err(GuiError::Config("max_connections must be at least 1".into()));
    }
    for (name, d) in [("header_timeout", config.header_timeout), ("ws_idle_timeout", config.ws_idle_timeout)] {
        if d < Duration::from_millis(10) {
            return Err(GuiError::Config(format!("{name} must be at least 10 ms, got {d:?}")));
        }
    }
    let std_listener =
        std::net::TcpListener::bind(config.listen).map_err(|source| GuiError::Bind { addr: config.listen, source })?;
    let addr = std_listener.local_addr().map_err(GuiError::Start)?;
    std_listener.set_nonblocking(true).map_err(GuiError::Start)?;
    let host_rule = Arc::new(hosts::HostRule::new(addr, &config.allowed_hosts).map_err(GuiError::Config)?);
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(1)
        .max_blocking_threads(4)
        .thread_name("situate-gui")
        .enable_all()
        .build()
        .map_err(GuiError::Start)?;
    let listener = {
        let _guard = runtime.enter();
        tokio::net::TcpListener::from_std(std_listener).map_err(GuiError::Start)?
    };
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let (wake_tx, wake_rx) = crossbeam_channel::unbounded();
    let stop = Arc::new(AtomicBool::new(false));
    // Events are subscribed to before the cycle is read: no change falls between the two.
    let events = handle.events();
    let observed_from = match ask(&handle, Request::QueryStats) {
        Ok(Reply::Stats(s)) => s.cycle,
        _ => 0,
    };
    // A tap has seen the manager's events since it was made (the history thread notes its
    // activation changes too): the activity holds from then.
    let observed_from = tap.as_ref().map_or(observed_from, |t| t.observed_from.min(observed_from));
    let (history, tap) = match tap {
        Some(tap) => {
            let mut h = History::new(tap.layout.clone(), config.history_frames, tap.observed_from);
            h.set_byte_budget(config.history_bytes);
            if let Some(replay) = &config.replay {
                h.set_events_mark(false);
                replay.events.iter().for_each(|e| h.push_recorded_event(e));
            }
            (Some(Arc::new(Mutex::new(h))), Some(tap))
        }
        None => (None, None),
    };
    let shared = Arc::new(Shared {
        handle: handle.clone(),
        run: RunInfo::new(),
        activity: Mutex::new(Activity { observed_from, ..Activity::default() }),
        outcome: Mutex::new(None),
        world: config.world,
        sample_hz: config.sample_hz,
        ws_idle: config.ws_idle_timeout,
        clients: AtomicUsize::new(0),
        next_client: AtomicU64::new(1),
        watched: Mutex::new(HashMap::new()),
        history: history.clone(),
        replay: config.replay,
        foxglove: foxglove::Hub::default(),
        telemetry: broadcast::channel(16).0,
        events: broadcast::channel(1024).0,
        wake: wake_tx.clone(),
        shutdown: shutdown_rx.clone(),
    });
    let mut threads = Vec::new();
    let spawn = |name: &str, f: Box<dyn FnOnce() + Send>| {
        std::thread::Builder::new().name(name.into()).spawn(f).map_err(GuiError::Start)
    };
    // Events: subscribed above, forwarded to every tab as they come.
    let (s, st) = (Arc::clone(&shared), Arc::clone(&stop));
    threads.push(spawn("situate-gui-events", Box::new(move || sample::forward_events(&s, &events, &st)))?);
    let (s, st) = (Arc::clone(&shared), Arc::clone(&stop));
    threads.push(spawn("situate-gui-sampler", Box::new(move || sample::sample_loop(&s, &wake_rx, &st)))?);
    if let (Some(history), Some(tap)) = (history, tap) {
        let st = Arc::clone(&stop);
        let s = Arc::clone(&shared);
        threads.push(spawn(
            "situate-gui-history",
            Box::new(move || sample::keep_history(&history, tap, &s.activity, &st)),
        )?);
        let (s, st) = (Arc::clone(&shared), Arc::clone(&stop));
        threads.push(spawn("situate-gui-foxglove", Box::new(move || foxglove::publish(&s, &st)))?);
    }
    let app = Router::new()
        .route("/ws", get(session::ws_upgrade))
        .route("/foxglove", get(foxglove::upgrade))
        .route("/api/world", get(world))
        .route("/metrics", get(metrics_page))
        .fallback(static_file)
        .with_state(Arc::clone(&shared))
        // One layer in front of every route, the fallback's static files included.
        .layer(axum::middleware::from_fn_with_state(host_rule, hosts::check_host));
    let limits = serve::Limits { max_connections: config.max_connections, header_timeout: config.header_timeout };
    threads.push(spawn(
        "situate-gui-server",
        Box::new(move || {
            runtime.block_on(serve::accept_loop(listener, app, limits, shutdown_rx));
            runtime.shutdown_timeout(Duration::from_secs(2));
        }),
    )?);
    tracing::info!(%addr, "GUI serving");
    Ok(GuiServer { addr, shutdown: shutdown_tx, stop, wake: wake_tx, threads, shared })
}

fn ask(handle: &Handle, request: Request) -> Result<Reply, ControlError> {
    handle.request_timeout(request, REQUEST_TIMEOUT)
}

/// Raises this process's soft limit on open files to its hard limit, and returns the limit now
/// in force. Each GUI connection, link client and recording takes a file descriptor, and the
/// common default soft limit (1024) is soon reached; a program serving them calls this at start.
pub fn raise_open_files_limit() -> std::io::Result<u64> {
    let mut limit = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
    // SAFETY: getrlimit writes the struct it is given, which lives for the call.
    if unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut limit) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    if limit.rlim_cur < limit.rlim_max {
        let raised = libc::rlimit { rlim_cur: limit.rlim_max, rlim_max: limit.rlim_max };
        // SAFETY: setrlimit reads the struct it is given, which lives for the call.
        if unsafe { libc::setrlimit(libc::RLIMIT_NOFILE, &raised) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
        limit = raised;
    }
    // rlim_t is narrower than u64 on some 32-bit targets.
    #[allow(clippy::useless_conversion)]
    Ok(u64::from(limit.rlim_cur))
}
