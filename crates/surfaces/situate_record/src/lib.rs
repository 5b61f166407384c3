//! Recording a robot's run to an MCAP file, for Foxglove, PlotJuggler,
//! Rerun or the `mcap` libraries.
//!
//! [`Recorder::start`] taps the manager's cycle ([`Manager::tap`]) and
//! subscribes to its events before it is spawned; a thread of its own writes
//! them as they come, so the file grows with the run and memory stays flat.
//! On the simulated clock the cycle waits for the writer when it is
//! [`QUEUE_FRAMES`] cycles behind (no robot time passes meanwhile: the run
//! is the same, only slower), so no cycle is lost. On the wall clock the
//! cycle never waits: a frame that finds the queue full is dropped and
//! counted ([`Summary::dropped`]), and the file says which cycles it lacks
//! (`situate/gaps` and the `situate_drops` metadata record), so a replay
//! never takes it for complete.
//!
//! What the file holds (JSON messages, each channel with a JSON Schema, so a
//! viewer needs no plug-in):
//! - one channel per signal leaf (topic: its path, such as `sonar.range` or
//!   `odom.x`), a message `{"cycle", "value"}` in each cycle that wrote it;
//! - one channel per kind of event (topic `situate/events/<kind>`: skill
//!   activations, parameter changes, monitor events, faults, the manager
//!   started or stopped, …), each message the event's JSON as the link
//!   publishes it (`docs/protocol.md`);
//! - `situate/prints`: every skill's prints, verbose or not
//!   (`{"cycle", "skill", "line"}`);
//! - `situate/winners`: who holds each resource, when that changes
//!   (`{"cycle", "resource", "skill"}`);
//! - `situate/keyframes`: every [`KEYFRAME_CYCLES`] cycles, every leaf's
//!   latest value and the cycle it was written in,
//!   `{"cycle", "leaves": {path: {"cycle", "value"}}}`;
//! - `situate/cycles`: one message per cycle, `{"cycle", "hash", "leaves"}`,
//!   the cycle's fingerprint ([`hash::cycle_hash`], 16 hex digits) and how
//!   many leaves were written: two runs are the same where these are;
//! - `situate/gaps`: cycles dropped while recording (wall clock only), one
//!   message per run of them, `{"cycle": first, "last", "count"}`, written
//!   as soon as the writer sees the gap (the cycles after it) or at the end;
//! - a metadata record `situate` (robot, period, leaves, the robot's wiring
//!   ([`wiring`]: each skill's ports, parameters and state, so a viewer needs
//!   no robot file), and what the caller adds: the robot file and its
//!   `--set`s, so `situate replay` can rebuild the robot), and at the end one `situate_drops`: `dropped_cycles` (how
//!   many) and `ranges` (which: a JSON list of `[first, last]`).
//!
//! A message's `log_time` and `publish_time` are Unix time in nanoseconds:
//! the wall-clock time the run started at (the metadata's
//! `time_origin_unix_ns`: when the recording started, less the manager's
//! clock then) plus the manager's clock at the cycle (simulated or wall), so
//! a tool showing them (Foxglove) shows the run's date and time of day, and
//! the manager's clock is `log_time - time_origin_unix_ns`. The cycle is in
//! every message.
//! The file is chunked (zstd) and indexed, so a reader can seek by time.

mod encode;
pub mod hash;
pub mod read;
pub mod replay;
mod schema;
pub mod wiring;

use std::collections::{BTreeMap, HashMap, VecDeque};
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::thread::JoinHandle;

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};
use serde_json::{json, Value as Json};
use situate_core::SignalType;
use situate_link::json::event_to_json;
use std::time::Duration;

use situate_manager::frame::{Drops, TapOptions};
use situate_manager::{Control, Event, Frame, Handle, Manager, Reply, Request, TapReceiver};

pub use schema::{leaf_schema, message_schema};

