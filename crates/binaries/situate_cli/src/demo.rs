//! `situate demo`: the delivery demo. The robot runs in this process (as
//! `situate run` would), the sequencer in a child process; Ctrl-C stops the
//! sequencer and prints the outcome. With the GUI, the robot (cycle stopped)
//! and the GUI stay up after the mission with its outcome on the page, until
//! Ctrl-C (or at once with `--exit-when-done`); headless, the demo ends with
//! the mission.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde_json::json;

use situate::manager::Control as _;

use crate::output::{problem, Exit, Out};
use crate::robot::{start_robot, RunOptions};
use crate::signals;
use crate::sim::{SimOverrides, WorldArgs};
use crate::Extensions;

#[derive(clap::Args)]
pub(crate) struct DemoOptions {
    /// The demo's robot file (default: demo/robot.yaml of the checkout or of the installed package).
    #[arg(long)]
    pub(crate) robot: Option<PathBuf>,
    /// Another building (a map file; see docs/maps.md).
    #[arg(long)]
    pub(crate) map: Option<PathBuf>,
    /// The simulator's seed.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    #[command(flatten)]
    pub(crate) world: WorldArgs,
    /// No GUI, and the simulated clock as fast as possible.
    #[arg(long)]
    pub(crate) headless: bool,
    /// `sequenced`: the sequencer switches skills on and off (the paper's way);
    /// `all-active`: every skill always on, priority arbitration only; `reactive`: no
    /// sequencer, a rule list picks the skills every cycle (demo/reactive.py).
    #[arg(long, default_value = "sequenced", value_parser = ["sequenced", "all-active", "reactive"])]
    pub(crate) mode: String,
    /// What to do: stops where the message is said, in order, separated by commas: `office`
    /// (the delivery) or `lobby:FLOOR` (in front of that floor's call button).
    #[arg(long, default_value = "office")]
    pub(crate) task: String,
    /// The sequencer program (default: demo/deliver.py next to the robot file).
    #[arg(long)]
    pub(crate) sequencer: Option<PathBuf>,
    /// The Python interpreter for the sequencer (default: the one the Python package's `situate`
    /// runs in; for the Rust binary .venv/bin/python, else python3).
    #[arg(long, env = "SITUATE_PYTHON")]
    pub(crate) python: Option<PathBuf>,
    /// With the GUI: simulated time runs this many times faster than real time.
    #[arg(long, default_value_t = 4.0)]
    pub(crate) speed: f64,
    /// The GUI's address (not with --headless).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub(crate) gui: String,
    /// Let the GUI answer to this host name too, besides localhost and its own address (e.g.
    /// robot.lan, without a port; repeat for several). Requests naming any other host are
    /// refused, a guard against DNS rebinding (docs/gui.md).
    #[arg(long, value_name = "NAME")]
    pub(crate) gui_allow_host: Vec<String>,
    /// Give up after this much simulated time, s.
    #[arg(long, default_value_t = 1800.0)]
    pub(crate) limit_s: f64,
    /// With the GUI: exit when the mission ends (by default the GUI stays up, showing the
    /// outcome, until Ctrl-C). Headless, the demo always exits when the mission ends.
    #[arg(long)]
    pub(crate) exit_when_done: bool,
    /// Record the run to this MCAP file: every signal, event, print and resource winner
    /// (docs/recording.md).
    #[arg(long, value_name = "FILE")]
    pub(crate) record: Option<PathBuf>,
    /// The delivery on the physics robot (MuJoCo, through ROS 2; docs/physics.md) instead of the
    /// 2-D simulator: `python -m situate.physics.deliver` with this seed, map, GUI and recording.
    /// Needs the Python package with its `physics` extra.
    #[arg(long)]
    pub(crate) physics: bool,
    /// The link's endpoint, where `situate stats`, `situate echo`… reach the demo's robot.
    /// Default: the one they connect to by default (tcp/127.0.0.1:7447), or, when another
    /// robot holds it, a free port (said at the start); headless, a free port.
    #[arg(long, value_name = "ENDPOINT")]
    pub(crate) listen: Option<String>,
}

