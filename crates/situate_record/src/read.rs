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

use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::io::Read as _;
use std::path::{Path, PathBuf};

use mcap::records::{op, Record};
use serde_json::Value as Json;

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

/// A record's name, for messages.
fn record_name(opcode: u8) -> String {
    let name = match opcode {
        op::HEADER => "header",
        op::FOOTER => "footer",
        op::SCHEMA => "schema",
        op::CHANNEL => "channel",
        op::MESSAGE => "message",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index",
        op::CHUNK_INDEX => "chunk index",
        op::ATTACHMENT => "attachment",
        op::ATTACHMENT_INDEX => "attachment index",
        op::STATISTICS => "statistics",
        op::METADATA => "metadata",
        op::METADATA_INDEX => "metadata index",
        op::SUMMARY_OFFSET => "summary offset",
        op::DATA_END => "data end",
        _ => return format!("unknown record type 0x{opcode:02x}"),
    };
    name.to_string()
}

/// One record of a run of records: its number in the run, where it starts
/// (in the run's bytes), its opcode and body; an error saying which record
/// the bytes end inside.
fn records(bytes: &[u8], start: usize) -> impl Iterator<Item = Result<(u64, usize, u8, &[u8]), String>> {
    let mut pos = start;
    let mut k = 0u64;
    std::iter::from_fn(move || {
        if pos >= bytes.len() {
            return None;
        }
        let at = pos;
        let left = bytes.len() - pos;
        if left < 9 {
            pos = bytes.len();
            return Some(Err(format!("record {k} at byte {at}: the bytes end inside its header ({left} of 9 bytes)")));
        }
        let opcode = bytes[pos];
        let mut len_bytes = [0u8; 8];
        len_bytes.copy_from_slice(&bytes[pos + 1..pos + 9]);
        let len = u64::from_le_bytes(len_bytes);
        let avail = (left - 9) as u64;
        if len > avail {
            pos = bytes.len();
            return Some(Err(format!(
                "record {k} at byte {at} ({}): its length, {len} bytes, runs past the end ({avail} bytes left)",
                record_name(opcode)
            )));
        }
        let body = &bytes[pos + 9..pos + 9 + len as usize];
        pos += 9 + len as usize;
        k += 1;
        Some(Ok((k - 1, at, opcode, body)))
    })
}

/// A recording being read.
struct Reader {
    rec: Recording,
    /// Channel id → topic.
    channels: HashMap<u16, String>,
    chunks: u64,
    /// Bytes decompressed so far.
    uncompressed: u64,
    /// `situate/gaps` markers: (first, last).
    gaps: Vec<(u64, u64)>,
    /// The `situate_drops` record: how many, which.
    drops: Option<(u64, Vec<(u64, u64)>)>,
    statistics: Option<mcap::records::Statistics>,
    /// Whether a file cut short is read up to where it ends.
    recover: bool,
    /// Where such a file ended: (byte, why, whether its data section was whole).
    cut: Option<(usize, String, bool)>,
}

impl Reader {
    fn bad(&self, message: String) -> ReadError {
        ReadError::Bad { path: self.rec.path.clone(), message }
    }