/// Frames the cycle may get ahead of the file by (at 100 Hz, 40 s).
pub const QUEUE_FRAMES: usize = 4096;

/// The cycle an event names (`None`: it names none).
fn event_cycle(event: &Event) -> Option<u64> {
    event_to_json(event).1.get("cycle").and_then(Json::as_u64)
}

/// The metadata record written when the recording ends: which cycles it
/// lacks (`dropped_cycles`, `ranges`).
pub const DROPS_METADATA: &str = "situate_drops";
/// The `situate` metadata's key for the run's start in Unix time (ns): every message's `log_time`
/// is it plus the manager's clock at the message's cycle.
pub const TIME_ORIGIN_METADATA: &str = "time_origin_unix_ns";

/// The topic of the gap markers: cycles dropped while recording.
pub const GAPS_TOPIC: &str = "situate/gaps";

/// How often the writer looks for new frames.
const POLL: Duration = Duration::from_millis(5);

/// A keyframe (`situate/keyframes`: every leaf's latest value) every this
/// many cycles, so a reader can have the state at any cycle from the
/// keyframe before it and at most this many cycles of messages.
pub const KEYFRAME_CYCLES: u64 = 100;

/// What went wrong with a recording.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: writing MCAP: {source}", path.display())]
    Mcap { path: PathBuf, source: mcap::McapError },
    #[error("{}: the recorder's thread ended without finishing the file", path.display())]
    Lost { path: PathBuf },
    #[error("{}: the robot did not start the recording: {message}", path.display())]
    Robot { path: PathBuf, message: String },
}

/// What a finished recording holds.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Summary {
    pub path: PathBuf,
    /// Cycles recorded.
    pub frames: u64,
    /// Messages written, all channels.
    pub messages: u64,
    pub channels: usize,
    /// Cycles lost because the writer fell behind by [`QUEUE_FRAMES`]
    /// (wall clock only: on the simulated clock the cycle waits).
    pub dropped: u64,
    /// Which: (first, last) ranges of cycles, as the file says them.
    pub dropped_ranges: Vec<(u64, u64)>,
    /// The file's size.
    pub bytes: u64,
    /// The first and last cycle recorded.
    pub cycles: Option<(u64, u64)>,
}

/// How a recording is made; [`Options::default`] for the usual.
#[derive(Debug, Clone)]
pub struct Options {
    /// Frames the cycle may get ahead of the file by ([`QUEUE_FRAMES`]).
    pub queue_frames: usize,
    /// For tests (a writer that falls behind, on demand): the writer waits
    /// for a message here before and after each round of reading the queue,
    /// so a sender (of a zero-capacity channel) that has sent two knows the
    /// writer read the queue once and reads it no more until it sends
    /// again. Once the sender is dropped it no longer waits. On the
    /// simulated clock a held writer holds the robot's cycle too;
    /// [`Recorder::finish`] waits for the writer: drop the sender first.
    #[doc(hidden)]
    pub hold: Option<Receiver<()>>,
}

impl Default for Options {
    fn default() -> Options {
        Options { queue_frames: QUEUE_FRAMES, hold: None }
    }
}

