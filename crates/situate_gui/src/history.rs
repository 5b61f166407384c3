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

use serde_json::{json, Map, Value as Json};
use situate_core::Value;
use situate_link::json::value_to_json;
use situate_manager::{Event, Frame, Graph, Manager, TapReceiver};

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

/// One port of a skill: the leaves that make its value.
#[derive(Debug, Clone, PartialEq)]
pub struct PortLayout {
    pub name: String,
    pub signal: String,
    /// Leaf indices (into [`Layout::leaves`]).
    pub leaves: Vec<usize>,
}

/// One skill instance as wired, and its state when the history began.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillLayout {
    pub name: String,
    pub active: bool,
    /// (name, value) of every parameter, in declaration order.
    pub params: Vec<(String, Value)>,
    pub inputs: Vec<PortLayout>,
    pub outputs: Vec<PortLayout>,
}

/// One leaf signal: its path and its writers (instance indices).
#[derive(Debug, Clone, PartialEq)]
pub struct LeafLayout {
    pub path: String,
    pub writers: Vec<usize>,
}

/// What a history needs to name what its frames hold: the leaves and the skills, by index as in
/// [`Frame`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Layout {
    pub leaves: Vec<LeafLayout>,
    pub skills: Vec<SkillLayout>,
}

impl Layout {
    /// The layout of a wired robot, with its skills' activation and parameters as built.
    pub fn of(graph: &Graph) -> Layout {
        let port = |p: &situate_manager::graph::PortBinding| PortLayout {
            name: p.name.clone(),
            signal: p.signal.clone(),
            leaves: p.leaves.clone(),
        };
        Layout {
            leaves: graph
                .leaves
                .iter()
                .map(|l| LeafLayout { path: l.path.clone(), writers: l.writers.iter().map(|(i, _)| *i).collect() })
                .collect(),
            skills: graph
                .instances
                .iter()
                .map(|d| SkillLayout {
                    name: d.name.clone(),
                    active: d.active,
                    params: d
                        .skill_type
                        .decl
                        .params
                        .iter()
                        .map(|p| p.name.clone())
                        .zip(d.params.iter().cloned())
                        .collect(),
                    inputs: d.inputs.iter().map(port).collect(),
                    outputs: d.outputs.iter().map(port).collect(),
                })
                .collect(),
        }
    }
}

/// A value's changes over the window, in cycle order, and the last one before it.
#[derive(Debug, Clone)]
struct Track<T> {
    before: Option<(u64, T)>,
    changes: VecDeque<(u64, T)>,
}

impl<T: PartialEq> Track<T> {
    fn new(initial: Option<(u64, T)>) -> Self {
        Track { before: initial, changes: VecDeque::new() }
    }

    /// The latest change at or before `cycle`.
    fn at(&self, cycle: u64) -> Option<&(u64, T)> {
        let n = self.changes.partition_point(|(c, _)| *c <= cycle);
        if n > 0 {
            self.changes.get(n - 1)
        } else {
            self.before.as_ref().filter(|(c, _)| *c <= cycle)
        }
    }

    fn last(&self) -> Option<&(u64, T)> {
        self.changes.back().or(self.before.as_ref())
    }

    /// Adds a change (in cycle order; one out of order is put in its place).
    fn push(&mut self, cycle: u64, value: T) {
        match self.changes.back() {
            Some((c, _)) if *c > cycle => {
                let at = self.changes.partition_point(|(c, _)| *c <= cycle);
                self.changes.insert(at, (cycle, value));
            }
            _ => self.changes.push_back((cycle, value)),
        }
    }

    /// Adds a change only when it changes the value.
    fn push_if_changed(&mut self, cycle: u64, value: T) {
        if self.last().map(|(_, v)| v != &value).unwrap_or(true) {
            self.push(cycle, value);
        }
    }

    /// Folds the changes before `first` into the one kept before the window.
    fn trim(&mut self, first: u64) {
        while self.changes.front().is_some_and(|(c, _)| *c < first) {
            self.before = self.changes.pop_front();
        }
    }
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

/// A phase's mark: its text, and who said it when the client gave a name (`deliver: leaving the
/// lab`).
fn phase_text(text: &str, client: Option<&str>) -> String {
    match client {
        Some(c) if !c.is_empty() => format!("{c}: {text}"),
        _ => text.to_string(),
    }
}

/// An event on the timeline.
#[derive(Debug, Clone, PartialEq)]
pub struct Mark {
    pub cycle: u64,
    /// `activation`, `param`, `priority`, `fault`, `monitor`, `manager`, `worker` or `phase`.
    pub kind: &'static str,
    pub text: String,
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

