//! Robot files: loading one (with what composes it at launch: `include:`,
//! `${ENV}` substitution and `--set`), checking it, starting it, running it until it
//! is told to stop, and serving one skill type out of process.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use serde_json::{json, Value as Json};
use situate::manager::{Control, Event, Manager, ManagerStats, SkillInfo};
use situate_link::{Link, LinkConfig};
use situate_robotfile::config::{ClockKind, ExecutorKind, RobotFile};
use situate_robotfile::spec::RobotSpec;
use situate_robotfile::yaml::Spanned;

use crate::args::{Compose, RunArgs};
use crate::client::{client_verb, Remote};
use crate::map;
use crate::output::{problem, Exit, Out, Problem};
use crate::signals;
use crate::sim::{SimOverrides, Simulation};
use crate::skill_types::{program_registry, registry_for, registry_with};
use crate::Extensions;

/// A robot file read and lifted into what the manager builds from.
pub(crate) struct Loaded {
    pub(crate) file: RobotFile,
    pub(crate) spec: RobotSpec,
    pub(crate) link: LinkConfig,
    /// The `ros2:` bridge's configuration, when the file has one.
    pub(crate) ros2: Option<situate_ros2::Ros2Config>,
    pub(crate) remote: Vec<(String, situate_core::SkillDecl)>,
}

/// Reads a robot file and those it includes (their `${NAME}`s replaced from the environment),
/// applies `--set`, and checks its `link:` and remote skills. Every problem
/// is a [`Problem`] of kind [`Exit::BadFile`] (or [`Exit::Usage`] for a bad `--set`).
pub(crate) fn load(path: &Path, compose: &Compose) -> anyhow::Result<Loaded> {
    let env = |name: &str| std::env::var(name).ok();
    let options = situate_robotfile::config::LoadOptions { env: Some(&env) };
    let mut robot_file = RobotFile::load_with(path, options).map_err(|errors| bad_file(path, &errors))?;
    apply_sets(&mut robot_file, &compose.set)?;
    let link = match &robot_file.link {
        None => LinkConfig::default(),
        Some(node) => match LinkConfig::from_node(node) {
            // What `run` gives Zenoh is checked here too, so `check` and `run` agree.
            Ok(l) => match l.zenoh_config() {
                Ok(_) => l,
                Err(e) => {
                    let at = node
                        .value
                        .as_map()
                        .and_then(|m| m.iter().find(|(k, _)| k.value == "zenoh").map(|(_, v)| v.pos))
                        .unwrap_or(node.pos);
                    let e = crate::output::clean(&e.to_string());
                    return Err(bad_file(
                        path,
                        &[robot_file.error(at, format!("`link`: Zenoh refuses this configuration: {e}"))],
                    ));
                }
            },
            Err(errors) => {
                let lines: Vec<_> = errors.iter().map(|e| robot_file.error(e.pos, e.message.clone())).collect();
                return Err(bad_file(path, &lines));
            }
        },
    };
    let ros2 = match &robot_file.ros2 {
        None => None,
        Some(node) => match situate_ros2::Ros2Config::from_node(node) {
            Ok(c) => Some(c),
            Err(e) => {
                let at = e.pos.unwrap_or(node.pos);
                return Err(bad_file(path, &[robot_file.error(at, format!("`ros2`: {}", e.message))]));
            }
        },
    };
    let remote = robot_file.remote_decls().map_err(|errors| bad_file(path, &errors))?;
    Ok(Loaded { spec: RobotSpec::from_file(&robot_file), link, ros2, remote, file: robot_file })
}

/// A file's problems, each on its line, then the count.
pub(crate) fn bad_file(path: &Path, errors: &[impl std::fmt::Display]) -> anyhow::Error {
    Problem::bad_file(path, errors.iter().map(ToString::to_string).collect()).into()
}