/// Where the demo's files may be: `demo/` in the current directory (a
/// checkout), then the host's package data (the wheel ships `demo/`,
/// `maps/` and `examples/`), then the data of the published crate this
/// program was built from (`cargo install situate_cli`).
fn demo_dirs(ext: &Extensions) -> Vec<PathBuf> {
    let mut dirs = vec![PathBuf::from(".")];
    dirs.extend(ext.data_dir.clone());
    let packaged = crate::packaged_data();
    if packaged.join("demo").is_dir() {
        dirs.push(packaged);
    }
    dirs
}

/// The robot file and the sequencer: as given, else found by [`demo_dirs`].
fn demo_files(demo: &DemoOptions, ext: &Extensions) -> anyhow::Result<(PathBuf, PathBuf)> {
    let robot = match &demo.robot {
        Some(r) => r.clone(),
        None => {
            let dirs = demo_dirs(ext);
            let found = dirs.iter().map(|d| d.join("demo/robot.yaml")).find(|p| p.is_file());
            found.ok_or_else(|| {
                let looked: Vec<String> = dirs.iter().map(|d| d.join("demo").display().to_string()).collect();
                problem(
                    Exit::Usage,
                    format!(
                        "no demo found (looked in {}): run it from the repository's top directory, install the \
                         Python package (which ships it), or give --robot and --sequencer",
                        looked.join(", ")
                    ),
                )
            })?
        }
    };
    let sequencer = match &demo.sequencer {
        Some(s) => s.clone(),
        None => robot.parent().unwrap_or(Path::new(".")).join("deliver.py"),
    };
    if !sequencer.is_file() {
        return Err(problem(Exit::Usage, format!("no sequencer at `{}` (give --sequencer)", sequencer.display())));
    }
    Ok((robot, sequencer))
}

/// The sequencer's interpreter: `--python` (or `$SITUATE_PYTHON`), else the
/// host's (the Python package's own), else `.venv/bin/python` of a checkout,
/// else `python3` from PATH.
fn interpreter(demo: &DemoOptions, ext: &Extensions) -> PathBuf {
    demo.python.clone().or_else(|| ext.interpreter.clone()).unwrap_or_else(|| {
        let venv = PathBuf::from(".venv/bin/python");
        if venv.is_file() {
            venv
        } else {
            PathBuf::from("python3")
        }
    })
}

