//! Requests: a verb's payload decoded into what the manager or the link
//! answers, with the limits a request is held to.

use std::collections::BTreeMap;
use std::sync::Arc;

use base64::Engine as _;
use serde_json::value::RawValue;
use serde_json::{Map, Value as Json};
use situate_core::Value;
use situate_manager::{MonitorCondition, MonitorMode, Request, MAX_ANY_CONDITIONS};

use super::values::{describe, json_to_float};
use super::{WireError, PROTOCOL, VERBS};

/// The largest request payload taken, in bytes (larger: `bad_request`, before parsing).
pub const MAX_PAYLOAD_BYTES: usize = 64 * 1024;
/// The longest name (skill, parameter, signal) a request may hold, in characters.
pub const MAX_NAME_CHARS: usize = 256;
/// The longest monitor condition, in characters (each of an `any`'s too;
/// with at most [`MAX_ANY_CONDITIONS`] of them, and the whole request within
/// [`MAX_PAYLOAD_BYTES`], an `any`'s text is bounded like a condition's).
pub const MAX_CONDITION_CHARS: usize = 4096;
/// The most items of a list argument (`skills`, `report`, `signals`).
pub const MAX_LIST_ITEMS: usize = 1024;
/// The most signals one `query_many` reads (its reply holds a reading of each, whole records
/// among them, so it is held well below [`MAX_LIST_ITEMS`]).
pub const MAX_QUERY_SIGNALS: usize = 256;

/// The slowest telemetry a client may ask for: a sample every 100 s.
pub const MIN_TELEMETRY_HZ: f64 = 0.01;
/// The fastest: 100 samples a second.
pub const MAX_TELEMETRY_HZ: f64 = 100.0;

/// What a verb turns into: a manager request, or something the link itself
/// answers.
#[derive(Debug, Clone, PartialEq)]
pub enum Decoded {
    Manager(Request),
    Hello,
    Telemetry { signals: Vec<String>, rate_hz: Option<f64> },
}

/// One argument as it came: JSON, or the text of a number (or of a list or
/// object holding one) too large for a 64-bit float, which JSON allows but
/// this decoder cannot hold.
#[derive(Debug)]
enum Arg {
    Json(Json),
    Huge(String),
}

impl Arg {
    /// The argument as a message shows it.
    fn describe(&self) -> String {
        match self {
            Arg::Json(j) => describe(j),
            Arg::Huge(text) => describe_huge(text),
        }
    }
}

fn describe_huge(text: &str) -> String {
    let text = text.trim();
    match text.chars().next() {
        Some('[') => "an array holding a number beyond the range of a 64-bit float".into(),
        Some('{') => "an object holding a number beyond the range of a 64-bit float".into(),
        _ => {
            let mut short: String = text.chars().take(40).collect();
            if short.len() < text.len() {
                short.push('…');
            }
            format!("{short} (beyond the range of a 64-bit float)")
        }
    }
}

struct Args<'a> {
    verb: &'a str,
    obj: Map<String, Json>,
    /// Members too large to hold, as their text.
    huge: BTreeMap<String, String>,
}

