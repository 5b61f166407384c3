//! Reading a recording back (for `situate replay`): the metadata, each
//! cycle's written leaves (as JSON: their types come from the robot the
//! replay builds) and fingerprint, the resources' winners and the events.
//!
//! The whole file is read into memory and indexed by cycle: a 10-minute
//! delivery is about 5 MB of file and a few tens of MB indexed. A file cut
//! short (a robot killed while recording) has no summary; it is read from
//! its start as far as it goes, and the problem, if any, is named.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value as Json;

/// What went wrong reading a recording.
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: not a readable MCAP file: {source}", path.display())]
    Mcap { path: PathBuf, source: mcap::McapError },
    #[error("{}: {message}", path.display())]
    Bad { path: PathBuf, message: String },
}

/// One recorded cycle.
#[derive(Debug, Clone, Default)]
pub struct Cycle {
    /// The manager's clock, ns.
    pub time_ns: u64,
    /// Its fingerprint (`situate/cycles`), when the recording has one.
    pub hash: Option<u64>,
    /// The leaves written in it: (path, value as recorded).
    pub leaves: Vec<(String, Json)>,
}

/// A recording, indexed by cycle.
#[derive(Debug, Clone, Default)]
pub struct Recording {
    pub path: PathBuf,
    /// The `situate` metadata record (robot, period_s, robot_file, sets, …).
    pub metadata: BTreeMap<String, String>,
    pub cycles: BTreeMap<u64, Cycle>,
    /// Changes of a resource's holder: (cycle, resource leaf, skill), in
    /// the order recorded ([`Recording::holder`] looks them up in an index
    /// made when the recording is read).
    pub winners: Vec<(u64, String, String)>,
    /// The events in the order they were recorded: (kind, the event's JSON).
    pub events: Vec<(String, Json)>,
    /// Keyframes by cycle: every leaf's latest (cycle written, value) then.
    pub keyframes: BTreeMap<u64, State>,
    /// Messages read, all channels.
    pub messages: u64,
    /// `winners` by resource: (cycle, skill), by cycle.
    holders: BTreeMap<String, Vec<(u64, String)>>,
}

/// Every leaf's latest value at a cycle: path → (the cycle it was written
/// in, the value as recorded).
pub type State = BTreeMap<String, (u64, Json)>;

impl Recording {
    /// Reads the recording at `path`.
    pub fn open(path: &Path) -> Result<Recording, ReadError> {
        let bytes = std::fs::read(path).map_err(|source| ReadError::Io { path: path.to_path_buf(), source })?;
        Recording::from_bytes(path, &bytes)
    }