    /// Whether the events given to [`History::push_event`] are marked on the timeline (default
    /// yes). A replay's timeline marks what the recording holds instead
    /// ([`History::push_recorded_event`]): the replayed manager's own events (only its live
    /// skills' changes) would show a part of the run twice and the rest not at all.
    pub fn set_events_mark(&mut self, on: bool) {
        self.events_mark = on;
    }

    /// A mark for an event as a recording holds it: the link's JSON of the event
    /// (`docs/protocol.md`, "Events"), `kind` among its members. The skills' state is not
    /// changed (a replay's comes from the replayed cycles). Prints and events without a cycle
    /// (but `worker_failed`, marked at the newest cycle held) are not marks.
    pub fn push_recorded_event(&mut self, event: &Json) {
        self.mark_event(event);
    }

    /// Marks an event given as the link's JSON of it (see [`History::push_recorded_event`]).
    fn mark_event(&mut self, event: &Json) {
        let s = |key: &str| event.get(key).and_then(Json::as_str).unwrap_or("?").to_string();
        let names = |key: &str| -> String {
            let list = event.get(key).and_then(Json::as_array).map(Vec::as_slice).unwrap_or_default();
            list.iter().filter_map(Json::as_str).collect::<Vec<_>>().join(", ")
        };
        let kind_name = event.get("kind").and_then(Json::as_str).unwrap_or("");
        let last_cycle = self.frames.back().map(|f| f.cycle).unwrap_or(self.observed_from);
        let cycle = match (event.get("cycle").and_then(Json::as_u64), kind_name) {
            (Some(c), _) => c,
            (None, "worker_failed") => last_cycle,
            (None, _) => return,
        };
        let (kind, text) = match kind_name {
            "activation_applied" => {
                let (on, off) = (names("activated"), names("deactivated"));
                let mut parts = Vec::new();
                if !on.is_empty() {
                    parts.push(format!("activated {on}"));
                }
                if !off.is_empty() {
                    parts.push(format!("deactivated {off}"));
                }
                ("activation", parts.join("; "))
            }
            "param_changed" => {
                let value = event.get("value").map(Json::to_string).unwrap_or_default();
                ("param", format!("{}.{} = {value}", s("skill"), s("param")))
            }
            "priority_changed" => {
                let p = event.get("priority").map(Json::to_string).unwrap_or_default();
                ("priority", format!("{} priority = {p}", s("skill")))
            }
            "skill_faulted" => ("fault", format!("{} faulted: {}", s("skill"), s("cause"))),
            "monitor_fired" => ("monitor", format!("monitor {} fired: {}", event["monitor"], s("condition"))),
            "monitor_cancelled" => {
                let why = match event.get("reason").and_then(Json::as_str) {
                    Some("forced") => "cancelled by another session",
                    Some("session_ended") => "gone with its session",
                    _ => "cancelled",
                };
                ("monitor", format!("monitor {} {why}: {}", event["monitor"], s("condition")))
            }
            "manager_started" => ("manager", "the cycle started".to_string()),
            "manager_stopped" => ("manager", "the cycle stopped".to_string()),
            "worker_failed" => ("worker", format!("worker {} failed ({}): {}", s("thread"), s("cause"), s("action"))),
            "phase" => ("phase", phase_text(&s("text"), event.get("client").and_then(Json::as_str))),
            _ => return,
        };
        self.insert_mark(cycle, kind, text);
    }

