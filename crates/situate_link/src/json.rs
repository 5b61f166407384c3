//! The protocol's JSON forms (docs/protocol.md): values by type, requests,
//! replies, errors and events.

use std::sync::Arc;

use base64::Engine as _;
use serde_json::{json, Map, Value as Json};
use situate_core::{ElemType, ParamType, SignalType, Value};
use situate_manager::control::{GraphInfo, MonitorInfo};
use situate_manager::{ControlError, Event, ManagerStats, MonitorMode, Reply, Request, SignalReading, SkillInfo};

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

// ----- values -------------------------------------------------------------

fn float_to_json(x: f64) -> Json {
    if x.is_finite() {
        json!(x)
    } else if x.is_nan() {
        json!("nan")
    } else if x > 0.0 {
        json!("inf")
    } else {
        json!("-inf")
    }
}

fn json_to_float(j: &Json) -> Option<f64> {
    match j {
        Json::Number(n) => n.as_f64(),
        Json::String(s) => match s.as_str() {
            "nan" => Some(f64::NAN),
            "inf" => Some(f64::INFINITY),
            "-inf" => Some(f64::NEG_INFINITY),
            _ => None,
        },
        _ => None,
    }
}

/// A value's JSON form (self-describing enough for any client; the type
/// travels beside it where it matters).
pub fn value_to_json(v: &Value) -> Json {
    match v {
        Value::Bool(b) => json!(b),
        Value::I64(x) => json!(x),
        Value::F64(x) => float_to_json(*x),
        Value::Str(s) => json!(&**s),
        Value::Bytes(b) => json!({"$bytes": base64::engine::general_purpose::STANDARD.encode(b)}),
        Value::F32s(a) => Json::Array(a.iter().map(|x| float_to_json(f64::from(*x))).collect()),
        Value::F64s(a) => Json::Array(a.iter().map(|x| float_to_json(*x)).collect()),
        Value::I64s(a) => Json::Array(a.iter().map(|x| json!(x)).collect()),
        Value::Record(r) => Json::Object(r.fields.iter().map(|(n, v)| (n.to_string(), value_to_json(v))).collect()),
    }
}

pub fn opt_value_to_json(v: &Option<Value>) -> Json {
    v.as_ref().map(value_to_json).unwrap_or(Json::Null)
}

/// Reads a value of type `ty`; the error says what was expected.
pub fn value_from_json(j: &Json, ty: &SignalType) -> Result<Value, String> {
    let fail = || format!("expected {ty}, got {}", describe(j));
    match ty {
        SignalType::Bool => j.as_bool().map(Value::Bool).ok_or_else(fail),
        SignalType::I64 => j.as_i64().map(Value::I64).ok_or_else(fail),
        SignalType::F64 => json_to_float(j).map(Value::F64).ok_or_else(fail),
        SignalType::Str => j.as_str().map(|s| Value::Str(Arc::from(s))).ok_or_else(fail),
        SignalType::Bytes => j
            .get("$bytes")
            .and_then(Json::as_str)
            .and_then(|b| base64::engine::general_purpose::STANDARD.decode(b).ok())
            .map(|b| Value::Bytes(Arc::from(b)))
            .ok_or_else(fail),
        SignalType::Array { elem, len } => {
            let items = j.as_array().ok_or_else(fail)?;
            if len.is_some_and(|n| n != items.len()) {
                return Err(format!("expected {ty}, got an array of {} elements", items.len()));
            }
            let v = match elem {
                ElemType::F32 => Value::F32s(
                    items
                        .iter()
                        .map(|x| json_to_float(x).map(|f| f as f32))
                        .collect::<Option<Vec<_>>>()
                        .ok_or_else(fail)?
                        .into(),
                ),
                ElemType::F64 => {
                    Value::F64s(items.iter().map(json_to_float).collect::<Option<Vec<_>>>().ok_or_else(fail)?.into())
                }
                ElemType::I64 => {
                    Value::I64s(items.iter().map(Json::as_i64).collect::<Option<Vec<_>>>().ok_or_else(fail)?.into())
                }
            };
            Ok(v)
        }
        SignalType::Record(rt) => {
            let obj = j.as_object().ok_or_else(fail)?;
            if let Some(extra) = obj.keys().find(|k| rt.field(k).is_none()) {
                return Err(format!("expected {ty}, got an unknown field `{extra}`"));
            }
            let mut fields = Vec::with_capacity(rt.fields.len());
            for (name, fty) in &rt.fields {
                let fj = obj.get(name).ok_or_else(|| format!("expected {ty}, field `{name}` is missing"))?;
                let fv = value_from_json(fj, fty).map_err(|e| format!("field `{name}`: {e}"))?;
                fields.push((Arc::from(name.as_str()), fv));
            }
            Ok(Value::Record(Arc::new(situate_core::RecordValue { fields })))
        }
    }
}

