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

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use serde_json::{json, Value as Json};
use situate_core::Value;
use situate_link::json as wire;
use situate_manager::{Reply, Request};
use tokio::sync::mpsc;

use crate::serve::{Beat, Keepalive};
use crate::{ask, History, Shared};

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

/// `status` levels (0 is info).
const WARNING: u8 = 1;
const ERROR: u8 = 2;

/// A binary Message Data frame: opcode 0x01, subscription id (u32 LE), receive timestamp (u64 LE,
/// nanoseconds), payload.
pub fn message_data(subscription: u32, timestamp_ns: u64, payload: &[u8]) -> Vec<u8> {
    let mut frame = Vec::with_capacity(13 + payload.len());
    frame.push(0x01);
    frame.extend_from_slice(&subscription.to_le_bytes());
    frame.extend_from_slice(&timestamp_ns.to_le_bytes());
    frame.extend_from_slice(payload);
    frame
}

/// The manager's clock at a cycle in nanoseconds (0 for a clock before 0 or not a number).
pub fn nanos(time_s: f64) -> u64 {
    if time_s.is_finite() && time_s > 0.0 {
        (time_s * 1e9).min(u64::MAX as f64) as u64
    } else {
        0
    }
}

/// A `status` message.
pub fn status(level: u8, message: &str) -> Json {
    json!({"op": "status", "level": level, "message": message})
}

/// The JSON Schema of a value as the link writes it (floats may be `"nan"`, `"inf"`, `"-inf"`).
pub fn value_schema(v: Option<&Value>) -> Json {
    let float = || json!({"anyOf": [{"type": "number"}, {"type": "string", "enum": ["nan", "inf", "-inf"]}]});
    match v {
        None => json!({}),
        Some(Value::Bool(_)) => json!({"type": "boolean"}),
        Some(Value::I64(_)) => json!({"type": "integer"}),
        Some(Value::F64(_)) => float(),
        Some(Value::Str(_)) => json!({"type": "string"}),
        Some(Value::Bytes(_)) => json!({"type": "object", "properties": {"$bytes": {"type": "string"}}}),
        Some(Value::F32s(_) | Value::F64s(_)) => json!({"type": "array", "items": float()}),
        Some(Value::I64s(_)) => json!({"type": "array", "items": {"type": "integer"}}),
        Some(Value::Record(r)) => {
            let properties: serde_json::Map<String, Json> =
                r.fields.iter().map(|(n, v)| (n.to_string(), value_schema(Some(v)))).collect();
            json!({"type": "object", "properties": properties})
        }
    }
}

fn message_schema(title: &str, value: Json) -> String {
    json!({
        "title": title,
        "type": "object",
        "properties": {"cycle": {"type": "integer", "minimum": 0}, "value": value},
        "required": ["cycle", "value"]
    })
    .to_string()
}

/// The `advertise` message: a channel per leaf (id = leaf index + 1), then the events' channel.
fn advertise(history: &History) -> Json {
    let last = history.span().map(|s| s.last_cycle).unwrap_or(0);
    let leaves = &history.layout().leaves;
    let mut channels: Vec<Json> = leaves
        .iter()
        .enumerate()
        .map(|(i, leaf)| {
            let schema = value_schema(history.value_at(i, last).map(|(_, v)| v));
            json!({"id": i + 1, "topic": leaf.path, "encoding": "json", "schemaName": format!("situate.{}", leaf.path),
                "schema": message_schema(&leaf.path, schema), "schemaEncoding": "jsonschema"})
        })
        .collect();
    let event = json!({"type": "object", "properties": {"kind": {"type": "string"}, "text": {"type": "string"}}});
    channels.push(json!({"id": leaves.len() + 1, "topic": EVENTS_TOPIC, "encoding": "json",
        "schemaName": "situate.Event", "schema": message_schema(EVENTS_TOPIC, event), "schemaEncoding": "jsonschema"}));
    for (k, known) in history_schemas(history).channels.iter().enumerate() {
        channels.push(json!({"id": leaves.len() + 2 + k, "topic": known.topic, "encoding": "json",
            "schemaName": known.kind.schema_name(), "schema": known.kind.schema().to_string(), "schemaEncoding": "jsonschema"}));
    }
    json!({"op": "advertise", "channels": channels})
}

/// The frame the robot's pose places `base_link` in: `world` for the ground truth (`truth.pose`),
/// `odom` for odometry (the frame of the start pose).
pub const BASE_FRAME: &str = "base_link";

/// What a channel in one of Foxglove's own schemas carries (its values: the leaves of
/// [`KnownChannel::leaves`], in order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Known {
    /// `foxglove.FrameTransforms`: `parent` → `base_link` from `x`, `y`, `theta`.
    Transform { parent: &'static str },
    /// `foxglove.PoseInFrame`: the pose `x`, `y`, `theta` in `frame`.
    Pose { frame: &'static str },
    /// `foxglove.LaserScan`: the sonar ring in `base_link`, sonar i at i·360°/n counter-clockwise
    /// from ahead.
    Scan,
}

/// A channel in one of Foxglove's schemas, from the leaves of the signals it shows.
#[derive(Debug, Clone, PartialEq)]
pub struct KnownChannel {
    pub topic: &'static str,
    pub kind: Known,
    pub leaves: Vec<usize>,
}

/// The channels in Foxglove's own schemas a robot's signals give (each only when its signals are
/// there): the robot's frame `base_link` (`foxglove/tf`), its pose (`foxglove/truth.pose`,
/// `foxglove/odom`) and the sonar ring as a laser scan (`foxglove/sonar`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Schemas {
    pub channels: Vec<KnownChannel>,
}

impl Schemas {
    /// From the signal leaves' paths (their index is the leaf's).
    pub fn of<'a>(paths: impl Iterator<Item = &'a str>) -> Schemas {
        let paths: Vec<&str> = paths.collect();
        let leaf = |p: &str| paths.iter().position(|q| *q == p);
        let pose = |record: &str| -> Option<Vec<usize>> {
            ["x", "y", "theta"].iter().map(|f| leaf(&format!("{record}.{f}"))).collect()
        };
        let (truth, odom) = (pose("truth.pose"), pose("odom"));
        let mut channels = Vec::new();
        let base = truth.clone().map(|l| (l, "world")).or_else(|| odom.clone().map(|l| (l, "odom")));
        if let Some((leaves, parent)) = base {
            channels.push(KnownChannel { topic: "foxglove/tf", kind: Known::Transform { parent }, leaves });
        }
        if let Some(leaves) = truth {
            channels.push(KnownChannel { topic: "foxglove/truth.pose", kind: Known::Pose { frame: "world" }, leaves });
        }
        if let Some(leaves) = odom {
            channels.push(KnownChannel { topic: "foxglove/odom", kind: Known::Pose { frame: "odom" }, leaves });
        }
        if let Some(l) = leaf("sonar.range") {
            channels.push(KnownChannel { topic: "foxglove/sonar", kind: Known::Scan, leaves: vec![l] });
        }
        Schemas { channels }
    }
}

fn history_schemas(history: &History) -> Schemas {
    Schemas::of(history.layout().leaves.iter().map(|l| l.path.as_str()))
}

