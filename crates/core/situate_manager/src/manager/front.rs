//! The part of a request's work that needs only the robot's wiring, which
//! never changes once built: names looked up (an unknown one refused with
//! its "did you mean"), parameter values checked, monitor conditions
//! compiled. A [`Handle`](crate::Handle) does it on the caller's thread (the
//! link's bridge, the GUI's server) before the request reaches the manager,
//! so no request, however large, costs the cycle's thread more than the
//! cheap rest: applying a change, or reading the state for a query.
//!
//! The manager runs the same checks for requests it handles itself
//! ([`Manager::request`](crate::Manager::request)); they are cheap to repeat.

use std::cell::RefCell;

use situate_core::{suggestion, SignalType};
use situate_expr::{Condition, Resolver};

use super::RefTarget;
use crate::control::{ControlError, Request};
use crate::graph::Graph;
use crate::monitor::{MonitorCondition, MAX_ANY_CONDITIONS};

/// A monitor compiled against the wiring: its references are local ids into
/// `targets`, turned into the manager's own when it is installed.
#[derive(Debug, Clone)]
pub(crate) struct PreparedMonitor {
    pub conditions: Vec<Condition>,
    pub any: bool,
    pub targets: Vec<RefTarget>,
    /// `report` names (records as their leaves) with local ids.
    pub reported: Vec<(String, usize)>,
}

pub(crate) fn find(graph: &Graph, name: &str) -> Result<usize, ControlError> {
    graph.instance(name).ok_or_else(|| ControlError::UnknownSkill {
        name: name.to_string(),
        suggestion: suggestion(name, graph.instances.iter().map(|d| d.name.as_str())),
    })
}

pub(crate) fn find_param(graph: &Graph, skill: &str, param: &str) -> Result<(usize, usize), ControlError> {
    let i = find(graph, skill)?;
    let decl = &graph.instances[i].skill_type.decl;
    match decl.param(param) {
        Some((p, _)) => Ok((i, p)),
        None => Err(ControlError::UnknownParam {
            skill: skill.into(),
            param: param.into(),
            suggestion: situate_core::param_suggestion(param, decl.params.iter().map(|p| p.name.as_str())),
        }),
    }
}

pub(crate) fn check_step(cycles: u64) -> Result<(), ControlError> {
    if cycles > 1_000_000_000 {
        return Err(ControlError::Invalid(format!("step: {cycles} cycles is too many at once")));
    }
    Ok(())
}

/// Checks `request` against the wiring and does the work that needs nothing
/// else: a refused request is refused here, with the manager's own error. A
/// `set_param` value is replaced by the checked one; an `AddMonitor`'s
/// conditions come back compiled.
pub(crate) fn prepare(graph: &Graph, request: &mut Request) -> Result<Option<PreparedMonitor>, ControlError> {
    match request {
        Request::Activate { skills, .. } | Request::Deactivate { skills } => {
            for n in skills.iter() {
                find(graph, n)?;
            }
        }
        Request::SetParam { skill, param, value } => {
            let (i, p) = find_param(graph, skill, param)?;
            let spec = &graph.instances[i].skill_type.decl.params[p];
            *value = spec.check(value).map_err(|e| ControlError::BadParam {
                skill: skill.clone(),
                param: param.clone(),
                reason: e.to_string(),
            })?;
        }
        Request::GetParam { skill, param } => {
            find_param(graph, skill, param)?;
        }
        Request::SetPriority { skill, .. } | Request::SetVerbose { skill, .. } | Request::QuerySkill { skill } => {
            find(graph, skill)?;
        }
        Request::QuerySignal { signal } if graph.signal_type(signal).is_none() => {
            return Err(unknown_signal(graph, signal));
        }
        Request::QuerySignals { signals } => {
            if let Some(s) = signals.iter().find(|s| graph.signal_type(s).is_none()) {
                return Err(unknown_signal(graph, s));
            }
        }
        Request::AddMonitor { condition, report, .. } => return prepare_monitor(graph, condition, report).map(Some),
        Request::Step { cycles } => check_step(*cycles)?,
        Request::Phase { text, .. } => check_phase(text)?,
        _ => {}
    }
    Ok(None)
}

/// A phase's text: 1 to [`crate::control::MAX_PHASE_TEXT`] characters, no control character
/// (one line on a timeline).
pub(crate) fn check_phase(text: &str) -> Result<(), ControlError> {
    let n = text.chars().count();
    if n == 0 || n > crate::control::MAX_PHASE_TEXT {
        return Err(ControlError::Invalid(format!(
            "`phase`: the text must be 1 to {} characters, got {n}",
            crate::control::MAX_PHASE_TEXT
        )));
    }
    if let Some(c) = text.chars().find(|c| c.is_control()) {
        return Err(ControlError::Invalid(format!(
            "`phase`: the text must be one line without control characters, got {:?} in it",
            c
        )));
    }
    Ok(())
}