/// A parameter value given by a client, before the manager's range check.
/// The type check happens in the manager too; this only maps JSON kinds.
pub fn param_from_json(j: &Json) -> Result<Value, String> {
    match j {
        Json::Bool(b) => Ok(Value::Bool(*b)),
        Json::Number(n) => match n.as_i64() {
            Some(i) => Ok(Value::I64(i)),
            None => n.as_f64().map(Value::F64).ok_or_else(|| "a number out of range".to_string()),
        },
        Json::String(s) => Ok(Value::Str(Arc::from(s.as_str()))),
        other => Err(format!("a parameter value is a bool, number or string, got {}", describe(other))),
    }
}

fn describe(j: &Json) -> String {
    match j {
        Json::Null => "null".into(),
        Json::Bool(b) => b.to_string(),
        Json::Number(n) => n.to_string(),
        Json::String(s) => {
            let short: String = s.chars().take(40).collect();
            format!("{short:?}")
        }
        Json::Array(_) => "an array".into(),
        Json::Object(_) => "an object".into(),
    }
}

pub fn param_type_name(t: ParamType) -> &'static str {
    t.name()
}

// ----- requests -----------------------------------------------------------

/// What a verb turns into: a manager request, or something the link itself
/// answers.
#[derive(Debug, Clone, PartialEq)]
pub enum Decoded {
    Manager(Request),
    Hello,
    Telemetry { signals: Vec<String>, rate_hz: Option<f64> },
}

struct Args<'a> {
    verb: &'a str,
    obj: Map<String, Json>,
}

impl Args<'_> {
    fn take(&mut self, name: &str) -> Option<Json> {
        self.obj.remove(name)
    }

    fn has(&self, name: &str) -> bool {
        self.obj.contains_key(name)
    }

    fn string(&mut self, name: &str) -> Result<String, WireError> {
        match self.take(name) {
            Some(Json::String(s)) => Ok(s),
            Some(other) => Err(self.wrong(name, "a string", &other)),
            None => Err(self.missing(name, "a string")),
        }
    }

    fn strings(&mut self, name: &str) -> Result<Vec<String>, WireError> {
        match self.take(name) {
            Some(Json::Array(items)) => items
                .into_iter()
                .map(|i| match i {
                    Json::String(s) => Ok(s),
                    other => Err(self.wrong(name, "a list of strings", &other)),
                })
                .collect(),
            // A lone string is refused like any other non-list (protocol.md): accepting it
            // would make `"wander"` and `["wander"]` two spellings of one request.
            Some(other) => Err(self.wrong(name, "a list of strings", &other)),
            None => Err(self.missing(name, "a list of strings")),
        }
    }

    fn boolean(&mut self, name: &str, default: Option<bool>) -> Result<bool, WireError> {
        match (self.take(name), default) {
            (Some(Json::Bool(b)), _) => Ok(b),
            (Some(other), _) => Err(self.wrong(name, "true or false", &other)),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(name, "true or false")),
        }
    }

    fn integer(&mut self, name: &str, lo: i64, hi: i64) -> Result<i64, WireError> {
        let what = format!("an integer in [{lo}, {hi}]");
        match self.take(name) {
            Some(Json::Number(n)) => match n.as_i64() {
                Some(i) if (lo..=hi).contains(&i) => Ok(i),
                _ => Err(self.wrong(name, &what, &Json::Number(n))),
            },
            Some(other) => Err(self.wrong(name, &what, &other)),
            None => Err(self.missing(name, &what)),
        }
    }

    fn wrong(&self, name: &str, what: &str, got: &Json) -> WireError {
        WireError::bad_request(format!("`{}`: argument `{name}` must be {what}, got {}", self.verb, describe(got)))
    }

    fn missing(&self, name: &str, what: &str) -> WireError {
        WireError::bad_request(format!("`{}`: missing argument `{name}` ({what})", self.verb))
    }

    fn finish(self) -> Result<(), WireError> {
        match self.obj.keys().next() {
            Some(k) if k != "protocol" => {
                Err(WireError::bad_request(format!("`{}`: unknown argument `{k}`", self.verb)))
            }
            _ => Ok(()),
        }
    }
}