/// Foxglove's `time` (`foxglove.Timestamp` in JSON): `{sec, nsec}`.
fn time_schema(description: &str) -> Json {
    json!({"type": "object", "title": "time", "description": description, "properties": {
        "sec": {"type": "integer", "minimum": 0},
        "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999}}})
}

fn vector3_schema(description: &str) -> Json {
    let n = |d: &str| json!({"type": "number", "description": d});
    json!({"title": "foxglove.Vector3", "description": description, "type": "object", "properties": {
        "x": n("x coordinate length"), "y": n("y coordinate length"), "z": n("z coordinate length")}})
}

fn quaternion_schema(description: &str) -> Json {
    let n = |d: &str| json!({"type": "number", "description": d});
    json!({"title": "foxglove.Quaternion", "description": description, "type": "object", "properties": {
        "x": n("x value"), "y": n("y value"), "z": n("z value"), "w": n("w value")}})
}

fn pose_schema(description: &str) -> Json {
    json!({"title": "foxglove.Pose", "description": description, "type": "object", "properties": {
        "position": vector3_schema("Point denoting position in 3D space"),
        "orientation": quaternion_schema("Quaternion denoting orientation in 3D space")}})
}

impl Known {
    /// The schema's name, as Foxglove knows it.
    pub fn schema_name(self) -> &'static str {
        match self {
            Known::Transform { .. } => "foxglove.FrameTransforms",
            Known::Pose { .. } => "foxglove.PoseInFrame",
            Known::Scan => "foxglove.LaserScan",
        }
    }

    /// The JSON Schema Foxglove publishes for it (its fields, types and titles).
    pub fn schema(self) -> Json {
        let string = |d: &str| json!({"type": "string", "description": d});
        let number = |d: &str| json!({"type": "number", "description": d});
        let numbers = |d: &str| json!({"type": "array", "items": {"type": "number"}, "description": d});
        let (description, properties) = match self {
            Known::Transform { .. } => (
                "An array of FrameTransform messages",
                json!({"transforms": {"type": "array", "description": "Array of transforms", "items": {
                    "title": "foxglove.FrameTransform",
                    "description": "A transform between two reference frames in 3D space",
                    "type": "object",
                    "properties": {
                        "timestamp": time_schema("Timestamp of transform"),
                        "parent_frame_id": string("Name of the parent frame"),
                        "child_frame_id": string("Name of the child frame"),
                        "translation": vector3_schema("Translation component of the transform"),
                        "rotation": quaternion_schema("Rotation component of the transform")}}}}),
            ),
            Known::Pose { .. } => (
                "A timestamped pose for an object or reference frame in 3D space",
                json!({
                    "timestamp": time_schema("Timestamp of pose"),
                    "frame_id": string("Frame of reference for pose position and orientation"),
                    "pose": pose_schema("Pose in 3D space")}),
            ),
            Known::Scan => (
                "A single scan from a planar laser range-finder",
                json!({
                    "timestamp": time_schema("Timestamp of scan"),
                    "frame_id": string("Frame of reference"),
                    "pose": pose_schema("Origin of scan relative to frame of reference"),
                    "start_angle": number("Bearing of first point, in radians"),
                    "end_angle": number("Bearing of last point, in radians"),
                    "ranges": numbers("Distance of detections from origin; assumed to be at equally-spaced angles between `start_angle` and `end_angle`"),
                    "intensities": numbers("Intensity of detections")}),
            ),
        };
        json!({"title": self.schema_name(), "description": description, "type": "object", "properties": properties})
    }

    /// The message of `values` (its leaves' values, in order) at `stamp_ns` (Unix nanoseconds).
    pub fn message(self, stamp_ns: u64, values: &[Value]) -> Json {
        let timestamp = json!({"sec": stamp_ns / 1_000_000_000, "nsec": stamp_ns % 1_000_000_000});
        let num = |i: usize| match values.get(i) {
            Some(Value::F64(x)) if x.is_finite() => *x,
            Some(Value::I64(x)) => *x as f64,
            _ => 0.0,
        };
        let (x, y, theta) = (num(0), num(1), num(2));
        // A turn of theta about z.
        let rotation = json!({"x": 0.0, "y": 0.0, "z": (theta / 2.0).sin(), "w": (theta / 2.0).cos()});
        let position = json!({"x": x, "y": y, "z": 0.0});
        match self {
            Known::Transform { parent } => json!({"transforms": [{"timestamp": timestamp,
                "parent_frame_id": parent, "child_frame_id": BASE_FRAME, "translation": position, "rotation": rotation}]}),
            Known::Pose { frame } => {
                json!({"timestamp": timestamp, "frame_id": frame, "pose": {"position": position, "orientation": rotation}})
            }
            Known::Scan => {
                let ranges: Vec<Json> = match values.first() {
                    Some(Value::F32s(r)) => r.iter().map(|v| finite(f64::from(*v))).collect(),
                    Some(Value::F64s(r)) => r.iter().map(|v| finite(*v)).collect(),
                    _ => vec![],
                };
                let step = if ranges.is_empty() { 0.0 } else { std::f64::consts::TAU / ranges.len() as f64 };
                let end = step * ranges.len().saturating_sub(1) as f64;
                json!({"timestamp": timestamp, "frame_id": BASE_FRAME,
                    "pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0}, "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 1.0}},
                    "start_angle": 0.0, "end_angle": end, "ranges": ranges, "intensities": []})
            }
        }
    }
}

/// A number, or null for one JSON cannot hold (NaN, an infinity).
fn finite(v: f64) -> Json {
    if v.is_finite() {
        json!(v)
    } else {
        Json::Null
    }
}

/// The bytes a message takes in a queue.
fn size(m: &Message) -> usize {
    match m {
        Message::Text(t) => t.as_str().len(),
        Message::Binary(b) => b.len(),
        _ => 0,
    }
}

/// One connected client, as the poller sees it.
pub struct Client {
    tx: mpsc::Sender<Message>,
    /// Subscription id → channel id.
    subs: Mutex<HashMap<u32, u32>>,
    /// Messages dropped because its queue was full.
    dropped: AtomicU64,
    /// The bytes of the messages queued.
    queued_bytes: AtomicUsize,
    /// `dropped` when last told to the client, and when.
    reported: Mutex<(u64, Option<Instant>)>,
    param_requests: AtomicUsize,
    /// The parameters it follows.
    params: Mutex<ParamSubs>,
}

/// The parameters a client follows: all of them, or those named.
#[derive(Debug, Default)]
struct ParamSubs {
    all: bool,
    names: HashSet<String>,
}

/// `parameterNames`: an array of strings (missing: none, which means all).
fn parameter_names(msg: &Json) -> Result<Vec<String>, String> {
    match msg.get("parameterNames") {
        None | Some(Json::Null) => Ok(vec![]),
        Some(Json::Array(a)) if a.iter().all(Json::is_string) => {
            Ok(a.iter().filter_map(Json::as_str).map(String::from).collect())
        }
        Some(_) => Err("`parameterNames` must be an array of strings".into()),
    }
}

