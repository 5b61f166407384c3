//! The robot's wiring in a recording, and a robot rebuilt from it alone.
//!
//! A recording holds every leaf a cycle wrote, but a leaf path does not say
//! which skill wrote it, through which port, nor what the skill declared
//! (`truth.pose` may be a record signal or a field of `truth`). So the
//! recorder also writes the robot's wiring into the `situate` metadata
//! record (key [`WIRING_METADATA`]): each skill instance with its type, kind,
//! state (active, priority, parameter values) when the recording started,
//! its ports and the signals they connect to, and its parameters'
//! declarations.
//!
//! From that, [`view`] builds a robot of players only (see
//! [`crate::replay`]): one per recorded skill, with its outputs wired to the
//! same signals, its parameters and priority, and its state at the start.
//! It needs neither the robot file nor any skill's code or library: a
//! recording can be opened, stepped and plotted on a machine that never had
//! the robot (`situate replay FILE --view`).

use std::sync::Arc;

use serde_json::{json, Value as Json};
use situate_core::{ParamSpec, ParamType, PortSpec, SignalType, SkillDecl, SkillKind, Value};
use situate_link::json::{value_from_json, value_to_json};
use situate_manager::control::SkillInfo;
use situate_manager::Registry;
use situate_robotfile::config::{ClockKind, ExecutorKind, MAX_DEADLINE_MS};
use situate_robotfile::spec::{RobotSpec, SkillSpec};

use crate::read::Recording;
use crate::replay::{player_type, Cast};

/// The `situate` metadata's key for the robot's wiring (a JSON object).
pub const WIRING_METADATA: &str = "wiring";

/// The wiring's format; a reader refuses another.
const VERSION: u64 = 1;

/// The wiring of a robot whose skills are `skills` (as
/// [`situate_manager::Request::QuerySkills`] answers), as the metadata holds it.
pub fn to_json(skills: &[SkillInfo]) -> Json {
    let skills: Vec<Json> = skills
        .iter()
        .map(|s| {
            let ports = |ports: &[situate_manager::control::PortInfo]| -> Vec<Json> {
                ports
                    .iter()
                    .map(|p| json!({"port": p.name, "signal": p.signal, "type": p.ty.to_string(), "optional": p.optional}))
                    .collect()
            };
            let params: Vec<Json> = s
                .params
                .iter()
                .map(|(spec, value)| {
                    json!({"name": spec.name, "type": spec.ty.name(), "value": value_to_json(value),
                           "default": value_to_json(&spec.default), "min": spec.min, "max": spec.max,
                           "unit": spec.unit, "doc": spec.doc})
                })
                .collect();
            json!({"name": s.name, "type": s.type_name, "kind": s.kind.name(), "doc": s.doc, "active": s.active,
                   "priority": s.priority, "inputs": ports(&s.inputs), "outputs": ports(&s.outputs), "params": params})
        })
        .collect();
    json!({"version": VERSION, "skills": skills})
}

/// A robot of players rebuilt from a recording's wiring ([`view`]).
pub struct View {
    pub spec: RobotSpec,
    pub registry: Registry,
    /// Every skill is a player; set `cast.tape` once the manager is built.
    pub cast: Cast,
}

/// Builds, from `rec`'s wiring alone, a robot whose every skill is a player
/// of its recorded outputs: same names, same output signals and types, same
/// parameters, priorities and state at the recording's start. The robot
/// runs on the simulated clock, serially, at the recorded period, with no
/// deadlines. A recording without wiring (made before it was recorded), or
/// with wiring that cannot be read, is an error saying which skill and field.
pub fn view(rec: &Recording) -> Result<View, String> {
    let Some(text) = rec.metadata.get(WIRING_METADATA) else {
        return Err(format!(
            "the recording holds no robot wiring (the `situate` metadata has no `{WIRING_METADATA}`: it was recorded \
             before recordings held it); replay it with its robot file instead (without --view)"
        ));
    };
    let bad = |message: String| format!("the metadata's `{WIRING_METADATA}`: {message}");
    let wiring: Json = serde_json::from_str(text).map_err(|e| bad(format!("not JSON: {e}")))?;
    match wiring.get("version").and_then(Json::as_u64) {
        Some(VERSION) => {}
        other => {
            return Err(bad(format!(
                "version {}, this situate reads version {VERSION}",
                other.map_or("missing".to_string(), |v| v.to_string())
            )))
        }
    }
    let skills = wiring.get("skills").and_then(Json::as_array).ok_or_else(|| bad("no `skills` list".into()))?;
    let mut spec = RobotSpec::new(rec.metadata.get("robot").map_or("recording", String::as_str));
    spec.clock = ClockKind::Simulated;
    spec.executor = ExecutorKind::Serial;
    if let Some(p) = rec.period_s() {
        spec.period_s = p;
    }
    let no_deadline = Some(MAX_DEADLINE_MS);
    spec.budget_ms = no_deadline;
    spec.liveness_ms = no_deadline;
    let mut registry = Registry::new();
    let mut cast = Cast::default();
    for (k, s) in skills.iter().enumerate() {
        let (decl, instance) = skill(s).map_err(|e| {
            let name = s.get("name").and_then(Json::as_str).map_or(String::new(), |n| format!(" (`{n}`)"));
            bad(format!("skill {k}{name}: {e}"))
        })?;
        let type_name = format!("replay.{}", instance.name);
        registry.add(player_type(&type_name, &decl, &instance.name, Arc::clone(&cast.tape)));
        let mut instance = instance;
        instance.type_name = type_name;
        instance.budget_ms = no_deadline;
        instance.liveness_ms = no_deadline;
        cast.players.push(instance.name.clone());
        spec.skills.push(instance);
    }
    Ok(View { spec, registry, cast })
}