/// Where a recording's cycles come from.
enum Source<'a> {
    /// A manager not spawned yet.
    Manager(&'a mut Manager),
    /// A running manager, and how long to wait for it.
    Handle(&'a Handle, Duration),
}

/// A recording under way (see the module).
pub struct Recorder {
    stop: Sender<()>,
    thread: JoinHandle<Result<Summary, RecordError>>,
    path: PathBuf,
}

impl Recorder {
    /// Starts recording `manager`'s cycles and events to `path` (created, or
    /// emptied). Call it before the manager is spawned or run. The file is
    /// opened here, so a path that cannot be written is an error now.
    pub fn start(path: &Path, manager: &mut Manager) -> Result<Recorder, RecordError> {
        Recorder::start_with(path, manager, BTreeMap::new())
    }

    /// [`Recorder::start`], with more entries for the metadata record
    /// (`situate replay` reads `robot_file` and `sets`, a JSON list).
    pub fn start_with(
        path: &Path,
        manager: &mut Manager,
        metadata: BTreeMap<String, String>,
    ) -> Result<Recorder, RecordError> {
        Recorder::start_from(path, Source::Manager(manager), metadata, Options::default())
    }

    /// [`Recorder::start_with`], made as `options` say.
    pub fn start_with_options(
        path: &Path,
        manager: &mut Manager,
        metadata: BTreeMap<String, String>,
        options: Options,
    ) -> Result<Recorder, RecordError> {
        Recorder::start_from(path, Source::Manager(manager), metadata, options)
    }

    /// Starts recording a manager that is running (spawned), from its next
    /// cycle on: the `record` request of the link. The file is created new;
    /// a robot that does not answer within `timeout` is an error.
    pub fn start_running(
        path: &Path,
        handle: &Handle,
        metadata: BTreeMap<String, String>,
        timeout: Duration,
    ) -> Result<Recorder, RecordError> {
        Recorder::start_from(path, Source::Handle(handle, timeout), metadata, Options::default())
    }

    /// [`Recorder::start_running`], made as `options` say.
    pub fn start_running_with_options(
        path: &Path,
        handle: &Handle,
        metadata: BTreeMap<String, String>,
        timeout: Duration,
        options: Options,
    ) -> Result<Recorder, RecordError> {
        Recorder::start_from(path, Source::Handle(handle, timeout), metadata, options)
    }

    fn start_from(
        path: &Path,
        mut source: Source<'_>,
        metadata: BTreeMap<String, String>,
        options: Options,
    ) -> Result<Recorder, RecordError> {
        let io = |source| RecordError::Io { path: path.to_path_buf(), source };
        let file = File::create(path).map_err(io)?;
        // Compressed on the writer's own thread (zstd's workers would run
        // beside the cycle at its priority, not the writer's), at zstd's
        // fastest level: the file is about 10 % larger than at its default.
        let mut writer = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_threads(0)
            .compression_level(1)
            .create(BufWriter::new(file))
            .map_err(|source| mcap_error(path, source))?;
        let graph = match &source {
            Source::Manager(m) => m.graph(),
            Source::Handle(h, _) => h.graph(),
        };
        let leaves: Vec<(String, SignalType)> = graph.leaves.iter().map(|l| (l.path.clone(), l.ty.clone())).collect();
        let robot = graph.robot.clone();
        let skills: Vec<String> = graph.instances.iter().map(|d| d.name.clone()).collect();
        let stats = match &mut source {
            Source::Manager(m) => m.stats().ok(),
            Source::Handle(h, timeout) => match h.request_timeout(Request::QueryStats, *timeout) {
                Ok(Reply::Stats(s)) => Some(s),
                _ => None,
            },
        };
        // A running robot's events first: a change made while the wiring is read is then in
        // the events (a manager not spawned changes only when its owner asks).
        let early_events = match &source {
            Source::Handle(h, _) => Some(h.events()),
            Source::Manager(_) => None,
        };
        // The skills' wiring and state now, so a viewer needs no robot file (`wiring`).
        let wired = match &mut source {
            Source::Manager(m) => m.request(Request::QuerySkills).ok(),
            Source::Handle(h, timeout) => h.request_timeout(Request::QuerySkills, *timeout).ok(),
        };
        let mut meta = metadata;
        if let Some(Reply::Skills(wired)) = wired {
            meta.insert(wiring::WIRING_METADATA.to_string(), wiring::to_json(&wired).to_string());
        }
        meta.insert("robot".to_string(), robot);
        if let Some(stats) = &stats {
            meta.insert("period_s".to_string(), stats.period_s.to_string());
        }
        meta.insert(
            "leaves".to_string(),
            serde_json::to_string(
                &leaves.iter().map(|(p, t)| json!({"path": p, "type": t.to_string()})).collect::<Vec<_>>(),
            )
            .unwrap_or_default(),
        );
        meta.insert("situate_version".to_string(), env!("CARGO_PKG_VERSION").to_string());
        // The run's start in Unix time: now, less the manager's clock now (0 before its first
        // cycle; the time run so far when recording a running robot).
        let now_ns = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX));
        let origin_ns = now_ns.saturating_sub(stats.as_ref().map_or(0, |s| nanos(s.time_s)));
        meta.insert(TIME_ORIGIN_METADATA.to_string(), origin_ns.to_string());
        writer
            .write_metadata(&mcap::records::Metadata { name: "situate".to_string(), metadata: meta })
            .map_err(|source| mcap_error(path, source))?;
        let period_s = stats.map(|s| s.period_s).unwrap_or(0.0);
        // The cycle waits for the writer on the simulated clock, and drops
        // (counted, and said in the file) on the wall clock.
        let tap_options = TapOptions::new(options.queue_frames).wait_if_simulated();
        let (tap, events) = match source {
            Source::Manager(m) => (m.tap(tap_options), m.events()),
            Source::Handle(h, timeout) => {
                // Events first: none of the tapped cycles' is missed.
                let events = early_events.unwrap_or_else(|| h.events());
                let tap = h
                    .tap(tap_options, timeout)
                    .map_err(|e| RecordError::Robot { path: path.to_path_buf(), message: e.to_string() })?;
                (tap, events)
            }
        };
        let (stop, stopped) = crossbeam_channel::bounded(1);
        let file = Writing {
            path: path.to_path_buf(),
            writer,
            leaves,
            skills,
            holders: HashMap::new(),
            leaf_channels: HashMap::new(),
            event_channels: HashMap::new(),
            print_channel: None,
            winner_channel: None,
            cycle_channel: None,
            keyframe_channel: None,
            gap_channel: None,
            last_cycle: None,
            lost: Drops::default(),
            latest: BTreeMap::new(),
            buf: Vec::new(),
            sequence: HashMap::new(),
            period_s,
            origin_ns,
            times: std::collections::VecDeque::new(),
            summary: Summary { path: path.to_path_buf(), ..Summary::default() },
        };
        let thread = std::thread::Builder::new()
            .name("situate-record".into())
            .spawn(move || {
                // On the simulated clock the cycle waits for the writer: a
                // writer giving way to other work would slow the robot too.
                if !tap.cycle_waits() {
                    lower_thread_priority();
                }
                file.run(tap, events, stopped, options.hold)
            })
            .map_err(io)?;
        Ok(Recorder { stop, thread, path: path.to_path_buf() })
    }

    /// The file being written.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes what is still queued, ends the file (its summary and index)
    /// and says what it holds. Call it after the manager has stopped, or at
    /// any time to end the recording there.
    pub fn finish(self) -> Result<Summary, RecordError> {
        let _ = self.stop.send(());
        match self.thread.join() {
            Ok(outcome) => outcome,
            Err(_) => Err(RecordError::Lost { path: self.path }),
        }
    }
}