impl Client {
    fn new(capacity: usize) -> (Arc<Client>, mpsc::Receiver<Message>) {
        let (tx, rx) = mpsc::channel(capacity.max(1));
        let client = Client {
            tx,
            subs: Mutex::new(HashMap::new()),
            dropped: AtomicU64::new(0),
            queued_bytes: AtomicUsize::new(0),
            reported: Mutex::new((0, None)),
            param_requests: AtomicUsize::new(0),
            params: Mutex::new(ParamSubs::default()),
        };
        (Arc::new(client), rx)
    }

    /// Queues a message without waiting, when there is room (in messages and in bytes).
    fn try_queue(&self, m: Message) -> bool {
        let n = size(&m);
        if self.queued_bytes.fetch_add(n, Ordering::SeqCst) + n > QUEUE_BYTES {
            self.queued_bytes.fetch_sub(n, Ordering::SeqCst);
            return false;
        }
        if self.tx.try_send(m).is_err() {
            self.queued_bytes.fetch_sub(n, Ordering::SeqCst);
            return false;
        }
        true
    }

    /// Queues a message without waiting: when the queue is full it is dropped and counted.
    fn offer(&self, m: Message) -> bool {
        let queued = self.try_queue(m);
        if !queued && !self.tx.is_closed() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
        queued
    }

    /// A queued message is being sent: its bytes leave the queue.
    fn taken(&self, m: &Message) {
        self.queued_bytes.fetch_sub(size(m), Ordering::SeqCst);
    }

    fn offer_json(&self, j: &Json) -> bool {
        self.offer(Message::Text(j.to_string().into()))
    }

    /// Messages dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Tells the client of its dropped messages, at most once a second.
    fn report_drops(&self) {
        let dropped = self.dropped();
        let mut r = self.reported.lock().unwrap_or_else(|p| p.into_inner());
        if dropped == r.0 || r.1.is_some_and(|t| t.elapsed() < Duration::from_secs(1)) {
            return;
        }
        let m = format!("{} messages dropped in all: this client reads too slowly for the robot", dropped);
        // Not counted when it finds no room either: it is tried again at the next poll.
        if self.try_queue(Message::Text(status(WARNING, &m).to_string().into())) {
            *r = (dropped, Some(Instant::now()));
        }
    }

    /// Handles `subscribe`: every subscription is checked alone; the refused ones are reported.
    fn subscribe(&self, msg: &Json, channels: u32) -> Vec<String> {
        let mut errors = Vec::new();
        let Some(list) = msg.get("subscriptions").and_then(Json::as_array) else {
            return vec!["subscribe: `subscriptions` must be an array of {id, channelId}".into()];
        };
        let mut subs = self.subs.lock().unwrap_or_else(|p| p.into_inner());
        for s in list {
            let id = s.get("id").and_then(Json::as_u64).and_then(|v| u32::try_from(v).ok());
            let channel = s.get("channelId").and_then(Json::as_u64).and_then(|v| u32::try_from(v).ok());
            let (Some(id), Some(channel)) = (id, channel) else {
                errors.push(format!("subscribe: {s} needs an `id` and a `channelId` (u32)"));
                continue;
            };
            if channel == 0 || channel > channels {
                errors.push(format!("subscribe: no channel {channel}"));
            } else if subs.contains_key(&id) {
                errors.push(format!("subscribe: subscription id {id} is in use"));
            } else if subs.values().any(|c| *c == channel) {
                errors.push(format!("subscribe: channel {channel} is subscribed already"));
            } else if subs.len() >= MAX_SUBSCRIPTIONS {
                errors.push(format!("subscribe: at most {MAX_SUBSCRIPTIONS} subscriptions per client"));
            } else {
                subs.insert(id, channel);
            }
        }
        errors
    }

    /// `subscribeParameterUpdates`: the names given (none: all of them) are added.
    fn subscribe_params(&self, msg: &Json) -> Vec<String> {
        let names = match parameter_names(msg) {
            Ok(n) => n,
            Err(e) => return vec![format!("subscribeParameterUpdates: {e}")],
        };
        let mut p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        if names.is_empty() {
            p.all = true;
            return vec![];
        }
        for n in names {
            if p.names.len() >= MAX_PARAM_NAMES {
                return vec![format!("subscribeParameterUpdates: at most {MAX_PARAM_NAMES} names per client")];
            }
            p.names.insert(n);
        }
        vec![]
    }

    /// `unsubscribeParameterUpdates`: the names given (none: all) are no longer followed; `known`
    /// are every parameter's name (following all, then some are left).
    fn unsubscribe_params(&self, msg: &Json, known: &[String]) -> Vec<String> {
        let names = match parameter_names(msg) {
            Ok(n) => n,
            Err(e) => return vec![format!("unsubscribeParameterUpdates: {e}")],
        };
        let mut p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        if names.is_empty() {
            *p = ParamSubs::default();
            return vec![];
        }
        if p.all {
            p.all = false;
            p.names = known.iter().cloned().collect();
        }
        for n in &names {
            p.names.remove(n);
        }
        vec![]
    }

    /// Whether it follows any parameter.
    fn follows_params(&self) -> bool {
        let p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        p.all || !p.names.is_empty()
    }

    /// The `parameterValues` of the changes it follows, if any.
    fn param_update(&self, changed: &[(&str, &Value)]) -> Option<Json> {
        let p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        let list: Vec<Json> = changed
            .iter()
            .filter(|(n, _)| p.all || p.names.contains(*n))
            .map(|(n, v)| parameter(n.to_string(), v))
            .collect();
        (!list.is_empty()).then(|| json!({"op": "parameterValues", "parameters": list}))
    }

    fn unsubscribe(&self, msg: &Json) -> Vec<String> {
        let Some(list) = msg.get("subscriptionIds").and_then(Json::as_array) else {
            return vec!["unsubscribe: `subscriptionIds` must be an array of numbers".into()];
        };
        let mut subs = self.subs.lock().unwrap_or_else(|p| p.into_inner());
        let mut errors = Vec::new();
        for id in list {
            match id.as_u64().and_then(|v| u32::try_from(v).ok()) {
                Some(id) if subs.remove(&id).is_some() => {}
                _ => errors.push(format!("unsubscribe: no subscription {id}")),
            }
        }
        errors
    }
}

/// The Foxglove clients connected now.
#[derive(Default)]
pub struct Hub {
    clients: Mutex<Vec<Arc<Client>>>,
}

impl Hub {
    /// Admits a client, or `None` when [`MAX_CLIENTS`] are connected.
    fn join(&self, capacity: usize) -> Option<(Arc<Client>, mpsc::Receiver<Message>)> {
        let mut clients = self.clients.lock().unwrap_or_else(|p| p.into_inner());
        if clients.len() >= MAX_CLIENTS {
            return None;
        }
        let (client, rx) = Client::new(capacity);
        clients.push(Arc::clone(&client));
        Some((client, rx))
    }

