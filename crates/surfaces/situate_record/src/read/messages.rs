//! What situate's messages and metadata records say: the cycles, fingerprints, winners,
//! keyframes, events, gap markers and dropped cycles, by topic.

use serde_json::Value as Json;

use super::reader::Reader;
use super::ReadError;

impl Reader {
    pub(super) fn message(&mut self, topic: &str, log_time: u64, bytes: &[u8], place: &str) -> Result<(), ReadError> {
        let data: Json = serde_json::from_slice(bytes)
            .map_err(|e| self.bad(format!("{place}: a message on `{topic}` is not JSON: {e}")))?;
        let cycle = || {
            data.get("cycle")
                .and_then(Json::as_u64)
                .ok_or_else(|| self.bad(format!("{place}: a message on `{topic}` has no cycle")))
        };
        match topic {
            "situate/cycles" => {
                let c = cycle()?;
                let hash =
                    data.get("hash").and_then(Json::as_str).and_then(|h| u64::from_str_radix(h, 16).ok()).ok_or_else(
                        || self.bad(format!("{place}: cycle {c}: `situate/cycles` has no readable hash")),
                    )?;
                let entry = self.rec.cycles.entry(c).or_default();
                entry.hash = Some(hash);
                entry.time_ns = log_time;
            }
            "situate/winners" => {
                let c = cycle()?;
                let field = |k: &str| data.get(k).and_then(Json::as_str).unwrap_or_default().to_string();
                self.rec.winners.push((c, field("resource"), field("skill")));
            }
            crate::GAPS_TOPIC => {
                let first = cycle()?;
                let last = data.get("last").and_then(Json::as_u64).filter(|&l| l >= first).ok_or_else(|| {
                    self.bad(format!("{place}: a gap marker from cycle {first} has no `last` cycle at or after it"))
                })?;
                self.gaps.push((first, last));
            }
            "situate/prints" => {}
            "situate/keyframes" => {
                let c = cycle()?;
                let leaves = data
                    .get("leaves")
                    .and_then(Json::as_object)
                    .ok_or_else(|| self.bad(format!("{place}: keyframe {c} has no leaves")))?;
                let state = leaves
                    .iter()
                    .map(|(path, l)| {
                        let at = l.get("cycle").and_then(Json::as_u64).unwrap_or(0);
                        (path.clone(), (at, l.get("value").cloned().unwrap_or(Json::Null)))
                    })
                    .collect();
                self.rec.keyframes.insert(c, state);
            }
            t if t.starts_with("situate/events/") => {
                self.rec.events.push((t["situate/events/".len()..].to_string(), data));
            }
            t if t.starts_with("situate/") => {}
            leaf => {
                let c = cycle()?;
                let value = data.get("value").cloned().unwrap_or(Json::Null);
                let entry = self.rec.cycles.entry(c).or_default();
                entry.time_ns = log_time;
                entry.leaves.push((leaf.to_string(), value));
            }
        }
        Ok(())
    }

    pub(super) fn metadata(&mut self, m: mcap::records::Metadata) -> Result<(), ReadError> {
        if m.name == "situate" {
            self.rec.metadata = m.metadata;
        } else if m.name == crate::DROPS_METADATA {
            let place = format!("the metadata record `{}`", crate::DROPS_METADATA);
            let count = m
                .metadata
                .get("dropped_cycles")
                .and_then(|c| c.parse::<u64>().ok())
                .ok_or_else(|| self.bad(format!("{place}: `dropped_cycles` is not a count")))?;
            let ranges: Vec<(u64, u64)> = m
                .metadata
                .get("ranges")
                .and_then(|r| serde_json::from_str(r).ok())
                .filter(|r: &Vec<(u64, u64)>| r.iter().all(|(a, b)| a <= b))
                .ok_or_else(|| self.bad(format!("{place}: `ranges` is not a JSON list of [first, last] cycles")))?;
            self.drops = Some((count, ranges));
        }
        Ok(())
    }
}
