//! A recording read whole: checked as a whole (metadata, counts, the cycles following one
//! another but for those dropped), cut to its last complete cycle when cut short, and indexed.

use std::collections::BTreeMap;

use serde_json::Value as Json;

use super::reader::Reader;
use super::{CutShort, ReadError, Recording};

impl Reader {
    /// Checks what was read as a whole, and indexes it.
    pub(super) fn finish(mut self) -> Result<Recording, ReadError> {
        if let Some((at, reason, whole)) = self.cut.take() {
            if self.rec.metadata.is_empty() {
                return Err(self.bad(format!(
                    "cut short at byte {at} before its `situate` metadata record was whole ({reason}): nothing of \
                     the run can be read"
                )));
            }
            self.trim_cut(at, reason, whole);
        }
        if self.rec.metadata.is_empty() {
            return Err(self.bad("no `situate` metadata record: not a recording made by situate".into()));
        }
        if let Some(s) = self.statistics.as_ref().filter(|_| self.rec.cut_short.is_none()) {
            if s.message_count != self.rec.messages || u64::from(s.chunk_count) != self.chunks {
                return Err(self.bad(format!(
                    "the summary counts {} messages in {} chunks, the data section holds {} in {}: a damaged file",
                    s.message_count, s.chunk_count, self.rec.messages, self.chunks
                )));
            }
        }
        let meta = |key: &str| format!("the metadata record `situate`, `{key}`");
        // Message times are Unix time (the run's start plus the manager's clock); a recording
        // made before they were has no origin, and its times are the manager's clock already.
        if let Some(o) = self.rec.metadata.get(crate::TIME_ORIGIN_METADATA) {
            let Ok(origin) = o.parse::<u64>() else {
                return Err(self.bad(format!(
                    "{}: `{o}` is not a time in nanoseconds since 1970 (a whole number)",
                    meta(crate::TIME_ORIGIN_METADATA)
                )));
            };
            for c in self.rec.cycles.values_mut() {
                c.time_ns = c.time_ns.saturating_sub(origin);
            }
        }
        if let Some(p) = self.rec.metadata.get("period_s") {
            let ok = p.parse::<f64>().ok().filter(|p| p.is_finite() && *p > 0.0 && *p <= 86_400.0);
            if ok.is_none() {
                return Err(self.bad(format!(
                    "{}: `{p}` is not a cycle period (a number of seconds > 0 and at most a day)",
                    meta("period_s")
                )));
            }
        }
        if let Some(sets) = self.rec.metadata.get("sets") {
            self.rec.sets = serde_json::from_str(sets)
                .map_err(|e| self.bad(format!("{}: not a JSON list of `--set`s (strings): {e}", meta("sets"))))?;
        }
        // Dropped cycles: the gap markers and the record at the end, merged.
        let mut dropped = std::mem::take(&mut self.gaps);
        let mut count = 0;
        if let Some((c, ranges)) = self.drops.take() {
            count = c;
            dropped.extend(ranges);
        }
        dropped.sort_unstable();
        let mut merged: Vec<(u64, u64)> = Vec::with_capacity(dropped.len());
        for (a, b) in dropped {
            match merged.last_mut() {
                Some((_, last)) if a <= last.saturating_add(1) => *last = (*last).max(b),
                _ => merged.push((a, b)),
            }
        }
        let total = merged.iter().fold(0u64, |n, (a, b)| n.saturating_add(b - a + 1));
        self.rec.dropped_count = count.max(total);
        self.rec.dropped = merged;
        // Every cycle has its fingerprint, and the cycles follow one another
        // but for those marked dropped: what a replay runs is bounded by
        // what the file holds.
        let mut prev: Option<u64> = None;
        for (&c, cycle) in &self.rec.cycles {
            if cycle.hash.is_none() {
                return Err(self.bad(format!(
                    "cycle {c}: leaves recorded but no `situate/cycles` message for it: a damaged file"
                )));
            }
            if let Some(p) = prev {
                if c > p + 1 && !self.covered(p + 1, c - 1) {
                    return Err(self.bad(format!(
                        "cycle {c} follows cycle {p}: the {} cycles between are neither in the file nor marked as \
                         dropped: a damaged file (or one recorded before situate marked dropped cycles)",
                        c - p - 1
                    )));
                }
            }
            prev = Some(c);
        }
        self.rec.holders = by_resource(&self.rec.winners);
        Ok(self.rec)
    }

    /// A file cut short at byte `at`: the last cycle begun may lack its
    /// fingerprint, keyframe, winners or events, so the cycles kept end one
    /// before it; what is later (cycles, events, winners, keyframes) is left
    /// out. When its data section is whole (the cut is in the summary after
    /// it), every cycle is kept.
    fn trim_cut(&mut self, at: usize, reason: String, whole: bool) {
        let begun = self.rec.cycles.keys().next_back().copied();
        let last =
            if whole { begun } else { begun.and_then(|b| self.rec.cycles.range(..b).next_back().map(|(&c, _)| c)) };
        let keep = |c: u64| last.is_some_and(|l| c <= l);
        let before = self.rec.cycles.len() as u64;
        self.rec.cycles.retain(|&c, _| keep(c));
        let cycles_dropped = before - self.rec.cycles.len() as u64;
        let cycle_of = |j: &Json| j.get("cycle").and_then(Json::as_u64).unwrap_or(0);
        self.rec.events.retain(|(_, j)| keep(cycle_of(j)));
        self.rec.winners.retain(|&(c, _, _)| keep(c));
        self.rec.keyframes.retain(|&c, _| keep(c));
        self.gaps.retain(|&(first, _)| keep(first));
        self.rec.cut_short =
            Some(CutShort { at_byte: at as u64, file_bytes: 0, last_cycle: last, cycles_dropped, reason });
    }

    /// Whether the cycles `first..=last` are all marked dropped.
    fn covered(&self, first: u64, last: u64) -> bool {
        let k = self.rec.dropped.partition_point(|&(_, end)| end < first);
        self.rec.dropped.get(k).is_some_and(|&(a, b)| a <= first && last <= b)
    }
}

/// Each resource's changes of holder, (cycle, skill), by cycle (those of
/// one cycle in the order recorded).
fn by_resource(winners: &[(u64, String, String)]) -> BTreeMap<String, Vec<(u64, String)>> {
    let mut holders: BTreeMap<String, Vec<(u64, String)>> = BTreeMap::new();
    for (c, resource, skill) in winners {
        holders.entry(resource.clone()).or_default().push((*c, skill.clone()));
    }
    for changes in holders.values_mut() {
        changes.sort_by_key(|&(c, _)| c);
    }
    holders
}