/// [`prepare`], the compiled monitor boxed (it travels in the request queue).
pub(crate) fn prepare_boxed(
    graph: &Graph,
    request: &mut Request,
) -> Result<Option<Box<PreparedMonitor>>, ControlError> {
    prepare(graph, request).map(|m| m.map(Box::new))
}

pub(crate) fn unknown_signal(graph: &Graph, path: &str) -> ControlError {
    ControlError::UnknownSignal { name: path.into(), suggestion: suggestion(path, graph.signal_names()) }
}

/// Compiles a monitor's conditions and resolves its `report` names.
pub(crate) fn prepare_monitor(
    graph: &Graph,
    condition: &MonitorCondition,
    report: &[String],
) -> Result<PreparedMonitor, ControlError> {
    let (texts, any) = match condition {
        MonitorCondition::One(c) => (std::slice::from_ref(c), false),
        MonitorCondition::Any(list) => (list.as_slice(), true),
    };
    if texts.is_empty() || texts.len() > MAX_ANY_CONDITIONS {
        return Err(ControlError::Invalid(format!(
            "monitor_add: `any` has {} conditions, it takes 1 to {MAX_ANY_CONDITIONS}",
            texts.len()
        )));
    }
    let resolver = GraphResolver { graph, targets: RefCell::new(Vec::new()) };
    let mut conditions = Vec::with_capacity(texts.len());
    for (i, text) in texts.iter().enumerate() {
        conditions.push(Condition::compile(text, &resolver).map_err(|e| ControlError::BadCondition {
            index: any.then_some(i),
            column: e.column,
            message: e.message.clone(),
            pointer: e.pointer(text),
        })?);
    }
    let mut reported = Vec::new();
    for name in report {
        let name = name.trim();
        // A whole record is reported as its leaves, each by its own name.
        let prefix = format!("{name}.");
        let mut leaves: Vec<&str> = if graph.records.contains_key(name) {
            graph.leaf_index.keys().filter(|k| k.starts_with(&prefix)).map(String::as_str).collect()
        } else {
            vec![name]
        };
        leaves.sort_unstable();
        for leaf in leaves {
            let (r, _) = resolver.resolve(leaf).map_err(ControlError::BadReport)?;
            reported.push((leaf.to_string(), r));
        }
    }
    Ok(PreparedMonitor { conditions, any, targets: resolver.targets.into_inner(), reported })
}

/// Resolves the names of conditions to local ids (interned in `targets`).
struct GraphResolver<'a> {
    graph: &'a Graph,
    targets: RefCell<Vec<RefTarget>>,
}

impl GraphResolver<'_> {
    fn intern(&self, target: RefTarget) -> usize {
        let mut targets = self.targets.borrow_mut();
        if let Some(i) = targets.iter().position(|t| *t == target) {
            return i;
        }
        targets.push(target);
        targets.len() - 1
    }
}

impl Resolver for GraphResolver<'_> {
    fn resolve(&self, path: &str) -> Result<(usize, SignalType), String> {
        let g = self.graph;
        if let Some(&l) = g.leaf_index.get(path) {
            return Ok((self.intern(RefTarget::Leaf(l)), g.leaves[l].ty.clone()));
        }
        if let Some(ty) = g.records.get(path) {
            // The expression language reports records as not comparable.
            return Ok((usize::MAX, ty.clone()));
        }
        match path {
            "time" => return Ok((self.intern(RefTarget::Time), SignalType::F64)),
            "cycle" => return Ok((self.intern(RefTarget::Cycle), SignalType::I64)),
            _ => {}
        }
        let first = path.split('.').next().unwrap_or(path);
        let is_signal_prefix = g.records.contains_key(first) || g.leaf_index.contains_key(first);
        if let Some((skill, param)) = path.split_once('.').filter(|_| !is_signal_prefix) {
            if let Some(i) = g.instance(skill) {
                let decl = &g.instances[i].skill_type.decl;
                return match decl.param(param) {
                    Some((p, spec)) => {
                        let ty = match spec.ty {
                            situate_core::ParamType::Bool => SignalType::Bool,
                            situate_core::ParamType::I64 => SignalType::I64,
                            situate_core::ParamType::F64 => SignalType::F64,
                            situate_core::ParamType::Str => SignalType::Str,
                        };
                        Ok((self.intern(RefTarget::Param(i, p)), ty))
                    }
                    None => Err(format!(
                        "skill `{skill}` has no parameter `{param}`{}",
                        suggestion(param, decl.params.iter().map(|p| p.name.as_str()))
                    )),
                };
            }
        }
        Err(format!("unknown signal `{path}`{}", suggestion(path, g.signal_names())))
    }
}
