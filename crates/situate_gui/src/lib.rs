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
use axum::extract::State;
use axum::http::{header, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use crossbeam_channel::Sender;
use serde_json::{json, Value as Json};
use situate_manager::{ControlError, Handle, Reply, Request};
use tokio::sync::{broadcast, watch};

pub mod formula;
pub mod foxglove;
pub mod history;
mod hosts;
pub mod metrics;
mod sample;
mod serve;
mod session;

pub use history::{History, HistoryError, HistoryTap, Layout};

mod assets {
    include!(concat!(env!("OUT_DIR"), "/assets.rs"));
}

/// How long a browser's request may wait for the manager.
const REQUEST_TIMEOUT: Duration = Duration::from_secs(5);
/// The largest message a browser may send.
const MAX_MESSAGE: usize = 64 * 1024;
/// The default cap on connections served at once ([`GuiConfig::max_connections`]).
pub const DEFAULT_MAX_CONNECTIONS: usize = 256;
/// The default time a connection has to send a whole request head ([`GuiConfig::header_timeout`]).
pub const DEFAULT_HEADER_TIMEOUT: Duration = Duration::from_secs(10);
/// The default time a WebSocket may stay silent, pings unanswered ([`GuiConfig::ws_idle_timeout`]).
pub const DEFAULT_WS_IDLE_TIMEOUT: Duration = Duration::from_secs(60);
/// The signals the world view draws, when they exist (`floor`: the robot's floor when its
/// `truth.pose` has none, as a ROS 2 ground-truth Odometry mapped onto it).
const WORLD_SIGNALS: [&str; 5] = ["truth.pose", "floor", "sonar.range", "truth.cars", "truth.people"];

/// Where and how the GUI serves.
#[derive(Debug, Clone, PartialEq)]
pub struct GuiConfig {
    /// The address to listen on (port 0: pick a free one). Bind only where told: the `situate`
    /// program's default is 127.0.0.1.
    pub listen: SocketAddr,
    /// The simulator's map (floors, walls, doors, barcodes, cars) for the world view, if any.
    pub world: Option<Json>,
    /// Telemetry samples per second while a browser is connected (default 10).
    pub sample_hz: f64,
    /// The cycles the timeline keeps (default [`history::DEFAULT_FRAMES`]), when the server is
    /// given a [`HistoryTap`].
    pub history_frames: usize,
    /// The memory the timeline may take (default [`history::DEFAULT_BYTES`]): when the values
    /// are large, it keeps fewer cycles.
    pub history_bytes: usize,
    /// Host names the server answers to besides `localhost`, loopback addresses and the bound
    /// address (e.g. `robot.lan`, without a port): a request naming any other host in `Host` is
    /// refused with `403`, so a web page cannot reach the robot by rebinding its own name.
    pub allowed_hosts: Vec<String>,
    /// The connections served at once, WebSockets included (default
    /// [`DEFAULT_MAX_CONNECTIONS`]); past it a new connection is answered `503` and closed.
    pub max_connections: usize,
    /// How long a connection may take to send a whole request head, and may stay idle between
    /// requests, before it is closed (default [`DEFAULT_HEADER_TIMEOUT`]).
    pub header_timeout: Duration,
    /// How long a WebSocket may send nothing and answer no ping before it is closed (default
    /// [`DEFAULT_WS_IDLE_TIMEOUT`]; pinged every third of it). Also the longest a send to it may
    /// wait for the client to read.
    pub ws_idle_timeout: Duration,
    /// Set when the robot served is a replay of a recording (`situate replay --gui`): the pages
    /// say so, the requests that would change the robot are refused (it ran the recording to its
    /// end; there is nothing live to change), and the timeline's marks are the recording's events.
    pub replay: Option<ReplayInfo>,
}

/// What a replay's GUI says of the recording it replays ([`GuiConfig::replay`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayInfo {
    /// The recording, as the user named it.
    pub file: String,
    /// One line on how the replay compared (`identical: every cycle matches the recording`).
    pub summary: String,
    /// The recording's events, in order, each the link's JSON of it (`docs/protocol.md`,
    /// "Events"): the timeline's marks and the page's event log.
    pub events: Vec<Json>,
}