impl Args<'_> {
    fn take(&mut self, name: &str) -> Option<Arg> {
        match self.obj.remove(name) {
            Some(j) => Some(Arg::Json(j)),
            None => self.huge.remove(name).map(Arg::Huge),
        }
    }

    /// `s` if it has at most `cap` characters, else a `bad_request` naming the limit.
    fn capped(&self, name: &str, s: String, cap: usize) -> Result<String, WireError> {
        if s.len() <= cap || s.chars().count() <= cap {
            Ok(s)
        } else {
            Err(WireError::bad_request(format!(
                "`{}`: argument `{name}` is {} characters long, at most {cap} are taken",
                self.verb,
                s.chars().count()
            )))
        }
    }

    /// The optional `session` secret, as the session's public id (see
    /// [`crate::client_session`]).
    fn session(&mut self) -> Result<Option<String>, WireError> {
        if !self.has("session") {
            return Ok(None);
        }
        crate::client_session::public_id(&self.string("session")?).map(Some)
    }

    fn has(&self, name: &str) -> bool {
        self.obj.contains_key(name) || self.huge.contains_key(name)
    }

    fn string(&mut self, name: &str) -> Result<String, WireError> {
        // A condition is a small expression; every other string names something.
        let cap = if name == "condition" { MAX_CONDITION_CHARS } else { MAX_NAME_CHARS };
        match self.take(name) {
            Some(Arg::Json(Json::String(s))) => self.capped(name, s, cap),
            Some(other) => Err(self.wrong(name, "a string", &other)),
            None => Err(self.missing(name, "a string")),
        }
    }

    /// The items of list argument `name` (described as `what`), after
    /// `too_many` (given their count) had nothing to object; a single string
    /// is refused (it is not a list of one).
    fn list(
        &mut self,
        name: &str,
        what: &str,
        too_many: impl Fn(usize) -> Option<String>,
    ) -> Result<Vec<Json>, WireError> {
        match self.take(name) {
            Some(Arg::Json(Json::Array(items))) => match too_many(items.len()) {
                Some(why) => Err(WireError::bad_request(format!("`{}`: argument `{name}` {why}", self.verb))),
                None => Ok(items),
            },
            Some(Arg::Json(Json::String(s))) => {
                let got = describe(&Json::String(s));
                Err(WireError::bad_request(format!(
                    "`{}`: argument `{name}`: expected {what}, got the string {got} (a list of one is written [{got}])",
                    self.verb
                )))
            }
            Some(other) => Err(self.wrong(name, what, &other)),
            None => Err(self.missing(name, what)),
        }
    }

    /// A list of names (each at most [`MAX_NAME_CHARS`] long).
    fn strings(&mut self, name: &str, of: &str) -> Result<Vec<String>, WireError> {
        let what = format!("a list of strings ({of})");
        let items = self.list(name, &what, |n| {
            (n > MAX_LIST_ITEMS).then(|| format!("has {n} items, at most {MAX_LIST_ITEMS} are taken"))
        })?;
        items
            .into_iter()
            .map(|i| match i {
                Json::String(s) => self.capped(name, s, MAX_NAME_CHARS),
                other => Err(self.wrong(name, &what, &Arg::Json(other))),
            })
            .collect()
    }

    /// `monitor_add`'s `any`: 1 to [`MAX_ANY_CONDITIONS`] condition strings,
    /// each at most [`MAX_CONDITION_CHARS`] long; a refusal names the item
    /// (`any[2]`).
    fn conditions(&mut self, name: &str) -> Result<Vec<String>, WireError> {
        self.texts(name, ("condition", "conditions"), MAX_ANY_CONDITIONS, MAX_CONDITION_CHARS)
    }

    /// `query_many`'s `signals`: 1 to [`MAX_QUERY_SIGNALS`] signal names, each
    /// at most [`MAX_NAME_CHARS`] long; a refusal names the item (`signals[2]`).
    fn signal_names(&mut self, name: &str) -> Result<Vec<String>, WireError> {
        self.texts(name, ("signal name", "signal names"), MAX_QUERY_SIGNALS, MAX_NAME_CHARS)
    }

    /// 1 to `most` strings, each at most `cap` characters long, called `noun`
    /// (singular, plural) in messages; a refusal names the item (`any[2]`).
    fn texts(&mut self, name: &str, noun: (&str, &str), most: usize, cap: usize) -> Result<Vec<String>, WireError> {
        let (one, many) = noun;
        let what = format!("a list of 1 to {most} strings ({many})");
        let items =
            self.list(name, &what, |n| (n == 0 || n > most).then(|| format!("has {n} {many}, it takes 1 to {most}")))?;
        items
            .into_iter()
            .enumerate()
            .map(|(i, item)| {
                let at = format!("{name}[{i}]");
                match item {
                    Json::String(s) => self.capped(&at, s, cap),
                    other => Err(self.wrong(&at, &format!("a string (a {one})"), &Arg::Json(other))),
                }
            })
            .collect()
    }

    fn boolean(&mut self, name: &str, default: Option<bool>) -> Result<bool, WireError> {
        match (self.take(name), default) {
            (Some(Arg::Json(Json::Bool(b))), _) => Ok(b),
            (Some(other), _) => Err(self.wrong(name, "true or false", &other)),
            (None, Some(d)) => Ok(d),
            (None, None) => Err(self.missing(name, "true or false")),
        }
    }

    fn integer(&mut self, name: &str, lo: i64, hi: i64) -> Result<i64, WireError> {
        let what = format!("an integer in [{lo}, {hi}]");
        match self.take(name) {
            Some(Arg::Json(Json::Number(n))) => match n.as_i64() {
                Some(i) if (lo..=hi).contains(&i) => Ok(i),
                _ => Err(self.wrong(name, &what, &Arg::Json(Json::Number(n)))),
            },
            Some(other) => Err(self.wrong(name, &what, &other)),
            None => Err(self.missing(name, &what)),
        }
    }

    fn wrong(&self, name: &str, what: &str, got: &Arg) -> WireError {
        WireError::bad_request(format!("`{}`: argument `{name}`: expected {what}, got {}", self.verb, got.describe()))
    }

    fn missing(&self, name: &str, what: &str) -> WireError {
        WireError::bad_request(format!("`{}`: missing argument `{name}` ({what})", self.verb))
    }

    fn finish(self) -> Result<(), WireError> {
        match self.obj.keys().chain(self.huge.keys()).find(|k| *k != "protocol") {
            Some(k) => Err(WireError::bad_request(format!("`{}`: unknown argument `{k}`", self.verb))),
            None => Ok(()),
        }
    }
}

