//! `situate replay FILE`: a recording fed back through the robot rebuilt
//! from its robot file (`situate_record::replay`): devices, and skills not
//! chosen to run live, played from the recording; the live skills' code run
//! now; every cycle compared with the recording. With `--view`, nothing is
//! re-simulated: every skill plays, on a robot built from the wiring the
//! recording holds (`situate_record::wiring`), no robot file needed.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use serde_json::json;
use situate::manager::Manager;
use situate_record::read::Recording;
use situate_record::replay;
use situate_robotfile::config::{ClockKind, ExecutorKind};

use crate::args::Compose;
use crate::output::{problem, Exit, Out};
use crate::robot::{bad_file, load, Loaded};
use crate::sim::SimOverrides;
use crate::skill_types::{program_registry, registry_for};
use crate::Extensions;

/// `situate replay`'s arguments.
#[derive(clap::Args)]
pub(crate) struct ReplayArgs {
    /// The recording (`situate run --record` or `situate demo --record`).
    pub(crate) file: PathBuf,
    /// Run this skill's code now (repeatable); every other skill plays its outputs from the
    /// recording. Default: every skill that can run here runs live. Devices always play.
    #[arg(long, value_name = "SKILL")]
    pub(crate) live: Vec<String>,
    /// The robot file (default: the one the recording names), e.g. one with a skill changed.
    #[arg(long)]
    pub(crate) robot: Option<PathBuf>,
    /// Compare from this cycle on (the cycles before it run too: a skill's memory is not in
    /// the recording, so a replay always starts at the recording's start).
    #[arg(long, value_name = "CYCLE")]
    pub(crate) from: Option<u64>,
    /// Stop after this cycle.
    #[arg(long, value_name = "CYCLE")]
    pub(crate) to: Option<u64>,
    /// Then serve the GUI here (an address, or a port on 127.0.0.1; default 127.0.0.1:8080) until
    /// Ctrl-C: its timeline holds every replayed cycle, to step, seek and play.
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub(crate) gui: Option<String>,
    /// Let the GUI answer to this host name too, besides localhost and its own address (e.g.
    /// robot.lan, without a port; repeat for several). Requests naming any other host are
    /// refused, a guard against DNS rebinding (docs/gui.md).
    #[arg(long, value_name = "NAME")]
    pub(crate) gui_allow_host: Vec<String>,
    /// Record the replay to this MCAP file.
    #[arg(long, value_name = "FILE")]
    pub(crate) record: Option<PathBuf>,
    /// Re-simulate nothing: every skill plays its outputs from the recording, on a robot built
    /// from the wiring the recording holds. Needs neither the robot file nor any skill's code, so
    /// it opens a recording made elsewhere (with --gui: to step, seek and plot it).
    #[arg(long, conflicts_with_all = ["live", "robot", "record"])]
    pub(crate) view: bool,
    /// Read a recording cut short (a robot killed while recording: no summary at its end) up to
    /// its last complete cycle. Such a replay is never called identical.
    #[arg(long)]
    pub(crate) recover: bool,
    /// Parameters over the recording's own `--set`s.
    #[command(flatten)]
    pub(crate) compose: Compose,
}

