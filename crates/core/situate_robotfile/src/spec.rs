//! What to build: a robot as a list of skill instances, from a robot file or
//! from code, and the diagnostics that building it can give.
//!
//! A [`RobotSpec`] is the robot file lifted into plain data, positions kept,
//! so the same checks (and the same `FILE:LINE:COL: error: …` messages) apply
//! whether the robot came from YAML or was assembled in a test.

use std::fmt;

use situate_core::Value;

use crate::config::{ClockKind, ExecutorKind, RobotFile, Section};
pub use crate::diagnostic::{Diagnostic, Severity};
use crate::yaml::Pos;

/// All diagnostics of a failed build, errors first.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct BuildError {
    pub diagnostics: Vec<Diagnostic>,
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, d) in self.diagnostics.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{d}")?;
        }
        Ok(())
    }
}

/// One parameter value given for an instance.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamEntry {
    pub name: String,
    pub value: Value,
    pub name_pos: Option<Pos>,
    pub value_pos: Option<Pos>,
    /// The value as a robot file writes it (`1e300`), quoted by messages
    /// instead of the value's own digits.
    pub written: Option<String>,
}

/// One port remap: `port` connects to `signal` instead of its default.
#[derive(Debug, Clone, PartialEq)]
pub struct RemapEntry {
    pub port: String,
    pub signal: String,
    pub port_pos: Option<Pos>,
    pub signal_pos: Option<Pos>,
}

/// One skill instance of a robot.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillSpec {
    pub name: String,
    pub type_name: String,
    pub active: bool,
    /// Overrides the type's declared priority.
    pub priority: Option<i32>,
    /// The worker period of a threaded skill (dskill or async cskill).
    pub period_ms: Option<f64>,
    /// Execution budget of one in-cycle run (overrides the robot's).
    pub budget_ms: Option<f64>,
    /// Liveness deadline of a threaded body's run (overrides the robot's).
    pub liveness_ms: Option<f64>,
    pub params: Vec<ParamEntry>,
    pub remap: Vec<RemapEntry>,
    /// Where the robot file put it (`devices` or `skills`), if it came from one.
    pub section: Option<Section>,
    pub pos: Option<Pos>,
    pub name_pos: Option<Pos>,
    pub type_pos: Option<Pos>,
    pub priority_pos: Option<Pos>,
}

impl SkillSpec {
    pub fn new(name: &str, type_name: &str) -> Self {
        SkillSpec {
            name: name.into(),
            type_name: type_name.into(),
            active: true,
            priority: None,
            period_ms: None,
            budget_ms: None,
            liveness_ms: None,
            params: Vec::new(),
            remap: Vec::new(),
            section: None,
            pos: None,
            name_pos: None,
            type_pos: None,
            priority_pos: None,
        }
    }

    pub fn active(mut self, active: bool) -> Self {
        self.active = active;
        self
    }

    pub fn priority(mut self, priority: i32) -> Self {
        self.priority = Some(priority);
        self
    }

    pub fn param(mut self, name: &str, value: Value) -> Self {
        self.params.push(ParamEntry { name: name.into(), value, name_pos: None, value_pos: None, written: None });
        self
    }

    pub fn remap(mut self, port: &str, signal: &str) -> Self {
        self.remap.push(RemapEntry { port: port.into(), signal: signal.into(), port_pos: None, signal_pos: None });
        self
    }

    pub fn period_ms(mut self, period_ms: f64) -> Self {
        self.period_ms = Some(period_ms);
        self
    }

    pub fn budget_ms(mut self, budget_ms: f64) -> Self {
        self.budget_ms = Some(budget_ms);
        self
    }

    pub fn liveness_ms(mut self, liveness_ms: f64) -> Self {
        self.liveness_ms = Some(liveness_ms);
        self
    }
}