/// A `set_param` value, read without knowing the parameter's type: any value
/// of some type reaches the manager, which refuses one that is not the
/// parameter's as `bad_param`, naming the expected type and range. A number
/// beyond a 64-bit float's range is read as infinite, as JSON readers do, and
/// so refused. JSON that is no value of any type (`null`, a list of strings)
/// is a wrongly typed argument.
fn param_value(arg: &Arg) -> Option<Value> {
    match arg {
        Arg::Json(j) => untyped_value(j),
        Arg::Huge(text) => match text.trim_start().chars().next() {
            Some('-') => Some(Value::F64(f64::NEG_INFINITY)),
            Some('[' | '{') => None,
            _ => Some(Value::F64(f64::INFINITY)),
        },
    }
}

/// A value by its JSON form alone (docs/protocol.md, "Values").
fn untyped_value(j: &Json) -> Option<Value> {
    match j {
        Json::Bool(b) => Some(Value::Bool(*b)),
        Json::Number(n) => match n.as_i64() {
            Some(i) => Some(Value::I64(i)),
            None => n.as_f64().map(Value::F64),
        },
        Json::String(s) => Some(Value::Str(Arc::from(s.as_str()))),
        Json::Array(items) => {
            if let Some(ints) = items.iter().map(Json::as_i64).collect::<Option<Vec<_>>>() {
                Some(Value::I64s(ints.into()))
            } else {
                Some(Value::F64s(items.iter().map(json_to_float).collect::<Option<Vec<_>>>()?.into()))
            }
        }
        Json::Object(o) => match (o.len(), o.get("$bytes").and_then(Json::as_str)) {
            (1, Some(b)) => {
                base64::engine::general_purpose::STANDARD.decode(b).ok().map(|b| Value::Bytes(Arc::from(b)))
            }
            _ => {
                let fields = o
                    .iter()
                    .map(|(name, v)| Some((Arc::from(name.as_str()), untyped_value(v)?)))
                    .collect::<Option<Vec<_>>>()?;
                Some(Value::Record(Arc::new(situate_core::RecordValue { fields })))
            }
        },
        Json::Null => None,
    }
}

