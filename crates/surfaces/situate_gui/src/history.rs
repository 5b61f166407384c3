//! A robot's recent past for the GUI's timeline: the last N cycles' frames ([`Frame`]: the values
//! written, the prints, the resources' winners) and the manager's events (activations, parameter
//! changes, faults, monitors) as marks, in memory bounded by N.
//!
//! A [`History`] is fed from any source: [`HistoryTap`] drains a live manager's tap on a thread
//! of its own (see [`crate::serve_with_history`]); a recording's reader can push the same frames
//! and events ([`History::push_frame`], [`History::push_event`]).
//!
//! Every leaf, every resource's winner, every skill's activation, fault and parameter is a
//! track: the changes inside the window, in cycle order, plus the last change before it. The
//! state at cycle k is each track's latest change at or before k, found by a binary search: a
//! seek costs O(tracks × log N) whatever N, with no keyframes to keep.

use std::collections::{HashMap, VecDeque};

use situate_core::Value;
use situate_manager::{Event, Frame};

mod layout;
mod marks;
mod queries;
mod tap;
#[cfg(test)]
mod tests;
mod track;

pub use layout::{Layout, LeafLayout, PortLayout, SkillLayout};
pub use marks::Mark;
pub use tap::HistoryTap;
use track::Track;

/// Frames kept by default (at 100 Hz, a minute; at the toy robot's 20 Hz, five).
pub const DEFAULT_FRAMES: usize = 6000;
/// The most frames a history may keep.
pub const MAX_FRAMES: usize = 1_000_000;
/// The memory a history may take by default (values, prints and bookkeeping, as estimated by
/// [`History::bytes`]): a robot writing large values (images, point clouds) keeps fewer cycles.
pub const DEFAULT_BYTES: usize = 256 << 20;
/// What one held value or print costs besides its own data (its place in a track, its cycle).
const ENTRY_BYTES: usize = 32;
/// Frames the cycle may get ahead of the history's thread by before they are dropped.
pub const TAP_QUEUE: usize = 1024;
/// The most marks kept (a storm of events cannot grow the history past it).
pub const MAX_MARKS: usize = 2_000;
/// A mark's text is cut to this many characters.
const MARK_TEXT: usize = 200;

/// Why a history cannot answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HistoryError {
    /// Nothing recorded yet.
    #[error("the history is empty: no cycle has been recorded yet")]
    Empty,
    /// The cycle is outside the window kept.
    #[error("cycle {cycle} is not in the history (it holds cycles {first}..={last})")]
    NotHeld { cycle: u64, first: u64, last: u64 },
    /// No leaf of the robot is, or is inside, this signal.
    #[error("no signal {0} in this robot's history")]
    UnknownSignal(String),
}

/// A cycle's own record: when, and what the skills printed in it.
#[derive(Debug, Clone)]
struct FrameMeta {
    cycle: u64,
    time_s: f64,
    prints: Vec<(usize, String)>,
    /// What the frame holds, estimated (see [`History::bytes`]).
    bytes: usize,
}

/// The memory a value takes, estimated from above (shared data counted at every use).
fn value_bytes(v: &Value) -> usize {
    std::mem::size_of::<Value>()
        + match v {
            Value::Bool(_) | Value::I64(_) | Value::F64(_) => 0,
            Value::Str(s) => s.len(),
            Value::Bytes(b) => b.len(),
            Value::F32s(a) => 4 * a.len(),
            Value::F64s(a) => 8 * a.len(),
            Value::I64s(a) => 8 * a.len(),
            Value::Record(r) => r.fields.iter().map(|(n, v)| n.len() + value_bytes(v)).sum(),
        }
}

/// The span a history holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    pub first_cycle: u64,
    pub last_cycle: u64,
    pub first_time_s: f64,
    pub last_time_s: f64,
    pub frames: usize,
}

/// The last N cycles of a robot (see the module).
#[derive(Debug)]
pub struct History {
    layout: Layout,
    capacity: usize,
    /// The memory it may take (estimated); the oldest frames go first when over it.
    byte_budget: usize,
    bytes: usize,
    /// The cycle the history began at: the skills' state as built holds from it.
    observed_from: u64,
    frames: VecDeque<FrameMeta>,
    leaves: Vec<Track<Value>>,
    /// Per leaf, the instance whose value it holds (written only on change).
    winners: Vec<Track<usize>>,
    active: Vec<Track<bool>>,
    faulted: Vec<Track<Option<String>>>,
    params: Vec<Vec<Track<Value>>>,
    skill_index: HashMap<String, usize>,
    marks: VecDeque<Mark>,
    /// Whether the events given to [`History::push_event`] are marks too (a replay's are not:
    /// its marks are the recording's, [`History::push_recorded_event`]).
    events_mark: bool,
    /// Frames the source lost (a tap's full queue).
    dropped: u64,
}