/// The verbs a replay's GUI refuses: each would change the robot, and a replay's robot has run
/// its recording to the end.
const CHANGING_VERBS: [&str; 9] =
    ["activate", "deactivate", "set_param", "set_priority", "set_verbose", "monitor_add", "run", "stop", "step"];
/// The most recorded events one `replay_events` reply carries (the newest).
const REPLAY_EVENTS: usize = 2000;

impl Default for GuiConfig {
    fn default() -> Self {
        GuiConfig {
            listen: SocketAddr::from(([127, 0, 0, 1], 0)),
            world: None,
            sample_hz: 10.0,
            history_frames: history::DEFAULT_FRAMES,
            history_bytes: history::DEFAULT_BYTES,
            allowed_hosts: Vec::new(),
            max_connections: DEFAULT_MAX_CONNECTIONS,
            header_timeout: DEFAULT_HEADER_TIMEOUT,
            ws_idle_timeout: DEFAULT_WS_IDLE_TIMEOUT,
            replay: None,
        }
    }
}

/// Why the GUI could not start.
#[derive(Debug, thiserror::Error)]
pub enum GuiError {
    /// The listening socket could not be opened.
    #[error("the GUI cannot listen on {addr}: {source} (is the port in use? choose another, or 0 for a free one)")]
    Bind {
        addr: SocketAddr,
        #[source]
        source: std::io::Error,
    },
    /// A configuration value is out of range.
    #[error("GUI configuration: {0}")]
    Config(String),
    /// The server's threads or runtime could not start.
    #[error("could not start the GUI server: {0}")]
    Start(#[source] std::io::Error),
}

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

/// When each skill's activation last changed, as far as this server has seen.
#[derive(Default)]
struct Activity {
    /// The manager's cycle when the server started watching its events.
    observed_from: u64,
    /// Per skill, the cycle of its last activation change (activation_applied, skill_faulted).
    changed: HashMap<String, u64>,
    /// Per skill, the `skill_faulted` events seen (for `/metrics`).
    faults: HashMap<String, u64>,
}

impl Activity {
    /// An activation change seen by the history's tap (which may see it after, or, from before
    /// the server started, instead of the events thread): the latest cycle wins, and faults are
    /// counted by the events thread only.
    fn note_change(&mut self, event: &situate_manager::Event) {
        use situate_manager::Event;
        let mut at = |skill: &String, cycle: u64| {
            let c = self.changed.entry(skill.clone()).or_insert(cycle);
            *c = (*c).max(cycle);
        };
        match event {
            Event::ActivationApplied { activated, deactivated, cycle } => {
                for s in activated.iter().chain(deactivated) {
                    at(s, *cycle);
                }
            }
            Event::SkillFaulted { skill, cycle, .. } => at(skill, *cycle),
            _ => {}
        }
    }

    fn note(&mut self, event: &situate_manager::Event) {
        use situate_manager::Event;
        match event {
            Event::ActivationApplied { activated, deactivated, cycle } => {
                for s in activated.iter().chain(deactivated) {
                    self.changed.insert(s.clone(), *cycle);
                }
            }
            Event::SkillFaulted { skill, cycle, .. } => {
                self.changed.insert(skill.clone(), *cycle);
                *self.faults.entry(skill.clone()).or_default() += 1;
            }
            _ => {}
        }
    }

