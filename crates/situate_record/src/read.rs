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
    /// Changes of a resource's holder: (cycle, resource leaf, skill).
    pub winners: Vec<(u64, String, String)>,
    /// The events in the order they were recorded: (kind, the event's JSON).
    pub events: Vec<(String, Json)>,
    /// Keyframes by cycle: every leaf's latest (cycle written, value) then.
    pub keyframes: BTreeMap<u64, State>,
    /// Messages read, all channels.
    pub messages: u64,
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
        self.winners.iter().rfind(|(c, r, _)| *c <= cycle && r == resource).map(|(_, _, s)| s.as_str())
    }
}