    fn leave(&self, client: &Arc<Client>) {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).retain(|c| !Arc::ptr_eq(c, client));
    }

    /// How many Foxglove clients are connected.
    pub fn len(&self) -> usize {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn snapshot(&self) -> Vec<Arc<Client>> {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}

/// Where the poller is: the last cycle sent, and how many marks of the last mark cycle were sent
/// (events may reach the history after their cycle's frame).
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct Cursor {
    pub cycle: u64,
    pub mark_cycle: u64,
    pub marks_at: usize,
}

/// A message taken from the history, encoded once the history's lock is released (values are
/// shared, so taking them is cheap).
enum Pending {
    Value {
        channel: u32,
        cycle: u64,
        time_s: f64,
        value: Value,
    },
    Mark {
        channel: u32,
        cycle: u64,
        time_s: f64,
        kind: &'static str,
        text: String,
    },
    /// A message in one of Foxglove's schemas ([`Schemas`]), of the values of one cycle.
    Known {
        channel: u32,
        time_s: f64,
        kind: Known,
        values: Vec<Value>,
    },
}

impl Pending {
    /// The channel, the timestamp (`epoch_ns` + the manager's clock, Unix nanoseconds) and the
    /// JSON payload.
    fn encode(self, epoch_ns: u64) -> (u32, u64, Bytes) {
        let stamp = |time_s: f64| epoch_ns.saturating_add(nanos(time_s));
        let (channel, time_s, body) = match self {
            Pending::Value { channel, cycle, time_s, value } => {
                (channel, time_s, json!({"cycle": cycle, "value": wire::value_to_json(&value)}))
            }
            Pending::Mark { channel, cycle, time_s, kind, text } => {
                (channel, time_s, json!({"cycle": cycle, "value": {"kind": kind, "text": text}}))
            }
            Pending::Known { channel, time_s, kind, values } => (channel, time_s, kind.message(stamp(time_s), &values)),
        };
        (channel, stamp(time_s), Bytes::from(body.to_string()))
    }
}

/// Takes from the history what is new since `cursor` on the channels wanted, and moves the
/// cursor past it (past everything held, wanted or not).
fn collect(history: &History, cursor: &mut Cursor, wanted: &[u32]) -> Vec<Pending> {
    let Some(span) = history.span() else { return Vec::new() };
    let leaves = history.layout().leaves.len() as u32;
    let events = leaves + 1;
    let time_of = |cycle| history.time_s_of(cycle).unwrap_or(span.last_time_s);
    let mut out = Vec::new();
    for &channel in wanted {
        if channel == 0 || channel > leaves {
            continue;
        }
        for (cycle, v) in history.values_after(channel as usize - 1, cursor.cycle) {
            out.push(Pending::Value { channel, cycle, time_s: time_of(cycle), value: v.clone() });
        }
    }
    for (k, known) in history_schemas(history).channels.iter().enumerate() {
        let channel = events + 1 + k as u32;
        if !wanted.contains(&channel) {
            continue;
        }
        // The cycles any of its leaves was written in, each sent once with the values then.
        let mut cycles: Vec<u64> =
            known.leaves.iter().flat_map(|&l| history.values_after(l, cursor.cycle).map(|(c, _)| c)).collect();
        cycles.sort_unstable();
        cycles.dedup();
        for cycle in cycles {
            let values: Option<Vec<Value>> =
                known.leaves.iter().map(|&l| history.value_at(l, cycle).map(|(_, v)| v.clone())).collect();
            if let Some(values) = values {
                out.push(Pending::Known { channel, time_s: time_of(cycle), kind: known.kind, values });
            }
        }
    }
    // Marks: those after the last mark cycle sent, and the late ones at it.
    let mut seen_at = 0;
    let (mut mark_cycle, mut marks_at) = (cursor.mark_cycle, cursor.marks_at);
    for m in history.marks() {
        if m.cycle < cursor.mark_cycle {
            continue;
        }
        if m.cycle == cursor.mark_cycle {
            seen_at += 1;
            if seen_at <= cursor.marks_at {
                continue;
            }
        }
        if wanted.contains(&events) {
            let (kind, text) = (m.kind, m.text.clone());
            out.push(Pending::Mark { channel: events, cycle: m.cycle, time_s: time_of(m.cycle), kind, text });
        }
        if m.cycle == mark_cycle {
            marks_at += 1;
        } else {
            (mark_cycle, marks_at) = (m.cycle, 1);
        }
    }
    cursor.cycle = cursor.cycle.max(span.last_cycle);
    (cursor.mark_cycle, cursor.marks_at) = (mark_cycle, marks_at);
    out
}

/// Sends what was collected to every client subscribed to its channel (never waiting).
fn deliver(clients: &[Arc<Client>], out: &[(u32, u64, Bytes)]) {
    for client in clients {
        let subs: Vec<(u32, u32)> =
            client.subs.lock().unwrap_or_else(|p| p.into_inner()).iter().map(|(s, c)| (*s, *c)).collect();
        if subs.is_empty() {
            continue;
        }
        for (channel, ts, payload) in out {
            for (sub, _) in subs.iter().filter(|(_, c)| c == channel) {
                client.offer(Message::Binary(message_data(*sub, *ts, payload).into()));
            }
        }
        client.report_drops();
    }
}

/// The poller: every [`POLL`], sends the history's new cycles to the subscribed clients, until
/// `stop`. With no client it only moves its cursor (a new subscriber gets what comes next).
pub(crate) fn publish(shared: &Shared, stop: &AtomicBool) {
    let Some(history) = shared.history.as_ref() else { return };
    let epoch_ns = run_epoch_ns(shared);
    let mut cursor = Cursor::default();
    let mut first = true;
    // Every parameter's value at the last poll, while a client follows any.
    let mut params: Option<Vec<(String, Value)>> = None;
    while !stop.load(Ordering::SeqCst) {
        let clients = shared.foxglove.snapshot();
        let mut wanted: Vec<u32> = clients
            .iter()
            .flat_map(|c| c.subs.lock().unwrap_or_else(|p| p.into_inner()).values().copied().collect::<Vec<_>>())
            .collect();
        wanted.sort_unstable();
        wanted.dedup();
        if first {
            // What the history held before the server started is the past, not live.
            wanted.clear();
            first = false;
        }
        let pending = {
            let h = history.lock().unwrap_or_else(|p| p.into_inner());
            collect(&h, &mut cursor, &wanted)
        };
        let out: Vec<(u32, u64, Bytes)> = pending.into_iter().map(|p| p.encode(epoch_ns)).collect();
        if !out.is_empty() || !clients.is_empty() {
            deliver(&clients, &out);
        }
        if clients.iter().any(|c| c.follows_params()) {
            let now = parameter_values(&history.lock().unwrap_or_else(|p| p.into_inner()));
            if let Some(before) = &params {
                let changed: Vec<(&str, &Value)> =
                    now.iter().zip(before).filter(|(a, b)| a.1 != b.1).map(|(a, _)| (a.0.as_str(), &a.1)).collect();
                if !changed.is_empty() {
                    for c in &clients {
                        if let Some(m) = c.param_update(&changed) {
                            c.offer_json(&m);
                        }
                    }
                }
            }
            params = Some(now);
        } else {
            params = None;
        }
        std::thread::sleep(POLL);
    }
}

/// The run's start on the wall clock (Unix nanoseconds): when the manager's clock read 0, taken as
/// the wall-clock time now less the manager's clock now (the server starts with the robot, so on
/// the simulated clock too this is about when the run began). Foxglove's timestamps are this plus
/// the manager's clock at the cycle: the run's own time, on the calendar (not 1970).
fn run_epoch_ns(shared: &Shared) -> u64 {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap_or_default();
    let now = u64::try_from(now.as_nanos()).unwrap_or(u64::MAX);
    match ask(&shared.handle, Request::QueryStats) {
        Ok(Reply::Stats(s)) => now.saturating_sub(nanos(s.time_s)),
        _ => nanos(shared.run.started_unix_s),
    }
}

/// Every parameter (`skill.param`) and its latest value as the history holds it (changes come
/// with the manager's events).
fn parameter_values(history: &History) -> Vec<(String, Value)> {
    let mut out = Vec::new();
    for (i, skill) in history.layout().skills.iter().enumerate() {
        for (j, (name, _)) in skill.params.iter().enumerate() {
            if let Some(v) = history.param_at(i, j, u64::MAX) {
                out.push((format!("{}.{}", skill.name, name), v.clone()));
            }
        }
    }
    out
}

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

fn server_info(shared: &Shared) -> Json {
    json!({"op": "serverInfo", "name": "situate", "capabilities": ["parameters", "parametersSubscribe"], "supportedEncodings": ["json"],
        "metadata": {"robot_run": shared.run.id}, "sessionId": shared.run.id})
}

/// A client's place in the hub, given back however its session ends.
struct Member<'a> {
    hub: &'a Hub,
    client: Arc<Client>,
}