/// Why a payload is not a JSON object of arguments (each caller words it).
enum NotAnObject {
    /// Larger than [`MAX_PAYLOAD_BYTES`]: its size (refused before parsing).
    TooLarge(usize),
    /// JSON, but not an object.
    Other(Json),
    /// Not JSON, as `serde_json` reads it.
    NotJson(serde_json::Error),
}

/// The payload as a JSON object, `{}` when empty (or only whitespace).
fn payload_object(payload: &[u8]) -> Result<Map<String, Json>, NotAnObject> {
    if payload.len() > MAX_PAYLOAD_BYTES {
        // Refused before parsing: no request, however large, may cost the robot more than this.
        return Err(NotAnObject::TooLarge(payload.len()));
    }
    if payload.iter().all(u8::is_ascii_whitespace) {
        return Ok(Map::new());
    }
    match serde_json::from_slice::<Json>(payload) {
        Ok(Json::Object(obj)) => Ok(obj),
        Ok(other) => Err(NotAnObject::Other(other)),
        Err(e) => Err(NotAnObject::NotJson(e)),
    }
}

/// The payload's members as arguments. A member JSON allows but this decoder
/// cannot hold (a number beyond a 64-bit float) is kept aside as its text, so
/// that its refusal names the argument.
fn payload_args<'a>(verb: &'a str, payload: &[u8]) -> Result<Args<'a>, WireError> {
    let first = match payload_object(payload) {
        Ok(obj) => return Ok(Args { verb, obj, huge: BTreeMap::new() }),
        Err(NotAnObject::TooLarge(n)) => {
            return Err(WireError::bad_request(format!(
                "`{verb}`: the request is {n} bytes, at most {MAX_PAYLOAD_BYTES} are taken"
            )))
        }
        Err(NotAnObject::Other(other)) => {
            return Err(WireError::bad_request(format!(
                "`{verb}`: the payload must be a JSON object, got {}",
                describe(&other)
            )))
        }
        Err(NotAnObject::NotJson(e)) => e,
    };
    let not_json = || WireError::bad_request(format!("`{verb}`: the payload is not JSON: {first}"));
    let mut args = Args { verb, obj: Map::new(), huge: BTreeMap::new() };
    let raw = serde_json::from_slice::<BTreeMap<String, Box<RawValue>>>(payload).map_err(|_| not_json())?;
    for (name, member) in raw {
        match serde_json::from_str::<Json>(member.get()) {
            Ok(j) => {
                args.obj.insert(name, j);
            }
            Err(e) if e.to_string().starts_with("number out of range") => {
                args.huge.insert(name, member.get().to_string());
            }
            Err(_) => return Err(not_json()),
        }
    }
    Ok(args)
}

/// The link's envelope for several requests in one query (not a manager request: no GUI verb).
pub const BATCH: &str = "batch";
/// Most requests one `batch` carries.
pub const MAX_BATCH: usize = 64;
/// Largest `batch` payload, bytes (each request in it is bounded by [`MAX_PAYLOAD_BYTES`] too).
pub const MAX_BATCH_BYTES: usize = 4 * MAX_PAYLOAD_BYTES;