/// Decodes a request payload for `verb`. Never panics, whatever the bytes.
pub fn decode_request(verb: &str, payload: &[u8]) -> Result<Decoded, WireError> {
    if !VERBS.contains(&verb) {
        return Err(WireError {
            kind: "unknown_verb",
            message: format!("unknown request `{verb}`{}", situate_core::suggestion(verb, VERBS.iter().copied())),
        });
    }
    let obj = if payload.iter().all(u8::is_ascii_whitespace) {
        Map::new()
    } else {
        match serde_json::from_slice::<Json>(payload) {
            Ok(Json::Object(o)) => o,
            Ok(other) => {
                return Err(WireError::bad_request(format!(
                    "`{verb}`: the payload must be a JSON object, got {}",
                    describe(&other)
                )))
            }
            // serde_json refuses a number beyond f64's range (1e400) while parsing; that is a
            // value out of range (`bad_param`, protocol.md), not malformed JSON.
            Err(e) if e.is_syntax() && e.to_string().starts_with("number out of range") => {
                return Err(WireError {
                    kind: "bad_param",
                    message: format!(
                        "`{verb}`: a number out of range at column {}: numbers must be finite 64-bit floats \
                         (magnitude at most 1.8e308; integers within ±9.2e18 for `i64`)",
                        e.column()
                    ),
                })
            }
            Err(e) => return Err(WireError::bad_request(format!("`{verb}`: the payload is not JSON: {e}"))),
        }
    };
    if let Some(p) = obj.get("protocol") {
        if p.as_i64() != Some(PROTOCOL) {
            return Err(WireError {
                kind: "protocol",
                message: format!("protocol {} is not supported; this manager speaks protocol {PROTOCOL}", describe(p)),
            });
        }
    }
    let mut a = Args { verb, obj };
    let decoded = match verb {
        "hello" => Decoded::Hello,
        "activate" => {
            let skills = a.strings("skills")?;
            let with_providers = a.boolean("with_providers", Some(false))?;
            Decoded::Manager(Request::Activate { skills, with_providers })
        }
        "deactivate" => Decoded::Manager(Request::Deactivate { skills: a.strings("skills")? }),
        "set_param" => {
            let skill = a.string("skill")?;
            let param = a.string("param")?;
            let raw = a.take("value").ok_or_else(|| a.missing("value", "a bool, number or string"))?;
            // A value of the wrong kind is the parameter's problem: `bad_param` (protocol.md).
            let value = param_from_json(&raw).map_err(|e| WireError {
                kind: "bad_param",
                message: format!("`set_param`: skill `{skill}`: parameter `{param}`: {e}"),
            })?;
            Decoded::Manager(Request::SetParam { skill, param, value })
        }
        "get_param" => {
            let skill = a.string("skill")?;
            let param = a.string("param")?;
            Decoded::Manager(Request::GetParam { skill, param })
        }
        "set_priority" => {
            let skill = a.string("skill")?;
            let priority = a.integer("priority", i64::from(i32::MIN), i64::from(i32::MAX))? as i32;
            Decoded::Manager(Request::SetPriority { skill, priority })
        }
        "set_verbose" => {
            let skill = a.string("skill")?;
            let verbose = a.boolean("verbose", None)?;
            Decoded::Manager(Request::SetVerbose { skill, verbose })
        }
        "query" => Decoded::Manager(Request::QuerySignal { signal: a.string("signal")? }),
        "skill" => Decoded::Manager(Request::QuerySkill { skill: a.string("skill")? }),
        "skills" => Decoded::Manager(Request::QuerySkills),
        "winners" => Decoded::Manager(Request::QueryWinners),
        "graph" => Decoded::Manager(Request::QueryGraph),
        "stats" => Decoded::Manager(Request::QueryStats),
        "monitor_add" => {
            let condition = a.string("condition")?;
            let mode = match a.take("mode") {
                None => MonitorMode::Once,
                Some(Json::String(s)) => MonitorMode::parse(&s).ok_or_else(|| {
                    WireError::bad_request(format!(
                        "`monitor_add`: mode must be \"once\", \"edge\" or \"level\", got {s:?}{}",
                        situate_core::suggestion(&s, ["once", "edge", "level"])
                    ))
                })?,
                Some(other) => return Err(a.wrong("mode", "\"once\", \"edge\" or \"level\"", &other)),
            };
            let pause = a.boolean("pause", Some(false))?;
            let report = if a.has("report") { a.strings("report")? } else { Vec::new() };
            Decoded::Manager(Request::AddMonitor { condition, mode, pause, report })
        }
        "monitor_cancel" => {
            Decoded::Manager(Request::CancelMonitor { monitor: a.integer("monitor", 0, i64::MAX)? as u64 })
        }
        "monitor_list" => Decoded::Manager(Request::ListMonitors),
        "telemetry" => {
            let signals = a.strings("signals")?;
            let rate_hz = match a.take("rate_hz") {
                None => None,
                Some(j) => match j.as_f64() {
                    Some(r) if r > 0.0 && r <= 100.0 => Some(r),
                    _ => return Err(a.wrong("rate_hz", "a number in (0, 100]", &j)),
                },
            };
            Decoded::Telemetry { signals, rate_hz }
        }
        "run" => Decoded::Manager(Request::Run),
        "stop" => Decoded::Manager(Request::Stop),
        "step" => Decoded::Manager(Request::Step { cycles: a.integer("cycles", 1, 1_000_000)? as u64 }),
        _ => unreachable!("verbs are checked above"),
    };
    a.finish()?;
    Ok(decoded)
}