impl Drop for Member<'_> {
    fn drop(&mut self) {
        self.hub.leave(&self.client);
    }
}

async fn session(shared: Arc<Shared>, mut socket: WebSocket) {
    let Some(history) = shared.history.as_ref() else { return };
    let (advertised, channel_count, known) = {
        let h = history.lock().unwrap_or_else(|p| p.into_inner());
        let known: Vec<String> = parameter_values(&h).into_iter().map(|(n, _)| n).collect();
        let count = h.layout().leaves.len() + 1 + history_schemas(&h).channels.len();
        (advertise(&h), count as u32, known)
    };
    let Some((client, mut rx)) = shared.foxglove.join(QUEUE) else {
        let m = status(ERROR, &format!("too many Foxglove clients (at most {MAX_CLIENTS})"));
        let keepalive = Keepalive::new(shared.ws_idle);
        let _ = keepalive.send(&mut socket, Message::Text(m.to_string().into())).await;
        keepalive.close(&mut socket).await;
        return;
    };
    let _member = Member { hub: &shared.foxglove, client: Arc::clone(&client) };
    let mut shutdown = shared.shutdown.clone();
    let mut keepalive = Keepalive::new(shared.ws_idle);
    tracing::debug!("Foxglove client connected");
    for m in [server_info(&shared), advertised] {
        if !keepalive.send(&mut socket, Message::Text(m.to_string().into())).await {
            return;
        }
    }
    loop {
        tokio::select! {
            _ = async { shutdown.wait_for(|s| *s).await.map(|_| ()) } => {
                keepalive.close(&mut socket).await;
                break;
            }
            beat = keepalive.beat() => match beat {
                Beat::Ping => {
                    if !keepalive.send(&mut socket, Message::Ping(Default::default())).await {
                        break;
                    }
                }
                Beat::Dead => {
                    tracing::debug!("Foxglove client silent for the idle timeout: closing");
                    keepalive.close(&mut socket).await;
                    break;
                }
            },
            incoming = socket.recv() => {
                if let Some(Ok(_)) = &incoming {
                    keepalive.heard();
                }
                match incoming {
                    Some(Ok(Message::Text(text))) => {
                        handle_text(&shared, &client, text.as_str(), channel_count, &known)
                    }
                    Some(Ok(Message::Binary(_))) => {
                        client.offer_json(&status(ERROR, "this server takes no client messages in binary (no clientPublish)"));
                    }
                    Some(Ok(Message::Close(_))) | Some(Err(_)) | None => break,
                    Some(Ok(_)) => {}
                }
            }
            Some(m) = rx.recv() => {
                client.taken(&m);
                if !keepalive.send(&mut socket, m).await {
                    break;
                }
            }
        }
    }
    tracing::debug!(dropped = client.dropped(), "Foxglove client disconnected");
}

/// One client text message: `subscribe`, `unsubscribe`, `getParameters`, `setParameters`,
/// `subscribeParameterUpdates`, `unsubscribeParameterUpdates`.
/// Anything else is answered by a `status` error.
fn handle_text(shared: &Arc<Shared>, client: &Arc<Client>, text: &str, channels: u32, known: &[String]) {
    let msg: Json = match serde_json::from_str(text) {
        Ok(j @ Json::Object(_)) => j,
        Ok(_) => {
            client.offer_json(&status(ERROR, "a client message must be a JSON object with an `op`"));
            return;
        }
        Err(e) => {
            client.offer_json(&status(ERROR, &format!("the message is not JSON: {e}")));
            return;
        }
    };
    let op = msg.get("op").and_then(Json::as_str).unwrap_or("");
    let errors = match op {
        "subscribe" => client.subscribe(&msg, channels),
        "unsubscribe" => client.unsubscribe(&msg),
        "subscribeParameterUpdates" => client.subscribe_params(&msg),
        "unsubscribeParameterUpdates" => client.unsubscribe_params(&msg, known),
        "getParameters" | "setParameters" => {
            if client.param_requests.fetch_add(1, Ordering::SeqCst) >= MAX_PARAM_REQUESTS {
                client.param_requests.fetch_sub(1, Ordering::SeqCst);
                vec![format!("{op}: too many parameter requests waiting (at most {MAX_PARAM_REQUESTS})")]
            } else {
                let (shared, client) = (Arc::clone(shared), Arc::clone(client));
                tokio::task::spawn_blocking(move || {
                    for m in parameters(&shared, &msg) {
                        client.offer_json(&m);
                    }
                    client.param_requests.fetch_sub(1, Ordering::SeqCst);
                });
                vec![]
            }
        }
        "" => vec!["a client message needs an `op` (a string)".into()],
        other => vec![format!("unsupported op `{other}`")],
    };
    for e in errors {
        client.offer_json(&status(ERROR, &e));
    }
}

/// A parameter value for Foxglove, with its `type` when it is a float (so `2.0` stays a float).
fn parameter(name: String, v: &Value) -> Json {
    let mut p = json!({"name": name, "value": wire::value_to_json(v)});
    match v {
        Value::F64(x) if x.is_finite() => p["type"] = json!("float64"),
        Value::F64s(a) if a.iter().all(|x| x.is_finite()) => p["type"] = json!("float64_array"),
        _ => {}
    }
    p
}

/// Every parameter as `skill.param` with its Foxglove form, or why the manager did not answer.
fn all_parameters(shared: &Shared) -> Result<Vec<(String, Json)>, String> {
    match ask(&shared.handle, Request::QuerySkills) {
        Ok(Reply::Skills(skills)) => Ok(skills
            .iter()
            .flat_map(|s| s.params.iter().map(move |(spec, v)| (format!("{}.{}", s.name, spec.name), v)))
            .map(|(name, v)| (name.clone(), parameter(name, v)))
            .collect()),
        Ok(other) => Err(format!("unexpected reply {other:?}")),
        Err(e) => Err(e.to_string()),
    }
}