/// The requests of a `batch` payload (`{"requests": [{"verb": …, "args": {…}}, …]}`), in
/// order: each verb and its arguments' JSON text as sent (`{}` without `args`), to be
/// decoded one by one with [`decode_request`] as if each came alone.
pub fn decode_batch(payload: &[u8]) -> Result<Vec<(String, Vec<u8>)>, WireError> {
    let bad = |m: String| WireError::bad_request(format!("`{BATCH}`: {m}"));
    if payload.len() > MAX_BATCH_BYTES {
        return Err(bad(format!("the request is {} bytes, at most {MAX_BATCH_BYTES} are taken", payload.len())));
    }
    let outer = serde_json::from_slice::<BTreeMap<String, Box<RawValue>>>(payload)
        .map_err(|e| bad(format!("the payload must be a JSON object with `requests`: {e}")))?;
    if let Some(other) = outer.keys().find(|k| k.as_str() != "requests") {
        return Err(bad(format!("unknown argument `{other}` (expected: requests)")));
    }
    let requests = outer.get("requests").ok_or_else(|| bad("missing `requests`: a list of requests".into()))?;
    let items = serde_json::from_str::<Vec<BTreeMap<String, Box<RawValue>>>>(requests.get())
        .map_err(|_| bad("`requests` must be a list of objects, each with `verb` and optional `args`".into()))?;
    if items.is_empty() || items.len() > MAX_BATCH {
        return Err(bad(format!("`requests` holds {} requests; 1 to {MAX_BATCH} are taken", items.len())));
    }
    items
        .into_iter()
        .enumerate()
        .map(|(i, item)| {
            let at = |m: String| bad(format!("request {i}: {m}"));
            if let Some(other) = item.keys().find(|k| !matches!(k.as_str(), "verb" | "args")) {
                return Err(at(format!("unknown key `{other}` (expected: verb, args)")));
            }
            let verb = item
                .get("verb")
                .and_then(|v| serde_json::from_str::<String>(v.get()).ok())
                .ok_or_else(|| at("`verb` must be a string".into()))?;
            if verb == BATCH {
                return Err(at("a batch cannot hold a batch".into()));
            }
            let args = item.get("args").map_or_else(|| b"{}".to_vec(), |a| a.get().as_bytes().to_vec());
            Ok((verb, args))
        })
        .collect()
}

/// The arguments of a request the program answers itself
/// ([`crate::server::Verbs`]): a JSON object no larger than
/// [`MAX_PAYLOAD_BYTES`], `{}` for an empty payload.
pub fn decode_args(verb: &str, payload: &[u8]) -> Result<Json, WireError> {
    payload_object(payload).map(Json::Object).map_err(|why| {
        WireError::bad_request(match why {
            NotAnObject::TooLarge(n) => format!("`{verb}`: the request is {n} bytes, more than {MAX_PAYLOAD_BYTES}"),
            NotAnObject::Other(_) => format!("`{verb}`: the arguments must be a JSON object"),
            NotAnObject::NotJson(e) => format!("`{verb}`: the arguments are not JSON: {e}"),
        })
    })
}