// ----- replies, errors, events ----------------------------------------------

pub fn ok(result: Json) -> Json {
    json!({ "ok": result })
}

pub fn wire_error(e: &WireError) -> Json {
    json!({"error": {"kind": e.kind, "message": e.message}})
}

pub fn control_error(e: &ControlError) -> Json {
    let kind = match e {
        ControlError::UnknownSkill { .. } => "unknown_skill",
        ControlError::UnknownParam { .. } => "unknown_param",
        ControlError::BadParam { .. } => "bad_param",
        ControlError::MissingProviders { .. } => "missing_providers",
        ControlError::UnknownSignal { .. } => "unknown_signal",
        ControlError::BadCondition { .. } => "bad_condition",
        ControlError::BadReport(_) => "unknown_signal",
        ControlError::UnknownMonitor(_) => "unknown_monitor",
        ControlError::Invalid(_) => "invalid",
        ControlError::Disconnected => "unavailable",
    };
    let mut err = json!({"kind": kind, "message": e.to_string()});
    match e {
        ControlError::MissingProviders { signals, providers, .. } => {
            err["signals"] = json!(signals);
            err["providers"] = json!(providers);
        }
        ControlError::BadCondition { column, pointer, message } => {
            err["column"] = json!(column);
            err["pointer"] = json!(pointer);
            err["message"] = json!(format!("column {column}: {message}"));
        }
        _ => {}
    }
    json!({ "error": err })
}

pub fn reading_to_json(r: &SignalReading) -> Json {
    json!({
        "signal": r.signal,
        "type": r.ty.to_string(),
        "value": opt_value_to_json(&r.value),
        "cycle": r.cycle,
        "writer": r.writer,
    })
}

pub fn skill_to_json(s: &SkillInfo) -> Json {
    let port = |p: &situate_manager::PortInfo| json!({"name": p.name, "signal": p.signal, "type": p.ty.to_string(), "optional": p.optional, "value": opt_value_to_json(&p.value)});
    json!({
        "name": s.name,
        "type_name": s.type_name,
        "kind": s.kind.name(),
        "doc": s.doc,
        "active": s.active,
        "faulted": s.faulted,
        "verbose": s.verbose,
        "priority": s.priority,
        "params": s.params.iter().map(|(spec, v)| json!({
            "name": spec.name,
            "type": spec.ty.name(),
            "value": value_to_json(v),
            "default": value_to_json(&spec.default),
            "min": spec.min,
            "max": spec.max,
            "unit": spec.unit,
            "doc": spec.doc,
        })).collect::<Vec<_>>(),
        "inputs": s.inputs.iter().map(port).collect::<Vec<_>>(),
        "outputs": s.outputs.iter().map(port).collect::<Vec<_>>(),
        "timing": {"runs": s.timing.runs, "last_ns": s.timing.last_ns, "max_ns": s.timing.max_ns, "total_ns": s.timing.total_ns},
        "prints": s.prints.iter().map(|(c, l)| json!([c, l])).collect::<Vec<_>>(),
    })
}

pub fn stats_to_json(s: &ManagerStats) -> Json {
    json!({
        "robot": s.robot,
        "cycle": s.cycle,
        "time_s": s.time_s,
        "running": s.running,
        "period_s": s.period_s,
        "last_cycle_ns": s.last_cycle_ns,
        "mean_cycle_ns": s.mean_cycle_ns,
        "max_cycle_ns": s.max_cycle_ns,
        "overruns": s.overruns,
        "active": s.active,
    })
}