/// `--set SKILL.PARAM=VALUE`: the value (YAML: a scalar or a list of
/// numbers) replaces the file's, or is added; the manager then checks it
/// against the parameter's declaration like a value written in the file.
fn apply_sets(robot_file: &mut RobotFile, sets: &[String]) -> anyhow::Result<()> {
    for set in sets {
        let usage = |why: String| problem(Exit::Usage, format!("--set {set}: {why}"));
        let Some((target, text)) = set.split_once('=') else {
            return Err(usage("expected SKILL.PARAM=VALUE, e.g. runaway.safe_distance=0.3".into()));
        };
        let Some((skill, param)) = target.trim().split_once('.') else {
            return Err(usage(format!("`{target}` is not SKILL.PARAM")));
        };
        let node = situate_robotfile::yaml::parse(text).map_err(|e| usage(format!("the value: {}", e.message)))?;
        let value = node
            .value
            .to_value()
            .or_else(|| node.value.to_f64s())
            .ok_or_else(|| usage("the value is not a scalar or a list of numbers".into()))?;
        let names: Vec<String> = robot_file.skills.iter().map(|e| e.name.value.clone()).collect();
        let Some(entry) = robot_file.skills.iter_mut().find(|e| e.name.value == skill) else {
            return Err(usage(format!(
                "no skill or device `{skill}` in {}{}",
                robot_file.file,
                situate_core::suggestion(skill, names.iter().map(String::as_str))
            )));
        };
        let written = Some(text.trim().to_string());
        match entry.params.iter_mut().find(|p| p.name.value == param) {
            Some(p) => {
                p.value = Spanned::new(value, p.value.pos);
                p.written = written;
            }
            None => entry.params.push(situate_robotfile::config::Param {
                name: Spanned::new(param.to_string(), entry.pos),
                value: Spanned::new(value, entry.pos),
                written,
            }),
        }
    }
    Ok(())
}

/// A robot file's graph, built without starting anything (`check`,
/// `signals FILE`, `graph FILE`): the same checks `run` makes.
pub(crate) fn static_graph(
    file: &Path,
    compose: &Compose,
    ext: &Extensions,
) -> anyhow::Result<(Loaded, situate::manager::Graph)> {
    if map::looks_like_map(file) {
        return Err(Problem::file_problem(format!(
            "{}: this is a map file: use `situate map check {}`",
            file.display(),
            file.display()
        ))
        .into());
    }
    let mut loaded = load(file, compose)?;
    let (mut registry, _sim) = registry_for(&loaded.file, program_registry(ext)?, ext, &SimOverrides::default())
        .map_err(|errors| bad_file(file, &errors))?;
    crate::ros2::add_devices(&mut loaded.spec, &mut registry, loaded.ros2.as_ref());
    // Every section `run` reads is checked by the code `run` uses.
    gui_address(&loaded.file, &RunOptions::default()).map_err(|e| bad_file(file, &[e]))?;
    for (_, decl) in &loaded.remote {
        // Checking needs the declaration only; nothing is created.
        registry.add(situate_core::SkillType::new(decl.clone(), || Err("not created by `check`".into())));
    }
    match situate::manager::Graph::build(&loaded.spec, &registry) {
        Ok(graph) => Ok((loaded, graph)),
        Err(e) => Err(build_failure(file, &e)),
    }
}

/// The manager's diagnostics (errors and warnings), then the count of errors.
fn build_failure(file: &Path, e: &situate_robotfile::spec::BuildError) -> anyhow::Error {
    let n = e.diagnostics.iter().filter(|d| d.is_error()).count();
    let mut p = Problem::bad_file(file, e.diagnostics.iter().map(ToString::to_string).collect());
    p.message = format!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" });
    p.into()
}

/// `situate check`.
pub(crate) fn check(file: &Path, compose: &Compose, ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let (_loaded, graph) = static_graph(file, compose, ext)?;
    let warnings: Vec<String> = graph.warnings.iter().map(ToString::to_string).collect();
    if !out.json {
        for w in &warnings {
            out.warn(w);
        }
    }
    let n = graph.instances.len();
    let result = json!({
        "file": file.display().to_string(),
        "ok": true,
        "robot": graph.robot,
        "skills": n,
        "signal_leaves": graph.leaves.len(),
        "warnings": warnings,
    });
    out.result(&result, || {
        format!(
            "{}: ok — robot `{}`, {n} skill{}, {} signal leaves",
            file.display(),
            graph.robot,
            if n == 1 { "" } else { "s" },
            graph.leaves.len()
        )
    });
    Ok(())
}

/// A link endpoint on a free TCP port of the loopback interface (`tcp/127.0.0.1:PORT`).
pub(crate) fn free_loopback_endpoint() -> anyhow::Result<String> {
    let port = situate_link::free_loopback_port()
        .map_err(|e| problem(Exit::Failure, format!("finding a free port for the link: {e}")))?;
    Ok(format!("tcp/127.0.0.1:{port}"))
}