pub(crate) fn replay_command(args: ReplayArgs, ext: &Extensions, out: Out) -> anyhow::Result<u8> {
    let started = Instant::now();
    let rec = if args.recover { Recording::open_cut_short(&args.file) } else { Recording::open(&args.file) }
        .map_err(|e| problem(Exit::BadFile, e.to_string()))?;
    if let Some(cut) = &rec.cut_short {
        out.warn(format_args!("warning: {}: {cut}; the replay cannot say the run is identical", args.file.display()));
    }
    if args.view && !args.compose.set.is_empty() {
        return Err(problem(Exit::Usage, "--view plays every skill from the recording: a --set would change nothing"));
    }
    match rec.span() {
        None => {}
        // A viewer runs no skill's code, so it needs no memory from before the first cycle.
        Some((first, _)) if first > 1 && !args.view => {
            return Err(problem(
                Exit::BadFile,
                format!(
                    "{}: the recording starts at cycle {first} (started on a running robot); a replay needs the run \
                     from its first cycle, since the skills' memory is not in the recording",
                    args.file.display()
                ),
            ))
        }
        Some(_) => {}
    }
    if rec.dropped_count > 0 {
        out.warn(format_args!(
            "warning: {} lacks {} cycles, dropped while recording ({}): the replay stops before the first and \
             cannot say the run is identical",
            args.file.display(),
            rec.dropped_count,
            ranges_text(&rec.dropped)
        ));
    }
    let Built { mut manager, cast, robot, compose, changes } =
        if args.view { view(&args, &rec)? } else { rebuild(&args, &rec, ext, out)? };
    let tape = replay::build_tape(&rec, manager.graph(), &cast.players)
        .map_err(|e| problem(Exit::BadFile, format!("{}: {e}", args.file.display())))?;
    let _ = cast.tape.set(tape);
    let recorder = match &args.record {
        Some(path) => {
            // Not with --view (clap refuses the pair): a rebuilt robot has its file.
            let robot = robot.as_deref().unwrap_or(std::path::Path::new(""));
            let mut meta = crate::robot::recording_metadata(robot, &compose.set, ClockKind::Simulated, None);
            for key in ["world", "seed", "map_file"] {
                if let Some(v) = rec.metadata.get(key) {
                    meta.insert(key.to_string(), v.clone());
                }
            }
            Some(
                situate_record::Recorder::start_with(path, &mut manager, meta)
                    .map_err(|e| problem(Exit::Usage, format!("--record: {e}")))?,
            )
        }
        None => None,
    };
    // A viewer may open a recording started on a running robot: compare from its first cycle.
    let first = if args.view { rec.span().map_or(0, |s| s.0) } else { 0 };
    let (from, to) = (args.from.unwrap_or(0).max(first), args.to.unwrap_or(u64::MAX));
    if from > to {
        return Err(problem(Exit::Usage, format!("--from {from} is after --to {to}")));
    }
    let gui_listen = match &args.gui {
        Some(text) => {
            Some(crate::robot::parse_gui_address(text).map_err(|e| problem(Exit::Usage, format!("--gui: {e}")))?)
        }
        None => None,
    };
    // For the GUI: every replayed cycle, and the replay's events, into its timeline.
    let (frames_tx, frames_rx) = crossbeam_channel::unbounded();
    let layout = gui_listen.map(|_| situate_gui::Layout::of(manager.graph()));
    let events = manager.events();
    let outcome = replay::run_window(&rec, &mut manager, &changes, from, to, |frame, _| {
        if layout.is_some() {
            let _ = frames_tx.send(frame.clone());
        }
    });
    drop(frames_tx);
    let gui_manager = match (gui_listen, layout) {
        (Some(listen), Some(layout)) => Some((listen, layout, manager)),
        _ => {
            drop(manager);
            None
        }
    };
    let recording = match recorder.map(situate_record::Recorder::finish).transpose() {
        Ok(r) => r,
        Err(e) => return Err(problem(Exit::Failure, format!("--record: {e}"))),
    };
    // What a file cut short lost is unknown: its replay is never identical.
    let identical = outcome.identical() && rec.cut_short.is_none();
    let span = rec.span();
    if out.json {
        stdoutln!(
            "{}",
            json!({
                "recording": args.file,
                "robot_file": robot,
            "view": args.view,
                "cycles": outcome.cycles,
                "first_cycle": span.map(|s| s.0.max(from)),
                "last_cycle": span.map(|s| s.1.min(to)),
                "matched": outcome.matched,
                "identical": identical,
                "first_difference": outcome.first.as_ref().map(replay::Divergence::to_json),
                "dropped_cycles": outcome.dropped,
                "dropped_ranges": outcome.dropped_ranges,
                "stopped_before": outcome.stopped_before,
                "cut_short": rec.cut_short.as_ref().map(|c| json!({"at_byte": c.at_byte, "file_bytes": c.file_bytes,
                    "last_cycle": c.last_cycle, "cycles_dropped": c.cycles_dropped, "reason": c.reason})),
                "live": cast.live,
                "played": cast.players,
                "wall_s": started.elapsed().as_secs_f64(),
                "replay_recording": recording.as_ref().map(crate::robot::recording_json),
            })
        );
    } else {
        if args.view {
            stdoutln!(
                "viewed {} cycles of {} in {:.2} s: every skill ({}) played from the recording, nothing re-simulated",
                outcome.cycles,
                args.file.display(),
                started.elapsed().as_secs_f64(),
                cast.players.len()
            );
        } else {
            stdoutln!(
                "replayed {} cycles of {} in {:.2} s: {} live ({}), {} played from the recording",
                outcome.cycles,
                args.file.display(),
                started.elapsed().as_secs_f64(),
                cast.live.len(),
                cast.live.join(", "),
                cast.players.len()
            );
        }
        for line in verdict(&outcome, identical, rec.cut_short.as_ref()) {
            stdoutln!("{line}");
        }
        if let Some(r) = &recording {
            stdout!("{}", crate::robot::recording_text(r));
        }
    }
    let code = if identical { Exit::Ok.code() } else { Exit::Failure.code() };
    if let Some((listen, layout, manager)) = gui_manager {
        let mut summary = verdict(&outcome, identical, rec.cut_short.as_ref()).join("; ");
        if args.view {
            summary = format!("viewed from the file alone, nothing re-simulated ({summary})");
        }
        let replay = situate_gui::ReplayInfo {
            file: args.file.display().to_string(),
            summary,
            events: rec.events.iter().map(|(_, e)| e.clone()).collect(),
        };
        let gui = GuiReplay { listen, allowed_hosts: &args.gui_allow_host, layout, replay };
        serve_gui(&rec, manager, gui, frames_rx, events, outcome.cycles, out)?;
    }
    Ok(code)
}

