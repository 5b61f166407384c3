//! JSON Schemas of the recorded messages, derived from the signal types.

use serde_json::{json, Value as Json};
use situate_core::{ElemType, SignalType};

/// A float as the link writes it: a number, or `"nan"`, `"inf"`, `"-inf"`.
fn float() -> Json {
    json!({"anyOf": [{"type": "number"}, {"type": "string", "enum": ["nan", "inf", "-inf"]}]})
}

/// The schema of a value of type `ty` in its JSON form (as the link writes it).
pub fn leaf_schema(ty: &SignalType) -> Json {
    match ty {
        SignalType::Bool => json!({"type": "boolean"}),
        SignalType::I64 => json!({"type": "integer"}),
        SignalType::F64 => float(),
        SignalType::Str => json!({"type": "string"}),
        SignalType::Bytes => json!({
            "type": "object",
            "properties": {"$bytes": {"type": "string", "contentEncoding": "base64"}},
            "required": ["$bytes"]
        }),
        SignalType::Array { elem, len } => {
            let items = match elem {
                ElemType::I64 => json!({"type": "integer"}),
                _ => float(),
            };
            let mut schema = json!({"type": "array", "items": items});
            if let Some(n) = len {
                schema["minItems"] = json!(n);
                schema["maxItems"] = json!(n);
            }
            schema
        }
        SignalType::Record(r) => {
            let properties: serde_json::Map<String, Json> =
                r.fields.iter().map(|(name, t)| (name.clone(), leaf_schema(t))).collect();
            let required: Vec<&String> = r.fields.iter().map(|(name, _)| name).collect();
            json!({"type": "object", "properties": properties, "required": required})
        }
    }
}

/// The schema of a signal's message: `{"cycle", "value"}`.
pub fn message_schema(ty: &SignalType) -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": format!("situate {ty}"),
        "type": "object",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0, "description": "the manager's cycle that wrote the value"},
            "value": leaf_schema(ty)
        },
        "required": ["cycle", "value"]
    })
}

/// The schema of an event's message (as `docs/protocol.md` gives it): an
/// object with its `kind` and, for every kind but a few, its `cycle`.
pub fn event_schema(kind: &str) -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": format!("situate event {kind}"),
        "type": "object",
        "properties": {
            "kind": {"type": "string", "const": kind},
            "cycle": {"type": "integer", "minimum": 0}
        },
        "required": ["kind"]
    })
}

/// The schema of a print: `{"cycle", "skill", "line"}`.
pub fn print_schema() -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "situate print",
        "type": "object",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0},
            "skill": {"type": "string"},
            "line": {"type": "string"}
        },
        "required": ["cycle", "skill", "line"]
    })
}

/// The schema of a change of a resource's holder: `{"cycle", "resource", "skill"}`.
pub fn winner_schema() -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "situate resource winner",
        "type": "object",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0},
            "resource": {"type": "string", "description": "the resource's signal leaf"},
            "skill": {"type": "string", "description": "the skill that holds it from this cycle on"}
        },
        "required": ["cycle", "resource", "skill"]
    })
}

/// The schema of a cycle's fingerprint: `{"cycle", "hash", "leaves"}`.
pub fn cycle_schema() -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "situate cycle",
        "type": "object",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0},
            "hash": {"type": "string", "pattern": "^[0-9a-f]{16}$", "description": "FNV-1a 64 of the leaves written and the resources' winners (docs/recording.md)"},
            "leaves": {"type": "integer", "minimum": 0, "description": "leaves written in the cycle"}
        },
        "required": ["cycle", "hash", "leaves"]
    })
}

/// The schema of a keyframe: `{"cycle", "leaves": {path: {"cycle", "value"}}}`.
pub fn keyframe_schema() -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "situate keyframe",
        "type": "object",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0},
            "leaves": {
                "type": "object",
                "description": "every leaf written so far: its latest value and the cycle it was written in",
                "additionalProperties": {
                    "type": "object",
                    "properties": {"cycle": {"type": "integer", "minimum": 0}, "value": {}},
                    "required": ["cycle", "value"]
                }
            }
        },
        "required": ["cycle", "leaves"]
    })
}

/// The schema of a gap marker: `{"cycle", "last", "count"}`, cycles dropped
/// while recording.
pub fn gap_schema() -> Json {
    json!({
        "$schema": "https://json-schema.org/draft/2020-12/schema",
        "title": "situate gap",
        "type": "object",
        "description": "cycles dropped while recording (the writer fell behind a wall-clock run): the file lacks them",
        "properties": {
            "cycle": {"type": "integer", "minimum": 0, "description": "the first cycle dropped"},
            "last": {"type": "integer", "minimum": 0, "description": "the last cycle dropped"},
            "count": {"type": "integer", "minimum": 1}
        },
        "required": ["cycle", "last", "count"]
    })
}