/// How to run a robot file: the command line's overrides.
#[derive(Default, Clone)]
pub(crate) struct RunOptions {
    pub(crate) cycles: Option<u64>,
    pub(crate) executor: Option<String>,
    pub(crate) clock: Option<String>,
    pub(crate) no_link: bool,
    pub(crate) listen: Vec<String>,
    /// When `listen` cannot be opened (another robot holds the port), listen on a free loopback
    /// port instead, and say so ([`Running::listen`] is where): `situate demo`'s default.
    pub(crate) listen_fallback: bool,
    pub(crate) sim: SimOverrides,
    /// Pacing of the simulated clock (× real time).
    pub(crate) speed: Option<f64>,
    /// Start with the cycle stopped (a sequencer starts it).
    pub(crate) stopped: bool,
    /// Serve the GUI here (overrides the file's `gui:` section).
    pub(crate) gui: Option<String>,
    /// No GUI even if the file asks for one.
    pub(crate) no_gui: bool,
    /// `--gui-allow-host`: names the GUI answers to besides its own address.
    pub(crate) gui_allow_hosts: Vec<String>,
    /// `--set`.
    pub(crate) compose: Compose,
    /// `--record`: the MCAP file.
    pub(crate) record: Option<PathBuf>,
    /// `--record-dir`: where the link's `record` request writes (default: the
    /// working directory).
    pub(crate) record_dir: Option<PathBuf>,
}

/// A robot running on its own threads, serving the link.
pub(crate) struct Running {
    pub(crate) handle: situate::manager::Handle,
    pub(crate) join: situate::manager::Joiner,
    pub(crate) events: crossbeam_channel::Receiver<Event>,
    pub(crate) served: Option<Link>,
    /// The ROS 2 bridge (its tokens withdrawn before the link's session closes).
    pub(crate) ros2: Option<situate_ros2::Bridge>,
    pub(crate) gui: Option<situate_gui::GuiServer>,
    pub(crate) sim: Option<Simulation>,
    pub(crate) robot: String,
    /// The endpoints the link listens on (empty without one).
    pub(crate) listen: Vec<String>,
    /// `--record`: ended after the manager, with what it holds.
    pub(crate) recorder: Option<situate_record::Recorder>,
    /// The link's `record` request: a recording it started is ended after
    /// the manager too.
    pub(crate) link_recorder: Option<Arc<crate::link_record::LinkRecorder>>,
}

/// What [`Running::finish`] leaves: the final statistics, the skills, and
/// the recording's outcome if one was made.
pub(crate) type Finished =
    (ManagerStats, Vec<SkillInfo>, Option<Result<situate_record::Summary, situate_record::RecordError>>);

impl Running {
    /// Stops everything and returns the final statistics, within
    /// [`signals::stop_bound`]: a cycle stuck in a skill's body (or a part
    /// that does not stop) is left behind, and the error says which.
    pub(crate) fn finish(self) -> Result<Finished, Stuck> {
        let Running { mut handle, join, served, ros2, gui, recorder, link_recorder, .. } = self;
        let stage = Arc::new(std::sync::atomic::AtomicU8::new(Stage::Stats as u8));
        let (tx, rx) = crossbeam_channel::bounded(1);
        let at = Arc::clone(&stage);
        // The teardown runs on a thread of its own, so that this one can give up on it.
        let teardown = move || {
            let stats = handle.stats();
            let skills = handle.skills();
            at.store(Stage::Gui as u8, Ordering::SeqCst);
            if let Some(gui) = gui {
                gui.stop();
            }
            at.store(Stage::Link as u8, Ordering::SeqCst);
            drop(ros2);
            drop(served);
            at.store(Stage::Cycle as u8, Ordering::SeqCst);
            let _ = handle.request(situate::manager::Request::Shutdown);
            let _ = join.join();
            // After the manager: every cycle it ran is in the file.
            let recorded = recorder.map(situate_record::Recorder::finish);
            match link_recorder.and_then(|l| l.finish()) {
                Some(Ok(s)) => tracing::info!("{}", recording_text(&s).trim_end()),
                Some(Err(e)) => tracing::error!("the recording started over the link: {e}"),
                None => {}
            }
            let _ = tx.send((stats, skills, recorded));
        };
        if let Err(e) = std::thread::Builder::new().name("situate-teardown".into()).spawn(teardown) {
            return Err(Stuck { stage: Stage::Spawn, detail: e.to_string() });
        }
        match rx.recv_timeout(signals::stop_bound()) {
            Ok((Ok(stats), Ok(skills), recorded)) => Ok((stats, skills, recorded)),
            Ok((Err(e), _, _) | (_, Err(e), _)) => Err(Stuck { stage: Stage::Stats, detail: e.to_string() }),
            Err(_) => {
                let stage = match stage.load(Ordering::SeqCst) {
                    s if s == Stage::Gui as u8 => Stage::Gui,
                    s if s == Stage::Link as u8 => Stage::Link,
                    s if s == Stage::Cycle as u8 => Stage::Cycle,
                    _ => Stage::Stats,
                };
                Err(Stuck { stage, detail: String::new() })
            }
        }
    }
}