/// The robot a replay runs, and what it needs besides.
struct Built {
    manager: Manager,
    cast: replay::Cast,
    /// The robot file it was rebuilt from (`None`: a viewer, built from the recording).
    robot: Option<PathBuf>,
    /// The `--set`s it was built with (the recording's, then the command line's).
    compose: Compose,
    /// The skills whose recorded activations and parameter changes are applied.
    changes: Vec<String>,
}

/// The robot rebuilt from its robot file, every skill that can run here live
/// (or those of `--live`), devices and the rest played.
fn rebuild(args: &ReplayArgs, rec: &Recording, ext: &Extensions, out: Out) -> anyhow::Result<Built> {
    let robot = match (&args.robot, rec.metadata.get("robot_file")) {
        (Some(r), _) => r.clone(),
        (None, Some(r)) => PathBuf::from(r),
        (None, None) => {
            return Err(problem(
                Exit::Usage,
                format!("{}: the recording names no robot file; give one with --robot", args.file.display()),
            ))
        }
    };
    if !robot.exists() && args.robot.is_none() {
        return Err(problem(
            Exit::BadFile,
            format!(
                "{}: the robot file the recording names, {}, is gone: give one with --robot, or view the recording \
                 without re-simulating it (--view)",
                args.file.display(),
                robot.display()
            ),
        ));
    }
    if rec.metadata.get("clock").is_some_and(|c| c == "wall") {
        out.warn(format_args!(
            "warning: {} was recorded on the wall clock: skills that read the time will differ (docs/recording.md, \"Replay\")",
            args.file.display()
        ));
    }
    // Checked when the recording was read: a `sets` that is not a list of
    // strings is a bad file there, not silently none here.
    let compose = Compose { set: rec.sets.iter().chain(args.compose.set.iter()).cloned().collect() };
    let Loaded { mut spec, remote, file: robot_file, ros2, .. } = load(&robot, &compose)?;
    let (mut registry, _world) = registry_for(&robot_file, program_registry(ext)?, ext, &SimOverrides::default())
        .map_err(|errors| bad_file(&robot, &errors))?;
    // The ROS 2 topics in are devices: they play back from the recording.
    crate::ros2::add_devices(&mut spec, &mut registry, ros2.as_ref());
    // What makes a run repeatable (docs/recording.md, "Replay").
    spec.clock = ClockKind::Simulated;
    spec.executor = ExecutorKind::Serial;
    if let Some(p) = rec.period_s() {
        spec.period_s = p;
    }
    let live = (!args.live.is_empty()).then_some(args.live.as_slice());
    let cast = replay::cast(&mut spec, &mut registry, &remote, live).map_err(|e| problem(Exit::Usage, e))?;
    let manager =
        Manager::build(&spec, &registry).map_err(|e| problem(Exit::BadFile, format!("{}: {e}", robot.display())))?;
    Ok(Built { manager, changes: cast.live.clone(), cast, robot: Some(robot), compose })
}

/// The robot rebuilt from the recording's wiring alone: every skill a
/// player, following its recorded activations and parameter changes.
fn view(args: &ReplayArgs, rec: &Recording) -> anyhow::Result<Built> {
    let situate_record::wiring::View { spec, registry, cast } = situate_record::wiring::view(rec)
        .map_err(|e| problem(Exit::BadFile, format!("{}: {e}", args.file.display())))?;
    let manager = Manager::build(&spec, &registry)
        .map_err(|e| problem(Exit::BadFile, format!("{}: the recorded wiring: {e}", args.file.display())))?;
    Ok(Built { manager, changes: cast.players.clone(), cast, robot: None, compose: Compose::default() })
}

/// How the replay compared with the recording, a line or a few.
fn verdict(outcome: &replay::Outcome, identical: bool, cut: Option<&situate_record::read::CutShort>) -> Vec<String> {
    let mut lines = compared(outcome, identical);
    if let Some(cut) = cut {
        let cut_line = format!("the recording was {cut}");
        if outcome.first.is_none() && outcome.dropped == 0 {
            lines = vec![format!(
                "not identical: {cut_line}; {} of {} cycles replayed match",
                outcome.matched, outcome.cycles
            )];
        } else {
            lines.push(format!("and {cut_line}"));
        }
    }
    lines
}