pub(crate) fn run_demo(demo: &DemoOptions, ext: &Extensions, out: Out) -> anyhow::Result<u8> {
    if demo.physics {
        return run_physics_demo(demo, ext, out);
    }
    let (robot_file, sequencer) = demo_files(demo, ext)?;
    // With the GUI, a person watches: the CLI's default endpoint, so that `situate stats` and
    // the rest reach the robot with no port to copy. Headless, many runs may go at once (the
    // experiment, the tests): a free port each, and another if that one is taken before the
    // link binds it (by another program's outgoing connection, say).
    let (listen, listen_fallback) = match (&demo.listen, demo.headless) {
        (Some(given), _) => (given.clone(), false),
        (None, false) => (situate_link::DEFAULT_ENDPOINT.to_string(), true),
        (None, true) => (crate::robot::free_loopback_endpoint()?, true),
    };
    let opts = RunOptions {
        clock: Some("simulated".into()),
        listen: vec![listen],
        listen_fallback,
        sim: SimOverrides { map: demo.map.clone(), seed: Some(demo.seed), world: demo.world.clone() },
        speed: if demo.headless { None } else { Some(demo.speed) },
        stopped: true,
        gui: (!demo.headless).then(|| demo.gui.clone()),
        no_gui: demo.headless,
        gui_allow_hosts: demo.gui_allow_host.clone(),
        record: demo.record.clone(),
        ..RunOptions::default()
    };
    // Ctrl-C (and SIGTERM, SIGHUP) stop the sequencer and end the demo with its outcome.
    let stop = signals::Stop::install()?;
    let running = start_robot(&robot_file, &opts, ext, out)?;
    let Some(sim) = &running.sim else {
        let _ = running.finish();
        return Err(problem(
            Exit::BadFile,
            format!("`{}` has no `simulator:` section: the demo needs the simulated robot", robot_file.display()),
        ));
    };
    let mission = sim.map.mission_json().to_string();
    let stops = situate_sim::task::parse(&demo.task)
        .and_then(|stops| situate_sim::task::check(&demo.task, &stops, &sim.map).map(|()| stops));
    let stops = match stops {
        Ok(stops) => stops,
        Err(e) => {
            let _ = running.finish();
            return Err(problem(Exit::Usage, format!("--task: {e}")));
        }
    };
    let endpoint = running.listen.join(",");
    let faults = FaultLog::start(&running.handle);
    let python = interpreter(demo, ext);
    let started = Instant::now();
    let mut command = std::process::Command::new(&python);
    command
        .arg(&sequencer)
        .args(["--connect", &endpoint, "--robot", &running.robot, "--mode", &demo.mode])
        .args(["--limit-s", &demo.limit_s.to_string(), "--mission", &mission])
        .args(["--seed", &demo.seed.to_string(), "--task", &demo.task])
        .args(if out.json { &["--quiet"][..] } else { &[][..] });
    let run =
        run_sequencer(command, &stop).with_context(|| format!("starting the sequencer with `{}`", python.display()));
    let wall_s = started.elapsed().as_secs_f64();
    if matches!(&run, Ok(r) if r.interrupted.is_none()) {
        settle_the_truth(&running.handle, &sim.world);
    }
    // With the GUI, the page keeps showing the robot where the mission left it, with the outcome,
    // until Ctrl-C: the cycle is stopped so what it shows is the end of the mission.
    let stay = match (&running.gui, &run) {
        (Some(_), Ok(r)) => r.interrupted.is_none() && !demo.exit_when_done,
        _ => false,
    };
    if stay {
        let _ = running.handle.request_timeout(situate::manager::Request::Stop, Duration::from_secs(2));
    }
    let (delivered_at, sim_time, made) = {
        let w = sim.world.lock().map_err(|_| anyhow::anyhow!("the simulator failed"))?;
        (w.delivered_at(), w.time_s(), situate_sim::task::judge(&sim.map, &stops, w.said()))
    };
    let task_done = made.iter().all(Option::is_some);
    // Arbitration of the base: how often `drive` changed hands (oscillation), for the experiment.
    let drive = {
        use situate::manager::Control;
        let mut handle = running.handle.clone();
        // A record resource is arbitrated leaf by leaf, all alike: its first leaf tells.
        let winners = handle.winners().unwrap_or_default();
        winners.into_iter().find(|w| w.signal == "drive" || w.signal.starts_with("drive."))
    };
    let mut running = Some(running);
    let (stats, skills, recorded) = if stay {
        let mut handle = running.as_ref().map(|r| r.handle.clone()).context("the robot")?;
        (handle.stats()?, handle.skills()?, None)
    } else {
        running.take().context("the robot")?.finish()?
    };
    // With the GUI staying up, the recording goes on until it closes (said then).
    let recording = recorded.transpose().map_err(|e| problem(Exit::Failure, format!("--record: {e}")))?;
    let run = run?;
    let faulted = faults.finish();
    let runs: u64 = skills.iter().filter(|s| s.kind != situate_core::SkillKind::Device).map(|s| s.timing.runs).sum();
    let cpu_ns: u64 =
        skills.iter().filter(|s| s.kind != situate_core::SkillKind::Device).map(|s| s.timing.total_ns).sum();
    let outcome = json!({
        "seed": demo.seed,
        "mode": demo.mode,
        "delivered": delivered_at.is_some(),
        "mission_time_s": delivered_at.unwrap_or(sim_time),
        "cycles": stats.cycle,
        "mean_cycle_ns": stats.mean_cycle_ns,
        "skill_runs": runs,
        "skill_cpu_ms": cpu_ns as f64 / 1e6,
        "wall_s": wall_s,
        "speedup": if wall_s > 0.0 { sim_time / wall_s } else { 0.0 },
        "task": demo.task,
        "stops": stops.iter().zip(&made).map(|(s, t)| json!({"stop": s.to_string(), "made_at_s": t})).collect::<Vec<_>>(),
        "task_done": task_done,
        "drive_winner_changes": drive.as_ref().map(|d| d.switches),
        "drive_held_cycles": drive.as_ref().map(|d| d.held_cycles),
        "task_time_s": if task_done { made.last().copied().flatten().unwrap_or(sim_time) } else { sim_time },
        "sequencer_exit": run.status.code(),
        "interrupted": run.interrupted.map(signals::name),
        "phase": run.phase,
        "recording": recording.as_ref().map(crate::robot::recording_json),
        "skills_faulted": faulted.iter().map(|(skill, cause, cycle)| json!({"skill": skill, "cause": cause, "cycle": cycle})).collect::<Vec<_>>(),
    });
    if out.json {
        stdoutln!("{outcome}");
    } else {
        let delivered = match delivered_at {
            Some(t) => format!("message delivered at t = {t:.1} s"),
            None => "message not delivered".to_string(),
        };
        match (run.interrupted, delivered_at) {
            (Some(sig), _) => stdoutln!(
                "demo: interrupted ({}) at t = {sim_time:.1} s{}, {delivered} (seed {})",
                signals::name(sig),
                run.phase.as_ref().map(|p| format!(" in phase {p}")).unwrap_or_default(),
                demo.seed
            ),
            (None, Some(_)) => stdoutln!("demo: {delivered} (seed {})", demo.seed),
            (None, None) => stdoutln!("demo: NOT delivered after {sim_time:.1} s (seed {})", demo.seed),
        }
        if stops != [situate_sim::task::Stop::Office] {
            let list: Vec<String> = stops
                .iter()
                .zip(&made)
                .map(|(s, t)| match t {
                    Some(t) => format!("{s} at {t:.1} s"),
                    None => format!("{s} not made"),
                })
                .collect();
            stdoutln!("demo: task {}: {}", if task_done { "done" } else { "NOT done" }, list.join(", "));
        }
        stdoutln!(
            "demo: {} cycles, {runs} skill runs, {:.1} ms in skills, {wall_s:.1} s wall ({:.0}× real time)",
            stats.cycle,
            cpu_ns as f64 / 1e6,
            if wall_s > 0.0 { sim_time / wall_s } else { 0.0 }
        );
        for (skill, cause, cycle) in &faulted {
            stdoutln!("demo: skill `{skill}` faulted at cycle {cycle}: {}", cause.lines().last().unwrap_or(cause));
        }
        if let Some(r) = &recording {
            stdout!("demo: {}", crate::robot::recording_text(r));
        }
    }
    let code = match (run.interrupted, task_done) {
        (Some(sig), _) => signals::status(sig),
        (None, true) => Exit::Ok.code(),
        (None, false) => Exit::Failure.code(),
    };
    if let Some(running) = running {
        if let Some(gui) = &running.gui {
            gui.set_outcome(outcome_for_page(delivered_at, sim_time, &run));
            out.note(format_args!(
                "the mission is over; the GUI stays on {} until Ctrl-C (--exit-when-done: exit at once)",
                gui.url()
            ));
        }
        while stop.signal().is_none() {
            std::thread::sleep(Duration::from_millis(50));
        }
        out.note(format_args!("{}: closing the GUI", stop.signal().map(signals::name).unwrap_or("stop")));
        let (_, _, recorded) = running.finish()?;
        match recorded {
            Some(Ok(r)) => out.note(format_args!("{}", crate::robot::recording_text(&r).trim_end())),
            Some(Err(e)) => return Err(problem(Exit::Failure, format!("--record: {e}"))),
            None => {}
        }
    }
    // A Ctrl-C after the mission only closes the GUI: the status is the mission's.
    Ok(code)
}

