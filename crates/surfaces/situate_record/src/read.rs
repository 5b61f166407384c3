//! Reading a recording back (for `situate replay`): the metadata, each
//! cycle's written leaves (as JSON: their types come from the robot the
//! replay builds) and fingerprint, the resources' winners, the events, and
//! the cycles dropped while recording.
//!
//! The whole file is read into memory and indexed by cycle: a 10-minute
//! delivery is about 5 MB of file and a few tens of MB indexed. Nothing in
//! the file is trusted: it must be a regular file of at most
//! [`MAX_FILE_BYTES`]; every record's length is checked against the bytes
//! present; every chunk must say its size truthfully, hold at most
//! [`MAX_CHUNK_BYTES`] uncompressed (all of them at most
//! [`MAX_UNCOMPRESSED_BYTES`]) and match its CRC; the data section's and the
//! summary's CRCs and the summary's message count must agree with what was
//! read; and the cycles must follow one another, but for those the file
//! marks as dropped. A file cut short (a robot killed while recording) has
//! no summary: [`Recording::open`] refuses it, saying where it ends;
//! [`Recording::open_cut_short`] reads it up to its last complete cycle and
//! says what it lost ([`CutShort`]). Each problem is named with where it is
//! (the record and its byte offset, the cycle).

use std::collections::{BTreeMap, HashMap};
use std::io::Read as _;
use std::path::{Path, PathBuf};

use serde_json::Value as Json;

mod finish;
mod messages;
mod reader;
mod records;

use reader::Reader;

/// The largest recording read (it is read whole, and indexed in memory at
/// about ten times its size).
pub const MAX_FILE_BYTES: u64 = 1 << 30;

/// The most one chunk may hold uncompressed (situate writes chunks of about
/// 1 MiB).
pub const MAX_CHUNK_BYTES: u64 = 64 << 20;

/// The most all chunks may hold uncompressed, together.
pub const MAX_UNCOMPRESSED_BYTES: u64 = 4 << 30;

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
    /// The run's `--set`s (the metadata's `sets`, a JSON list of strings).
    pub sets: Vec<String>,
    pub cycles: BTreeMap<u64, Cycle>,
    /// Cycles dropped while recording (the writer fell behind a wall-clock
    /// run): (first, last) ranges, in order, apart from each other. They
    /// may lie past the last cycle recorded.
    pub dropped: Vec<(u64, u64)>,
    /// How many cycles were dropped (at least the ranges' total).
    pub dropped_count: u64,
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
    /// Read from a file cut short ([`Recording::open_cut_short`]): where it
    /// ends and what was kept. `None`: a complete file.
    pub cut_short: Option<CutShort>,
    /// `winners` by resource: (cycle, skill), by cycle.
    holders: BTreeMap<String, Vec<(u64, String)>>,
}

/// What a recording cut short (a robot killed while recording, a full disk)
/// kept and lost. Its end is in the last chunk that was not written whole,
/// and the last cycle written before it may lack a message (the writer puts
/// a cycle's leaves, then its fingerprint, keyframe and winners), so the
/// cycles kept end one before the last one begun.
#[derive(Debug, Clone, PartialEq)]
pub struct CutShort {
    /// Where the readable records end (the file's size past them).
    pub at_byte: u64,
    pub file_bytes: u64,
    /// The last cycle kept (`None`: none was complete).
    pub last_cycle: Option<u64>,
    /// Cycles begun in the file but not kept (the last one or two).
    pub cycles_dropped: u64,
    /// Why the file ends there, as the reader found it.
    pub reason: String,
}

impl std::fmt::Display for CutShort {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "cut short at byte {} of {} (not finished: the robot was killed, or its disk filled): ",
            self.at_byte, self.file_bytes
        )?;
        match self.last_cycle {
            Some(c) => write!(f, "read up to cycle {c}, the last complete one")?,
            None => write!(f, "no complete cycle in it")?,
        }
        if self.cycles_dropped > 0 {
            write!(f, " ({} later cycle(s) begun but incomplete, left out)", self.cycles_dropped)?;
        }
        Ok(())
    }
}

