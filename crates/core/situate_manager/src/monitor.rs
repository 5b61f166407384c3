//! Monitors: conditions the sequencer asks the skill manager to watch.
//!
//! The sequencer knows what matters to the task; only the skill level sees
//! high-frequency data (paper 3.2.2). A monitor is a condition over signals
//! and parameters (see [`crate::expr`]), compiled once and evaluated at the
//! end of every cycle; when it holds, an event goes back to the sequencer.
//!
//! Modes:
//! - [`MonitorMode::Once`]: the first cycle it holds, then it is removed;
//! - [`MonitorMode::Edge`]: every cycle it holds after a cycle it did not (a
//!   condition already true at its first evaluation fires then);
//! - [`MonitorMode::Level`]: every cycle it holds.
//!
//! A condition whose values are missing (never written, index out of range)
//! does not hold.
//!
//! A monitor watches one condition, or any of several (`any`, at most
//! [`MAX_ANY_CONDITIONS`]): it then holds in a cycle where at least one of
//! them holds, and the modes apply to that disjunction. Each condition is
//! compiled once; each is evaluated at the end of a cycle in which a name it
//! reads changed (see [`Monitors::evaluate`]), and the ones that held are
//! kept as a bit set, turned into the event's `held` indexes only when the
//! monitor fires. The sequencer learns which of its alternatives happened
//! without evaluating anything itself.
//!
//! A monitor's events carry the value of every name its conditions read,
//! and of the names it was asked to `report` besides: what the sequencer
//! will read next arrives with the event, as of the cycle it fired in.
//!
//! A monitor added with `pause` also stops the cycle at the end of the cycle
//! it fires in (the manager then serves requests until told to run again),
//! and ends a `step` there.
//! A sequencer that reacts to the event and then resumes the cycle makes
//! its decisions at exactly the cycle the condition held, however slow the
//! link: runs on the simulated clock replay exactly.

use std::fmt;

use situate_expr::{Condition, Lookup};

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MonitorMode {
    Once,
    Edge,
    Level,
}

impl MonitorMode {
    pub fn parse(text: &str) -> Option<MonitorMode> {
        match text {
            "once" => Some(MonitorMode::Once),
            "edge" => Some(MonitorMode::Edge),
            "level" => Some(MonitorMode::Level),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            MonitorMode::Once => "once",
            MonitorMode::Edge => "edge",
            MonitorMode::Level => "level",
        }
    }
}

impl fmt::Display for MonitorMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The most conditions one `any` monitor watches (the bit set of those that
/// held is one `u64`).
pub const MAX_ANY_CONDITIONS: usize = 64;

/// What a monitor watches: one condition, or any of several.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum MonitorCondition {
    /// One condition; its events' `held` is `[0]`.
    One(String),
    /// Any of these (1 to [`MAX_ANY_CONDITIONS`]); its events' `held` lists
    /// the indexes of those that held in the cycle it fired in.
    Any(Vec<String>),
}

impl MonitorCondition {
    /// The conditions' texts, in order (one for [`MonitorCondition::One`]).
    pub fn texts(&self) -> &[String] {
        match self {
            MonitorCondition::One(c) => std::slice::from_ref(c),
            MonitorCondition::Any(list) => list,
        }
    }
}

impl From<&str> for MonitorCondition {
    fn from(condition: &str) -> Self {
        MonitorCondition::One(condition.to_string())
    }
}

impl From<String> for MonitorCondition {
    fn from(condition: String) -> Self {
        MonitorCondition::One(condition)
    }
}

/// The disjunction's text as one condition: `(a) || (b) || (c)`.
pub fn any_source(conditions: &[String]) -> String {
    conditions.iter().map(|c| format!("({c})")).collect::<Vec<_>>().join(" || ")
}

pub(crate) struct Monitor {
    pub id: u64,
    /// Compiled once, in the order given.
    pub conditions: Vec<Condition>,
    /// Added with `any` (else one condition).
    pub any: bool,
    /// The text events and the list show: the condition, or the disjunction
    /// of an `any`'s.
    pub source: String,
    /// Every name the conditions read, each once, in first-use order, with
    /// its reference id.
    pub reads: Vec<(String, usize)>,
    pub mode: MonitorMode,
    pub holds: bool,
    /// Bit `i`: condition `i` held at the last evaluation.
    pub held: u64,
    /// Not evaluated yet: the first evaluation runs every condition.
    pub new: bool,
    pub fired: u64,
    pub pause: bool,
    /// Extra names the events carry, as written, with their reference ids.
    pub report: Vec<(String, usize)>,
    /// The names `report` asked for, as written (records not expanded).
    pub report_asked: Vec<String>,
    /// The session that holds it (`None`: the program itself).
    pub session: Option<String>,
    /// The name its client gave, if any.
    pub client: Option<String>,
}