/// A whole robot: its name, its cycle and its skill instances.
#[derive(Debug, Clone, PartialEq)]
pub struct RobotSpec {
    pub robot: String,
    pub period_s: f64,
    pub clock: ClockKind,
    pub executor: ExecutorKind,
    pub threads: Option<usize>,
    /// Default execution budget of a sync cskill's run, ms (the skill
    /// manager's `graph::default_budget` when not given).
    pub budget_ms: Option<f64>,
    /// Default liveness deadline of a threaded body's run, ms (the skill
    /// manager's `graph::default_liveness` when not given).
    pub liveness_ms: Option<f64>,
    pub skills: Vec<SkillSpec>,
    /// The robot file it came from, for messages.
    pub file: Option<String>,
    /// The files a position may be in, by [`Pos::src`]: `[0]` the robot
    /// file, then those it includes (empty: all positions are in `file`).
    pub sources: Vec<String>,
}

impl RobotSpec {
    pub fn new(robot: &str) -> Self {
        RobotSpec {
            robot: robot.into(),
            period_s: 0.05,
            clock: ClockKind::Wall,
            executor: ExecutorKind::Serial,
            threads: None,
            budget_ms: None,
            liveness_ms: None,
            skills: Vec::new(),
            file: None,
            sources: Vec::new(),
        }
    }

    /// The default execution budget of every sync cskill, ms.
    pub fn budget_ms(mut self, budget_ms: f64) -> Self {
        self.budget_ms = Some(budget_ms);
        self
    }

    /// The default liveness deadline of every async cskill and dskill, ms.
    pub fn liveness_ms(mut self, liveness_ms: f64) -> Self {
        self.liveness_ms = Some(liveness_ms);
        self
    }

    pub fn period_s(mut self, period_s: f64) -> Self {
        self.period_s = period_s;
        self
    }

    pub fn clock(mut self, clock: ClockKind) -> Self {
        self.clock = clock;
        self
    }

    pub fn executor(mut self, executor: ExecutorKind, threads: Option<usize>) -> Self {
        self.executor = executor;
        self.threads = threads;
        self
    }

    pub fn skill(mut self, skill: SkillSpec) -> Self {
        self.skills.push(skill);
        self
    }

    /// Lifts a parsed robot file.
    pub fn from_file(file: &RobotFile) -> Self {
        RobotSpec {
            robot: file.robot.value.clone(),
            period_s: file.cycle.period_s,
            clock: file.cycle.clock,
            executor: file.cycle.executor,
            threads: file.cycle.threads,
            budget_ms: file.cycle.budget_ms,
            liveness_ms: file.cycle.liveness_ms,
            file: Some(file.file.clone()),
            sources: file.sources.iter().map(|s| s.file.clone()).collect(),
            skills: file
                .skills
                .iter()
                .map(|e| SkillSpec {
                    name: e.name.value.clone(),
                    type_name: e.type_name.value.clone(),
                    active: e.active,
                    priority: e.priority.as_ref().map(|p| p.value),
                    period_ms: e.period_ms.as_ref().map(|p| p.value),
                    budget_ms: e.budget_ms.as_ref().map(|p| p.value),
                    liveness_ms: e.liveness_ms.as_ref().map(|p| p.value),
                    params: e
                        .params
                        .iter()
                        .map(|p| ParamEntry {
                            name: p.name.value.clone(),
                            value: p.value.value.clone(),
                            name_pos: Some(p.name.pos),
                            value_pos: Some(p.value.pos),
                            written: p.written.clone(),
                        })
                        .collect(),
                    remap: e
                        .remap
                        .iter()
                        .map(|(k, v)| RemapEntry {
                            port: k.value.clone(),
                            signal: v.value.clone(),
                            port_pos: Some(k.pos),
                            signal_pos: Some(v.pos),
                        })
                        .collect(),
                    section: Some(e.section),
                    pos: Some(e.pos),
                    name_pos: Some(e.name.pos),
                    type_pos: Some(e.type_name.pos),
                    priority_pos: e.priority.as_ref().map(|p| p.pos),
                })
                .collect(),
        }
    }

    /// A diagnostic at `pos`, naming the file the position is in (this
    /// robot's file, or one it includes).
    pub fn diag(&self, severity: Severity, pos: Option<Pos>, message: String) -> Diagnostic {
        let file = match pos {
            Some(p) if p.src > 0 => self.sources.get(p.src).cloned().or_else(|| self.file.clone()),
            _ => self.file.clone(),
        };
        Diagnostic { severity, file, pos, element: None, message }
    }
}