    /// Reads a recording held in memory (`path` names it in errors).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Recording, ReadError> {
        let mcap_error = |source| ReadError::Mcap { path: path.to_path_buf(), source };
        let bad = |message: String| ReadError::Bad { path: path.to_path_buf(), message };
        let mut rec = Recording { path: path.to_path_buf(), ..Recording::default() };
        for record in mcap::read::LinearReader::new(bytes).map_err(mcap_error)? {
            if let mcap::records::Record::Metadata(m) = record.map_err(mcap_error)? {
                if m.name == "situate" {
                    rec.metadata = m.metadata;
                }
            }
        }
        if rec.metadata.is_empty() {
            return Err(bad("no `situate` metadata record: not a recording made by situate".into()));
        }
        for message in mcap::MessageStream::new(bytes).map_err(mcap_error)? {
            let message = message.map_err(mcap_error)?;
            rec.messages += 1;
            let topic = message.channel.topic.as_str();
            let data: Json = serde_json::from_slice(&message.data)
                .map_err(|e| bad(format!("a message on `{topic}` is not JSON: {e}")))?;
            let cycle = || {
                data.get("cycle")
                    .and_then(Json::as_u64)
                    .ok_or_else(|| bad(format!("a message on `{topic}` has no cycle")))
            };
            match topic {
                "situate/cycles" => {
                    let c = cycle()?;
                    let hash = data
                        .get("hash")
                        .and_then(Json::as_str)
                        .and_then(|h| u64::from_str_radix(h, 16).ok())
                        .ok_or_else(|| bad(format!("cycle {c}: `situate/cycles` has no readable hash")))?;
                    let entry = rec.cycles.entry(c).or_default();
                    entry.hash = Some(hash);
                    entry.time_ns = message.log_time;
                }
                "situate/winners" => {
                    let c = cycle()?;
                    let field = |k: &str| data.get(k).and_then(Json::as_str).unwrap_or_default().to_string();
                    rec.winners.push((c, field("resource"), field("skill")));
                }
                "situate/prints" => {}
                "situate/keyframes" => {
                    let c = cycle()?;
                    let leaves = data
                        .get("leaves")
                        .and_then(Json::as_object)
                        .ok_or_else(|| bad(format!("keyframe {c} has no leaves")))?;
                    let state = leaves
                        .iter()
                        .map(|(path, l)| {
                            let at = l.get("cycle").and_then(Json::as_u64).unwrap_or(0);
                            (path.clone(), (at, l.get("value").cloned().unwrap_or(Json::Null)))
                        })
                        .collect();
                    rec.keyframes.insert(c, state);
                }
                t if t.starts_with("situate/events/") => {
                    rec.events.push((t["situate/events/".len()..].to_string(), data));
                }
                t if t.starts_with("situate/") => {}
                leaf => {
                    let c = cycle()?;
                    let value = data.get("value").cloned().unwrap_or(Json::Null);
                    let entry = rec.cycles.entry(c).or_default();
                    entry.time_ns = message.log_time;
                    entry.leaves.push((leaf.to_string(), value));
                }
            }
        }
        rec.holders = by_resource(&rec.winners);
        Ok(rec)
    }

    /// The cycle period the recording was made with, s.
    pub fn period_s(&self) -> Option<f64> {
        self.metadata.get("period_s").and_then(|p| p.parse().ok())
    }

    /// The first and last cycle recorded.
    pub fn span(&self) -> Option<(u64, u64)> {
        Some((*self.cycles.keys().next()?, *self.cycles.keys().next_back()?))
    }

    /// Every leaf's latest value at the end of `cycle`: from the keyframe at
    /// or before it, then the cycles after that one (at most
    /// [`crate::KEYFRAME_CYCLES`] of them).
    pub fn state_at(&self, cycle: u64) -> State {
        let (mut state, from) = match self.keyframes.range(..=cycle).next_back() {
            Some((&k, s)) => (s.clone(), k + 1),
            None => (State::new(), 0),
        };
        if from > cycle {
            return state;
        }
        for (&c, rec) in self.cycles.range(from..=cycle) {
            for (path, value) in &rec.leaves {
                state.insert(path.clone(), (c, value.clone()));
            }
        }
        state
    }

    /// Who held `resource` in `cycle` (the last change at or before it).
    pub fn holder(&self, resource: &str, cycle: u64) -> Option<&str> {
        let changes = self.holders.get(resource)?;
        let k = changes.partition_point(|&(c, _)| c <= cycle);
        k.checked_sub(1).map(|j| changes[j].1.as_str())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A recording holding only these changes of holder, (cycle, resource,
    /// skill), in this order.
    fn with_winners(winners: &[(u64, &str, &str)]) -> Recording {
        let mut w = mcap::WriteOptions::new().create(std::io::Cursor::new(Vec::new())).unwrap();
        let metadata = BTreeMap::from([("robot".to_string(), "test".to_string())]);
        w.write_metadata(&mcap::records::Metadata { name: "situate".into(), metadata }).unwrap();
        let schema = w.add_schema("situate.winner", "jsonschema", b"{}").unwrap();
        let channel = w.add_channel(schema, "situate/winners", "json", &BTreeMap::new()).unwrap();
        for (k, &(cycle, resource, skill)) in winners.iter().enumerate() {
            let header = mcap::records::MessageHeader {
                channel_id: channel,
                sequence: k as u32,
                log_time: cycle,
                publish_time: cycle,
            };
            let data = serde_json::json!({"cycle": cycle, "resource": resource, "skill": skill});
            w.write_to_known_channel(&header, &serde_json::to_vec(&data).unwrap()).unwrap();
        }
        w.finish().unwrap();
        let bytes = w.into_inner().into_inner();
        Recording::from_bytes(Path::new("winners.mcap"), &bytes).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn holder_is_the_last_change_at_or_before_the_cycle() {
        let rec = with_winners(&[
            (10, "arm.cmd", "low"),
            (12, "wheels.cmd", "nav"),
            (20, "arm.cmd", "high"),
            (35, "arm.cmd", "low"),
            (35, "wheels.cmd", "dock"),
            (35, "wheels.cmd", "stop"),
        ]);
        assert_eq!(rec.winners.len(), 6);
        // Before the resource's first change: no one.
        assert_eq!(rec.holder("arm.cmd", 0), None);
        assert_eq!(rec.holder("arm.cmd", 9), None);
        assert_eq!(rec.holder("wheels.cmd", 11), None);
        // At a change's cycle: that change.
        assert_eq!(rec.holder("arm.cmd", 10), Some("low"));
        assert_eq!(rec.holder("arm.cmd", 20), Some("high"));
        assert_eq!(rec.holder("wheels.cmd", 12), Some("nav"));
        // Two changes in one cycle: the later one recorded.
        assert_eq!(rec.holder("wheels.cmd", 35), Some("stop"));
        // Between changes, and after the last: the one before.
        assert_eq!(rec.holder("arm.cmd", 11), Some("low"));
        assert_eq!(rec.holder("arm.cmd", 34), Some("high"));
        assert_eq!(rec.holder("arm.cmd", u64::MAX), Some("low"));
        assert_eq!(rec.holder("wheels.cmd", 34), Some("nav"));
        // Another resource's changes are not this one's.
        assert_eq!(rec.holder("gripper.cmd", 20), None);
        assert_eq!(rec.holder("arm", 20), None);
        // The same answers as a scan of every change, at every cycle.
        for resource in ["arm.cmd", "wheels.cmd", "gripper.cmd"] {
            for cycle in 0..40 {
                let scan =
                    rec.winners.iter().rfind(|(c, r, _)| *c <= cycle && r == resource).map(|(_, _, s)| s.as_str());
                assert_eq!(rec.holder(resource, cycle), scan, "{resource} at {cycle}");
            }
        }
    }
}