impl History {
    /// An empty history of at most `capacity` frames (at least 1, at most [`MAX_FRAMES`]), the
    /// skills' state as in `layout` from cycle `observed_from` on.
    pub fn new(layout: Layout, capacity: usize, observed_from: u64) -> History {
        let capacity = capacity.clamp(1, MAX_FRAMES);
        let skills = &layout.skills;
        History {
            capacity,
            byte_budget: DEFAULT_BYTES,
            bytes: 0,
            observed_from,
            frames: VecDeque::new(),
            leaves: layout.leaves.iter().map(|_| Track::new(None)).collect(),
            winners: layout.leaves.iter().map(|_| Track::new(None)).collect(),
            active: skills.iter().map(|s| Track::new(Some((observed_from, s.active)))).collect(),
            faulted: skills.iter().map(|_| Track::new(Some((observed_from, None)))).collect(),
            params: skills
                .iter()
                .map(|s| s.params.iter().map(|(_, v)| Track::new(Some((observed_from, v.clone())))).collect())
                .collect(),
            skill_index: skills.iter().enumerate().map(|(i, s)| (s.name.clone(), i)).collect(),
            marks: VecDeque::new(),
            events_mark: true,
            dropped: 0,
            layout,
        }
    }

    pub fn capacity(&self) -> usize {
        self.capacity
    }

    /// Limits the memory the frames held may take (estimated, at least one frame is kept);
    /// [`DEFAULT_BYTES`] unless set.
    pub fn set_byte_budget(&mut self, bytes: usize) {
        self.byte_budget = bytes;
        self.evict();
    }

    /// The memory the frames held take, estimated from above: their values, prints and winner
    /// changes with their bookkeeping (one value per signal kept from before the window is not
    /// counted).
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    pub fn byte_budget(&self) -> usize {
        self.byte_budget
    }

    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// How many frames are held.
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Frames the source lost.
    pub fn dropped(&self) -> u64 {
        self.dropped
    }

    /// Sets the count of frames the source lost.
    pub fn set_dropped(&mut self, dropped: u64) {
        self.dropped = dropped;
    }

    /// The cycles held, or `None` while empty.
    pub fn span(&self) -> Option<Span> {
        let (first, last) = (self.frames.front()?, self.frames.back()?);
        Some(Span {
            first_cycle: first.cycle,
            last_cycle: last.cycle,
            first_time_s: first.time_s,
            last_time_s: last.time_s,
            frames: self.frames.len(),
        })
    }

    /// The marks on the window, oldest first.
    pub fn marks(&self) -> impl Iterator<Item = &Mark> {
        self.marks.iter()
    }

    /// Adds one cycle's frame. Frames come in cycle order: one not after the last is ignored.
    /// When the history is full, the oldest frame goes.
    pub fn push_frame(&mut self, frame: Frame) {
        if let Some(last) = self.frames.back() {
            if frame.cycle <= last.cycle {
                tracing::debug!(cycle = frame.cycle, last = last.cycle, "history: a frame out of order, ignored");
                return;
            }
        }
        let cycle = frame.cycle;
        let mut bytes = std::mem::size_of::<FrameMeta>();
        for (leaf, value) in frame.values.iter() {
            if let Some(track) = self.leaves.get_mut(leaf) {
                let value = value.to_value();
                bytes += ENTRY_BYTES + value_bytes(&value);
                track.push(cycle, value);
            }
        }
        for (leaf, inst) in frame.winners {
            if let Some(track) = self.winners.get_mut(leaf) {
                bytes += ENTRY_BYTES;
                track.push_if_changed(cycle, inst);
            }
        }
        bytes += frame.prints.iter().map(|(_, line)| ENTRY_BYTES + line.len()).sum::<usize>();
        self.bytes += bytes;
        self.frames.push_back(FrameMeta { cycle, time_s: frame.time_s, prints: frame.prints, bytes });
        self.evict();
    }