/// Answers `getParameters` and `setParameters` (blocking: asks the manager). Returns the messages
/// to send: `status` errors for what was refused, then `parameterValues` when an answer is due.
fn parameters(shared: &Shared, msg: &Json) -> Vec<Json> {
    let op = msg.get("op").and_then(Json::as_str).unwrap_or("");
    let id = msg.get("id").cloned().filter(|i| !i.is_null());
    let mut out = Vec::new();
    let names: Vec<String> = if op == "getParameters" {
        match parameter_names(msg) {
            Ok(n) => n,
            Err(e) => return vec![status(ERROR, &format!("getParameters: {e}"))],
        }
    } else {
        let Some(list) = msg.get("parameters").and_then(Json::as_array) else {
            return vec![status(ERROR, "setParameters: `parameters` must be an array of {name, value}")];
        };
        let mut set = Vec::new();
        for p in list {
            let Some(name) = p.get("name").and_then(Json::as_str) else {
                out.push(status(ERROR, &format!("setParameters: {p} has no `name`")));
                continue;
            };
            if let Err(e) = set_parameter(shared, name, p.get("value")) {
                out.push(status(ERROR, &format!("setParameters: {name}: {e}")));
            }
            set.push(name.to_string());
        }
        if id.is_none() {
            return out;
        }
        set
    };
    match all_parameters(shared) {
        Ok(all) => {
            let values: Vec<Json> = if names.is_empty() {
                all.into_iter().map(|(_, p)| p).collect()
            } else {
                let by_name: HashMap<String, Json> = all.into_iter().collect();
                names.iter().filter_map(|n| by_name.get(n).cloned()).collect()
            };
            let mut reply = json!({"op": "parameterValues", "parameters": values});
            if let Some(id) = id {
                reply["id"] = id;
            }
            out.push(reply);
        }
        Err(e) => out.push(status(ERROR, &format!("{op}: the skill manager did not answer: {e}"))),
    }
    out
}