    fn to_json(&self) -> Json {
        json!({"observed_from": self.observed_from, "changed": self.changed})
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

// ----- HTTP -----------------------------------------------------------------------------------

/// `GET /metrics`: asks the manager off the server's thread (a scrape may wait for a cycle).
async fn metrics_page(State(shared): State<Arc<Shared>>) -> Response {
    match tokio::task::spawn_blocking(move || scrape(&shared)).await {
        Ok(Ok(text)) => ([(header::CONTENT_TYPE, metrics::CONTENT_TYPE)], text).into_response(),
        Ok(Err(e)) => {
            (StatusCode::SERVICE_UNAVAILABLE, format!("the skill manager did not answer: {e}\n")).into_response()
        }
        Err(_) => (StatusCode::INTERNAL_SERVER_ERROR, "the scrape failed\n").into_response(),
    }
}

fn scrape(shared: &Shared) -> Result<String, ControlError> {
    let stats = match ask(&shared.handle, Request::QueryStats)? {
        Reply::Stats(s) => s,
        other => return Err(ControlError::Invalid(format!("unexpected reply {other:?}"))),
    };
    let skills = match ask(&shared.handle, Request::QuerySkills)? {
        Reply::Skills(s) => s,
        other => return Err(ControlError::Invalid(format!("unexpected reply {other:?}"))),
    };
    let faults = shared.activity.lock().unwrap_or_else(|p| p.into_inner()).faults.clone();
    Ok(metrics::render(&stats, &skills, &faults))
}

async fn world(State(shared): State<Arc<Shared>>) -> Response {
    axum::Json(shared.world.clone().unwrap_or(Json::Null)).into_response()
}

fn content_type(path: &str) -> &'static str {
    match path.rsplit('.').next().unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" | "map" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "ico" => "image/x-icon",
        "woff2" => "font/woff2",
        _ => "application/octet-stream",
    }
}

/// The page served when the web app was not built into this program.
pub const PLACEHOLDER: &str = "<!doctype html><html><head><meta charset=\"utf-8\"><title>situate GUI</title></head>\
<body><h1>situate GUI: the web app is not built</h1><p>This program was compiled without <code>web/dist</code>. \
Run <code>make gui</code> (or <code>scripts/gui.sh build</code>), then rebuild the program.</p></body></html>";

/// Whether the web app was embedded at compile time.
pub fn has_web_app() -> bool {
    !assets::ASSETS.is_empty()
}

async fn static_file(uri: Uri) -> Response {
    let path = uri.path().trim_start_matches('/');
    let path = if path.is_empty() { "index.html" } else { path };
    if let Some((_, bytes)) = assets::ASSETS.iter().find(|(p, _)| *p == path) {
        let cache = if path.starts_with("assets/") { "public, max-age=31536000, immutable" } else { "no-cache" };
        return ([(header::CONTENT_TYPE, content_type(path)), (header::CACHE_CONTROL, cache)], *bytes).into_response();
    }
    if path == "favicon.ico" {
        return StatusCode::NO_CONTENT.into_response();
    }
    if path == "index.html" {
        return ([(header::CONTENT_TYPE, "text/html; charset=utf-8")], PLACEHOLDER).into_response();
    }
    (StatusCode::NOT_FOUND, format!("no such file: /{path}")).into_response()
}

#[cfg(test)]
pub(crate) mod tests {
    use std::io::{Read, Write};
    use std::net::TcpStream;

    use situate::manager::{Control, Manager, RobotSpec, SkillSpec};

    use super::*;
    use crate::session::hello_message;

    pub(crate) fn robot() -> (Handle, situate_manager::Joiner) {
        let spec = RobotSpec::new("guitest")
            .skill(SkillSpec::new("sonar", "toy.sonar"))
            .skill(SkillSpec::new("wheels", "toy.wheels"))
            .skill(SkillSpec::new("runaway", "toy.runaway"))
            .skill(SkillSpec::new("wander", "toy.wander").active(false));
        let manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        manager.spawn(true)
    }

