//! The protocol's own messages: the binary Message Data frame, `status`, and `advertise` with
//! the JSON Schemas of situate's channels (a leaf's `{"cycle", "value"}`, the events').

use serde_json::{json, Value as Json};
use situate_core::Value;

use super::schemas::history_schemas;
use super::EVENTS_TOPIC;
use crate::History;

/// `status` levels (0 is info).
pub(super) const WARNING: u8 = 1;
pub(super) const ERROR: u8 = 2;

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
pub(super) fn advertise(history: &History) -> Json {
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
