//! What the GUI asks a history, answered in JSON: the span and the marks (`history`), signals
//! over the span (`history_series`), and the state at a cycle (`history_frame`).

use serde_json::{json, Map, Value as Json};
use situate_core::Value;
use situate_link::json::value_to_json;

use super::{FrameMeta, History, HistoryError, PortLayout};

impl History {
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
