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
//! A monitor's events carry the value of every name its condition reads,
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

use crate::expr::{Condition, Lookup};

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

pub(crate) struct Monitor {
    pub id: u64,
    pub condition: Condition,
    pub mode: MonitorMode,
    pub holds: bool,
    pub fired: u64,
    pub pause: bool,
    /// Extra names the events carry, as written, with their reference ids.
    pub report: Vec<(String, usize)>,
    /// The names `report` asked for, as written (records not expanded).
    pub report_asked: Vec<String>,
}

#[derive(Default)]
pub(crate) struct Monitors {
    pub list: Vec<Monitor>,
    next_id: u64,
}

impl Monitors {
    pub fn add(
        &mut self,
        condition: Condition,
        mode: MonitorMode,
        pause: bool,
        report: Vec<(String, usize)>,
        report_asked: Vec<String>,
    ) -> u64 {
        self.next_id += 1;
        let id = self.next_id;
        self.list.push(Monitor { id, condition, mode, holds: false, fired: 0, pause, report, report_asked });
        id
    }

    pub fn cancel(&mut self, id: u64) -> bool {
        let before = self.list.len();
        self.list.retain(|m| m.id != id);
        self.list.len() != before
    }

    /// Evaluates every monitor; calls `fire` for each that fires this cycle.
    pub fn evaluate(&mut self, lookup: &dyn Lookup, mut fire: impl FnMut(&Monitor)) {
        self.list.retain_mut(|m| {
            let holds = m.condition.eval(lookup) == Some(true);
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