/// `situate demo --physics`: the physics robot's delivery, run by the Python package
/// (`situate.physics.deliver`: the robot, the MuJoCo world and the sequencer), its exit status
/// passed on (0: delivered, 1: not, 3: a map that cannot be read).
fn run_physics_demo(demo: &DemoOptions, ext: &Extensions, out: Out) -> anyhow::Result<u8> {
    let refused =
        [(demo.mode != "sequenced", "--mode"), (demo.task != "office", "--task"), (demo.listen.is_some(), "--listen")];
    if let Some((_, what)) = refused.iter().find(|(given, _)| *given) {
        return Err(problem(Exit::Usage, format!("{what}: not with --physics (the physics robot's demo takes --map, --seed, --robot, --sequencer, --gui, --speed, --record, --limit-s, --people, --door-closures, --dead-sonar, --exit-when-done)")));
    }
    let dirs = demo_dirs(ext);
    let find = |given: &Option<PathBuf>, name: &str| {
        given.clone().or_else(|| dirs.iter().map(|d| d.join(name)).find(|p| p.is_file())).ok_or_else(|| {
            problem(
                Exit::Usage,
                format!("no {name} found: run it from the repository's top directory or install the Python package"),
            )
        })
    };
    let robot = find(&demo.robot, "demo/physics.yaml")?;
    let sequencer = match &demo.sequencer {
        Some(s) => s.clone(),
        None => robot.parent().unwrap_or(Path::new(".")).join("deliver.py"),
    };
    let map = find(&demo.map, "maps/default.yaml")?;
    let python = interpreter(demo, ext);
    let mut command = std::process::Command::new(&python);
    command
        .args(["-m", "situate.physics.deliver", "--seed", &demo.seed.to_string()])
        .arg("--map")
        .arg(&map)
        .arg("--robot")
        .arg(&robot)
        .arg("--sequencer")
        .arg(&sequencer)
        .args(["--limit-s", &demo.limit_s.to_string()])
        .args(demo.world.to_args());
    if !demo.headless {
        command.args(["--gui", &demo.gui, "--time-scale", &demo.speed.to_string()]);
    }
    if let Some(r) = &demo.record {
        command.arg("--record").arg(r);
    }
    if demo.exit_when_done {
        command.arg("--exit-when-done");
    }
    if out.json {
        command.arg("--json");
    }
    // The robot runs in this very program when it is one of its own (the Rust build); the
    // Python package's runs in its interpreter, which the module uses by default.
    if ext.interpreter.is_none() {
        if let Ok(me) = std::env::current_exe() {
            command.arg("--program").arg(me);
        }
    }
    let status = command.status().with_context(|| {
        format!("starting the physics demo with `{}` (it needs the Python package)", python.display())
    })?;
    Ok(status.code().and_then(|c| u8::try_from(c).ok()).unwrap_or(Exit::Failure.code()))
}