fn graph_to_json(g: &GraphInfo) -> Json {
    json!({
        "skills": g.skills.iter().map(|s| json!({
            "name": s.name, "kind": s.kind.name(), "active": s.active, "priority": s.priority,
            "inputs": s.inputs, "outputs": s.outputs,
        })).collect::<Vec<_>>(),
        "signals": g.signals.iter().map(|s| json!({
            "signal": s.signal, "type": s.ty.to_string(), "writers": s.writers, "readers": s.readers,
        })).collect::<Vec<_>>(),
    })
}

fn monitor_to_json(m: &MonitorInfo) -> Json {
    json!({
        "monitor": m.monitor, "condition": m.condition, "mode": m.mode.name(), "fired": m.fired, "holds": m.holds,
        "pause": m.pause, "report": m.report,
    })
}

/// A manager reply's `ok` result.
pub fn reply_to_json(reply: &Reply) -> Json {
    match reply {
        Reply::Done => Json::Null,
        Reply::Activation { changed, at_cycle } => json!({"changed": changed, "at_cycle": at_cycle}),
        Reply::Param(v) => value_to_json(v),
        Reply::Signal(r) => reading_to_json(r),
        Reply::Skill(s) => skill_to_json(s),
        Reply::Skills(list) => Json::Array(list.iter().map(skill_to_json).collect()),
        Reply::Winners(w) => Json::Array(
            w.iter()
                .map(|w| json!({"signal": w.signal, "writers": w.writers, "winner": w.winner, "cycle": w.cycle}))
                .collect(),
        ),
        Reply::Graph(g) => graph_to_json(g),
        Reply::Stats(s) => stats_to_json(s),
        Reply::MonitorAdded(id) => json!({ "monitor": id }),
        Reply::Monitors(list) => Json::Array(list.iter().map(monitor_to_json).collect()),
    }
}

