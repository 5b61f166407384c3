//! Where and how the GUI serves ([`GuiConfig`], with its defaults and a replay's
//! [`ReplayInfo`]), and why it could not start ([`GuiError`]).

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::Value as Json;

use crate::history;
#[cfg(doc)]
use crate::HistoryTap;

/// The default cap on connections served at once ([`GuiConfig::max_connections`]).
pub const DEFAULT_MAX_CONNECTIONS: usize = 256;
/// The default time a connection has to send a whole request head ([`GuiConfig::header_timeout`]).
pub const DEFAULT_HEADER_TIMEOUT: Duration = Duration::from_secs(10);
/// The default time a WebSocket may stay silent, pings unanswered ([`GuiConfig::ws_idle_timeout`]).
pub const DEFAULT_WS_IDLE_TIMEOUT: Duration = Duration::from_secs(60);

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