    fn insert_mark(&mut self, cycle: u64, kind: &'static str, text: String) {
        let text = if text.chars().count() > MARK_TEXT {
            format!("{}…", text.chars().take(MARK_TEXT).collect::<String>())
        } else {
            text
        };
        let at = self.marks.partition_point(|m| m.cycle <= cycle);
        self.marks.insert(at, Mark { cycle, kind, text });
        while self.marks.len() > MAX_MARKS {
            self.marks.pop_front();
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

    /// `history`: the span held and the marks.
    pub fn summary_json(&self) -> Json {
        let span = self.span();
        json!({
            "first_cycle": span.map(|s| s.first_cycle),
            "last_cycle": span.map(|s| s.last_cycle),
            "first_time_s": span.map(|s| s.first_time_s),
            "last_time_s": span.map(|s| s.last_time_s),
            "frames": self.frames.len(),
            "capacity": self.capacity,
            "bytes": self.bytes,
            "byte_budget": self.byte_budget,
            "dropped": self.dropped,
            "marks": self.marks.iter().map(|m| json!({"cycle": m.cycle, "kind": m.kind, "text": m.text})).collect::<Vec<_>>(),
        })
    }

    /// A signal's value at `cycle`: a leaf's, or a record assembled from its leaves (null until
    /// every field has been written), with the oldest field's cycle.
    fn assemble(&self, leaves: &[usize], signal: &str, cycle: u64) -> Option<(u64, Json)> {
        if let [leaf] = leaves {
            if self.layout.leaves.get(*leaf).is_some_and(|l| l.path == signal) {
                return self.value_at(*leaf, cycle).map(|(c, v)| (c, value_to_json(v)));
            }
        }
        let mut record = Map::new();
        let mut oldest = u64::MAX;
        for &leaf in leaves {
            let path = &self.layout.leaves.get(leaf)?.path;
            let (c, value) = self.value_at(leaf, cycle)?;
            oldest = oldest.min(c);
            let rel = path.strip_prefix(signal).and_then(|r| r.strip_prefix('.')).unwrap_or(path);
            let mut fields = rel.split('.').peekable();
            let mut at = &mut record;
            while let Some(field) = fields.next() {
                if fields.peek().is_none() {
                    at.insert(field.to_string(), value_to_json(value));
                } else {
                    let next = at.entry(field.to_string()).or_insert_with(|| Json::Object(Map::new()));
                    if !next.is_object() {
                        *next = Json::Object(Map::new());
                    }
                    let Json::Object(m) = next else { return None };
                    at = m;
                }
            }
        }
        (!leaves.is_empty()).then_some((oldest, Json::Object(record)))
    }

    /// `history_series`: `signals` over the whole span held, on the robot's time: at most
    /// `max_points` cycles, evenly spread over the frames held (every frame when they are fewer),
    /// the last frame always among them. For each: `cycles`, `times` (the manager's clock, s) and,
    /// per signal, `values` (its latest value at or before the cycle, records assembled; null
    /// before its first write) and `written` (the cycle that value was written in), so a reader
    /// tells a stale value from a fresh one.
    pub fn series_json(
        &self,
        signals: &[String],
        formulas: &[std::sync::Arc<crate::formula::Derived>],
        max_points: usize,
    ) -> Result<Json, HistoryError> {
        let leaves: Vec<Vec<usize>> = signals
            .iter()
            .map(|name| {
                let leaves = self.leaves_of(name);
                if leaves.is_empty() {
                    Err(HistoryError::UnknownSignal(name.clone()))
                } else {
                    Ok(leaves)
                }
            })
            .collect::<Result<_, _>>()?;
        let n = self.frames.len();
        if n == 0 {
            return Err(HistoryError::Empty);
        }
        let step = n.div_ceil(max_points.max(2));
        let mut picked: Vec<&FrameMeta> = self.frames.iter().step_by(step).collect();
        if let Some(last) = self.frames.back() {
            if picked.last().is_none_or(|f| f.cycle != last.cycle) {
                picked.push(last);
            }
        }
        let mut series = Map::new();
        for (name, leaves) in signals.iter().zip(&leaves) {
            let (mut values, mut written) = (Vec::with_capacity(picked.len()), Vec::with_capacity(picked.len()));
            for f in &picked {
                match self.assemble(leaves, name, f.cycle) {
                    Some((c, v)) => {
                        values.push(v);
                        written.push(json!(c));
                    }
                    None => {
                        values.push(Json::Null);
                        written.push(Json::Null);
                    }
                }
            }
            series.insert(name.clone(), json!({"values": values, "written": written}));
        }
        // A derived series: its value at each point from its leaves' values then.
        for f in formulas {
            let leaves: Vec<Option<usize>> =
                f.leaves().iter().map(|p| self.layout.leaves.iter().position(|l| &l.path == p)).collect();
            let (mut values, mut written) = (Vec::with_capacity(picked.len()), Vec::with_capacity(picked.len()));
            for frame in &picked {
                let at: Vec<Option<(u64, &Value)>> =
                    leaves.iter().map(|l| l.and_then(|l| self.value_at(l, frame.cycle))).collect();
                match f.eval(&at) {
                    Some((c, v)) => {
                        values.push(json!(v));
                        written.push(json!(c));
                    }
                    None => {
                        values.push(Json::Null);
                        written.push(Json::Null);
                    }
                }
            }
            series.insert(f.source().to_string(), json!({"values": values, "written": written, "formula": true}));
        }
        Ok(json!({
            "cycles": picked.iter().map(|f| f.cycle).collect::<Vec<_>>(),
            "times": picked.iter().map(|f| f.time_s).collect::<Vec<_>>(),
            "frames": n,
            "signals": series,
        }))
    }

    /// The leaves making the signal `name` (the leaf itself, or a record's fields).
    fn leaves_of(&self, name: &str) -> Vec<usize> {
        let prefix = format!("{name}.");
        self.layout
            .leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| l.path == name || l.path.starts_with(&prefix))
            .map(|(i, _)| i)
            .collect()
    }

    /// `history_frame`: the state at `cycle` — every leaf's latest value at or before it, the
    /// records named in `records` assembled, that cycle's prints, the resources' winners, each
    /// skill's activation, fault, parameters and ports.
    pub fn frame_json(&self, cycle: u64, records: &[&str]) -> Result<Json, HistoryError> {
        let span = self.span().ok_or(HistoryError::Empty)?;
        if cycle < span.first_cycle || cycle > span.last_cycle {
            return Err(HistoryError::NotHeld { cycle, first: span.first_cycle, last: span.last_cycle });
        }
        let at = self.frames.partition_point(|f| f.cycle <= cycle);
        // `cycle` ≥ the first frame's: at least one frame is at or before it.
        let Some(frame) = self.frames.get(at.saturating_sub(1)) else { return Err(HistoryError::Empty) };
        let skill_name = |i: usize| self.layout.skills.get(i).map(|s| s.name.clone()).unwrap_or_default();
        let mut signals = Map::new();
        for (i, leaf) in self.layout.leaves.iter().enumerate() {
            if let Some((c, v)) = self.value_at(i, cycle) {
                signals.insert(leaf.path.clone(), json!({"signal": leaf.path, "value": value_to_json(v), "cycle": c}));
            }
        }
        for name in records {
            if signals.contains_key(*name) {
                continue;
            }
            let leaves = self.leaves_of(name);
            if let Some((c, v)) = self.assemble(&leaves, name, cycle) {
                signals.insert(name.to_string(), json!({"signal": name, "value": v, "cycle": c}));
            }
        }
        let winners: Vec<Json> = self
            .layout
            .leaves
            .iter()
            .enumerate()
            .filter(|(_, l)| l.writers.len() > 1)
            .map(|(i, l)| {
                let winner = self.winner_at(i, cycle).map(skill_name);
                let written = self.value_at(i, cycle).map(|(c, _)| c);
                json!({"signal": l.path, "writers": l.writers.iter().map(|&w| skill_name(w)).collect::<Vec<_>>(),
                    "winner": winner, "cycle": written})
            })
            .collect();
        let mut changed = Map::new();
        let skills: Vec<Json> = self
            .layout
            .skills
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let active = self.active[i].at(cycle);
                if let Some((c, _)) = active.filter(|(c, _)| *c > self.observed_from) {
                    changed.insert(s.name.clone(), json!(c));
                }
                let faulted = self.faulted[i].at(cycle).and_then(|(_, f)| f.clone());
                let params: Vec<Json> = s
                    .params
                    .iter()
                    .enumerate()
                    .map(|(p, (name, initial))| {
                        let v = self.param_at(i, p, cycle).unwrap_or(initial);
                        json!({"name": name, "value": value_to_json(v)})
                    })
                    .collect();
                let ports = |ports: &[PortLayout]| -> Vec<Json> {
                    ports
                        .iter()
                        .map(|p| {
                            let v = self.assemble(&p.leaves, &p.signal, cycle);
                            json!({"name": p.name, "signal": p.signal, "value": v.map(|(_, v)| v)})
                        })
                        .collect()
                };
                json!({"name": s.name, "active": active.map(|(_, a)| *a).unwrap_or(s.active), "faulted": faulted,
                    "params": params, "inputs": ports(&s.inputs), "outputs": ports(&s.outputs)})
            })
            .collect();
        let prints: Vec<Json> = if frame.cycle == cycle {
            frame.prints.iter().map(|(i, line)| json!({"skill": skill_name(*i), "line": line})).collect()
        } else {
            Vec::new()
        };
        Ok(json!({
            "cycle": cycle,
            "time_s": frame.time_s,
            "exact": frame.cycle == cycle,
            "first_cycle": span.first_cycle,
            "last_cycle": span.last_cycle,
            "signals": signals,
            "prints": prints,
            "winners": winners,
            "skills": skills,
            "activity": {"observed_from": self.observed_from, "changed": changed},
        }))
    }
}