/// Where [`Running::finish`] was when it gave up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Stage {
    Spawn,
    Stats,
    Gui,
    Link,
    Cycle,
}

/// A stop that did not complete: what did not stop.
#[derive(Debug)]
pub(crate) struct Stuck {
    stage: Stage,
    detail: String,
}

impl std::fmt::Display for Stuck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let bound = signals::bound_text();
        match self.stage {
            Stage::Spawn => write!(f, "could not stop the robot: {}", self.detail),
            Stage::Stats if !self.detail.is_empty() => {
                write!(f, "the manager did not give its final statistics: {}", self.detail)
            }
            Stage::Stats | Stage::Cycle => write!(
                f,
                "the cycle did not stop within {bound} of the shutdown request (it is stuck, most likely \
                 in a skill's body that does not return); exiting without it"
            ),
            Stage::Gui => write!(f, "the GUI did not stop within {bound}; exiting without it"),
            Stage::Link => write!(f, "the link did not close within {bound}; exiting without it"),
        }
    }
}

impl std::error::Error for Stuck {}

/// Loads, checks and starts a robot file.
pub(crate) fn start_robot(file: &Path, opts: &RunOptions, ext: &Extensions, out: Out) -> anyhow::Result<Running> {
    let Loaded { mut spec, mut link, ros2, remote, file: robot_file } = load(file, &opts.compose)?;
    let (mut registry, sim) =
        registry_for(&robot_file, program_registry(ext)?, ext, &opts.sim).map_err(|errors| bad_file(file, &errors))?;
    let shown = crate::sim::shown_building(&robot_file, &opts.sim).map_err(|errors| bad_file(file, &errors))?;
    if opts.no_link && !remote.is_empty() {
        let names: Vec<&str> = remote.iter().map(|(n, _)| n.as_str()).collect();
        return Err(problem(
            Exit::Usage,
            format!("remote skills ({}) need the link; drop --no-link", names.join(", ")),
        ));
    }
    let gui_listen = gui_address(&robot_file, opts).map_err(|e| {
        let kind = if opts.gui.is_some() { Exit::Usage } else { Exit::BadFile };
        Problem { prefix: "", ..Problem::new(kind, e) }
    })?;
    if let Some(e) = &opts.executor {
        spec.executor = if e == "parallel" { ExecutorKind::Parallel } else { ExecutorKind::Serial };
    }
    if let Some(c) = &opts.clock {
        spec.clock = if c == "simulated" { ClockKind::Simulated } else { ClockKind::Wall };
    }
    if !opts.listen.is_empty() {
        link.listen = opts.listen.clone();
    }
    let session = if opts.no_link {
        None
    } else {
        let refused = |link: &LinkConfig, e: &dyn std::fmt::Display| {
            problem(
                Exit::Failure,
                format!(
                    "opening the link on {} (is another robot using it? try --listen or --no-link): {}",
                    link.listen.join(", "),
                    crate::output::clean(&format!("{e:#}"))
                ),
            )
        };
        let opened = match Link::open(&link) {
            Ok(opened) => opened,
            Err(e) if opts.listen_fallback => {
                let taken = link.listen.join(", ");
                tracing::debug!(error = %e, "the link's endpoint is taken");
                // A free port can be taken too before the link binds it (the kernel may give it
                // to any outgoing connection meanwhile): a few tries.
                let mut tries = 0;
                let opened = loop {
                    link.listen = vec![free_loopback_endpoint()?];
                    match Link::open(&link) {
                        Ok(opened) => break opened,
                        Err(_) if tries < 3 => tries += 1,
                        Err(e) => return Err(refused(&link, &e)),
                    }
                };
                out.note(format_args!(
                    "{taken} is taken (another robot?): the link listens on {} instead (`--connect {}`)",
                    link.listen.join(", "),
                    link.listen.join(",")
                ));
                opened
            }
            Err(e) => return Err(refused(&link, &e)),
        };
        Some(opened)
    };
    if let Some(session) = &session {
        for (name, decl) in remote {
            let timeout = robot_file
                .skills
                .iter()
                .find(|e| e.name.value == name)
                .and_then(|e| e.timeout_ms.as_ref())
                .map(|t| Duration::from_secs_f64(t.value.min(86_400_000.0) / 1e3));
            registry.add(situate_link::RemoteSkill::skill_type_with_timeout(
                session,
                &robot_file.robot.value,
                &name,
                decl,
                timeout,
            ));
        }
    }
    // The ROS 2 node, and its topics in as devices of the robot: declared before the build,
    // which wires their signals like any device's.
    let ros2_node = crate::ros2::declare(&mut spec, &mut registry, ros2.as_ref(), session.as_ref())?;
    let mut manager = Manager::build(&spec, &registry).map_err(|e| build_failure(file, &e))?;
    for w in &manager.graph().warnings {
        out.warn(w);
    }
    manager.stop_after(opts.cycles);
    manager.set_speed(opts.speed);
    let events = manager.events();
    let mut metadata = recording_metadata(file, &opts.compose.set, spec.clock, sim.as_ref());
    if let Some((path, map)) = &shown {
        metadata.insert("world".to_string(), map.world_json().to_string());
        metadata.insert("map_file".to_string(), path.display().to_string());
    }
    let recorder = match &opts.record {
        Some(path) => Some(
            situate_record::Recorder::start_with(path, &mut manager, metadata.clone())
                .map_err(|e| problem(Exit::Usage, format!("--record: {e}")))?,
        ),
        None => None,
    };
    // The GUI's timeline taps the cycle too (beside a recording: each tap gets every cycle).
    let gui_tap = gui_listen.map(|_| situate_gui::HistoryTap::new(&mut manager));
    // ROS time: the robot waits, stopped, for /clock to step it (situate_ros2::clock).
    let ros_time = ros2.as_ref().is_some_and(|c| c.use_sim_time) && ros2_node.is_some();
    let (handle, join) = manager.spawn(!opts.stopped && !ros_time);
    let mut running = Running {
        handle,
        join,
        events,
        served: None,
        ros2: None,
        gui: None,
        sim,
        robot: spec.robot.clone(),
        listen: if opts.no_link { Vec::new() } else { link.listen.clone() },
        recorder,
        link_recorder: None,
    };
    if let Some(session) = session {
        let dir = match &opts.record_dir {
            Some(d) => d.clone(),
            None => std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")),
        };
        let link_recorder = crate::link_record::LinkRecorder::new(dir, running.handle.clone(), metadata);
        let mut verbs = situate_link::Verbs::default();
        verbs.0.insert("record".to_string(), link_recorder.verb());
        running.link_recorder = Some(link_recorder);
        match Link::serve_with(&spec.robot, running.handle.clone(), session, &link, verbs).context("serving the link") {
            Ok(l) => {
                out.note(format_args!(
                    "robot `{}` serving situate/{}/** on {}",
                    spec.robot,
                    spec.robot,
                    link.listen.join(", ")
                ));
                inject_panics(&l);
                running.served = Some(l);
            }
            Err(e) => {
                let _ = running.finish();
                return Err(e);
            }
        }
    }
    if let (Some(config), Some((node, inputs)), Some(_)) = (&ros2, ros2_node, &running.served) {
        let topics_in = config.topics.iter().filter(|t| t.direction == situate_ros2::Direction::In).count();
        match situate_ros2::Bridge::start_on(node, Some(inputs), running.handle.clone(), config) {
            Ok(bridge) => {
                out.note(format_args!(
                    "ROS 2 node on domain {} ({} topics out, {topics_in} in)",
                    config.domain_id,
                    bridge.topics().len()
                ));
                running.ros2 = Some(bridge);
                if ros_time && !opts.stopped {
                    // ROS time: the cycle follows /clock from its first message; a `stop` (or a
                    // pausing monitor) holds it, a `run` lets it go on.
                    let _ = running.handle.request_timeout(situate::manager::Request::Run, Duration::from_secs(30));
                }
            }
            Err(e) => {
                let _ = running.finish();
                return Err(anyhow::anyhow!("starting the ROS 2 bridge: {e}"));
            }
        }
    } else if ros2.is_some() {
        out.warn(format_args!("`ros2:` needs the link: no ROS 2 bridge with --no-link"));
    }
    if let Some(listen) = gui_listen {
        let world = running.sim.as_ref().map(|s| &s.map).or(shown.as_ref().map(|(_, m)| m)).map(|m| m.world_json());
        let allowed_hosts = opts.gui_allow_hosts.clone();
        let config = situate_gui::GuiConfig { listen, world, allowed_hosts, ..situate_gui::GuiConfig::default() };
        match situate_gui::serve_with_history(running.handle.clone(), config, gui_tap) {
            Ok(g) => {
                out.note(format_args!("GUI on {}", g.url()));
                running.gui = Some(g);
            }
            Err(e) => {
                let _ = running.finish();
                return Err(anyhow::anyhow!("starting the GUI on {listen}: {e}"));
            }
        }
    }
    Ok(running)
}