/// Sets `skill.param` through the manager, as the link's `set_param` would.
fn set_parameter(shared: &Shared, name: &str, value: Option<&Json>) -> Result<(), String> {
    let Some((skill, param)) = name.split_once('.') else {
        return Err("a parameter is named `skill.param`".into());
    };
    let Some(value) = value.filter(|v| !v.is_null()) else {
        return Err("a parameter cannot be unset".into());
    };
    let args = json!({"skill": skill, "param": param, "value": value}).to_string();
    let request = match wire::decode_request("set_param", args.as_bytes()) {
        Ok(wire::Decoded::Manager(r)) => r,
        Ok(_) => return Err("not a parameter change".into()),
        Err(e) => return Err(e.message),
    };
    ask(&shared.handle, request).map(|_| ()).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::history::{Layout, LeafLayout};
    use situate_manager::{Event, Frame};

    fn history() -> History {
        let leaves =
            ["odom.x", "sonar.range"].iter().map(|p| LeafLayout { path: p.to_string(), writers: vec![] }).collect();
        History::new(Layout { leaves, skills: vec![] }, 100, 0)
    }

    fn frame(cycle: u64, values: Vec<(usize, Value)>) -> Frame {
        Frame { cycle, time_s: cycle as f64 * 0.05, values: values.into(), prints: vec![], winners: vec![] }
    }

    #[test]
    fn a_message_data_frame_is_opcode_subscription_timestamp_payload_little_endian() {
        let f = message_data(0x0102_0304, 0x1122_3344_5566_7788, b"{\"cycle\":3}");
        assert_eq!(f[0], 0x01);
        assert_eq!(&f[1..5], &[0x04, 0x03, 0x02, 0x01]);
        assert_eq!(&f[5..13], &[0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11]);
        assert_eq!(&f[13..], b"{\"cycle\":3}");
        assert_eq!(nanos(1.5), 1_500_000_000);
        assert_eq!(nanos(-1.0), 0);
        assert_eq!(nanos(f64::NAN), 0);
    }

    #[test]
    fn the_poller_sends_every_cycle_past_the_last_sent_once() {
        let mut h = history();
        let mut cursor = Cursor::default();
        for c in 1..=3 {
            h.push_frame(frame(c, vec![(0, Value::F64(c as f64)), (1, Value::F64(0.5))]));
        }
        let out: Vec<_> = collect(&h, &mut cursor, &[1]).into_iter().map(|p| p.encode(0)).collect();
        let cycles: Vec<Json> = out
            .iter()
            .map(|(ch, _, p)| {
                assert_eq!(*ch, 1);
                serde_json::from_slice::<Json>(p).expect("JSON")
            })
            .collect();
        assert_eq!(
            cycles,
            vec![
                json!({"cycle": 1, "value": 1.0}),
                json!({"cycle": 2, "value": 2.0}),
                json!({"cycle": 3, "value": 3.0})
            ]
        );
        assert_eq!(out[2].1, 150_000_000, "the manager's clock at cycle 3");
        assert!(collect(&h, &mut cursor, &[1]).is_empty(), "nothing new");
        h.push_frame(frame(4, vec![(0, Value::F64(4.0))]));
        h.push_event(&Event::ManagerStopped { cycle: 4 });
        let out: Vec<_> = collect(&h, &mut cursor, &[1, 2, 3]).into_iter().map(|p| p.encode(0)).collect();
        let topics: Vec<u32> = out.iter().map(|(c, _, _)| *c).collect();
        assert_eq!(topics, vec![1, 3], "x at cycle 4 and the event (sonar.range was not written): {out:?}");
        let event: Json = serde_json::from_slice(&out[1].2).expect("JSON");
        assert_eq!(event["cycle"], 4);
        assert!(event["value"]["kind"].is_string(), "{event}");
        // An event of a cycle already sent, arriving late, is still sent once.
        h.push_event(&Event::ManagerStopped { cycle: 4 });
        assert_eq!(collect(&h, &mut cursor, &[3]).len(), 1);
        assert!(collect(&h, &mut cursor, &[3]).is_empty());
    }

    #[test]
    fn clients_subscriptions_and_queues_are_bounded() {
        let hub = Hub::default();
        let mut joined: Vec<_> = (0..MAX_CLIENTS).map(|_| hub.join(4).expect("admitted")).collect();
        assert!(hub.join(4).is_none(), "no more than MAX_CLIENTS");
        let (client, mut rx) = joined.remove(0);
        hub.leave(&client);
        assert_eq!(hub.len(), MAX_CLIENTS - 1);
        assert!(hub.join(4).is_some(), "a place freed");
        // Subscriptions: bad ones are refused one by one.
        let errors = client.subscribe(&json!({"subscriptions": [{"id": 1, "channelId": 1}, {"id": 1, "channelId": 2},
            {"id": 2, "channelId": 1}, {"id": 3, "channelId": 99}, {"id": -1, "channelId": 1}, {"id": 4, "channelId": 2}]}), 3);
        assert_eq!(errors.len(), 4, "{errors:?}");
        assert!(errors[0].contains("id 1 is in use"), "{errors:?}");
        assert!(errors[1].contains("subscribed already"), "{errors:?}");
        assert!(errors[2].contains("no channel 99"), "{errors:?}");
        assert_eq!(client.subscribe(&json!({"subscriptions": 3}), 3).len(), 1);
        let _ = client.unsubscribe(&json!({"subscriptionIds": [4]}));
        let many: Vec<Json> = (10..10 + MAX_SUBSCRIPTIONS as u32).map(|i| json!({"id": i, "channelId": i})).collect();
        let errors = client.subscribe(&json!({"subscriptions": many}), u32::MAX);
        assert_eq!(errors.len(), 1, "one held already, so the last is one too many: {errors:?}");
        assert!(errors[0].contains(&format!("at most {MAX_SUBSCRIPTIONS}")), "{errors:?}");
        client.subs.lock().expect("lock").retain(|id, _| *id == 1);
        assert_eq!(client.unsubscribe(&json!({"subscriptionIds": [1, 77]})).len(), 1, "77 was never subscribed");
        // A full queue drops and counts, without waiting.
        let out: Vec<(u32, u64, Bytes)> = (0..10).map(|i| (2, i, Bytes::from_static(b"{}"))).collect();
        client.subs.lock().expect("lock").insert(5, 2);
        deliver(&[Arc::clone(&client)], &out);
        assert_eq!(client.dropped(), 6, "4 queued, 6 dropped");
        let mut frames = Vec::new();
        while let Ok(m) = rx.try_recv() {
            client.taken(&m);
            frames.push(m);
        }
        assert_eq!(frames.len(), 4);
        match &frames[0] {
            Message::Binary(b) => assert_eq!(&b[..], &message_data(5, 0, b"{}")[..]),
            other => panic!("a binary frame, got {other:?}"),
        }
        assert_eq!(client.queued_bytes.load(Ordering::SeqCst), 0, "all taken");
        frames.iter().for_each(|m| assert!(size(m) > 0));
        // The bytes are bounded too: one message of more than half the budget leaves no room for a second.
        let big = Bytes::from(vec![b'x'; QUEUE_BYTES / 2 + 1]);
        let before = client.dropped();
        deliver(&[Arc::clone(&client)], &[(2, 0, big.clone()), (2, 1, big)]);
        assert_eq!(client.dropped(), before + 1, "the second big message is dropped");
        let m = rx.try_recv().expect("the first is queued");
        client.taken(&m);
        // Room again: the client is told of its losses.
        client.report_drops();
        match rx.try_recv() {
            Ok(Message::Text(t)) => {
                let s: Json = serde_json::from_str(t.as_str()).expect("JSON");
                assert_eq!(s["op"], "status");
                assert_eq!(s["level"], WARNING);
                assert!(s["message"].as_str().unwrap_or("").starts_with("7 messages dropped"), "{s}");
            }
            other => panic!("a status, got {other:?}"),
        }
    }

    #[test]
    fn a_client_follows_the_parameters_it_names_or_all() {
        let (client, _rx) = Client::new(4);
        let (r, p) = ("circle.radius", "circle.period_s");
        let (v, w) = (Value::F64(3.0), Value::F64(9.0));
        let changed = [(r, &v), (p, &w)];
        assert!(!client.follows_params());
        assert_eq!(client.param_update(&changed), None);
        assert!(client.subscribe_params(&json!({"parameterNames": [r]})).is_empty());
        let m = client.param_update(&changed).expect("an update");
        assert_eq!(m["op"], "parameterValues");
        assert_eq!(m["parameters"], json!([{"name": r, "value": 3.0, "type": "float64"}]));
        assert!(client.subscribe_params(&json!({"parameterNames": []})).is_empty(), "all");
        assert_eq!(client.param_update(&changed).expect("an update")["parameters"].as_array().map(Vec::len), Some(2));
        let known = [r.to_string(), p.to_string()];
        assert!(client.unsubscribe_params(&json!({"parameterNames": [r]}), &known).is_empty());
        assert_eq!(client.param_update(&changed).expect("an update")["parameters"][0]["name"], p);
        assert!(client.unsubscribe_params(&json!({}), &known).is_empty());
        assert!(!client.follows_params());
        assert_eq!(client.subscribe_params(&json!({"parameterNames": "x"})).len(), 1, "a bad list is an error");
    }

    /// The head of the server's answer to an upgrade request to `/foxglove`.
    fn upgrade_head(addr: std::net::SocketAddr, extra: &str) -> String {
        use std::io::{Read, Write};
        let mut s = std::net::TcpStream::connect(addr).expect("connect");
        s.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
        let request = format!(
            "GET /foxglove HTTP/1.1\r\nHost: {addr}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
             Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{extra}\r\n"
        );
        s.write_all(request.as_bytes()).expect("write");
        let (mut buf, mut chunk) = (Vec::new(), [0u8; 4096]);
        while !String::from_utf8_lossy(&buf).contains("\r\n\r\n") {
            match s.read(&mut chunk) {
                Ok(0) | Err(_) => break,
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
            }
        }
        String::from_utf8_lossy(&buf).to_ascii_lowercase()
    }

    #[test]
    fn the_route_selects_the_subprotocol_refuses_other_sites_and_needs_a_history() {
        use situate::manager::{Control, Manager, RobotSpec, SkillSpec};
        let spec = RobotSpec::new("foxtest").skill(SkillSpec::new("sonar", "toy.sonar"));
        let mut manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
        let tap = crate::HistoryTap::new(&mut manager);
        let (mut handle, join) = manager.spawn(true);
        let gui = crate::serve_with_history(handle.clone(), crate::GuiConfig::default(), Some(tap)).expect("serve");
        let ok = upgrade_head(gui.local_addr(), "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n");
        assert!(ok.starts_with("http/1.1 101"), "{ok}");
        assert!(ok.contains("sec-websocket-protocol: foxglove.websocket.v1"), "{ok}");
        let foxglove_app = upgrade_head(gui.local_addr(), "Origin: https://app.foxglove.dev\r\n");
        assert!(foxglove_app.starts_with("http/1.1 101"), "{foxglove_app}");
        let evil = upgrade_head(gui.local_addr(), "Origin: https://evil.example\r\n");
        assert!(evil.starts_with("http/1.1 403"), "{evil}");
        gui.stop();
        let plain = crate::serve(handle.clone(), crate::GuiConfig::default()).expect("serve");
        let none = upgrade_head(plain.local_addr(), "");
        assert!(none.starts_with("http/1.1 503"), "no history, no Foxglove: {none}");
        plain.stop();
        let _ = handle.request(Request::Shutdown);
        let _ = join.join();
    }

    #[test]
    fn only_foxglove_this_server_or_no_origin_may_connect() {
        let headers = |origin: Option<&str>| {
            let mut h = HeaderMap::new();
            h.insert(header::HOST, "127.0.0.1:8080".parse().expect("header"));
            if let Some(o) = origin {
                h.insert(header::ORIGIN, o.parse().expect("header"));
            }
            h
        };
        assert!(origin_allowed(&headers(None)), "the desktop app sends no origin");
        assert!(origin_allowed(&headers(Some("https://app.foxglove.dev"))));
        assert!(origin_allowed(&headers(Some("http://127.0.0.1:8080"))));
        assert!(!origin_allowed(&headers(Some("https://evil.example"))));
        assert!(!origin_allowed(&headers(Some("https://app.foxglove.dev.evil.example"))));
    }

    #[test]
    fn the_advertisement_names_every_leaf_and_the_events_with_json_schemas() {
        let mut h = history();
        h.push_frame(frame(1, vec![(0, Value::F64(1.0))]));
        let a = advertise(&h);
        let channels = a["channels"].as_array().expect("channels");
        assert_eq!(channels.len(), 4);
        assert_eq!(channels[0]["topic"], "odom.x");
        assert_eq!(channels[0]["id"], 1);
        assert_eq!(channels[2]["topic"], EVENTS_TOPIC);
        assert_eq!(channels[3]["topic"], "foxglove/sonar", "sonar.range as a laser scan too");
        for c in &channels[..3] {
            assert_eq!(c["encoding"], "json");
            assert_eq!(c["schemaEncoding"], "jsonschema");
            let schema: Json = serde_json::from_str(c["schema"].as_str().expect("a string")).expect("JSON");
            assert_eq!(schema["required"], json!(["cycle", "value"]));
        }
        let x: Json = serde_json::from_str(channels[0]["schema"].as_str().unwrap_or("")).expect("JSON");
        assert_eq!(x["properties"]["value"]["anyOf"][0]["type"], "number");
        assert_eq!(value_schema(Some(&Value::I64s(vec![1].into())))["items"]["type"], "integer");
    }

    #[test]
    fn the_robot_frame_pose_and_sonar_are_published_in_foxgloves_schemas() {
        let paths = [
            "truth.pose.x",
            "truth.pose.y",
            "truth.pose.theta",
            "truth.pose.floor",
            "sonar.range",
            "odom.x",
            "odom.y",
            "odom.theta",
        ];
        let leaves = paths.iter().map(|p| LeafLayout { path: p.to_string(), writers: vec![] }).collect();
        let mut h = History::new(Layout { leaves, skills: vec![] }, 100, 0);
        let known = history_schemas(&h);
        let topics: Vec<_> = known.channels.iter().map(|c| (c.topic, c.kind.schema_name())).collect();
        assert_eq!(
            topics,
            vec![
                ("foxglove/tf", "foxglove.FrameTransforms"),
                ("foxglove/truth.pose", "foxglove.PoseInFrame"),
                ("foxglove/odom", "foxglove.PoseInFrame"),
                ("foxglove/sonar", "foxglove.LaserScan")
            ]
        );
        assert_eq!(known.channels[0].kind, Known::Transform { parent: "world" }, "the ground truth places the robot");
        let odom_only = Schemas::of(["odom.x", "odom.y", "odom.theta"].into_iter());
        assert_eq!(odom_only.channels[0].kind, Known::Transform { parent: "odom" });
        assert!(Schemas::of(["odom.x", "odom.y"].into_iter()).channels.is_empty(), "no theta, no pose");
        // The advertisement: the leaves, the events, then these, with Foxglove's schemas.
        let a = advertise(&h);
        let channels = a["channels"].as_array().expect("channels");
        assert_eq!(channels.len(), paths.len() + 1 + 4);
        let scan = &channels[paths.len() + 4];
        assert_eq!(
            (scan["topic"].as_str(), scan["id"].as_u64()),
            (Some("foxglove/sonar"), Some(paths.len() as u64 + 5))
        );
        assert_eq!(scan["schemaEncoding"], "jsonschema");
        let schema: Json = serde_json::from_str(scan["schema"].as_str().unwrap_or("")).expect("JSON");
        assert_eq!(schema["title"], "foxglove.LaserScan");
        assert_eq!(schema["properties"]["timestamp"]["properties"]["nsec"]["maximum"], 999_999_999);
        let tf: Json = serde_json::from_str(channels[paths.len() + 1]["schema"].as_str().unwrap_or("")).expect("JSON");
        assert_eq!(tf["properties"]["transforms"]["items"]["properties"]["child_frame_id"]["type"], "string");
        // Messages: one per cycle a pose leaf was written in, with the values of that cycle.
        let ring: Vec<f32> = (0..24).map(|i| 1.0 + i as f32 / 10.0).collect();
        h.push_frame(frame(
            1,
            vec![
                (0, Value::F64(2.0)),
                (1, Value::F64(3.0)),
                (2, Value::F64(std::f64::consts::FRAC_PI_2)),
                (4, Value::F32s(ring.into())),
            ],
        ));
        h.push_frame(frame(2, vec![(2, Value::F64(0.0))]));
        let base = paths.len() as u32 + 2;
        let mut cursor = Cursor::default();
        let epoch = 1_700_000_000_000_000_000;
        let out: Vec<_> =
            collect(&h, &mut cursor, &[base, base + 1, base + 3]).into_iter().map(|p| p.encode(epoch)).collect();
        let ids: Vec<u32> = out.iter().map(|o| o.0).collect();
        assert_eq!(ids, vec![base, base, base + 1, base + 1, base + 3], "tf and pose at cycles 1 and 2, the scan at 1");
        let msg = |k: usize| serde_json::from_slice::<Json>(&out[k].2).expect("JSON");
        let tf1 = msg(0);
        let t = &tf1["transforms"][0];
        assert_eq!((t["parent_frame_id"].as_str(), t["child_frame_id"].as_str()), (Some("world"), Some(BASE_FRAME)));
        assert_eq!((t["translation"]["x"].as_f64(), t["translation"]["y"].as_f64()), (Some(2.0), Some(3.0)));
        let half = (std::f64::consts::FRAC_PI_4).sin();
        assert!((t["rotation"]["z"].as_f64().unwrap_or(0.0) - half).abs() < 1e-12, "{t}");
        assert_eq!(
            out[0].1, 1_700_000_000_050_000_000,
            "the run's start on the wall clock + the manager's clock at cycle 1"
        );
        assert_eq!(t["timestamp"], json!({"sec": 1_700_000_000u64, "nsec": 50_000_000}));
        let pose2 = msg(3);
        assert_eq!(pose2["frame_id"], "world");
        assert_eq!(pose2["pose"]["position"]["x"], 2.0, "x at cycle 2 is the one of cycle 1 (written then)");
        assert_eq!(pose2["pose"]["orientation"]["w"], 1.0, "theta 0 at cycle 2");
        let scan = msg(4);
        assert_eq!(scan["frame_id"], BASE_FRAME);
        assert_eq!(scan["ranges"].as_array().map(Vec::len), Some(24));
        assert_eq!(scan["start_angle"], 0.0);
        assert!((scan["end_angle"].as_f64().unwrap_or(0.0) - 23.0 * 15f64.to_radians()).abs() < 1e-12, "{scan}");
        assert!((scan["ranges"][3].as_f64().unwrap_or(0.0) - 1.3).abs() < 1e-6);
    }
}