/// A live manager's tap for a history: its frames and events from before it was spawned, and its
/// layout. Make it with [`HistoryTap::new`] before [`Manager::spawn`] and give it to
/// [`crate::serve_with_history`].
/// [`HistoryTap::from_channels`] feeds a history from any source (a recording's reader, a test).
pub struct HistoryTap {
    pub(crate) frames: crossbeam_channel::Receiver<Frame>,
    /// The manager's tap, for the count of frames it dropped.
    pub(crate) tap: Option<TapReceiver>,
    pub(crate) events: crossbeam_channel::Receiver<Event>,
    pub(crate) layout: Layout,
    pub(crate) observed_from: u64,
}

impl HistoryTap {
    /// Taps `manager`'s cycle ([`Manager::tap`], which never makes the cycle wait: a frame that
    /// finds the queue full is dropped and counted) and subscribes to its events. Beside a
    /// recording's tap: each tap gets every cycle.
    pub fn new(manager: &mut Manager) -> HistoryTap {
        let tap = manager.tap(TAP_QUEUE);
        let events = manager.events();
        HistoryTap {
            frames: tap.frames.clone(),
            tap: Some(tap),
            events,
            layout: Layout::of(manager.graph()),
            observed_from: manager.cycle_count(),
        }
    }

    /// Frames and events from any source, in cycle order, named by `layout`; the skills' state
    /// as in `layout` from cycle `observed_from` on. The history takes them as they come until
    /// both channels close (a source may block on a full bounded channel: nothing waits on it).
    pub fn from_channels(
        layout: Layout,
        frames: crossbeam_channel::Receiver<Frame>,
        events: crossbeam_channel::Receiver<Event>,
        observed_from: u64,
    ) -> HistoryTap {
        HistoryTap { frames, tap: None, events, layout, observed_from }
    }