/// How the cycles replayed compared with the recording's.
fn compared(outcome: &replay::Outcome, identical: bool) -> Vec<String> {
    match &outcome.first {
        None if identical => vec!["identical: every cycle matches the recording".to_string()],
        None if outcome.dropped > 0 => vec![format!(
            "not identical: the recording lacks {} cycles, dropped while recording ({}){}; {} of {} cycles replayed \
             match",
            outcome.dropped,
            ranges_text(&outcome.dropped_ranges),
            match outcome.stopped_before {
                Some(c) => format!(", so the replay stopped before cycle {c}"),
                None => String::new(),
            },
            outcome.matched,
            outcome.cycles
        )],
        None => vec!["nothing to compare: the recording has no cycles".to_string()],
        Some(d) => {
            let mut lines = vec![format!("differs from {d}")];
            if !d.others.is_empty() {
                lines.push(format!("  also differing in that cycle: {}", d.others.join(", ")));
            }
            lines.push(format!("{} of {} cycles match", outcome.matched, outcome.cycles));
            if outcome.dropped > 0 {
                lines.push(format!(
                    "and the recording lacks {} cycles, dropped while recording ({})",
                    outcome.dropped,
                    ranges_text(&outcome.dropped_ranges)
                ));
            }
            lines
        }
    }
}

/// Where and how a replay's GUI serves.
struct GuiReplay<'a> {
    listen: std::net::SocketAddr,
    allowed_hosts: &'a [String],
    layout: situate_gui::Layout,
    replay: situate_gui::ReplayInfo,
}

/// Cycle ranges as `cycles 5-50, cycle 60, cycles 70-80`, the first ten.
fn ranges_text(ranges: &[(u64, u64)]) -> String {
    const SHOWN: usize = 10;
    let mut text: Vec<String> = ranges
        .iter()
        .take(SHOWN)
        .map(|&(a, b)| if a == b { format!("cycle {a}") } else { format!("cycles {a}-{b}") })
        .collect();
    if ranges.len() > SHOWN {
        text.push(format!("and {} more ranges", ranges.len() - SHOWN));
    }
    text.join(", ")
}

/// Serves the GUI on the replayed robot, stopped after its last cycle, its
/// timeline holding the replay, until Ctrl-C.
fn serve_gui(
    rec: &Recording,
    manager: Manager,
    gui: GuiReplay<'_>,
    frames: crossbeam_channel::Receiver<situate::manager::Frame>,
    events: crossbeam_channel::Receiver<situate::manager::Event>,
    cycles: u64,
    out: Out,
) -> anyhow::Result<()> {
    let stop = crate::signals::Stop::install()?;
    let (handle, join) = manager.spawn(false);
    let world = rec.metadata.get("world").and_then(|w| serde_json::from_str(w).ok());
    let history_frames = usize::try_from(cycles)
        .unwrap_or(usize::MAX)
        .saturating_add(16)
        .clamp(situate_gui::history::DEFAULT_FRAMES, situate_gui::history::MAX_FRAMES);
    let GuiReplay { listen, allowed_hosts, layout, replay } = gui;
    let config = situate_gui::GuiConfig {
        listen,
        world,
        history_frames,
        allowed_hosts: allowed_hosts.to_vec(),
        replay: Some(replay),
        ..situate_gui::GuiConfig::default()
    };
    let tap = situate_gui::HistoryTap::from_channels(layout, frames, events, 0);
    let gui = situate_gui::serve_with_history(handle.clone(), config, Some(tap))
        .map_err(|e| problem(Exit::Failure, format!("starting the GUI on {listen}: {e}")))?;
    out.note(format_args!("GUI on {}: the replay's cycles are on its timeline; Ctrl-C to end", gui.url()));
    while stop.signal().is_none() {
        std::thread::sleep(Duration::from_millis(50));
    }
    gui.stop();
    let mut handle = handle;
    let _ = situate::manager::Control::request(&mut handle, situate::manager::Request::Shutdown);
    let _ = join.join_timeout(Duration::from_secs(10));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::ranges_text;

    #[test]
    fn replay_names_the_dropped_cycles_ten_ranges_at_most() {
        assert_eq!(ranges_text(&[(5, 50), (60, 60)]), "cycles 5-50, cycle 60");
        let many: Vec<(u64, u64)> = (0..13).map(|k| (10 * k, 10 * k + 1)).collect();
        let text = ranges_text(&many);
        assert!(text.starts_with("cycles 0-1, cycles 10-11"), "{text}");
        assert!(text.ends_with("cycles 90-91, and 3 more ranges"), "{text}");
    }
}
