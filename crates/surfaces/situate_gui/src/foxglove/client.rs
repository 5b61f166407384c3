//! One connected Foxglove client as the poller and its session see it (its subscriptions, its
//! bounded send queue, the parameters it follows), and the hub of those connected.

use std::collections::{HashMap, HashSet};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use axum::extract::ws::Message;
use serde_json::{json, Value as Json};
use situate_core::Value;
use tokio::sync::mpsc;

use super::params::{parameter, parameter_names};
use super::protocol::{status, WARNING};
use super::{MAX_CLIENTS, MAX_PARAM_NAMES, MAX_SUBSCRIPTIONS, QUEUE_BYTES};

/// The bytes a message takes in a queue.
pub(super) fn size(m: &Message) -> usize {
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
    pub(super) subs: Mutex<HashMap<u32, u32>>,
    /// Messages dropped because its queue was full.
    dropped: AtomicU64,
    /// The bytes of the messages queued.
    pub(super) queued_bytes: AtomicUsize,
    /// `dropped` when last told to the client, and when.
    reported: Mutex<(u64, Option<Instant>)>,
    pub(super) param_requests: AtomicUsize,
    /// The parameters it follows.
    params: Mutex<ParamSubs>,
}

/// The parameters a client follows: all of them, or those named.
#[derive(Debug, Default)]
struct ParamSubs {
    all: bool,
    names: HashSet<String>,
}

impl Client {
    pub(super) fn new(capacity: usize) -> (Arc<Client>, mpsc::Receiver<Message>) {
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
    pub(super) fn offer(&self, m: Message) -> bool {
        let queued = self.try_queue(m);
        if !queued && !self.tx.is_closed() {
            self.dropped.fetch_add(1, Ordering::Relaxed);
        }
        queued
    }

    /// A queued message is being sent: its bytes leave the queue.
    pub(super) fn taken(&self, m: &Message) {
        self.queued_bytes.fetch_sub(size(m), Ordering::SeqCst);
    }

    pub(super) fn offer_json(&self, j: &Json) -> bool {
        self.offer(Message::Text(j.to_string().into()))
    }

    /// Messages dropped so far.
    pub fn dropped(&self) -> u64 {
        self.dropped.load(Ordering::Relaxed)
    }

    /// Tells the client of its dropped messages, at most once a second.
    pub(super) fn report_drops(&self) {
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
    pub(super) fn subscribe(&self, msg: &Json, channels: u32) -> Vec<String> {
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
    pub(super) fn subscribe_params(&self, msg: &Json) -> Vec<String> {
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
    pub(super) fn unsubscribe_params(&self, msg: &Json, known: &[String]) -> Vec<String> {
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
    pub(super) fn follows_params(&self) -> bool {
        let p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        p.all || !p.names.is_empty()
    }

    /// The `parameterValues` of the changes it follows, if any.
    pub(super) fn param_update(&self, changed: &[(&str, &Value)]) -> Option<Json> {
        let p = self.params.lock().unwrap_or_else(|p| p.into_inner());
        let list: Vec<Json> = changed
            .iter()
            .filter(|(n, _)| p.all || p.names.contains(*n))
            .map(|(n, v)| parameter(n.to_string(), v))
            .collect();
        (!list.is_empty()).then(|| json!({"op": "parameterValues", "parameters": list}))
    }

    pub(super) fn unsubscribe(&self, msg: &Json) -> Vec<String> {
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
    pub(super) fn join(&self, capacity: usize) -> Option<(Arc<Client>, mpsc::Receiver<Message>)> {
        let mut clients = self.clients.lock().unwrap_or_else(|p| p.into_inner());
        if clients.len() >= MAX_CLIENTS {
            return None;
        }
        let (client, rx) = Client::new(capacity);
        clients.push(Arc::clone(&client));
        Some((client, rx))
    }

    pub(super) fn leave(&self, client: &Arc<Client>) {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).retain(|c| !Arc::ptr_eq(c, client));
    }

    /// How many Foxglove clients are connected.
    pub fn len(&self) -> usize {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub(super) fn snapshot(&self) -> Vec<Arc<Client>> {
        self.clients.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}