fn mcap_error(path: &Path, source: mcap::McapError) -> RecordError {
    RecordError::Mcap { path: path.to_path_buf(), source }
}

/// The writer's side.
struct Writing {
    path: PathBuf,
    writer: mcap::Writer<BufWriter<File>>,
    leaves: Vec<(String, SignalType)>,
    /// Instance names.
    skills: Vec<String>,
    /// Who held each resource leaf at the last change.
    holders: HashMap<usize, usize>,
    leaf_channels: HashMap<usize, u16>,
    event_channels: HashMap<&'static str, u16>,
    print_channel: Option<u16>,
    winner_channel: Option<u16>,
    cycle_channel: Option<u16>,
    keyframe_channel: Option<u16>,
    gap_channel: Option<u16>,
    /// The last cycle written.
    last_cycle: Option<u64>,
    /// The cycles the file lacks, as its gap markers say them.
    lost: Drops,
    /// Every leaf's latest value and its cycle, for keyframes.
    latest: BTreeMap<usize, (u64, Vec<u8>)>,
    /// A message's bytes (reused).
    buf: Vec<u8>,
    sequence: HashMap<u16, u32>,
    period_s: f64,
    /// The run's start in Unix time (ns), added to the manager's clock in every message's time.
    origin_ns: u64,
    /// The recent frames' cycles and times, for the time of events (an
    /// event may be read after frames of later cycles).
    times: std::collections::VecDeque<(u64, f64)>,
    summary: Summary,
}