    /// Walks the file's records: header, data section, data end, summary,
    /// footer, magic.
    fn read(&mut self, bytes: &[u8]) -> Result<(), ReadError> {
        if bytes.len() < mcap::MAGIC.len() || &bytes[..mcap::MAGIC.len()] != mcap::MAGIC {
            return Err(self.bad("not an MCAP file: it does not start with the MCAP magic bytes".into()));
        }
        // Where the data section ends and the summary starts, once seen.
        let mut summary_start: Option<usize> = None;
        // Where the records read so far end (a file cut short ends there).
        let mut end = mcap::MAGIC.len();
        for record in records(bytes, mcap::MAGIC.len()) {
            let (k, at, opcode, body) = match record {
                Ok(r) => r,
                Err(m) if self.recover => {
                    self.cut = Some((end, m, summary_start.is_some()));
                    return Ok(());
                }
                Err(m) => {
                    return Err(self
                        .bad(format!("{m}: the file is cut short or damaged (--recover reads the cycles before it)")))
                }
            };
            // A power cut leaves blocks of zeros where the last writes were to go.
            if self.recover && opcode == 0 && bytes[at..].iter().all(|&b| b == 0) {
                let reason = format!("the rest of the file, {} bytes from byte {at}, is zeros", bytes.len() - at);
                self.cut = Some((at, reason, summary_start.is_some()));
                return Ok(());
            }
            end = at + 9 + body.len();
            let place = || format!("record {k} at byte {at} ({})", record_name(opcode));
            let parse = |this: &Self| {
                mcap::parse_record(opcode, body).map_err(|e| this.bad(format!("{}: {e}: a damaged file", place())))
            };
            if k == 0 && opcode != op::HEADER {
                return Err(self.bad(format!("{}: the file does not begin with an MCAP header", place())));
            }
            match opcode {
                op::HEADER if k == 0 => {}
                op::SCHEMA | op::CHANNEL | op::MESSAGE => {
                    let record = parse(self)?;
                    self.inner(record, &place())?;
                }
                op::CHUNK if summary_start.is_none() => self.chunk(body, &place())?,
                op::METADATA => {
                    if let Record::Metadata(m) = parse(self)? {
                        self.metadata(m)?;
                    }
                }
                op::STATISTICS => {
                    if let Record::Statistics(s) = parse(self)? {
                        self.statistics = Some(s);
                    }
                }
                op::MESSAGE_INDEX
                | op::CHUNK_INDEX
                | op::ATTACHMENT
                | op::ATTACHMENT_INDEX
                | op::METADATA_INDEX
                | op::SUMMARY_OFFSET => {}
                op::DATA_END if summary_start.is_none() => {
                    if let Record::DataEnd(end) = parse(self)? {
                        let computed = crc32fast::hash(&bytes[..at]);
                        if end.data_section_crc != 0 && end.data_section_crc != computed {
                            return Err(self.bad(format!(
                                "{}: the data section's CRC is {:08x}, the file's says {:08x}: the file was changed \
                                 or damaged after it was written",
                                place(),
                                computed,
                                end.data_section_crc
                            )));
                        }
                    }
                    summary_start = Some(at + 9 + body.len());
                }
                op::FOOTER => {
                    let Some(start) = summary_start else {
                        return Err(self.bad(format!("{}: a footer before the data end record", place())));
                    };
                    if let Record::Footer(footer) = parse(self)? {
                        // Over the summary section and the footer up to its CRC.
                        let end = at + 9 + 16;
                        if footer.summary_crc != 0 && end <= bytes.len() {
                            let computed = crc32fast::hash(&bytes[start..end]);
                            if computed != footer.summary_crc {
                                return Err(self.bad(format!(
                                    "{}: the summary's CRC is {:08x}, the footer says {:08x}: a damaged summary",
                                    place(),
                                    computed,
                                    footer.summary_crc
                                )));
                            }
                        }
                    }
                    let tail = &bytes[at + 9 + body.len()..];
                    if tail != mcap::MAGIC {
                        return Err(self.bad(format!(
                            "byte {}: the file does not end with the MCAP magic bytes after its footer: cut short or \
                             damaged",
                            at + 9 + body.len()
                        )));
                    }
                    return Ok(());
                }
                _ => return Err(self.bad(format!("{}: not a record a recording holds here: a damaged file", place()))),
            }
        }
        let missing = if summary_start.is_some() { "footer" } else { "data end record, summary and footer" };
        if self.recover {
            // The data section was read whole when the summary began: only the
            // index is lost, and nothing of the run.
            self.cut = Some((end, format!("the file ends without its {missing}"), summary_start.is_some()));
            return Ok(());
        }
        Err(self.bad(format!(
            "the file ends at byte {} without its {missing}: it was cut short (a recording that was not finished, \
             such as a robot killed while recording; --recover reads the cycles it holds)",
            bytes.len(),
        )))
    }