/// Decodes a request payload for `verb`. Never panics, whatever the bytes.
pub fn decode_request(verb: &str, payload: &[u8]) -> Result<Decoded, WireError> {
    if !VERBS.contains(&verb) {
        return Err(WireError {
            kind: "unknown_verb",
            message: format!("unknown request `{verb}`{}", situate_core::suggestion(verb, VERBS.iter().copied())),
        });
    }
    let mut a = payload_args(verb, payload)?;
    match a.take("protocol") {
        None => {}
        Some(Arg::Json(Json::Number(n))) if n.as_i64() == Some(PROTOCOL) => {}
        Some(Arg::Json(Json::Number(n))) if n.is_i64() || n.is_u64() => {
            return Err(WireError {
                kind: "protocol",
                message: format!("protocol {n} is not supported; this manager speaks protocol {PROTOCOL}"),
            })
        }
        Some(other) => {
            return Err(a.wrong("protocol", &format!("an integer (this manager speaks protocol {PROTOCOL})"), &other))
        }
    }
    let decoded = match verb {
        "hello" => Decoded::Hello,
        "activate" => {
            let skills = a.strings("skills", "skill names")?;
            let with_providers = a.boolean("with_providers", Some(false))?;
            Decoded::Manager(Request::Activate { skills, with_providers })
        }
        "deactivate" => Decoded::Manager(Request::Deactivate { skills: a.strings("skills", "skill names")? }),
        "set_param" => {
            let skill = a.string("skill")?;
            let param = a.string("param")?;
            const VALUE: &str = "a value: a bool, number, string, list of numbers, bytes or record";
            let raw = a.take("value").ok_or_else(|| a.missing("value", VALUE))?;
            let value = param_value(&raw).ok_or_else(|| a.wrong("value", VALUE, &raw))?;
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
        // One moment's readings: the manager answers the whole list between two cycles.
        "query_many" => Decoded::Manager(Request::QuerySignals { signals: a.signal_names("signals")? }),
        "skill" => Decoded::Manager(Request::QuerySkill { skill: a.string("skill")? }),
        "skills" => Decoded::Manager(Request::QuerySkills),
        "winners" => Decoded::Manager(Request::QueryWinners),
        "graph" => Decoded::Manager(Request::QueryGraph),
        "stats" => Decoded::Manager(Request::QueryStats),
        "monitor_add" => {
            let condition = match (a.has("condition"), a.has("any")) {
                (false, false) => {
                    return Err(a.missing(
                        "condition",
                        &format!("a string, or instead `any`: a list of 1 to {MAX_ANY_CONDITIONS} strings"),
                    ))
                }
                (true, false) => MonitorCondition::One(a.string("condition")?),
                (false, true) => MonitorCondition::Any(a.conditions("any")?),
                (true, true) => {
                    return Err(WireError::bad_request(
                        "`monitor_add`: give either `condition` (one) or `any` (a list), not both",
                    ))
                }
            };
            let mode = match a.take("mode") {
                None => MonitorMode::Once,
                Some(Arg::Json(Json::String(s))) => MonitorMode::parse(&s).ok_or_else(|| {
                    WireError::bad_request(format!(
                        "`monitor_add`: mode must be \"once\", \"edge\" or \"level\", got {s:?}{}",
                        situate_core::suggestion(&s, ["once", "edge", "level"])
                    ))
                })?,
                Some(other) => return Err(a.wrong("mode", "\"once\", \"edge\" or \"level\"", &other)),
            };
            let pause = a.boolean("pause", Some(false))?;
            let report = if a.has("report") { a.strings("report", "signal or parameter names")? } else { Vec::new() };
            let session = a.session()?;
            let client = if a.has("client") { Some(a.string("client")?) } else { None };
            Decoded::Manager(Request::AddMonitor { condition, mode, pause, report, session, client })
        }
        "monitor_cancel" => {
            let monitor = a.integer("monitor", 0, i64::MAX)? as u64;
            Decoded::Manager(Request::CancelMonitor { monitor, session: a.session()?, force: false })
        }
        "monitor_list" => Decoded::Manager(Request::ListMonitors),
        "telemetry" => {
            let signals = a.strings("signals", "signal names")?;
            let rate_hz = match a.take("rate_hz") {
                None => None,
                Some(Arg::Json(Json::Number(n))) => match n.as_f64() {
                    Some(r) if (MIN_TELEMETRY_HZ..=MAX_TELEMETRY_HZ).contains(&r) => Some(r),
                    _ => {
                        return Err(WireError {
                            kind: "bad_param",
                            message: format!(
                                "`telemetry`: `rate_hz` must be a number from {MIN_TELEMETRY_HZ} to \
                                 {MAX_TELEMETRY_HZ} (a sample at least every 100 s), got {n}"
                            ),
                        })
                    }
                },
                Some(other) => {
                    return Err(a.wrong(
                        "rate_hz",
                        &format!("a number from {MIN_TELEMETRY_HZ} to {MAX_TELEMETRY_HZ}"),
                        &other,
                    ))
                }
            };
            Decoded::Telemetry { signals, rate_hz }
        }
        "run" => Decoded::Manager(Request::Run),
        "stop" => Decoded::Manager(Request::Stop),
        "step" => Decoded::Manager(Request::Step { cycles: a.integer("cycles", 1, 1_000_000)? as u64 }),
        "phase" => {
            let text = a.string("text")?;
            let client = if a.has("client") { Some(a.string("client")?) } else { None };
            Decoded::Manager(Request::Phase { text, client })
        }
        _ => unreachable!("verbs are checked above"),
    };
    a.finish()?;
    Ok(decoded)
}

#[cfg(test)]
mod tests;