impl Writing {
    fn run(
        mut self,
        tap: TapReceiver,
        events: Receiver<Event>,
        stop: Receiver<()>,
        mut hold: Option<Receiver<()>>,
    ) -> Result<Summary, RecordError> {
        // Polled, not waited on: a reader blocked on the queue would be woken
        // by the cycle's every send, a system call on the cycle's thread
        // (about a sixth of the demo's cycle). Polled, the cycle's send only
        // queues; the file lags the robot by at most a poll.
        // The test hook: a message before and one after each round.
        let wait = |hold: &mut Option<Receiver<()>>| {
            if hold.as_ref().is_some_and(|h| h.recv().is_err()) {
                *hold = None;
            }
        };
        // Events come before their cycle's frame (the manager sends them first); each is written
        // right after the frame of its cycle, so a file cut short (a robot killed) holds the
        // events of every cycle it holds.
        let mut pending: VecDeque<Event> = VecDeque::new();
        loop {
            wait(&mut hold);
            let mut open = true;
            loop {
                match tap.frames.try_recv() {
                    Ok(frame) => {
                        self.frame_and_events(&frame, &mut pending, &events)?;
                        tap.give_back(frame);
                    }
                    Err(TryRecvError::Empty) => break,
                    // The manager is gone: nothing more will come.
                    Err(TryRecvError::Disconnected) => {
                        open = false;
                        break;
                    }
                }
            }
            wait(&mut hold);
            // After the frames sent before them: an event is timed by its
            // cycle, from the frames around it.
            pending.extend(events.try_iter());
            for event in pending.drain(..) {
                self.event(&event)?;
            }
            if !open {
                break;
            }
            match stop.recv_timeout(POLL) {
                Err(RecvTimeoutError::Timeout) => {}
                Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
            }
        }
        // What is queued still goes in, each frame followed by its cycle's events as in a
        // round (a stop can come with hundreds of frames queued: their events written after all
        // of them were lost from a file cut among them), then the events left.
        while let Ok(frame) = tap.frames.try_recv() {
            self.frame_and_events(&frame, &mut pending, &events)?;
        }
        pending.extend(events.try_iter());
        for event in pending.drain(..) {
            self.event(&event)?;
        }
        // The cycles lost after the last one written (those between were
        // marked as the frames after them came).
        let drops = tap.drops();
        // Gone before the file's end is written: a cycle waiting for room
        // goes on now.
        drop(tap);
        let after = self.last_cycle.map_or(0, |c| c + 1);
        for &(first, last) in &drops.ranges {
            if last >= after {
                self.gap(first.max(after), last)?;
            }
        }
        self.summary.dropped = self.lost.count;
        self.summary.dropped_ranges = self.lost.ranges.clone();
        let ranges = serde_json::to_string(&self.lost.ranges).unwrap_or_default();
        let metadata = BTreeMap::from([
            ("dropped_cycles".to_string(), self.lost.count.to_string()),
            ("ranges".to_string(), ranges),
        ]);
        self.writer
            .write_metadata(&mcap::records::Metadata { name: DROPS_METADATA.to_string(), metadata })
            .map_err(|source| mcap_error(&self.path, source))?;
        self.writer.finish().map_err(|source| mcap_error(&self.path, source))?;
        self.summary.channels = self.leaf_channels.len()
            + self.event_channels.len()
            + usize::from(self.print_channel.is_some())
            + usize::from(self.winner_channel.is_some())
            + usize::from(self.cycle_channel.is_some())
            + usize::from(self.keyframe_channel.is_some())
            + usize::from(self.gap_channel.is_some());
        self.summary.bytes = std::fs::metadata(&self.path).map(|m| m.len()).unwrap_or(0);
        Ok(self.summary)
    }