    /// A chunk: its header checked, decompressed (bounded), its CRC
    /// checked, its records read.
    fn chunk(&mut self, body: &[u8], place: &str) -> Result<(), ReadError> {
        let (header, data) = match mcap::parse_record(op::CHUNK, body) {
            Ok(Record::Chunk { header, data }) => (header, data),
            Ok(_) => return Err(self.bad(format!("{place}: not a chunk"))),
            Err(e) => return Err(self.bad(format!("{place}: {e}: a damaged chunk header"))),
        };
        let header_len = 8 + 8 + 8 + 4 + 4 + header.compression.len() + 8;
        let held = body.len().saturating_sub(header_len) as u64;
        if header.compressed_size != held {
            return Err(self.bad(format!(
                "{place}: its header says {} compressed bytes, the record holds {held}: a damaged chunk header",
                header.compressed_size
            )));
        }
        if header.uncompressed_crc == 0 {
            return Err(self.bad(format!(
                "{place}: its header has no CRC (situate writes one in every chunk): a damaged chunk header"
            )));
        }
        if header.uncompressed_size > MAX_CHUNK_BYTES {
            return Err(self.bad(format!(
                "{place}: its header says {} bytes uncompressed, more than the {MAX_CHUNK_BYTES} a chunk may hold \
                 (situate writes about 1 MiB): a damaged chunk header",
                header.uncompressed_size
            )));
        }
        self.uncompressed += header.uncompressed_size;
        if self.uncompressed > MAX_UNCOMPRESSED_BYTES {
            return Err(self.bad(format!(
                "{place}: the chunks so far hold more than {MAX_UNCOMPRESSED_BYTES} bytes uncompressed, more than a \
                 recording is read up to"
            )));
        }
        let content: Cow<'_, [u8]> = match header.compression.as_str() {
            "zstd" => Cow::Owned(
                zstd::bulk::decompress(&data, header.uncompressed_size as usize)
                    .map_err(|e| self.bad(format!("{place}: cannot be decompressed ({e}): a damaged chunk")))?,
            ),
            "" => data,
            other => {
                return Err(self.bad(format!("{place}: compressed with `{other}`; situate writes zstd (or nothing)")))
            }
        };
        if content.len() as u64 != header.uncompressed_size {
            return Err(self.bad(format!(
                "{place}: it holds {} bytes uncompressed, its header says {}: a damaged chunk",
                content.len(),
                header.uncompressed_size
            )));
        }
        let crc = crc32fast::hash(&content);
        if crc != header.uncompressed_crc {
            return Err(self.bad(format!(
                "{place}: its CRC is {crc:08x}, its header says {:08x}: a damaged chunk",
                header.uncompressed_crc
            )));
        }
        self.chunks += 1;
        for record in records(&content, 0) {
            let (k, at, opcode, body) =
                record.map_err(|m| self.bad(format!("{place}, its {m} of its records: a damaged chunk")))?;
            let inner = || format!("{place}, its record {k} at byte {at} of its records ({})", record_name(opcode));
            if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                return Err(self.bad(format!("{}: not a record a chunk holds: a damaged chunk", inner())));
            }
            let record =
                mcap::parse_record(opcode, body).map_err(|e| self.bad(format!("{}: {e}: a damaged chunk", inner())))?;
            self.inner(record, &inner())?;
        }
        Ok(())
    }

    /// A schema, a channel or a message.
    fn inner(&mut self, record: Record<'_>, place: &str) -> Result<(), ReadError> {
        match record {
            Record::Channel(c) => {
                if let Some(topic) = self.channels.get(&c.id) {
                    if *topic != c.topic {
                        return Err(self.bad(format!(
                            "{place}: channel {} is `{}` here and `{topic}` before: a damaged file",
                            c.id, c.topic
                        )));
                    }
                }
                self.channels.insert(c.id, c.topic);
            }
            Record::Message { header, data } => {
                self.rec.messages += 1;
                let Some(topic) = self.channels.get(&header.channel_id).cloned() else {
                    return Err(self.bad(format!(
                        "{place}: a message on channel {}, which no channel record before it defines: a damaged file",
                        header.channel_id
                    )));
                };
                self.message(&topic, header.log_time, &data, place)?;
            }
            _ => {}
        }
        Ok(())
    }

    fn message(&mut self, topic: &str, log_time: u64, bytes: &[u8], place: &str) -> Result<(), ReadError> {
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

    fn metadata(&mut self, m: mcap::records::Metadata) -> Result<(), ReadError> {
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

    /// Checks what was read as a whole, and indexes it.
    fn finish(mut self) -> Result<Recording, ReadError> {
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