    /// Frames lost before they reached the history (a live tap's full queue).
    pub(crate) fn dropped(&self) -> u64 {
        self.tap.as_ref().map(TapReceiver::dropped).unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use std::time::Instant;

    use super::*;

    fn layout() -> Layout {
        let port = |name: &str, signal: &str, leaves: Vec<usize>| PortLayout {
            name: name.into(),
            signal: signal.into(),
            leaves,
        };
        Layout {
            leaves: vec![
                LeafLayout { path: "pose.x".into(), writers: vec![0] },
                LeafLayout { path: "pose.y".into(), writers: vec![0] },
                LeafLayout { path: "cmd".into(), writers: vec![0, 1] },
            ],
            skills: vec![
                SkillLayout {
                    name: "a".into(),
                    active: true,
                    params: vec![("gain".into(), Value::F64(1.0))],
                    inputs: vec![],
                    outputs: vec![port("pose", "pose", vec![0, 1]), port("cmd", "cmd", vec![2])],
                },
                SkillLayout {
                    name: "b".into(),
                    active: false,
                    params: vec![],
                    inputs: vec![port("pose", "pose", vec![0, 1])],
                    outputs: vec![port("cmd", "cmd", vec![2])],
                },
            ],
        }
    }

    fn frame(cycle: u64, values: Vec<(usize, Value)>) -> Frame {
        Frame { cycle, time_s: cycle as f64 * 0.01, values: values.into(), prints: vec![], winners: vec![] }
    }

    #[test]
    fn a_series_spans_the_whole_history_on_robot_time_records_assembled_and_says_when_each_value_was_written() {
        let mut h = History::new(layout(), 100, 0);
        assert_eq!(h.series_json(&["pose".into()], &[], 10), Err(HistoryError::Empty));
        for c in 1..=50 {
            // pose.y is written every other cycle: its value then is the one of the cycle before.
            let mut values = vec![(0, Value::F64(c as f64))];
            if c % 2 == 1 {
                values.push((1, Value::F64(-(c as f64))));
            }
            h.push_frame(frame(c, values));
        }
        let all = h.series_json(&["pose".into(), "pose.x".into()], &[], 100).expect("series");
        assert_eq!(all["cycles"].as_array().map(Vec::len), Some(50), "every frame when they are fewer: {all}");
        assert_eq!(all["times"][9], json!(0.1));
        assert_eq!(all["signals"]["pose"]["values"][9], json!({"x": 10.0, "y": -9.0}));
        assert_eq!(all["signals"]["pose"]["written"][9], json!(9), "the oldest leaf's write");
        assert_eq!(all["signals"]["pose.x"]["values"][9], json!(10.0));
        let few = h.series_json(&["pose.x".into()], &[], 10).expect("series");
        let cycles: Vec<u64> = few["cycles"].as_array().expect("cycles").iter().filter_map(Json::as_u64).collect();
        assert_eq!(cycles, vec![1, 6, 11, 16, 21, 26, 31, 36, 41, 46, 50], "spread, the last among them");
        assert_eq!(h.series_json(&["pose.z".into()], &[], 10), Err(HistoryError::UnknownSignal("pose.z".into())));
        // Before its first write a signal is null.
        let cmd = h.series_json(&["cmd".into()], &[], 10).expect("series");
        assert_eq!(cmd["signals"]["cmd"]["values"][0], Json::Null);
    }

    #[test]
    fn the_frame_past_the_capacity_evicts_the_first() {
        let mut h = History::new(layout(), 3, 0);
        assert!(h.span().is_none());
        assert_eq!(h.frame_json(0, &[]), Err(HistoryError::Empty));
        for c in 1..=3 {
            h.push_frame(frame(c, vec![(0, Value::F64(c as f64))]));
        }
        assert_eq!(h.span().map(|s| (s.first_cycle, s.last_cycle, s.frames)), Some((1, 3, 3)));
        h.push_frame(frame(4, vec![(0, Value::F64(4.0))]));
        let span = h.span().expect("frames");
        assert_eq!((span.first_cycle, span.last_cycle, span.frames), (2, 4, 3));
        assert_eq!(h.len(), 3);
        assert!(matches!(h.frame_json(1, &[]), Err(HistoryError::NotHeld { cycle: 1, first: 2, last: 4 })));
        // The evicted frames' values are folded: no more than one change per leaf before the window.
        assert_eq!(h.leaves[0].changes.len(), 3);
        assert_eq!(h.leaves[0].before, Some((1, Value::F64(1.0))));
        // Memory stays bounded however long the run.
        for c in 5..10_000 {
            h.push_frame(frame(c, vec![(0, Value::F64(c as f64)), (2, Value::F64(0.5))]));
        }
        assert_eq!(h.len(), 3);
        assert!(h.leaves.iter().all(|t| t.changes.len() <= 3), "tracks hold the window only");
        // An out-of-order frame is ignored.
        h.push_frame(frame(5, vec![(0, Value::F64(-1.0))]));
        assert_eq!(h.value_at(0, 9999), Some((9999, &Value::F64(9999.0))));
    }

    #[test]
    fn the_value_at_cycle_k_is_the_latest_written_at_or_before_k() {
        let mut h = History::new(layout(), 100, 0);
        h.push_frame(frame(10, vec![(0, Value::F64(1.0)), (1, Value::F64(2.0))]));
        h.push_frame(frame(11, vec![(0, Value::F64(3.0))]));
        h.push_frame(frame(12, vec![]));
        // A dropped frame: cycle 13 is missing.
        h.push_frame(frame(14, vec![(1, Value::F64(5.0))]));
        assert_eq!(h.value_at(0, 10), Some((10, &Value::F64(1.0))));
        assert_eq!(h.value_at(0, 12), Some((11, &Value::F64(3.0))));
        assert_eq!(h.value_at(1, 13), Some((10, &Value::F64(2.0))));
        assert_eq!(h.value_at(1, 14), Some((14, &Value::F64(5.0))));
        assert_eq!(h.value_at(2, 14), None, "never written");
        let f = h.frame_json(13, &["pose"]).expect("held");
        assert_eq!(f["exact"], false, "cycle 13 has no frame of its own");
        assert_eq!(f["time_s"], json!(12.0 * 0.01), "the time of the frame before");
        assert_eq!(f["signals"]["pose.x"]["value"], 3.0);
        assert_eq!(f["signals"]["pose.x"]["cycle"], 11);
        assert_eq!(f["signals"]["pose"]["value"], json!({"x": 3.0, "y": 2.0}), "the record assembled: {f}");
        assert_eq!(f["signals"]["pose"]["cycle"], 10, "the oldest field's cycle");
        assert!(f["signals"].get("cmd").is_none());
        let a = &f["skills"][0];
        assert_eq!(a["outputs"][0]["value"], json!({"x": 3.0, "y": 2.0}));
        assert_eq!(a["outputs"][1]["value"], Json::Null, "cmd never written");
        let f = h.frame_json(10, &[]).expect("held");
        assert_eq!(f["skills"][1]["inputs"][0]["value"], json!({"x": 1.0, "y": 2.0}));
        assert_eq!(f["exact"], true);
    }

    #[test]
    fn marks_activations_parameters_faults_and_winners_follow_the_cycle() {
        let mut h = History::new(layout(), 100, 0);
        for c in 1..=5 {
            h.push_frame(Frame {
                cycle: c,
                time_s: c as f64,
                values: vec![(2, Value::F64(c as f64))].into(),
                prints: if c == 3 { vec![(0, "hello".into())] } else { vec![] },
                winners: vec![(2, 0)],
            });
        }
        h.push_event(&Event::ActivationApplied { activated: vec!["b".into()], deactivated: vec![], cycle: 6 });
        h.push_event(&Event::ParamChanged {
            skill: "a".into(),
            param: "gain".into(),
            value: Value::F64(2.5),
            cycle: 7,
        });
        h.push_event(&Event::Print { skill: "a".into(), line: "not a mark".into(), cycle: 7 });
        for c in 6..=10 {
            h.push_frame(Frame {
                cycle: c,
                time_s: c as f64,
                values: Default::default(),
                prints: vec![],
                winners: vec![(2, 1)],
            });
        }
        h.push_event(&Event::SkillFaulted { skill: "b".into(), cause: "panicked".into(), cycle: 9 });
        let marks: Vec<_> = h.marks().map(|m| (m.cycle, m.kind)).collect();
        assert_eq!(marks, vec![(6, "activation"), (7, "param"), (9, "fault")]);
        let summary = h.summary_json();
        assert_eq!(summary["marks"][1]["text"], "a.gain = 2.5");
        assert_eq!(summary["marks"][0]["text"], "activated b");
        assert_eq!((summary["first_cycle"].as_u64(), summary["last_cycle"].as_u64()), (Some(1), Some(10)));
        assert_eq!(h.active_at(1, 5), Some(false), "b inactive as built");
        assert_eq!(h.active_at(1, 6), Some(true));
        assert_eq!(h.active_at(1, 9), Some(false), "faulted");
        assert_eq!(h.param_at(0, 0, 6), Some(&Value::F64(1.0)));
        assert_eq!(h.param_at(0, 0, 7), Some(&Value::F64(2.5)));
        assert_eq!(h.winner_at(2, 5), Some(0));
        assert_eq!(h.winner_at(2, 6), Some(1));
        let f = h.frame_json(3, &[]).expect("held");
        assert_eq!(f["prints"], json!([{"skill": "a", "line": "hello"}]));
        assert_eq!(f["winners"], json!([{"signal": "cmd", "writers": ["a", "b"], "winner": "a", "cycle": 3}]));
        assert_eq!(f["skills"][1]["active"], false);
        assert_eq!(f["activity"]["changed"], json!({}));
        let f = h.frame_json(9, &[]).expect("held");
        assert_eq!(f["skills"][1]["faulted"], "panicked");
        assert_eq!(f["skills"][0]["params"], json!([{"name": "gain", "value": 2.5}]));
        assert_eq!(f["activity"]["changed"], json!({"b": 9}));
        assert_eq!(f["winners"][0]["winner"], "b");
        assert_eq!(f["prints"], json!([]));
        // Marks go with the frames they fall before.
        let mut small = History::new(layout(), 2, 0);
        small.push_event(&Event::ManagerStarted { cycle: 1 });
        for c in 1..=4 {
            small.push_frame(frame(c, vec![]));
        }
        assert_eq!(small.marks().count(), 0, "the mark of cycle 1 left with its frame");
    }

    #[test]
    fn large_values_keep_fewer_frames_within_the_byte_budget() {
        let mut h = History::new(layout(), 1000, 0);
        h.set_byte_budget(100_000);
        let image = |c: u64| Value::Bytes(vec![c as u8; 10_000].into());
        for c in 0..100 {
            h.push_frame(frame(c, vec![(2, image(c)), (0, Value::F64(c as f64))]));
            assert!(h.bytes() <= 100_000, "over budget at cycle {c}: {} bytes", h.bytes());
        }
        let span = h.span().expect("frames");
        assert!(span.frames >= 5 && span.frames < 10, "about 100 kB of 10 kB frames: {span:?}");
        assert_eq!(span.last_cycle, 99);
        assert_eq!(h.value_at(2, 99), Some((99, &image(99))));
        // Tracks hold the window only (and one value from before it).
        assert_eq!(h.leaves[2].changes.len(), span.frames);
        // A frame larger than the whole budget is kept alone.
        h.push_frame(frame(100, vec![(2, Value::Bytes(vec![0; 200_000].into()))]));
        assert_eq!(h.len(), 1);
        assert_eq!(h.span().map(|s| s.first_cycle), Some(100));
        assert_eq!(h.value_at(0, 100), Some((99, &Value::F64(99.0))), "the value before the window stays");
    }

    #[test]
    fn marks_are_bounded_too() {
        let mut h = History::new(layout(), 10, 0);
        for c in 0..(MAX_MARKS as u64 + 50) {
            h.push_event(&Event::ManagerStopped { cycle: c });
        }
        assert_eq!(h.marks().count(), MAX_MARKS);
        assert_eq!(h.marks().next().map(|m| m.cycle), Some(50));
    }

    /// Ten minutes at 100 Hz: the time of a seek is reported (not asserted: it depends on the
    /// machine and the build).
    #[test]
    fn a_seek_in_ten_minutes_at_100_hz() {
        let leaves = 40;
        let layout = Layout {
            leaves: (0..leaves).map(|i| LeafLayout { path: format!("s{i}"), writers: vec![0] }).collect(),
            skills: vec![SkillLayout {
                name: "a".into(),
                active: true,
                params: vec![("p".into(), Value::I64(0))],
                inputs: vec![],
                outputs: (0..leaves)
                    .map(|i| PortLayout { name: format!("o{i}"), signal: format!("s{i}"), leaves: vec![i] })
                    .collect(),
            }],
        };
        let frames = 60_000;
        let mut h = History::new(layout, frames, 0);
        let started = Instant::now();
        for c in 0..frames as u64 {
            // Every leaf every cycle, but one written every 1000 cycles only.
            let values = (0..leaves)
                .filter(|&i| i != 0 || c % 1000 == 0)
                .map(|i| (i, Value::F64((c * i as u64) as f64)))
                .collect();
            h.push_frame(Frame { cycle: c, time_s: c as f64 / 100.0, values, prints: vec![], winners: vec![] });
        }
        let fill = started.elapsed();
        let mut worst = std::time::Duration::ZERO;
        for k in [0, 12_345, 29_999, 59_999] {
            let t = Instant::now();
            let f = h.frame_json(k, &[]).expect("held");
            worst = worst.max(t.elapsed());
            assert_eq!(f["cycle"], k);
            assert_eq!(f["signals"]["s3"]["value"], json!((k * 3) as f64));
            assert_eq!(f["signals"]["s0"]["cycle"], k / 1000 * 1000);
        }
        eprintln!("history: {frames} frames of {leaves} leaves filled in {fill:?}; the slowest of 4 seeks {worst:?}");
    }
}