    /// Drops the oldest frames while more are held than the capacity, or than the byte budget
    /// allows (the newest frame stays, whatever its size).
    fn evict(&mut self) {
        let mut evicted = false;
        while self.frames.len() > self.capacity || (self.bytes > self.byte_budget && self.frames.len() > 1) {
            let Some(old) = self.frames.pop_front() else { break };
            self.bytes -= old.bytes;
            evicted = true;
        }
        if evicted {
            self.trim();
        }
    }

    /// Folds everything before the first frame kept into the tracks' last change before it.
    fn trim(&mut self) {
        let Some(first) = self.frames.front().map(|f| f.cycle) else { return };
        self.leaves.iter_mut().for_each(|t| t.trim(first));
        self.winners.iter_mut().for_each(|t| t.trim(first));
        self.active.iter_mut().for_each(|t| t.trim(first));
        self.faulted.iter_mut().for_each(|t| t.trim(first));
        self.params.iter_mut().flatten().for_each(|t| t.trim(first));
        while self.marks.front().is_some_and(|m| m.cycle < first) {
            self.marks.pop_front();
        }
    }

    /// Adds one of the manager's events: activations, faults and parameter changes change the
    /// skills' state from their cycle on; every event but a print is a mark.
    pub fn push_event(&mut self, event: &Event) {
        match event {
            Event::ActivationApplied { activated, deactivated, cycle } => {
                for name in activated {
                    if let Some(&i) = self.skill_index.get(name) {
                        self.active[i].push(*cycle, true);
                        self.faulted[i].push_if_changed(*cycle, None);
                    }
                }
                for name in deactivated {
                    if let Some(&i) = self.skill_index.get(name) {
                        self.active[i].push(*cycle, false);
                    }
                }
            }
            Event::ParamChanged { skill, param, value, cycle } => {
                if let Some(&i) = self.skill_index.get(skill) {
                    if let Some(p) = self.layout.skills[i].params.iter().position(|(n, _)| n == param) {
                        self.params[i][p].push(*cycle, value.clone());
                    }
                }
            }
            Event::SkillFaulted { skill, cause, cycle } => {
                if let Some(&i) = self.skill_index.get(skill) {
                    self.active[i].push(*cycle, false);
                    self.faulted[i].push(*cycle, Some(cause.clone()));
                }
            }
            _ => {}
        }
        if self.events_mark && !matches!(event, Event::Print { .. }) {
            // One description of an event as a mark, live or recorded: from its link JSON.
            self.mark_event(&situate_link::json::event_to_json(event).1);
        }
    }

    /// A leaf's latest value at or before `cycle`, with the cycle it was written in.
    pub fn value_at(&self, leaf: usize, cycle: u64) -> Option<(u64, &Value)> {
        self.leaves.get(leaf)?.at(cycle).map(|(c, v)| (*c, v))
    }

    /// The values written to a leaf in the cycles after `after` that the window holds, oldest
    /// first (the live feeds' source: every cycle past the last one sent).
    pub fn values_after(&self, leaf: usize, after: u64) -> impl Iterator<Item = (u64, &Value)> {
        self.leaves.get(leaf).into_iter().flat_map(move |t| {
            let from = t.changes.partition_point(|(c, _)| *c <= after);
            t.changes.range(from..).map(|(c, v)| (*c, v))
        })
    }

    /// The manager's clock (seconds) at a cycle the window holds.
    pub fn time_s_of(&self, cycle: u64) -> Option<f64> {
        let at = self.frames.partition_point(|f| f.cycle < cycle);
        self.frames.get(at).filter(|f| f.cycle == cycle).map(|f| f.time_s)
    }

    /// Whether a skill was active at `cycle` (its state as built before any change).
    pub fn active_at(&self, skill: usize, cycle: u64) -> Option<bool> {
        self.active.get(skill)?.at(cycle).map(|(_, a)| *a)
    }

    /// A skill's parameter at `cycle`.
    pub fn param_at(&self, skill: usize, param: usize, cycle: u64) -> Option<&Value> {
        self.params.get(skill)?.get(param)?.at(cycle).map(|(_, v)| v)
    }

    /// Who held a resource leaf at `cycle`.
    pub fn winner_at(&self, leaf: usize, cycle: u64) -> Option<usize> {
        self.winners.get(leaf)?.at(cycle).map(|(_, i)| *i)
    }
}