/// Most cycles [`settle_the_truth`] runs.
const SETTLE_CYCLES: u64 = 5;

/// The delivery happens in the world when the speaker says the message, after the simulator's
/// ground truth (`sim.truth`) was read in that cycle: the robot's own `truth.mission.delivered`
/// says so one cycle later. The sequencer ends on the speaker's word, so the run (and its
/// recording, and the page) would end before the robot's signals show the outcome. Cycles are
/// stepped until they do (a few at most); a robot file without `sim.truth` is left as it is.
fn settle_the_truth(handle: &situate::manager::Handle, world: &situate_sim::SharedWorld) {
    use situate::manager::Control;
    let delivered = world.lock().map(|w| w.delivered_at().is_some()).unwrap_or(false);
    if !delivered {
        return;
    }
    let mut handle = handle.clone();
    for _ in 0..SETTLE_CYCLES {
        match handle.query("truth.mission.delivered") {
            Ok(r) if r.value == Some(situate_core::Value::Bool(false)) => {}
            _ => return, // said, or no such signal
        }
        if handle.step(1).is_err() {
            return;
        }
    }
}

/// The mission's outcome as the page shows it: delivered, or not and why.
fn outcome_for_page(delivered_at: Option<f64>, sim_time: f64, run: &SequencerRun) -> situate_gui::Outcome {
    if let Some(t) = delivered_at {
        return situate_gui::Outcome { ok: true, summary: format!("delivered: message delivered at t = {t:.1} s") };
    }
    let mut why = match (&run.failure, run.status.code()) {
        (Some(reason), _) => reason.clone(),
        (None, Some(0)) => "the sequencer ended without delivering".to_string(),
        (None, Some(c)) => format!("the sequencer exited with status {c}"),
        (None, None) => "the sequencer was killed".to_string(),
    };
    if let Some(p) = &run.phase {
        why.push_str(&format!(" (in phase {p})"));
    }
    situate_gui::Outcome { ok: false, summary: format!("failed at t = {sim_time:.1} s: {why}") }
}

