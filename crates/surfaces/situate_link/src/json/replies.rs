//! Replies, errors and events in their JSON forms.

use serde_json::{json, Map, Value as Json};
use situate_manager::control::{GraphInfo, MonitorInfo};
use situate_manager::{ControlError, Event, ManagerStats, Reply, SignalReading, SkillInfo};

use super::values::{opt_value_to_json, value_to_json};
use super::WireError;

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
        ControlError::NotOwner(_) => "not_owner",
        ControlError::Invalid(_) => "invalid",
        ControlError::Interrupted(_) => "interrupted",
        ControlError::Disconnected => "unavailable",
    };
    let mut err = json!({"kind": kind, "message": e.to_string()});
    match e {
        ControlError::MissingProviders { signals, providers, .. } => {
            err["signals"] = json!(signals);
            err["providers"] = json!(providers);
        }
        ControlError::BadCondition { index, column, pointer, message } => {
            err["column"] = json!(column);
            err["pointer"] = json!(pointer);
            match index {
                Some(i) => {
                    err["index"] = json!(i);
                    err["message"] = json!(format!("any[{i}]: column {column}: {message}"));
                }
                None => err["message"] = json!(format!("column {column}: {message}")),
            }
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
        "late_starts": s.late_starts,
        "request_hold_ns": s.request_hold_ns,
        "lost_ns": s.lost_ns,
        "worker_failures": s.worker_failures,
        "rate_hz": s.rate_hz,
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
        "monitor": m.monitor, "condition": m.condition, "any": m.any, "mode": m.mode.name(), "fired": m.fired,
        "holds": m.holds, "pause": m.pause, "report": m.report, "session": m.session, "client": m.client,
    })
}

/// A manager reply's `ok` result.
pub fn reply_to_json(reply: &Reply) -> Json {
    match reply {
        Reply::Done => Json::Null,
        Reply::Activation { changed, at_cycle } => json!({"changed": changed, "at_cycle": at_cycle}),
        Reply::Param(v) => value_to_json(v),
        Reply::Signal(r) => reading_to_json(r),
        Reply::Signals(list) => Json::Array(list.iter().map(reading_to_json).collect()),
        Reply::Skill(s) => skill_to_json(s),
        Reply::Skills(list) => Json::Array(list.iter().map(skill_to_json).collect()),
        Reply::Winners(w) => Json::Array(
            w.iter()
                .map(|w| {
                    json!({"signal": w.signal, "writers": w.writers, "winner": w.winner, "cycle": w.cycle,
                        "switches": w.switches, "held_cycles": w.held_cycles})
                })
                .collect(),
        ),
        Reply::Graph(g) => graph_to_json(g),
        Reply::Stats(s) => stats_to_json(s),
        Reply::MonitorAdded(id) => json!({ "monitor": id }),
        Reply::Monitors(list) => Json::Array(list.iter().map(monitor_to_json).collect()),
        Reply::MonitorsCancelled(ids) => json!({ "cancelled": ids }),
        Reply::Ticked { ran, cycle } => json!({ "ran": ran, "cycle": cycle }),
    }
}

/// An event's key suffix and JSON form.
pub fn event_to_json(e: &Event) -> (&'static str, Json) {
    match e {
        Event::MonitorFired { monitor, condition, cycle, time_s, values, held } => (
            "monitor_fired",
            json!({
                "kind": "monitor_fired", "monitor": monitor, "condition": condition, "cycle": cycle, "time_s": time_s,
                "values": values.iter().map(|(n, v)| (n.clone(), opt_value_to_json(v))).collect::<Map<_, _>>(),
                "held": held,
            }),
        ),
        Event::ActivationApplied { activated, deactivated, cycle } => (
            "activation_applied",
            json!({"kind": "activation_applied", "activated": activated, "deactivated": deactivated, "cycle": cycle}),
        ),
        Event::PriorityChanged { skill, priority, cycle } => (
            "priority_changed",
            json!({"kind": "priority_changed", "skill": skill, "priority": priority, "cycle": cycle}),
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
        Event::MonitorCancelled { monitor, condition, session, reason, cycle } => (
            "monitor_cancelled",
            json!({"kind": "monitor_cancelled", "monitor": monitor, "condition": condition, "session": session,
                   "reason": reason.name(), "cycle": cycle}),
        ),
        Event::ManagerStarted { cycle } => ("manager_started", json!({"kind": "manager_started", "cycle": cycle})),
        Event::ManagerStopped { cycle } => ("manager_stopped", json!({"kind": "manager_stopped", "cycle": cycle})),
        Event::WorkerFailed { thread, cause, action } => {
            ("worker_failed", json!({"kind": "worker_failed", "thread": thread, "cause": cause, "action": action}))
        }
        Event::Phase { text, client, cycle } => {
            ("phase", json!({"kind": "phase", "text": text, "client": client, "cycle": cycle}))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::Value;
    use situate_manager::MonitorMode;

    #[test]
    fn events_errors_and_the_list_say_which_condition_of_an_any() {
        let (key, j) = event_to_json(&Event::MonitorFired {
            monitor: 4,
            condition: "(a) || (b)".into(),
            cycle: 9,
            time_s: 0.9,
            values: vec![("a".into(), Some(Value::Bool(false))), ("b".into(), Some(Value::Bool(true)))],
            held: vec![1],
        });
        assert_eq!(key, "monitor_fired");
        assert_eq!(
            j,
            json!({"kind": "monitor_fired", "monitor": 4, "condition": "(a) || (b)", "cycle": 9, "time_s": 0.9,
                   "values": {"a": false, "b": true}, "held": [1]})
        );
        let bad = ControlError::BadCondition { index: Some(2), column: 5, message: "m".into(), pointer: "p".into() };
        assert_eq!(
            control_error(&bad),
            json!({"error": {"kind": "bad_condition", "message": "any[2]: column 5: m", "column": 5, "pointer": "p", "index": 2}})
        );
        let bad = ControlError::BadCondition { index: None, column: 5, message: "m".into(), pointer: "p".into() };
        assert_eq!(
            control_error(&bad),
            json!({"error": {"kind": "bad_condition", "message": "column 5: m", "column": 5, "pointer": "p"}})
        );
        let info = MonitorInfo {
            monitor: 1,
            condition: "(a) || (b)".into(),
            any: Some(vec!["a".into(), "b".into()]),
            mode: MonitorMode::Once,
            fired: 0,
            holds: false,
            pause: false,
            report: vec![],
            session: None,
            client: None,
        };
        assert_eq!(monitor_to_json(&info)["any"], json!(["a", "b"]));
        assert_eq!(monitor_to_json(&MonitorInfo { any: None, ..info })["any"], Json::Null);
    }
}
