//! Foxglove live: the Foxglove WebSocket protocol (subprotocol `foxglove.websocket.v1`) at
//! `/foxglove` on the GUI's server, so Foxglove shows the robot's signals live and its parameters
//! (docs/foxglove.md).
//!
//! Every signal leaf is a channel (topic = its path, e.g. `odom.x`), plus `situate/events` for the
//! manager's events; a message is the JSON `{"cycle": N, "value": V}` (values as the link writes
//! them). A robot with a pose and a sonar ring (`truth.pose` or `odom`, `sonar.range`) also has
//! channels in Foxglove's own schemas ([`Schemas`]: `foxglove.FrameTransforms`,
//! `foxglove.PoseInFrame`, `foxglove.LaserScan`), so Foxglove's 3D panel shows the robot and its
//! sonar. Every message is stamped with the run's time: the wall clock at the run's start plus the
//! manager's clock at its cycle (`run_epoch_ns`). Messages come from the [`History`]: one
//! thread polls it ([`POLL`]) and sends every cycle it holds past the last one sent, so the
//! robot's cycle pays nothing for Foxglove.
//!
//! Parameters (`skill.param`) are read with `QuerySkills` and set with `SetParam` through the
//! manager's handle, so Foxglove can do only what the link allows; a refused value comes back as
//! a `status` error naming the parameter. A client following parameters
//! (`subscribeParameterUpdates`) is sent every change the history sees.
//!
//! Bounded: at most [`MAX_CLIENTS`] clients, [`MAX_SUBSCRIPTIONS`] subscriptions each, a send
//! queue of [`QUEUE`] messages and [`QUEUE_BYTES`] per client (a slow client loses messages, counted and told in a
//! `status` warning: neither the poller nor the server ever waits for it), client messages of
//! at most 64 KiB; a bad client message is answered by a `status` error. Like every route, it
//! answers only requests naming this server in `Host` (lib.rs, "Who may connect"); a client that
//! sends nothing and answers no ping for [`crate::GuiConfig::ws_idle_timeout`] is closed.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::ws::WebSocketUpgrade;
use axum::extract::State;
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};

#[cfg(doc)]
use crate::History;
use crate::Shared;

mod client;
mod connection;
mod params;
mod poller;
mod protocol;
mod schemas;
#[cfg(test)]
mod tests;

pub use client::{Client, Hub};
use connection::session;
pub(crate) use poller::publish;
pub use poller::Cursor;
pub use protocol::{message_data, nanos, status, value_schema};
pub use schemas::{Known, KnownChannel, Schemas, BASE_FRAME};

/// The WebSocket subprotocol spoken.
pub const SUBPROTOCOL: &str = "foxglove.websocket.v1";
/// The topic of the manager's events.
pub const EVENTS_TOPIC: &str = "situate/events";
/// The most Foxglove clients at once.
pub const MAX_CLIENTS: usize = 8;
/// The most subscriptions one client may hold.
pub const MAX_SUBSCRIPTIONS: usize = 1024;
/// Messages queued for one client before new ones are dropped.
pub const QUEUE: usize = 4096;
/// Bytes queued for one client before new messages are dropped (large values fill it first).
pub const QUEUE_BYTES: usize = 16 << 20;
/// How often the history is polled for new cycles.
pub const POLL: Duration = Duration::from_millis(20);
/// Parameter names one client may follow (`subscribeParameterUpdates`), besides "all".
pub const MAX_PARAM_NAMES: usize = 4096;
/// Parameter requests one client may have waiting for the manager.
const MAX_PARAM_REQUESTS: usize = 2;
/// The web apps of Foxglove, allowed besides pages of this server and clients sending no origin.
const FOXGLOVE_ORIGINS: [&str; 2] = ["https://app.foxglove.dev", "https://studio.foxglove.dev"];

/// A Foxglove client's origin: none (Foxglove's desktop app, a script), a page of this server,
/// or Foxglove's web app. Any other web page is refused (it could read the robot and set its
/// parameters from the user's browser).
fn origin_allowed(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else { return true };
    let Ok(origin) = origin.to_str() else { return false };
    crate::session::same_origin(headers) || FOXGLOVE_ORIGINS.contains(&origin.trim_end_matches('/'))
}

/// `GET /foxglove`: the WebSocket upgrade (selecting `foxglove.websocket.v1` when asked).
pub(crate) async fn upgrade(State(shared): State<Arc<Shared>>, headers: HeaderMap, ws: WebSocketUpgrade) -> Response {
    if !origin_allowed(&headers) {
        tracing::warn!("refused a Foxglove WebSocket from another origin");
        return (StatusCode::FORBIDDEN, "cross-origin WebSocket refused").into_response();
    }
    if shared.history.is_none() {
        return (StatusCode::SERVICE_UNAVAILABLE, "Foxglove live needs the GUI's history (it is off)\n")
            .into_response();
    }
    ws.protocols([SUBPROTOCOL])
        .max_message_size(crate::MAX_MESSAGE)
        .on_upgrade(move |socket| session(shared, socket))
        .into_response()
}