/// Every leaf's latest value at a cycle: path → (the cycle it was written
/// in, the value as recorded).
pub type State = BTreeMap<String, (u64, Json)>;

impl Recording {
    /// Reads the recording at `path`: a regular file of at most
    /// [`MAX_FILE_BYTES`] (a device, a pipe or a directory is refused
    /// before anything is read).
    pub fn open(path: &Path) -> Result<Recording, ReadError> {
        Recording::open_with(path, false)
    }

    /// [`Recording::open`], but a file cut short (no data end, summary or
    /// footer: a robot killed while recording) is read up to its last
    /// complete cycle, and [`Recording::cut_short`] says where it ended and
    /// what was left out. A complete file reads as with `open`. Damage that
    /// is not a cut (a CRC that does not match, a chunk that lies about its
    /// size) is refused as with `open`.
    pub fn open_cut_short(path: &Path) -> Result<Recording, ReadError> {
        Recording::open_with(path, true)
    }

    fn open_with(path: &Path, recover: bool) -> Result<Recording, ReadError> {
        let io = |source| ReadError::Io { path: path.to_path_buf(), source };
        let bad = |message: String| ReadError::Bad { path: path.to_path_buf(), message };
        let file = std::fs::File::open(path).map_err(io)?;
        let meta = file.metadata().map_err(io)?;
        if !meta.is_file() {
            return Err(bad("not a regular file (a recording is an MCAP file, made by `--record`)".into()));
        }
        let len = meta.len();
        if len > MAX_FILE_BYTES {
            return Err(bad(format!(
                "{len} bytes: larger than the {} bytes a recording is read up to (it is read whole into memory)",
                MAX_FILE_BYTES
            )));
        }
        // No more than the size said: a file that grows meanwhile is read
        // as it was.
        let mut bytes = Vec::with_capacity(len as usize);
        file.take(len).read_to_end(&mut bytes).map_err(io)?;
        Recording::read_bytes(path, &bytes, recover)
    }

    /// Reads a recording held in memory (`path` names it in errors).
    pub fn from_bytes(path: &Path, bytes: &[u8]) -> Result<Recording, ReadError> {
        Recording::read_bytes(path, bytes, false)
    }

    /// [`Recording::from_bytes`], reading a recording cut short as
    /// [`Recording::open_cut_short`] does.
    pub fn from_bytes_cut_short(path: &Path, bytes: &[u8]) -> Result<Recording, ReadError> {
        Recording::read_bytes(path, bytes, true)
    }

    fn read_bytes(path: &Path, bytes: &[u8], recover: bool) -> Result<Recording, ReadError> {
        let mut reader = Reader {
            recover,
            cut: None,
            rec: Recording { path: path.to_path_buf(), ..Recording::default() },
            channels: HashMap::new(),
            chunks: 0,
            uncompressed: 0,
            gaps: Vec::new(),
            drops: None,
            statistics: None,
        };
        reader.read(bytes)?;
        let mut rec = reader.finish()?;
        if let Some(cut) = &mut rec.cut_short {
            cut.file_bytes = bytes.len() as u64;
        }
        Ok(rec)
    }

    /// The cycle period the recording was made with, s (checked when the
    /// file is read: finite, > 0 and at most a day).
    pub fn period_s(&self) -> Option<f64> {
        self.metadata.get("period_s").and_then(|p| p.parse().ok())
    }

    /// The first and last cycle recorded.
    pub fn span(&self) -> Option<(u64, u64)> {
        Some((*self.cycles.keys().next()?, *self.cycles.keys().next_back()?))
    }

    /// The first cycle dropped while recording at or after `cycle`.
    pub fn first_dropped_from(&self, cycle: u64) -> Option<u64> {
        let k = self.dropped.partition_point(|&(_, last)| last < cycle);
        self.dropped.get(k).map(|&(first, _)| first.max(cycle))
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