    pub(crate) fn shared(handle: Handle) -> Shared {
        let (wake, _) = crossbeam_channel::unbounded();
        Shared {
            handle,
            run: RunInfo::new(),
            activity: Mutex::new(Activity::default()),
            outcome: Mutex::new(None),
            world: None,
            sample_hz: 10.0,
            ws_idle: DEFAULT_WS_IDLE_TIMEOUT,
            clients: AtomicUsize::new(0),
            next_client: AtomicU64::new(1),
            watched: Mutex::new(HashMap::new()),
            history: None,
            replay: None,
            foxglove: foxglove::Hub::default(),
            telemetry: broadcast::channel(4).0,
            events: broadcast::channel(4).0,
            wake,
            shutdown: watch::channel(false).1,
        }
    }

    pub(crate) fn http(addr: SocketAddr, request: &str) -> String {
        let mut s = TcpStream::connect(addr).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
        s.write_all(request.as_bytes()).expect("write");
        let mut buf = Vec::new();
        let mut chunk = [0u8; 4096];
        // Read the head (and whatever body came with it); upgrades never close the stream.
        while let Ok(n) = s.read(&mut chunk) {
            if n == 0 {
                break;
            }
            buf.extend_from_slice(&chunk[..n]);
            let text = String::from_utf8_lossy(&buf);
            // An upgrade request keeps the connection open: its head is the whole answer.
            if request.contains("Upgrade: websocket") && text.contains("\r\n\r\n") {
                break;
            }
        }
        String::from_utf8_lossy(&buf).into_owned()
    }