#[derive(Default)]
pub(crate) struct Monitors {
    pub list: Vec<Monitor>,
    next_id: u64,
    /// Conditions evaluated so far (see [`Monitors::evaluate`]).
    pub evaluations: u64,
}

impl Monitors {
    /// Adds a monitor on `conditions` (1 to [`MAX_ANY_CONDITIONS`], checked
    /// by the caller); `any` says it was asked as a list.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &mut self,
        conditions: Vec<Condition>,
        any: bool,
        mode: MonitorMode,
        pause: bool,
        report: Vec<(String, usize)>,
        report_asked: Vec<String>,
        session: Option<String>,
        client: Option<String>,
    ) -> u64 {
        debug_assert!((1..=MAX_ANY_CONDITIONS).contains(&conditions.len()));
        self.next_id += 1;
        let id = self.next_id;
        let source = if any {
            any_source(&conditions.iter().map(|c| c.source().to_string()).collect::<Vec<_>>())
        } else {
            conditions.first().map(|c| c.source().to_string()).unwrap_or_default()
        };
        let mut reads: Vec<(String, usize)> = Vec::new();
        for c in &conditions {
            for (&r, name) in c.refs().iter().zip(c.ref_names()) {
                if !reads.iter().any(|(n, _)| n == name) {
                    reads.push((name.clone(), r));
                }
            }
        }
        self.list.push(Monitor {
            id,
            conditions,
            any,
            source,
            reads,
            mode,
            holds: false,
            held: 0,
            new: true,
            fired: 0,
            pause,
            report,
            report_asked,
            session,
            client,
        });
        id
    }

    /// The monitors of `session` and the conditions they watch.
    pub fn count_of(&self, session: Option<&str>) -> (usize, usize) {
        self.list
            .iter()
            .filter(|m| m.session.as_deref() == session)
            .fold((0, 0), |(n, c), m| (n + 1, c + m.conditions.len()))
    }

    /// How many conditions all the monitors watch (what a cycle evaluates).
    pub fn condition_count(&self) -> usize {
        self.list.iter().map(|m| m.conditions.len()).sum()
    }

    /// The monitor `id`, if it is there.
    pub fn get(&self, id: u64) -> Option<&Monitor> {
        self.list.iter().find(|m| m.id == id)
    }

    /// Removes monitor `id`; returns it.
    pub fn cancel(&mut self, id: u64) -> Option<Monitor> {
        let i = self.list.iter().position(|m| m.id == id)?;
        Some(self.list.remove(i))
    }

    /// Removes every monitor of `session`; returns them, in the order they were added.
    pub fn end_session(&mut self, session: &str) -> Vec<Monitor> {
        let (gone, kept) =
            std::mem::take(&mut self.list).into_iter().partition(|m| m.session.as_deref() == Some(session));
        self.list = kept;
        gone
    }

    /// Evaluates every monitor; calls `fire` for each that fires this cycle.
    ///
    /// A condition is evaluated only when something it reads may have
    /// changed since its last evaluation — `changed(ref)` says so for each
    /// name it reads (a signal written this cycle, a parameter set, `time`
    /// and `cycle` always) — and at a monitor's first evaluation; otherwise
    /// it holds as it last did (conditions are pure functions of what they
    /// read). The modes then apply as ever: a `level` monitor whose inputs
    /// are unchanged and which held fires again without any evaluation. So a
    /// cycle costs a check of each condition's names, and evaluations only
    /// for what changed.
    pub fn evaluate(&mut self, lookup: &dyn Lookup, changed: &dyn Fn(usize) -> bool, mut fire: impl FnMut(&Monitor)) {
        let evaluations = &mut self.evaluations;
        self.list.retain_mut(|m| {
            let mut held = m.held;
            for (i, c) in m.conditions.iter().enumerate() {
                if !m.new && !c.refs().iter().any(|&r| changed(r)) {
                    continue;
                }
                *evaluations += 1;
                if c.eval(lookup) == Some(true) {
                    held |= 1 << i;
                } else {
                    held &= !(1 << i);
                }
            }
            m.new = false;
            m.held = held;
            let holds = held != 0;
            let fires = match m.mode {
                MonitorMode::Once | MonitorMode::Level => holds,
                MonitorMode::Edge => holds && !m.holds,
            };
            m.holds = holds;
            if fires {
                m.fired += 1;
                fire(m);
            }
            !(fires && m.mode == MonitorMode::Once)
        });
    }
}

impl Monitor {
    /// The indexes of the conditions that held at the last evaluation, in order.
    pub fn held_indexes(&self) -> Vec<usize> {
        (0..self.conditions.len()).filter(|&i| self.held & (1 << i) != 0).collect()
    }
}