/// A GUI address as written: `127.0.0.1:8080`, or a port on 127.0.0.1.
pub(crate) fn parse_gui_address(text: &str) -> Result<std::net::SocketAddr, String> {
    text.parse().or_else(|_| {
        text.parse::<u16>()
            .map(|port| std::net::SocketAddr::from(([127, 0, 0, 1], port)))
            .map_err(|_| format!("`{text}` is not an address like 127.0.0.1:8080 or a port number"))
    })
}

/// Where to serve the GUI: `--gui ADDR`, else the file's `gui: {listen: ADDR}`
/// (or `gui: {port: N}` on 127.0.0.1), else nowhere.
pub(crate) fn gui_address(robot_file: &RobotFile, opts: &RunOptions) -> Result<Option<std::net::SocketAddr>, String> {
    if opts.no_gui {
        return Ok(None);
    }
    let parse = parse_gui_address;
    if let Some(text) = &opts.gui {
        return parse(text).map(Some).map_err(|e| format!("--gui: {e}"));
    }
    let Some(node) = &robot_file.gui else { return Ok(None) };
    let Some(entries) = node.value.as_map() else {
        return Err(robot_file
            .error(node.pos, "`gui` expects a mapping such as `{listen: 127.0.0.1:8080}`")
            .to_string());
    };
    let mut addr = None;
    for (key, value) in entries {
        let text = value.value.as_text().map(str::to_string).or_else(|| value.value.as_i64().map(|n| n.to_string()));
        match (key.value.as_str(), text) {
            ("listen" | "port", Some(t)) => match parse(&t) {
                Ok(a) => addr = Some(a),
                Err(e) => return Err(robot_file.error(value.pos, format!("`gui.{}`: {e}", key.value)).to_string()),
            },
            ("listen" | "port", None) => {
                return Err(robot_file.error(value.pos, format!("`gui.{}` expects an address", key.value)).to_string())
            }
            (other, _) => {
                return Err(robot_file
                    .error(
                        key.pos,
                        format!(
                            "unknown key `{other}` in `gui`{}",
                            situate_core::suggestion(other, ["listen", "port"])
                        ),
                    )
                    .to_string())
            }
        }
    }
    Ok(addr)
}