    #[test]
    fn serves_the_app_the_world_and_refuses_cross_origin_sockets() {
        let (mut handle, join) = robot();
        let world = json!({"floors": [], "cars": [], "robot_radius": 0.25});
        let gui =
            serve(handle.clone(), GuiConfig { world: Some(world.clone()), ..GuiConfig::default() }).expect("serve");
        let addr = gui.local_addr();
        assert!(addr.ip().is_loopback());
        assert_ne!(addr.port(), 0);
        let get = |path: &str, host: &str| {
            http(addr, &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"))
        };
        let page = get("/", &addr.to_string());
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        assert!(page.contains("<html") || page.contains("<!doctype html>"), "{page}");
        if !has_web_app() {
            assert!(page.contains("make gui"), "the placeholder says what to run: {page}");
        }
        let w = get("/api/world", &addr.to_string());
        assert!(w.contains("\"robot_radius\":0.25"), "{w}");
        let missing = get("/nope.js", &addr.to_string());
        assert!(missing.starts_with("HTTP/1.1 404"), "{missing}");
        let upgrade = |host: &str, origin: &str| {
            format!(
                "GET /ws HTTP/1.1\r\nHost: {host}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
                 Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{origin}\r\n"
            )
        };
        let evil = http(addr, &upgrade(&addr.to_string(), "Origin: http://evil.example\r\n"));
        assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
        let ok = http(addr, &upgrade(&addr.to_string(), &format!("Origin: http://{addr}\r\n")));
        assert!(ok.starts_with("HTTP/1.1 101"), "{ok}");
        // DNS rebinding: a page at evil.example, its name pointed at this machine, is its own
        // origin; only the Host tells it apart, on every route.
        let port = addr.port();
        let rebound = format!("evil.example:{port}");
        let evil = http(addr, &upgrade(&rebound, &format!("Origin: http://{rebound}\r\n")));
        assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
        let page = get("/", &rebound);
        assert!(page.contains("--gui-allow-host evil.example"), "the refusal says how to allow a name: {page}");
        for path in ["/", "/index.html", "/api/world", "/metrics", "/nope.js", "/foxglove"] {
            let page = get(path, &rebound);
            assert!(page.starts_with("HTTP/1.1 403"), "{path}: {page}");
        }
        let no_host = http(addr, "GET /api/world HTTP/1.0\r\n\r\n");
        assert!(no_host.starts_with("HTTP/1.0 400") || no_host.starts_with("HTTP/1.1 400"), "{no_host}");
        assert!(no_host.contains("no Host header"), "{no_host}");
        let absolute = http(
            addr,
            &format!("GET http://{rebound}/api/world HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"),
        );
        assert!(absolute.starts_with("HTTP/1.1 403"), "the request-target's host counts too: {absolute}");
        // What a browser sends for this server: its address (browser tests open
        // http://127.0.0.1:<port>/), localhost, or a tunnel's port.
        for host in [format!("localhost:{port}"), format!("[::1]:{port}"), "localhost:9000".into()] {
            let page = get("/api/world", &host);
            assert!(page.starts_with("HTTP/1.1 200"), "{host}: {page}");
        }
        gui.stop();
        // A name the user allows.
        let gui = serve(handle.clone(), GuiConfig { allowed_hosts: vec!["Robot.LAN".into()], ..GuiConfig::default() })
            .expect("serve");
        let (addr, port) = (gui.local_addr(), gui.local_addr().port());
        let named = format!("robot.lan:{port}");
        let ok = http(addr, &upgrade(&named, &format!("Origin: http://{named}\r\n")));
        assert!(ok.starts_with("HTTP/1.1 101"), "{ok}");
        let evil = http(addr, &upgrade(&rebound, &format!("Origin: http://{rebound}\r\n")));
        assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
        gui.stop();
        match serve(handle.clone(), GuiConfig { allowed_hosts: vec!["robot.lan:80".into()], ..GuiConfig::default() }) {
            Err(GuiError::Config(m)) => assert!(m.contains("without a port"), "{m}"),
            Err(other) => panic!("expected a config error, got {other}"),
            Ok(_) => panic!("expected a config error"),
        }
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn every_server_is_a_new_run_named_in_the_hello_with_its_outcome() {
        let (mut handle, join) = robot();
        let first = serve(handle.clone(), GuiConfig::default()).expect("serve");
        let second = serve(handle.clone(), GuiConfig::default()).expect("serve");
        let hello = hello_message(&first.shared, 1);
        assert_eq!(hello["type"], "hello");
        assert_eq!(hello["run"]["id"], first.run_id(), "{hello}");
        let started = hello["run"]["started_unix_s"].as_f64().unwrap_or(0.0);
        assert!(started > 1.6e9, "a wall-clock start time: {hello}");
        assert_ne!(first.run_id(), second.run_id(), "a restarted server is a new run");
        assert_eq!(hello["outcome"], Json::Null, "no outcome yet");
        let mut listener = first.shared.events.subscribe();
        first.set_outcome(Outcome { ok: false, summary: "not delivered: gave up at t = 1800 s".into() });
        let hello = hello_message(&first.shared, 2);
        assert_eq!(hello["outcome"]["ok"], false, "{hello}");
        assert_eq!(hello["outcome"]["summary"], "not delivered: gave up at t = 1800 s");
        let sent: Json = serde_json::from_str(listener.try_recv().expect("the outcome is sent to open pages").as_str())
            .expect("JSON");
        assert_eq!(sent["type"], "outcome");
        assert_eq!(sent["summary"], "not delivered: gave up at t = 1800 s");
        first.stop();
        second.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn metrics_count_cycles_skill_time_and_faults_in_prometheus_text_format() {
        let (mut handle, join) = robot();
        let gui = serve(handle.clone(), GuiConfig::default()).expect("serve");
        let scrape = |addr| {
            let page = http(addr, &format!("GET /metrics HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"));
            assert!(page.starts_with("HTTP/1.1 200"), "{page}");
            assert!(page.to_ascii_lowercase().contains("content-type: text/plain; version=0.0.4"), "{page}");
            let body = page.split_once("\r\n\r\n").map(|(_, b)| b.to_string()).unwrap_or_default();
            metrics::tests::parse(&body)
        };
        let before = scrape(gui.local_addr());
        let cycles_before = before["situate_cycles_total{robot=\"guitest\"}"];
        handle.step(5).expect("step");
        let after = scrape(gui.local_addr());
        assert!(after["situate_cycles_total{robot=\"guitest\"}"] >= cycles_before + 5.0, "{after:?}");
        for skill in ["sonar", "wheels", "runaway", "wander"] {
            let active = after[&format!("situate_skill_active{{robot=\"guitest\",skill=\"{skill}\"}}")];
            assert_eq!(active, if skill == "wander" { 0.0 } else { 1.0 }, "{skill}");
        }
        assert!(after["situate_skill_runs_total{robot=\"guitest\",skill=\"runaway\"}"] >= 1.0, "{after:?}");
        assert!(after.contains_key("situate_cycle_overruns_total{robot=\"guitest\"}"));
        assert_eq!(after["situate_skill_faults_total{robot=\"guitest\",skill=\"runaway\"}"], 0.0);
        // A fault as the events thread records it.
        gui.shared.activity.lock().expect("lock").note(&situate_manager::Event::SkillFaulted {
            skill: "runaway".into(),
            cause: "panicked: test".into(),
            cycle: 9,
        });
        let faulted = scrape(gui.local_addr());
        assert_eq!(faulted["situate_skill_faults_total{robot=\"guitest\",skill=\"runaway\"}"], 1.0);
        assert_eq!(faulted["situate_skill_faults_total{robot=\"guitest\",skill=\"wander\"}"], 0.0);
        gui.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn the_open_files_limit_is_raised_to_the_hard_limit() {
        let get = || {
            let mut l = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
            // SAFETY: getrlimit writes the struct it is given.
            assert_eq!(unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut l) }, 0);
            l
        };
        let before = get();
        if before.rlim_cur == before.rlim_max && before.rlim_max > 64 {
            // Lowered a little first (other tests run beside this one), so there is a raise to see.
            let lowered = libc::rlimit { rlim_cur: before.rlim_max - 1, rlim_max: before.rlim_max };
            // SAFETY: setrlimit reads the struct it is given.
            assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_NOFILE, &lowered) }, 0);
        }
        let now = raise_open_files_limit().expect("raised");
        let after = get();
        assert_eq!(after.rlim_cur, after.rlim_max, "the soft limit is the hard one");
        #[allow(clippy::useless_conversion)]
        let soft = u64::from(after.rlim_cur);
        assert_eq!(soft, now);
    }