/// One skill of the wiring: its declaration (outputs connected to the
/// recorded signals) and its instance (state at the start).
fn skill(s: &Json) -> Result<(SkillDecl, SkillSpec), String> {
    let text = |j: &Json, key: &str| -> Result<String, String> {
        j.get(key).and_then(Json::as_str).map(String::from).ok_or_else(|| format!("`{key}` is not a string"))
    };
    let name = text(s, "name")?;
    let kind = text(s, "kind")?;
    let kind = SkillKind::parse(&kind).ok_or_else(|| format!("`kind` {kind:?} is not sync, async or device"))?;
    let mut decl = SkillDecl::new(&text(s, "type")?, kind);
    decl.doc = s.get("doc").and_then(Json::as_str).unwrap_or_default().to_string();
    decl.priority = s
        .get("priority")
        .and_then(Json::as_i64)
        .and_then(|p| i32::try_from(p).ok())
        .ok_or_else(|| "`priority` is not a 32-bit integer".to_string())?;
    let active = s.get("active").and_then(Json::as_bool).ok_or_else(|| "`active` is not true or false".to_string())?;
    for (k, p) in
        s.get("outputs").and_then(Json::as_array).ok_or_else(|| "no `outputs` list".to_string())?.iter().enumerate()
    {
        let at = |e: String| format!("output {k}: {e}");
        let ty = text(p, "type").map_err(at)?;
        let ty = SignalType::parse(&ty).map_err(|e| at(format!("type {ty:?}: {e}")))?;
        let mut port = PortSpec::new(&text(p, "port").map_err(at)?, ty);
        port.signal = text(p, "signal").map_err(at)?;
        decl.outputs.push(port);
    }
    let mut instance = SkillSpec::new(&name, &decl.type_name).active(active).priority(decl.priority);
    for (k, p) in
        s.get("params").and_then(Json::as_array).ok_or_else(|| "no `params` list".to_string())?.iter().enumerate()
    {
        let pname = text(p, "name").map_err(|e| format!("parameter {k}: {e}"))?;
        let at = |e: String| format!("parameter `{pname}`: {e}");
        let ty = match text(p, "type").map_err(at)?.as_str() {
            "bool" => ParamType::Bool,
            "i64" => ParamType::I64,
            "f64" => ParamType::F64,
            "string" => ParamType::Str,
            other => return Err(at(format!("type {other:?} is not bool, i64, f64 or string"))),
        };
        let value = |key: &str| -> Result<Value, String> {
            let signal = match ty {
                ParamType::Bool => SignalType::Bool,
                ParamType::I64 => SignalType::I64,
                ParamType::F64 => SignalType::F64,
                ParamType::Str => SignalType::Str,
            };
            value_from_json(p.get(key).unwrap_or(&Json::Null), &signal).map_err(|e| at(format!("`{key}`: {e}")))
        };
        let bound = |key: &str| p.get(key).and_then(Json::as_f64);
        let mut param = ParamSpec::new(&pname, ty, value("default")?).range(bound("min"), bound("max"));
        param.unit = p.get("unit").and_then(Json::as_str).unwrap_or_default().to_string();
        param.doc = p.get("doc").and_then(Json::as_str).unwrap_or_default().to_string();
        decl.params.push(param);
        instance = instance.param(&pname, value("value")?);
    }
    Ok((decl, instance))
}