/// `situate run`.
pub(crate) fn run_robot(args: RunArgs, ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let RunArgs {
        file,
        cycles,
        executor,
        clock,
        no_link,
        listen,
        map,
        seed,
        world,
        speed,
        stopped,
        gui,
        no_gui,
        gui_allow_host,
        record,
        record_dir,
        compose,
    } = args;
    let opts = RunOptions {
        cycles,
        executor,
        clock,
        no_link,
        listen,
        listen_fallback: false,
        sim: SimOverrides { map, seed, world },
        speed,
        stopped,
        gui,
        no_gui,
        gui_allow_hosts: gui_allow_host,
        compose,
        record,
        record_dir,
    };
    // Before starting: a signal during the start stops the robot once started.
    let interrupted = signals::Stop::install()?;
    let running = start_robot(&file, &opts, ext, out)?;
    let started = Instant::now();
    loop {
        if let Some(sig) = interrupted.signal() {
            out.note(format_args!("{}: stopping (again to exit at once)", signals::name(sig)));
            break;
        }
        match running.events.recv_timeout(Duration::from_millis(100)) {
            Ok(Event::SkillFaulted { skill, cause, cycle }) if !out.quiet => {
                eprintln!("cycle {cycle}: skill `{skill}` faulted: {cause}")
            }
            Ok(Event::ManagerStopped { cycle }) if cycles.is_some_and(|n| cycle >= n) => break,
            _ => {}
        }
        if cycles.is_some() && started.elapsed() > Duration::from_secs(1) {
            // A stop requested over the link also ends a bounded run. Bounded:
            // a stuck cycle must not keep this loop from seeing a signal.
            let asked =
                running.handle.request_timeout(situate::manager::Request::QueryStats, Duration::from_millis(200));
            if let Ok(situate::manager::Reply::Stats(s)) = asked {
                if cycles.is_some_and(|n| s.cycle >= n) && !s.running {
                    break;
                }
            }
        }
    }
    match running.finish() {
        Ok((stats, skills, recorded)) => {
            let recording = match recorded.transpose() {
                Ok(summary) => summary,
                Err(e) => return Err(problem(Exit::Failure, format!("--record: {e}"))),
            };
            let mut json = summary_json(&stats, &skills);
            if let Some(r) = &recording {
                json["recording"] = recording_json(r);
            }
            out.result(&json, || {
                let mut text = summary_text(&stats, &skills);
                if let Some(r) = &recording {
                    if !text.is_empty() && !text.ends_with('\n') {
                        text.push('\n');
                    }
                    text.push_str(recording_text(r).trim_end());
                }
                text
            });
            Ok(())
        }
        Err(stuck) => Err(Problem {
            lines: vec![format!("situate: {stuck}")],
            ..Problem::new(Exit::Failure, "no summary: the manager did not answer").said_by_situate()
        }
        .into()),
    }
}