    /// Marks the cycles `first..=last` as dropped, in the file (at once, so
    /// a file cut short says it too) and in the summary.
    fn gap(&mut self, first: u64, last: u64) -> Result<(), RecordError> {
        let channel = match self.gap_channel {
            Some(c) => c,
            None => {
                let schema = serde_json::to_vec(&schema::gap_schema()).unwrap_or_default();
                let c = self.channel("situate.gap", &schema, GAPS_TOPIC, &[])?;
                self.gap_channel = Some(c);
                c
            }
        };
        let count = last - first + 1;
        tracing::warn!("recording {}: cycles {first} to {last} dropped (the writer fell behind)", self.path.display());
        self.lost.add_range(first, last);
        let time = nanos(self.time_of(Some(first)));
        self.write(channel, time, &json!({"cycle": first, "last": last, "count": count}))
    }

    fn frame(&mut self, frame: &Frame) -> Result<(), RecordError> {
        // Cycles are numbered one after the other: a jump is frames the
        // tap dropped.
        if let Some(prev) = self.last_cycle {
            if frame.cycle > prev + 1 {
                self.gap(prev + 1, frame.cycle - 1)?;
            }
        }
        self.last_cycle = Some(frame.cycle);
        let time = nanos(frame.time_s);
        for (leaf, value) in frame.values.iter() {
            let channel = match self.leaf_channels.get(&leaf) {
                Some(&c) => c,
                None => {
                    let Some((path, ty)) = self.leaves.get(leaf) else { continue };
                    let schema = serde_json::to_vec(&message_schema(ty)).unwrap_or_default();
                    let (path, ty) = (path.clone(), ty.to_string());
                    let c = self.channel(&format!("situate.{ty}"), &schema, &path, &[("type", ty.as_str())])?;
                    self.leaf_channels.insert(leaf, c);
                    c
                }
            };
            let mut bytes = std::mem::take(&mut self.buf);
            bytes.clear();
            let at = encode::leaf_message(&mut bytes, frame.cycle, value);
            let written = self.write_bytes(channel, time, &bytes);
            // Kept as its JSON (for the keyframes): the value is borrowed from
            // the frame, which goes back to the cycle.
            let latest = self.latest.entry(leaf).or_default();
            latest.0 = frame.cycle;
            latest.1.clear();
            latest.1.extend_from_slice(&bytes[at]);
            self.buf = bytes;
            written?;
        }
        for (i, line) in &frame.prints {
            let channel = self.print_channel()?;
            let skill = self.skills.get(*i).cloned().unwrap_or_default();
            self.write(channel, time, &json!({"cycle": frame.cycle, "skill": skill, "line": line}))?;
        }
        let hash = hash::cycle_hash(
            frame.values.iter().filter_map(|(leaf, v)| Some((self.leaves.get(leaf)?.0.as_str(), v))),
            frame
                .winners
                .iter()
                .filter_map(|&(leaf, i)| Some((self.leaves.get(leaf)?.0.as_str(), self.skills.get(i)?.as_str()))),
        );
        let channel = self.cycle_channel()?;
        let data = json!({"cycle": frame.cycle, "hash": hash::hex(hash), "leaves": frame.values.len()});
        self.write(channel, time, &data)?;
        if frame.cycle.is_multiple_of(KEYFRAME_CYCLES) {
            let mut bytes = std::mem::take(&mut self.buf);
            bytes.clear();
            let leaves = &self.leaves;
            encode::keyframe(
                &mut bytes,
                frame.cycle,
                self.latest.iter().filter_map(|(leaf, (c, v))| Some((leaves.get(*leaf)?.0.as_str(), *c, v.as_slice()))),
            );
            let channel = self.keyframe_channel()?;
            let written = self.write_bytes(channel, time, &bytes);
            self.buf = bytes;
            written?;
        }
        for &(leaf, i) in &frame.winners {
            if self.holders.insert(leaf, i) == Some(i) {
                continue;
            }
            let channel = self.winner_channel()?;
            let resource = self.leaves.get(leaf).map(|(p, _)| p.clone()).unwrap_or_default();
            let skill = self.skills.get(i).cloned().unwrap_or_default();
            self.write(channel, time, &json!({"cycle": frame.cycle, "resource": resource, "skill": skill}))?;
        }
        self.summary.frames += 1;
        self.summary.cycles = Some(match self.summary.cycles {
            Some((first, _)) => (first, frame.cycle),
            None => (frame.cycle, frame.cycle),
        });
        if self.times.len() == 2 * QUEUE_FRAMES {
            self.times.pop_front();
        }
        self.times.push_back((frame.cycle, frame.time_s));
        Ok(())
    }

