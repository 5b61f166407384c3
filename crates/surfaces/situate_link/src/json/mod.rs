//! The protocol's JSON forms (docs/protocol.md): values by type, requests,
//! replies, errors and events.

mod replies;
mod requests;
mod values;

pub use replies::{
    control_error, event_to_json, ok, reading_to_json, reply_to_json, skill_to_json, stats_to_json, wire_error,
};
pub use requests::{
    decode_args, decode_batch, decode_request, Decoded, BATCH, MAX_BATCH, MAX_BATCH_BYTES, MAX_CONDITION_CHARS,
    MAX_LIST_ITEMS, MAX_NAME_CHARS, MAX_PAYLOAD_BYTES, MAX_QUERY_SIGNALS, MAX_TELEMETRY_HZ, MIN_TELEMETRY_HZ,
};
pub use values::{opt_value_to_json, param_from_json, param_type_name, value_from_json, value_to_json};

/// The protocol version this crate speaks.
pub const PROTOCOL: i64 = 1;

/// Every request verb, in the order of docs/protocol.md.
pub const VERBS: &[&str] = &[
    "hello",
    "activate",
    "deactivate",
    "set_param",
    "get_param",
    "set_priority",
    "set_verbose",
    "query",
    "query_many",
    "skill",
    "skills",
    "winners",
    "graph",
    "stats",
    "monitor_add",
    "monitor_cancel",
    "monitor_list",
    "telemetry",
    "run",
    "stop",
    "step",
    "phase",
];

/// A request the link could not even hand to the manager.
#[derive(Debug, Clone, PartialEq)]
pub struct WireError {
    pub kind: &'static str,
    pub message: String,
}

impl WireError {
    pub fn bad_request(message: impl Into<String>) -> Self {
        WireError { kind: "bad_request", message: message.into() }
    }
}
