//! Starting a robot file with the command line's overrides ([`RunOptions`]): the manager
//! on its own threads, the link (on a free port when asked and the endpoint is taken), its
//! remote skills, the ROS 2 bridge, a recording and the GUI; and where the GUI is served.

use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::Context as _;
use situate::manager::Manager;
use situate_link::{Link, LinkConfig};
use situate_robotfile::config::{ClockKind, ExecutorKind, RobotFile};

use super::check::build_failure;
use super::recording::recording_metadata;
use super::running::Running;
use super::{bad_file, load, Loaded};
use crate::args::Compose;
use crate::output::{problem, Exit, Out, Problem};
use crate::sim::SimOverrides;
use crate::skill_types::{program_registry, registry_for};
use crate::Extensions;

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