    /// Writes a frame, then the events read so far of its cycle and the cycles before it: the
    /// manager sends a cycle's events before its frame, so they are all there, and a file cut
    /// short after them holds them.
    fn frame_and_events(
        &mut self,
        frame: &Frame,
        pending: &mut VecDeque<Event>,
        events: &Receiver<Event>,
    ) -> Result<(), RecordError> {
        self.frame(frame)?;
        pending.extend(events.try_iter());
        while pending.front().is_some_and(|e| event_cycle(e).is_none_or(|c| c <= frame.cycle)) {
            if let Some(e) = pending.pop_front() {
                self.event(&e)?;
            }
        }
        Ok(())
    }

    fn event(&mut self, event: &Event) -> Result<(), RecordError> {
        let (kind, data) = event_to_json(event);
        let channel = match self.event_channels.get(kind) {
            Some(&c) => c,
            None => {
                let schema = serde_json::to_vec(&schema::event_schema(kind)).unwrap_or_default();
                let c =
                    self.channel(&format!("situate.event.{kind}"), &schema, &format!("situate/events/{kind}"), &[])?;
                self.event_channels.insert(kind, c);
                c
            }
        };
        let cycle = data.get("cycle").and_then(Json::as_u64);
        let time_s = match data.get("time_s").and_then(Json::as_f64) {
            Some(t) => t,
            None => self.time_of(cycle),
        };
        self.write(channel, nanos(time_s), &data)
    }

    /// The manager's clock at `cycle`: that frame's time when it is among
    /// the recent ones; else from the nearest recent frame, a period per cycle
    /// apart (exact on a simulated clock), or from cycle 0 at time 0.
    fn time_of(&self, cycle: Option<u64>) -> f64 {
        let Some(cycle) = cycle else {
            return self.times.back().map_or(0.0, |&(_, t)| t);
        };
        let k = self.times.partition_point(|&(c, _)| c < cycle);
        let near = match (self.times.get(k), k.checked_sub(1).and_then(|j| self.times.get(j))) {
            (Some(&(c, t)), _) if c == cycle => return t,
            (Some(&after), None) => after,
            (_, Some(&before)) => before,
            // Before any frame: cycles a period apart from 0.
            (None, None) => (0, 0.0),
        };
        let (c, t) = near;
        (t + (cycle as f64 - c as f64) * self.period_s).max(0.0)
    }

    /// The channel of the prints, made on first use.
    fn print_channel(&mut self) -> Result<u16, RecordError> {
        if let Some(c) = self.print_channel {
            return Ok(c);
        }
        let schema = serde_json::to_vec(&schema::print_schema()).unwrap_or_default();
        let c = self.channel("situate.print", &schema, "situate/prints", &[])?;
        self.print_channel = Some(c);
        Ok(c)
    }