/// `situate serve-skill`: one instance of a skill type, served out of
/// process until Ctrl-C (docs/protocol.md, "Remote skills").
pub(crate) fn serve_skill(
    skill: &str,
    name: Option<String>,
    libraries: &[PathBuf],
    python: &[PathBuf],
    remote: &Remote,
    ext: &Extensions,
    out: Out,
) -> anyhow::Result<()> {
    if skill.contains(':') {
        return Err(problem(
            Exit::Usage,
            format!(
                "`{skill}` names a Python function (MODULE:FUNCTION): serve it with the `situate` that the Python \
                 package installs (scripts/python.sh, then .venv/bin/situate serve-skill {skill} --robot ROBOT)"
            ),
        ));
    }
    let registry = registry_with(libraries, python, ext)?;
    let Some(ty) = registry.get(skill) else {
        let known: Vec<&str> = registry.names().collect();
        return Err(problem(
            Exit::Usage,
            format!(
                "no skill type `{skill}`{}; give the library that defines it with --library (known here: {})",
                situate_core::suggestion(skill, known.iter().copied()),
                known.join(", ")
            ),
        ));
    };
    let name = name.unwrap_or_else(|| skill.rsplit('.').next().unwrap_or(skill).to_string());
    client_verb(remote, |client, robot| {
        let stop = signals::Stop::install()?;
        // The body runs on this thread: one that never returns is left behind.
        let stuck = format!(
            "`{name}`'s body did not return within {} of the stop request; exiting without it",
            signals::bound_text()
        );
        let watchdog = stop.watchdog(move || stuck);
        let stats = situate_link::serve_skill(client.session(), robot, &name, ty, stop.flag(), || {
            out.note(format_args!(
                "serving `{name}` (type `{skill}`) of robot `{robot}` on situate/{robot}/remote/{name}/inputs; \
                 Ctrl-C stops"
            ));
        });
        drop(watchdog);
        let s = stats.map_err(|e| problem(Exit::Failure, e.to_string()))?;
        let stopped_by = stop.signal().map(signals::name);
        let result = json!({
            "skill": name, "type": skill, "robot": robot, "signal": stopped_by,
            "received": s.received, "computed": s.computed, "dropped": s.dropped, "errors": s.errors,
        });
        if out.json {
            stdoutln!("{result}");
        } else {
            out.note(format_args!(
                "stopped{}; {} inputs received, {} runs, {} dropped as stale, {} errors",
                stopped_by.map(|s| format!(" ({s})")).unwrap_or_default(),
                s.received,
                s.computed,
                s.dropped,
                s.errors
            ));
        }
        Ok(())
    })
}

/// The summary under `--json`: the protocol's `stats` and `skills` replies (docs/protocol.md).
fn summary_json(stats: &ManagerStats, skills: &[SkillInfo]) -> Json {
    json!({
        "stats": situate_link::json::stats_to_json(stats),
        "skills": skills.iter().map(situate_link::json::skill_to_json).collect::<Vec<_>>(),
    })
}