/// An event's key suffix and JSON form.
pub fn event_to_json(e: &Event) -> (&'static str, Json) {
    match e {
        Event::MonitorFired { monitor, condition, cycle, time_s, values } => (
            "monitor_fired",
            json!({
                "kind": "monitor_fired", "monitor": monitor, "condition": condition, "cycle": cycle, "time_s": time_s,
                "values": values.iter().map(|(n, v)| (n.clone(), opt_value_to_json(v))).collect::<Map<_, _>>(),
            }),
        ),
        Event::ActivationApplied { activated, deactivated, cycle } => (
            "activation_applied",
            json!({"kind": "activation_applied", "activated": activated, "deactivated": deactivated, "cycle": cycle}),
        ),
        Event::ParamChanged { skill, param, value, cycle } => (
            "param_changed",
            json!({"kind": "param_changed", "skill": skill, "param": param, "value": value_to_json(value), "cycle": cycle}),
        ),
        Event::SkillFaulted { skill, cause, cycle } => {
            ("skill_faulted", json!({"kind": "skill_faulted", "skill": skill, "cause": cause, "cycle": cycle}))
        }
        Event::Print { skill, line, cycle } => {
            ("print", json!({"kind": "print", "skill": skill, "line": line, "cycle": cycle}))
        }
        Event::ManagerStarted { cycle } => ("manager_started", json!({"kind": "manager_started", "cycle": cycle})),
        Event::ManagerStopped { cycle } => ("manager_stopped", json!({"kind": "manager_stopped", "cycle": cycle})),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_round_trip_by_type() {
        let t = SignalType::parse("{range: f32[3], id: i64, name: string, raw: bytes, ok: bool, x: f64}").unwrap();
        let v = situate_core::record_value(vec![
            ("range", Value::F32s(vec![0.5, f32::INFINITY, 2.0].into())),
            ("id", Value::I64(3)),
            ("name", Value::Str("door".into())),
            ("raw", Value::Bytes(vec![0u8, 255, 7].into())),
            ("ok", Value::Bool(true)),
            ("x", Value::F64(-1.25)),
        ]);
        let j = value_to_json(&v);
        assert_eq!(j["range"], json!([0.5, "inf", 2.0]));
        assert_eq!(j["raw"], json!({"$bytes": "AP8H"}));
        assert_eq!(value_from_json(&j, &t).unwrap(), v);
    }

    #[test]
    fn wrongly_typed_values_name_the_expectation() {
        let t = SignalType::parse("{v: f64, w: f64}").unwrap();
        assert_eq!(
            value_from_json(&json!({"v": 1}), &t).unwrap_err(),
            "expected {v: f64, w: f64}, field `w` is missing"
        );
        assert_eq!(value_from_json(&json!({"v": 1, "w": "x"}), &t).unwrap_err(), "field `w`: expected f64, got \"x\"");
        assert_eq!(
            value_from_json(&json!([1, 2]), &SignalType::parse("f32[3]").unwrap()).unwrap_err(),
            "expected f32[3], got an array of 2 elements"
        );
        // An integer is fine where a float is expected.
        assert_eq!(value_from_json(&json!(2), &SignalType::F64).unwrap(), Value::F64(2.0));
    }

    #[test]
    fn requests_decode_and_bad_ones_say_why() {
        assert_eq!(
            decode_request("activate", br#"{"skills": ["wander", "runaway"]}"#).unwrap(),
            Decoded::Manager(Request::Activate {
                skills: vec!["wander".into(), "runaway".into()],
                with_providers: false
            })
        );
        assert_eq!(decode_request("stats", b"").unwrap(), Decoded::Manager(Request::QueryStats));
        let e = decode_request("activte", b"{}").unwrap_err();
        assert_eq!(
            (e.kind, e.message.as_str()),
            ("unknown_verb", "unknown request `activte` — did you mean `activate`?")
        );
        let e = decode_request("activate", b"{\"skills\": 3}").unwrap_err();
        assert_eq!(e.message, "`activate`: argument `skills` must be a list of strings, got 3");
        let e = decode_request("step", b"{\"cycles\": 0}").unwrap_err();
        assert_eq!(e.message, "`step`: argument `cycles` must be an integer in [1, 1000000], got 0");
        let e = decode_request("stats", b"[1]").unwrap_err();
        assert_eq!(e.message, "`stats`: the payload must be a JSON object, got an array");
        let e = decode_request("stats", b"{\"protocol\": 2}").unwrap_err();
        assert_eq!(e.kind, "protocol");
        let e = decode_request("query", b"{\"signal\": \"x\", \"extra\": 1}").unwrap_err();
        assert_eq!(e.message, "`query`: unknown argument `extra`");
        let e = decode_request("set_param", b"{\"skill\": \"r\", \"param\": \"p\", \"value\": [1]}").unwrap_err();
        assert_eq!(e.kind, "bad_param");
        assert!(e.message.contains("a parameter value is a bool, number or string"), "{}", e.message);
    }

    #[test]
    fn a_string_where_a_list_is_expected_is_refused() {
        for (verb, payload, arg) in [
            ("activate", r#"{"skills": "wander"}"#, "skills"),
            ("deactivate", r#"{"skills": "wander"}"#, "skills"),
            ("monitor_add", r#"{"condition": "x.y > 1", "report": "x"}"#, "report"),
            ("telemetry", r#"{"signals": "odom"}"#, "signals"),
        ] {
            let e = decode_request(verb, payload.as_bytes()).unwrap_err();
            assert_eq!(e.kind, "bad_request", "{verb}");
            assert_eq!(
                e.message,
                format!(
                    "`{verb}`: argument `{arg}` must be a list of strings, got \"{}\"",
                    if arg == "skills" {
                        "wander"
                    } else if arg == "report" {
                        "x"
                    } else {
                        "odom"
                    }
                )
            );
        }
    }

    #[test]
    fn a_number_beyond_a_float_is_bad_param_not_bad_json() {
        for payload in
            [r#"{"skill": "r", "param": "p", "value": 1e400}"#, r#"{"skill": "r", "param": "p", "value": -1e309}"#]
        {
            let e = decode_request("set_param", payload.as_bytes()).unwrap_err();
            assert_eq!(e.kind, "bad_param", "{payload}: {}", e.message);
            assert!(e.message.contains("out of range at column"), "{}", e.message);
            assert!(e.message.contains("1.8e308"), "names the range: {}", e.message);
        }
        // Truly malformed JSON stays `bad_request`.
        assert_eq!(decode_request("set_param", b"{\"value\": 1e}").unwrap_err().kind, "bad_request");
    }

    #[test]
    fn random_bytes_never_panic_the_decoder() {
        let mut x: u64 = 0x243F_6A88_85A3_08D3;
        for i in 0..20_000 {
            let len = i % 64;
            let bytes: Vec<u8> = (0..len)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    (x & 0xff) as u8
                })
                .collect();
            let verb = VERBS[i % VERBS.len()];
            let _ = decode_request(verb, &bytes);
        }
    }
}