    /// The channel of the keyframes, made on first use.
    fn keyframe_channel(&mut self) -> Result<u16, RecordError> {
        if let Some(c) = self.keyframe_channel {
            return Ok(c);
        }
        let schema = serde_json::to_vec(&schema::keyframe_schema()).unwrap_or_default();
        let c = self.channel("situate.keyframe", &schema, "situate/keyframes", &[])?;
        self.keyframe_channel = Some(c);
        Ok(c)
    }

    /// The channel of the cycles' hashes, made on first use.
    fn cycle_channel(&mut self) -> Result<u16, RecordError> {
        if let Some(c) = self.cycle_channel {
            return Ok(c);
        }
        let schema = serde_json::to_vec(&schema::cycle_schema()).unwrap_or_default();
        let c = self.channel("situate.cycle", &schema, "situate/cycles", &[])?;
        self.cycle_channel = Some(c);
        Ok(c)
    }

    /// The channel of the resources' holders, made on first use.
    fn winner_channel(&mut self) -> Result<u16, RecordError> {
        if let Some(c) = self.winner_channel {
            return Ok(c);
        }
        let schema = serde_json::to_vec(&schema::winner_schema()).unwrap_or_default();
        let c = self.channel("situate.winner", &schema, "situate/winners", &[])?;
        self.winner_channel = Some(c);
        Ok(c)
    }

    fn channel(
        &mut self,
        schema_name: &str,
        schema: &[u8],
        topic: &str,
        meta: &[(&str, &str)],
    ) -> Result<u16, RecordError> {
        let schema_id = self
            .writer
            .add_schema(schema_name, "jsonschema", schema)
            .map_err(|source| mcap_error(&self.path, source))?;
        let meta: BTreeMap<String, String> = meta.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect();
        self.writer.add_channel(schema_id, topic, "json", &meta).map_err(|source| mcap_error(&self.path, source))
    }

    fn write(&mut self, channel: u16, time_ns: u64, data: &Json) -> Result<(), RecordError> {
        let bytes = serde_json::to_vec(data).unwrap_or_default();
        self.write_bytes(channel, time_ns, &bytes)
    }

    fn write_bytes(&mut self, channel: u16, time_ns: u64, bytes: &[u8]) -> Result<(), RecordError> {
        let sequence = self.sequence.entry(channel).or_insert(0);
        *sequence = sequence.wrapping_add(1);
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: *sequence,
            log_time: self.origin_ns.saturating_add(time_ns),
            publish_time: self.origin_ns.saturating_add(time_ns),
        };
        self.writer.write_to_known_channel(&header, bytes).map_err(|source| mcap_error(&self.path, source))?;
        self.summary.messages += 1;
        Ok(())
    }
}

/// On the wall clock the writer yields the CPU to the cycle and to the
/// sequencer: its work (encoding JSON, compressing) can wait, within the
/// queue's 4,096 cycles, theirs cannot. On Linux it runs at nice +10;
/// elsewhere, or if refused, as it is. (On the simulated clock the cycle
/// waits for the writer, which keeps the thread's priority.)
fn lower_thread_priority() {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: gettid has no preconditions; setpriority on our own thread
        // id only changes its scheduling weight and reports failure by its
        // result. Lowering a priority needs no privilege.
        let result = unsafe {
            let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
            libc::setpriority(libc::PRIO_PROCESS, tid, 10)
        };
        if result != 0 {
            tracing::debug!("could not lower the recorder thread's priority");
        }
    }
}

/// Seconds of the manager's clock as MCAP nanoseconds (negative: 0).
fn nanos(time_s: f64) -> u64 {
    if time_s.is_finite() && time_s > 0.0 {
        (time_s * 1e9).round() as u64
    } else {
        0
    }
}