/// The skills that faulted during the mission (a body over its budget on a busy machine, say),
/// collected from the manager's events by a thread of its own, so that the event queue is
/// always read: the outcome says which faulted, and when.
struct FaultLog {
    stop: Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<Vec<(String, String, u64)>>,
}

impl FaultLog {
    fn start(handle: &situate::manager::Handle) -> FaultLog {
        use std::sync::atomic::{AtomicBool, Ordering};
        let events = handle.events();
        let stop = Arc::new(AtomicBool::new(false));
        let stopped = Arc::clone(&stop);
        let thread = std::thread::spawn(move || {
            let mut faulted = Vec::new();
            while !stopped.load(Ordering::Relaxed) {
                match events.recv_timeout(Duration::from_millis(50)) {
                    Ok(situate::manager::Event::SkillFaulted { skill, cause, cycle }) => {
                        faulted.push((skill, cause, cycle))
                    }
                    Ok(_) | Err(crossbeam_channel::RecvTimeoutError::Timeout) => {}
                    Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break,
                }
            }
            // What arrived before the stop still counts.
            faulted.extend(events.try_iter().filter_map(|e| match e {
                situate::manager::Event::SkillFaulted { skill, cause, cycle } => Some((skill, cause, cycle)),
                _ => None,
            }));
            faulted
        });
        FaultLog { stop, thread }
    }

    /// The faults so far, oldest first (and the thread ended).
    fn finish(self) -> Vec<(String, String, u64)> {
        self.stop.store(true, std::sync::atomic::Ordering::Relaxed);
        self.thread.join().unwrap_or_default()
    }
}

/// How long the sequencer has to end after it is told to stop, before it is killed.
const SEQUENCER_BOUND: Duration = Duration::from_secs(5);

/// How the demo's sequencer ended.
struct SequencerRun {
    status: std::process::ExitStatus,
    /// The signal that stopped the demo, if one did.
    interrupted: Option<i32>,
    /// The last phase the sequencer announced (`phase N: …`), as `N (what it does)`.
    phase: Option<String>,
    /// Why the mission failed, as the sequencer said it (`mission failed: …`).
    failure: Option<String>,
}

/// Runs the sequencer to its end, its output passed through (and its
/// phases noted). On a stop request it is told to stop (SIGTERM; a Ctrl-C at
/// a terminal reaches it directly too) and killed if it has not ended
/// within [`SEQUENCER_BOUND`].
fn run_sequencer(mut command: std::process::Command, stop: &signals::Stop) -> std::io::Result<SequencerRun> {
    let mut child = command.stdout(std::process::Stdio::piped()).spawn()?;
    let noted = Arc::new(std::sync::Mutex::new(Noted::default()));
    let relay = child.stdout.take().map(|out| {
        let noted = Arc::clone(&noted);
        std::thread::spawn(move || relay_lines(out, &noted))
    });
    let mut interrupted = None;
    let mut deadline = None;
    let status = loop {
        if let Some(status) = child.try_wait()? {
            break status;
        }
        if let (None, Some(sig)) = (interrupted, stop.signal()) {
            interrupted = Some(sig);
            eprintln!("situate: {}: stopping the sequencer (again to exit at once)", signals::name(sig));
            terminate(&mut child);
            deadline = Some(Instant::now() + SEQUENCER_BOUND);
        }
        if deadline.is_some_and(|d| Instant::now() > d) {
            eprintln!("situate: the sequencer did not stop within {} s: killed", SEQUENCER_BOUND.as_secs());
            let _ = child.kill();
            break child.wait()?;
        }
        // Short: the headless speed counts the wall time up to here (a 20 ms poll was 1-3 %).
        std::thread::sleep(Duration::from_millis(2));
    };
    // A Ctrl-C at a terminal may end the sequencer before the loop above sees it.
    let interrupted = interrupted.or_else(|| stop.signal());
    if let Some(relay) = relay {
        let _ = relay.join();
    }
    let Noted { phase, failure } = noted.lock().map(|n| n.clone()).unwrap_or_default();
    Ok(SequencerRun { status, interrupted, phase, failure })
}