    #[test]
    fn a_busy_port_and_a_bad_rate_are_clear_errors() {
        let (mut handle, join) = robot();
        let taken = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
        let addr = taken.local_addr().expect("addr");
        match serve(handle.clone(), GuiConfig { listen: addr, ..GuiConfig::default() }) {
            Err(e @ GuiError::Bind { .. }) => assert!(e.to_string().contains(&addr.to_string()), "{e}"),
            Err(other) => panic!("expected a bind error, got {other}"),
            Ok(_) => panic!("expected a bind error"),
        }
        match serve(handle.clone(), GuiConfig { sample_hz: 0.0, ..GuiConfig::default() }) {
            Err(GuiError::Config(m)) => assert!(m.contains("sample_hz"), "{m}"),
            Err(other) => panic!("expected a config error, got {other}"),
            Ok(_) => panic!("expected a config error"),
        }
        match serve(handle.clone(), GuiConfig { history_frames: 0, ..GuiConfig::default() }) {
            Err(GuiError::Config(m)) => assert!(m.contains("history_frames"), "{m}"),
            Err(other) => panic!("expected a config error, got {other}"),
            Ok(_) => panic!("expected a config error"),
        }
        for (config, name) in [
            (GuiConfig { max_connections: 0, ..GuiConfig::default() }, "max_connections"),
            (GuiConfig { header_timeout: Duration::ZERO, ..GuiConfig::default() }, "header_timeout"),
            (GuiConfig { ws_idle_timeout: Duration::from_millis(1), ..GuiConfig::default() }, "ws_idle_timeout"),
        ] {
            match serve(handle.clone(), config) {
                Err(GuiError::Config(m)) => assert!(m.contains(name), "{m}"),
                Err(other) => panic!("expected a config error, got {other}"),
                Ok(_) => panic!("expected a config error"),
            }
        }
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }
}
