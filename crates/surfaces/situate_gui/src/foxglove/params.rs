//! Parameters (`skill.param`) over Foxglove: their names and Foxglove form, `getParameters` and
//! `setParameters` answered through the manager's handle.

use std::collections::HashMap;

use serde_json::{json, Value as Json};
use situate_core::Value;
use situate_link::json as wire;
use situate_manager::{Reply, Request};

use super::protocol::{status, ERROR};
use crate::{ask, Shared};

/// `parameterNames`: an array of strings (missing: none, which means all).
pub(super) fn parameter_names(msg: &Json) -> Result<Vec<String>, String> {
    match msg.get("parameterNames") {
        None | Some(Json::Null) => Ok(vec![]),
        Some(Json::Array(a)) if a.iter().all(Json::is_string) => {
            Ok(a.iter().filter_map(Json::as_str).map(String::from).collect())
        }
        Some(_) => Err("`parameterNames` must be an array of strings".into()),
    }
}

/// A parameter value for Foxglove, with its `type` when it is a float (so `2.0` stays a float).
pub(super) fn parameter(name: String, v: &Value) -> Json {
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
pub(super) fn parameters(shared: &Shared, msg: &Json) -> Vec<Json> {
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