/// Asks a child process to stop (SIGTERM).
fn terminate(child: &mut std::process::Child) {
    #[cfg(unix)]
    {
        if let Ok(pid) = libc::pid_t::try_from(child.id()) {
            // SAFETY: kill(2) on our own child's id, which is not yet reaped.
            unsafe { libc::kill(pid, libc::SIGTERM) };
        }
    }
    #[cfg(not(unix))]
    let _ = child.kill();
}

/// What the sequencer's narrative said: its last phase, and why it failed.
#[derive(Clone, Default)]
struct Noted {
    phase: Option<String>,
    failure: Option<String>,
}

/// Copies the sequencer's output to ours line by line, noting its phases and failure.
fn relay_lines(out: impl std::io::Read, noted: &std::sync::Mutex<Noted>) {
    use std::io::{BufRead as _, Write as _};
    let mut out = std::io::BufReader::new(out);
    let mut line = Vec::new();
    loop {
        line.clear();
        match out.read_until(b'\n', &mut line) {
            Ok(0) | Err(_) => return,
            Ok(_) => {}
        }
        let text = String::from_utf8_lossy(&line);
        if let Ok(mut n) = noted.lock() {
            if let Some(p) = phase_of(&text) {
                n.phase = Some(p);
            }
            if let Some(at) = text.find("mission failed: ") {
                n.failure = Some(text[at + "mission failed: ".len()..].trim_end().to_string());
            }
        }
        // The sequencer's own "interrupted" line: the demo says it once, after, with the
        // simulator's time (the sequencer's is the last it read) and the signal that came first.
        if is_interruption(&text) {
            continue;
        }
        let mut stdout = std::io::stdout().lock();
        let _ = stdout.write_all(&line);
        let _ = stdout.flush();
    }
}

/// Whether a sequencer's line says it was interrupted: `[  20.2 s] interrupted (SIGINT) …` or
/// `interrupted (SIGINT) before the mission started` (demo/deliver.py).
fn is_interruption(line: &str) -> bool {
    let line = line.trim_start();
    let rest = match line.strip_prefix('[') {
        Some(stamped) => stamped.split_once("] ").map_or("", |(_, rest)| rest),
        None => line,
    };
    rest.starts_with("interrupted (SIG")
}

/// `N (what it does)` from a narrative line `[  12.3 s] phase N: what it does`.
fn phase_of(line: &str) -> Option<String> {
    let at = line.find("phase ")?;
    let rest = &line[at + "phase ".len()..];
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let text = rest[digits..].strip_prefix(": ")?;
    (digits > 0).then(|| format!("{} ({})", &rest[..digits], text.trim_end()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sequencers_interruption_line_is_known_and_no_other() {
        assert!(is_interruption("[   20.2 s] interrupted (SIGINT) in phase 1 (wandering), message not delivered\n"));
        assert!(is_interruption("interrupted (SIGTERM) before the mission started\n"));
        assert!(!is_interruption("[   20.2 s] phase 1: wandering about the lab\n"));
        assert!(!is_interruption("[   20.2 s]     said: \"interrupted (SIGINT)\" is what I heard\n"));
        assert!(!is_interruption("[ unterminated interrupted (SIGINT)\n"));
    }
}