/// What a recording keeps of how the robot was built, for `situate replay`:
/// the robot file (absolute), the `--set`s given, the clock, and the
/// simulator's building and seed (for the GUI's world view of a replay).
pub(crate) fn recording_metadata(
    file: &Path,
    sets: &[String],
    clock: ClockKind,
    sim: Option<&Simulation>,
) -> std::collections::BTreeMap<String, String> {
    let file = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let mut meta = std::collections::BTreeMap::new();
    meta.insert("robot_file".to_string(), file.display().to_string());
    meta.insert("sets".to_string(), serde_json::to_string(sets).unwrap_or_default());
    let clock = match clock {
        ClockKind::Simulated => "simulated",
        ClockKind::Wall => "wall",
    };
    meta.insert("clock".to_string(), clock.to_string());
    if let Some(sim) = sim {
        meta.insert("world".to_string(), sim.map.world_json().to_string());
        meta.insert("seed".to_string(), sim.seed.to_string());
        meta.insert("map_file".to_string(), sim.map_path.display().to_string());
    }
    meta
}

/// A finished recording in JSON (`"recording"` of `run` and `demo`).
pub(crate) fn recording_json(r: &situate_record::Summary) -> Json {
    json!({
        "path": r.path.display().to_string(),
        "cycles": r.frames,
        "first_cycle": r.cycles.map(|c| c.0),
        "last_cycle": r.cycles.map(|c| c.1),
        "messages": r.messages,
        "channels": r.channels,
        "dropped_cycles": r.dropped,
        "bytes": r.bytes,
    })
}

/// A finished recording, one line.
pub(crate) fn recording_text(r: &situate_record::Summary) -> String {
    let size = if r.bytes >= 1_000_000 {
        format!("{:.1} MB", r.bytes as f64 / 1e6)
    } else {
        format!("{:.1} kB", r.bytes as f64 / 1e3)
    };
    format!(
        "recorded {} cycles ({} messages on {} channels, {size}{}) to {}\n",
        r.frames,
        r.messages,
        r.channels,
        if r.dropped > 0 { format!("; {} cycles dropped: the disk did not keep up", r.dropped) } else { String::new() },
        r.path.display()
    )
}

fn summary_text(stats: &ManagerStats, skills: &[SkillInfo]) -> String {
    use std::fmt::Write as _;
    let mut text = String::new();
    let _ = writeln!(text, "robot `{}`: {} cycles, {:.3} s on its clock", stats.robot, stats.cycle, stats.time_s);
    let _ = writeln!(
        text,
        "cycle time: mean {:.1} µs, max {:.1} µs; period {:.1} ms; overruns {}; late starts {}",
        stats.mean_cycle_ns / 1e3,
        stats.max_cycle_ns as f64 / 1e3,
        stats.period_s * 1e3,
        stats.overruns,
        stats.late_starts
    );
    let _ = writeln!(
        text,
        "{:<16} {:<8} {:>8} {:>10} {:>10} {:>10}  state",
        "skill", "kind", "runs", "mean µs", "max µs", "total ms"
    );
    for s in skills {
        let state = match (&s.faulted, s.active) {
            (Some(cause), _) => format!("faulted: {cause}"),
            (None, true) => "active".to_string(),
            (None, false) => "inactive".to_string(),
        };
        let _ = writeln!(
            text,
            "{:<16} {:<8} {:>8} {:>10.2} {:>10.2} {:>10.3}  {state}",
            s.name,
            s.kind.name(),
            s.timing.runs,
            s.timing.mean_ns() / 1e3,
            s.timing.max_ns as f64 / 1e3,
            s.timing.total_ns as f64 / 1e6
        );
    }
    text.trim_end().to_string()
}

/// A hook for tests from outside the program: `SITUATE_TEST_PANIC=<thread>[,<thread>…]` makes each
/// named link thread (`situate-link-req`, `situate-link-events`, `situate-link-telemetry`) panic
/// once, so a test can see the `worker_failed` event and the restart as a client does. Unknown
/// names are warned about and ignored.
fn inject_panics(link: &Link) {
    let Ok(names) = std::env::var("SITUATE_TEST_PANIC") else { return };
    for name in names.split(',').map(str::trim).filter(|n| !n.is_empty()) {
        if situate_link::server::THREADS.contains(&name) {
            tracing::warn!(thread = name, "SITUATE_TEST_PANIC: this link thread will panic once");
            link.inject_panic(name);
        } else {
            tracing::warn!(thread = name, "SITUATE_TEST_PANIC names no link thread; ignored");
        }
    }
}
