//! The poller: one thread taking every new cycle, event and parameter change from the history
//! and sending it to the clients subscribed, stamped with the run's time.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::ws::Message;
use serde_json::json;
use situate_core::Value;
use situate_link::json as wire;
use situate_manager::{Reply, Request};

use super::client::Client;
use super::protocol::{message_data, nanos};
use super::schemas::{history_schemas, Known};
#[cfg(doc)]
use super::Schemas;
use super::POLL;
use crate::{ask, History, Shared};

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
pub(super) enum Pending {
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
    pub(super) fn encode(self, epoch_ns: u64) -> (u32, u64, Bytes) {
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
pub(super) fn collect(history: &History, cursor: &mut Cursor, wanted: &[u32]) -> Vec<Pending> {
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
pub(super) fn deliver(clients: &[Arc<Client>], out: &[(u32, u64, Bytes)]) {
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
pub(super) fn parameter_values(history: &History) -> Vec<(String, Value)> {
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
