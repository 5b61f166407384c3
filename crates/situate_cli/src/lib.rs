//! The `situate` program: check and run robot files, and talk to a running
//! skill manager over the link. The same program is installed by the Rust
//! build (`situate` binary) and by the Python wheel (which calls [`main`]).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};
use serde_json::{json, Value as Json};
use situate::manager::{
    ClockKind, Control, Event, ExecutorKind, Manager, ManagerStats, Registry, RobotFile, RobotSpec, SkillInfo,
};
use situate_link::{Client, ClientError, Link, LinkConfig};

mod client;
mod demo;
mod map;
mod signals;
mod sim;

use client::{client_verb, Remote};
use demo::{run_demo, DemoOptions};
pub use sim::Simulation;
use sim::{simulation, SimOverrides, WorldArgs};

#[derive(Parser)]
#[command(
    name = "situate",
    version,
    about = "The reactive layer of a robot: check and run robot files, drive a running one"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Check a robot file statically; every problem is reported as FILE:LINE:COL.
    Check { file: PathBuf },
    /// Run a robot file, serving the link, and print a summary at the end.
    Run {
        file: PathBuf,
        /// Stop after this many cycles (default: run until interrupted).
        #[arg(long)]
        cycles: Option<u64>,
        /// Override the file's executor.
        #[arg(long, value_parser = ["serial", "parallel"])]
        executor: Option<String>,
        /// Override the file's clock.
        #[arg(long, value_parser = ["wall", "simulated"])]
        clock: Option<String>,
        /// Do not open the link (no network at all).
        #[arg(long)]
        no_link: bool,
        /// Override the link's listen endpoints (e.g. tcp/127.0.0.1:7448).
        #[arg(long)]
        listen: Vec<String>,
        /// Override the simulator's map file (robot files with `simulator:`).
        #[arg(long)]
        map: Option<PathBuf>,
        /// Override the simulator's seed.
        #[arg(long)]
        seed: Option<u64>,
        #[command(flatten)]
        world: WorldArgs,
        /// On the simulated clock, run at this many times real time (default: as fast as possible).
        #[arg(long)]
        speed: Option<f64>,
        /// Serve the debugging GUI at this address (e.g. 127.0.0.1:8080, or a port).
        #[arg(long)]
        gui: Option<String>,
        /// No GUI, even if the robot file has a `gui:` section.
        #[arg(long, conflicts_with = "gui")]
        no_gui: bool,
    },
    /// The delivery demo: the simulated robot, the skill manager and the Python sequencer of
    /// demo/deliver.py (and the GUI unless --headless). Prints one line per phase and the outcome.
    Demo(DemoOptions),
    /// Generate a skill's typed I/O (structs or classes and the glue) from its YAML manifest.
    Gen {
        /// `c`, `cpp` or `python`.
        #[arg(value_parser = ["c", "cpp", "c++", "python", "py"])]
        lang: String,
        manifest: PathBuf,
        /// The directory to write into.
        #[arg(short, long, default_value = ".")]
        out: PathBuf,
    },
    /// List the skill types this program knows, with their declarations (and those of the
    /// libraries and Python files given).
    Types {
        /// A shared library of C/C++ skill types (repeatable).
        #[arg(long)]
        library: Vec<PathBuf>,
        /// A Python file of @situate.skill types (repeatable; the Python package's `situate`).
        #[arg(long)]
        python: Vec<PathBuf>,
    },
    /// Serve a skill out of process, as a running robot's remote skill (an asynchronous cskill
    /// over the link): a type from a C/C++ library (`--library`), a built-in type, a Python file's
    /// type (`--python`, in the Python package's `situate`), or a Python function `MODULE:FUNCTION`
    /// decorated with @situate.remote_skill (the Python package's `situate` only).
    #[command(name = "serve-skill")]
    ServeSkill {
        /// The skill type (e.g. `c.runaway`), or `MODULE:FUNCTION` for a Python remote skill.
        skill: String,
        /// The skill's name in the robot file (default: the type's name after its last dot).
        #[arg(long)]
        name: Option<String>,
        /// A shared library to load skill types from (repeatable).
        #[arg(long)]
        library: Vec<PathBuf>,
        /// A Python file to load skill types from (repeatable; the Python package's `situate`).
        #[arg(long)]
        python: Vec<PathBuf>,
        #[command(flatten)]
        remote: Remote,
    },

    /// Building maps for the simulator (docs/maps.md): generate one, check one.
    #[command(subcommand)]
    Map(map::MapCommand),

    #[command(flatten)]
    Client(client::ClientCommand),
}

/// Loads the skill types of one `python:` file of a robot file.
pub type PythonLoader = Arc<dyn Fn(&Path) -> Result<Vec<situate_core::SkillType>, String> + Send + Sync>;

/// What a host adds to the program. The Python package's `situate` passes a
/// [`PythonLoader`], so robot files run from it can hold in-process Python
/// skills; the Rust binary has none and says where to get one.
#[derive(Default, Clone)]
pub struct Extensions {
    pub python: Option<PythonLoader>,
}

/// Runs the program with these arguments (the first is the program name).
pub fn main<I, T>(args: I) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    main_with(args, Extensions::default())
}

/// [`main`] with a host's [`Extensions`].
pub fn main_with<I, T>(args: I, ext: Extensions) -> ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let _ = tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "warn,zenoh=error".into()),
        )
        .with_writer(std::io::stderr)
        .try_init();
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return if e.use_stderr() { ExitCode::from(2) } else { ExitCode::SUCCESS };
        }
    };
    match run(cli, &ext) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

struct Loaded {
    file: RobotFile,
    spec: RobotSpec,
    link: LinkConfig,
    remote: Vec<(String, situate_core::SkillDecl)>,
}

fn load(file: &Path) -> Result<Loaded, ExitCode> {
    let robot_file = match RobotFile::load(file) {
        Ok(f) => f,
        Err(errors) => return Err(report(file, &errors)),
    };
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
                    eprintln!("{}", robot_file.error(at, format!("`link`: Zenoh refuses this configuration: {e}")));
                    count_line(file, 1);
                    return Err(ExitCode::FAILURE);
                }
            },
            Err(errors) => {
                for e in &errors {
                    eprintln!("{}", robot_file.error(e.pos, e.message.clone()));
                }
                count_line(file, errors.len());
                return Err(ExitCode::FAILURE);
            }
        },
    };
    let remote = match robot_file.remote_decls() {
        Ok(r) => r,
        Err(errors) => return Err(report(file, &errors)),
    };
    Ok(Loaded { spec: RobotSpec::from_file(&robot_file), link, remote, file: robot_file })
}

/// Prints every error, then the count line; the exit code of a failure.
fn report(file: &Path, errors: &[impl std::fmt::Display]) -> ExitCode {
    for e in errors {
        eprintln!("{e}");
    }
    count_line(file, errors.len());
    ExitCode::FAILURE
}

fn count_line(file: &Path, n: usize) {
    eprintln!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" });
}

fn run(cli: Cli, ext: &Extensions) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Check { file } => check(&file, ext),
        Command::Run { file, cycles, executor, clock, no_link, listen, map, seed, world, speed, gui, no_gui } => {
            let opts = RunOptions {
                cycles,
                executor,
                clock,
                no_link,
                listen,
                sim: SimOverrides { map, seed, world },
                speed,
                stopped: false,
                gui,
                no_gui,
            };
            run_robot(&file, &opts, ext)
        }
        Command::Demo(demo) => run_demo(&demo, ext),
        Command::Gen { lang, manifest, out } => generate(&lang, &manifest, &out),
        Command::Types { library, python } => {
            types(&registry_with(&library, &python, ext)?);
            Ok(ExitCode::SUCCESS)
        }
        Command::Client(command) => client::run(command),
        Command::Map(command) => map::map_command(command),
        Command::ServeSkill { skill, name, library, python, remote } => {
            serve_skill(&skill, name, &library, &python, &remote, ext)
        }
    }
}

/// The built-in skill types and those of `--library` and `--python` files.
fn registry_with(libraries: &[PathBuf], python: &[PathBuf], ext: &Extensions) -> anyhow::Result<Registry> {
    let mut registry = builtin_registry();
    for path in libraries {
        for t in load_library(path).map_err(|e| anyhow::anyhow!("--library {}: {e}", path.display()))? {
            registry.add(t);
        }
    }
    for path in python {
        let loader = ext.python.as_ref().ok_or_else(|| {
            anyhow::anyhow!(
                "--python {}: Python skills run in the Python package's `situate` (`make python`, then \
                 `.venv/bin/situate`); this binary has no Python inside",
                path.display()
            )
        })?;
        for t in loader(path).map_err(|e| anyhow::anyhow!("--python {}: {e}", path.display()))? {
            registry.add(t);
        }
    }
    Ok(registry)
}

/// `situate serve-skill`: one instance of a skill type, served out of
/// process until Ctrl-C (docs/protocol.md, "Remote skills").
fn serve_skill(
    skill: &str,
    name: Option<String>,
    libraries: &[PathBuf],
    python: &[PathBuf],
    remote: &Remote,
    ext: &Extensions,
) -> anyhow::Result<ExitCode> {
    if skill.contains(':') {
        anyhow::bail!(
            "`{skill}` names a Python function (MODULE:FUNCTION): serve it with the `situate` that the Python \
             package installs (scripts/python.sh, then .venv/bin/situate serve-skill {skill} --robot ROBOT)"
        );
    }
    let registry = registry_with(libraries, python, ext)?;
    let Some(ty) = registry.get(skill) else {
        let known: Vec<&str> = registry.names().collect();
        anyhow::bail!(
            "no skill type `{skill}`{}; give the library that defines it with --library (known here: {})",
            situate_core::suggestion(skill, known.iter().copied()),
            known.join(", ")
        );
    };
    let name = name.unwrap_or_else(|| skill.rsplit('.').next().unwrap_or(skill).to_string());
    let mut result = Ok(ExitCode::SUCCESS);
    client_verb(remote, |client, robot| {
        let stop = interrupt_flag()?;
        // The body runs on this thread: one that never returns is left behind.
        let stuck = format!(
            "`{name}`'s body did not return within {} of the stop request; exiting without it",
            signals::bound_text()
        );
        let watchdog = stop.watchdog(move || stuck);
        let stats = situate_link::serve_skill(client.session(), robot, &name, ty, stop.flag(), || {
            eprintln!(
                "situate: serving `{name}` (type `{skill}`) of robot `{robot}` on situate/{robot}/remote/{name}/inputs; \
                 Ctrl-C stops"
            );
        });
        drop(watchdog);
        match stats {
            Ok(s) => eprintln!(
                "situate: stopped{}; {} inputs received, {} runs, {} dropped as stale, {} errors",
                stop.signal().map(|s| format!(" ({})", signals::name(s))).unwrap_or_default(),
                s.received,
                s.computed,
                s.dropped,
                s.errors
            ),
            Err(e) => {
                eprintln!("error: {e}");
                result = Ok(ExitCode::FAILURE);
            }
        }
        Ok(())
    })?;
    result
}

/// SIGINT, SIGTERM and SIGHUP ask for a stop while the result lives; a
/// second signal ends the process at once (see [`signals`]).
fn interrupt_flag() -> anyhow::Result<signals::Stop> {
    signals::Stop::install()
}

/// The skill types a robot file can name: the built-in libraries, the
/// simulator's devices when it has a `simulator:` section, then the file's
/// own `libraries:` and `python:` files. Errors name the file's line.
fn registry_for(
    robot_file: &RobotFile,
    ext: &Extensions,
    over: &SimOverrides,
) -> Result<(Registry, Option<Simulation>), Vec<String>> {
    let mut registry = builtin_registry();
    let sim = simulation(robot_file, over)?;
    if let Some(sim) = &sim {
        situate_sim::register(&mut registry, sim.world.clone());
    }
    let mut errors = Vec::new();
    for lib in &robot_file.libraries {
        let path = robot_file.resolve(&lib.value);
        match load_library(&path) {
            Ok(types) => {
                for t in types {
                    registry.add(t);
                }
            }
            Err(e) => errors.push(robot_file.error(lib.pos, e).to_string()),
        }
    }
    for py in &robot_file.python {
        let path = robot_file.resolve(&py.value);
        let result = match &ext.python {
            Some(loader) => loader(&path),
            None => Err(format!(
                "`{}`: Python skills run in the Python package's `situate` (install the wheel: `make python`, \
                 then `.venv/bin/situate`); this binary has no Python inside",
                py.value
            )),
        };
        match result {
            Ok(types) => {
                for t in types {
                    registry.add(t);
                }
            }
            Err(e) => errors.push(robot_file.error(py.pos, e).to_string()),
        }
    }
    if errors.is_empty() {
        Ok((registry, sim))
    } else {
        Err(errors)
    }
}

/// The skill types every robot file can name: the toys and the standard
/// skill library (`std.*`).
fn builtin_registry() -> Registry {
    let mut registry = situate_toys::registry();
    situate_skills::register(&mut registry);
    registry
}

fn load_library(path: &Path) -> Result<Vec<situate_core::SkillType>, String> {
    situate_cabi::load_library(path).map_err(|e| e.to_string())
}

fn check(file: &Path, ext: &Extensions) -> anyhow::Result<ExitCode> {
    if map::looks_like_map(file) {
        eprintln!("{}: this is a map file: use `situate map check {}`", file.display(), file.display());
        return Ok(ExitCode::FAILURE);
    }
    let loaded = match load(file) {
        Ok(s) => s,
        Err(code) => return Ok(code),
    };
    let (mut registry, _sim) = match registry_for(&loaded.file, ext, &SimOverrides::default()) {
        Ok(r) => r,
        Err(errors) => return Ok(report(file, &errors)),
    };
    // Every section `run` reads is checked by the code `run` uses.
    if let Err(e) = gui_address(&loaded.file, &RunOptions::default()) {
        return Ok(report(file, &[e]));
    }
    for (_, decl) in &loaded.remote {
        // Checking needs the declaration only; nothing is created.
        registry.add(situate_core::SkillType::new(decl.clone(), || Err("not created by `check`".into())));
    }
    match situate::manager::Graph::build(&loaded.spec, &registry) {
        Ok(graph) => {
            for w in &graph.warnings {
                eprintln!("{w}");
            }
            let n = graph.instances.len();
            println!(
                "{}: ok — robot `{}`, {n} skill{}, {} signal leaves",
                file.display(),
                graph.robot,
                if n == 1 { "" } else { "s" },
                graph.leaves.len()
            );
            Ok(ExitCode::SUCCESS)
        }
        Err(e) => {
            for d in &e.diagnostics {
                eprintln!("{d}");
            }
            count_line(file, e.diagnostics.iter().filter(|d| d.is_error()).count());
            Ok(ExitCode::FAILURE)
        }
    }
}

/// How to run a robot file: the command line's overrides.
#[derive(Default, Clone)]
struct RunOptions {
    cycles: Option<u64>,
    executor: Option<String>,
    clock: Option<String>,
    no_link: bool,
    listen: Vec<String>,
    sim: SimOverrides,
    /// Pacing of the simulated clock (× real time).
    speed: Option<f64>,
    /// Start with the cycle stopped (a sequencer starts it).
    stopped: bool,
    /// Serve the GUI here (overrides the file's `gui:` section).
    gui: Option<String>,
    /// No GUI even if the file asks for one.
    no_gui: bool,
}

/// A robot running on its own threads, serving the link.
struct Running {
    handle: situate::manager::Handle,
    join: situate::manager::Joiner,
    events: crossbeam_channel::Receiver<Event>,
    served: Option<Link>,
    gui: Option<situate_gui::GuiServer>,
    sim: Option<Simulation>,
    robot: String,
}

impl Running {
    /// Stops everything and returns the final statistics, within
    /// [`signals::stop_bound`]: a cycle stuck in a skill's body (or a part
    /// that does not stop) is left behind, and the error says which.
    fn finish(self) -> Result<(ManagerStats, Vec<SkillInfo>), Stuck> {
        let Running { mut handle, join, served, gui, .. } = self;
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
            drop(served);
            at.store(Stage::Cycle as u8, Ordering::SeqCst);
            let _ = handle.request(situate::manager::Request::Shutdown);
            let _ = join.join();
            let _ = tx.send((stats, skills));
        };
        if let Err(e) = std::thread::Builder::new().name("situate-teardown".into()).spawn(teardown) {
            return Err(Stuck { stage: Stage::Spawn, detail: e.to_string() });
        }
        match rx.recv_timeout(signals::stop_bound()) {
            Ok((Ok(stats), Ok(skills))) => Ok((stats, skills)),
            Ok((Err(e), _) | (_, Err(e))) => Err(Stuck { stage: Stage::Stats, detail: e.to_string() }),
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
enum Stage {
    Spawn,
    Stats,
    Gui,
    Link,
    Cycle,
}

/// A stop that did not complete: what did not stop.
#[derive(Debug)]
struct Stuck {
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

/// Loads, checks and starts a robot file. `Err(Ok(code))`: the problems
/// were reported already.
fn start_robot(file: &Path, opts: &RunOptions, ext: &Extensions) -> Result<Running, anyhow::Result<ExitCode>> {
    let Loaded { mut spec, mut link, remote, file: robot_file } = match load(file) {
        Ok(s) => s,
        Err(code) => return Err(Ok(code)),
    };
    let (mut registry, sim) = match registry_for(&robot_file, ext, &opts.sim) {
        Ok(r) => r,
        Err(errors) => return Err(Ok(report(file, &errors))),
    };
    if opts.no_link && !remote.is_empty() {
        let names: Vec<&str> = remote.iter().map(|(n, _)| n.as_str()).collect();
        return Err(Err(anyhow::anyhow!("remote skills ({}) need the link; drop --no-link", names.join(", "))));
    }
    let gui_listen = match gui_address(&robot_file, opts) {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            return Err(Ok(ExitCode::FAILURE));
        }
    };
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
        match Link::open(&link).with_context(|| {
            format!(
                "opening the link on {} (is another robot using it? try --listen or --no-link)",
                link.listen.join(", ")
            )
        }) {
            Ok(s) => Some(s),
            Err(e) => return Err(Err(e)),
        }
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
    let mut manager = match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            count_line(file, e.diagnostics.iter().filter(|d| d.is_error()).count());
            return Err(Ok(ExitCode::FAILURE));
        }
    };
    for w in &manager.graph().warnings {
        eprintln!("{w}");
    }
    manager.stop_after(opts.cycles);
    manager.set_speed(opts.speed);
    let events = manager.events();
    let (handle, join) = manager.spawn(!opts.stopped);
    let mut running = Running { handle, join, events, served: None, gui: None, sim, robot: spec.robot.clone() };
    if let Some(session) = session {
        match Link::serve(&spec.robot, running.handle.clone(), session, &link).context("serving the link") {
            Ok(l) => {
                eprintln!(
                    "situate: robot `{}` serving situate/{}/** on {}",
                    spec.robot,
                    spec.robot,
                    link.listen.join(", ")
                );
                running.served = Some(l);
            }
            Err(e) => {
                let _ = running.finish();
                return Err(Err(e));
            }
        }
    }
    if let Some(listen) = gui_listen {
        let world = running.sim.as_ref().map(|s| s.map.world_json());
        let config = situate_gui::GuiConfig { listen, world, ..situate_gui::GuiConfig::default() };
        match situate_gui::serve(running.handle.clone(), config) {
            Ok(g) => {
                eprintln!("situate: GUI on {}", g.url());
                running.gui = Some(g);
            }
            Err(e) => {
                let _ = running.finish();
                return Err(Err(anyhow::anyhow!("starting the GUI on {listen}: {e}")));
            }
        }
    }
    Ok(running)
}

/// Where to serve the GUI: `--gui ADDR`, else the file's `gui: {listen: ADDR}`
/// (or `gui: {port: N}` on 127.0.0.1), else nowhere.
fn gui_address(robot_file: &RobotFile, opts: &RunOptions) -> Result<Option<std::net::SocketAddr>, String> {
    if opts.no_gui {
        return Ok(None);
    }
    let parse = |text: &str| -> Result<std::net::SocketAddr, String> {
        text.parse().or_else(|_| {
            text.parse::<u16>()
                .map(|port| std::net::SocketAddr::from(([127, 0, 0, 1], port)))
                .map_err(|_| format!("`{text}` is not an address like 127.0.0.1:8080 or a port number"))
        })
    };
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

fn run_robot(file: &Path, opts: &RunOptions, ext: &Extensions) -> anyhow::Result<ExitCode> {
    // Before starting: a signal during the start stops the robot once started.
    let interrupted = interrupt_flag()?;
    let running = match start_robot(file, opts, ext) {
        Ok(r) => r,
        Err(done) => return done,
    };
    let cycles = opts.cycles;
    let started = Instant::now();
    loop {
        if let Some(sig) = interrupted.signal() {
            eprintln!("situate: {}: stopping (again to exit at once)", signals::name(sig));
            break;
        }
        match running.events.recv_timeout(Duration::from_millis(100)) {
            Ok(Event::SkillFaulted { skill, cause, cycle }) => {
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
        Ok((stats, skills)) => {
            print_summary(&stats, &skills);
            Ok(ExitCode::SUCCESS)
        }
        Err(stuck) => {
            eprintln!("situate: {stuck}");
            eprintln!("situate: no summary: the manager did not answer");
            Ok(ExitCode::FAILURE)
        }
    }
}

fn generate(lang: &str, manifest: &Path, out: &Path) -> anyhow::Result<ExitCode> {
    let lang = situate_cabi::Lang::parse(lang).ok_or_else(|| anyhow::anyhow!("unknown language `{lang}`"))?;
    let files = match situate_cabi::generate(lang, manifest) {
        Ok(f) => f,
        Err(e) => {
            eprintln!("{e}");
            return Ok(ExitCode::FAILURE);
        }
    };
    std::fs::create_dir_all(out).with_context(|| format!("creating `{}`", out.display()))?;
    for f in files {
        let path = out.join(&f.path);
        std::fs::write(&path, f.contents).with_context(|| format!("writing `{}`", path.display()))?;
        println!("{}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn types(registry: &Registry) {
    for name in registry.names() {
        let Some(t) = registry.get(name) else { continue };
        let d = &t.decl;
        println!("{name} ({}, priority {})", d.kind, d.priority);
        for line in d.doc.lines() {
            println!("    {line}");
        }
        for p in &d.inputs {
            println!("    in  {}: {}{}", p.name, p.ty, if p.optional { " (optional)" } else { "" });
        }
        for p in &d.outputs {
            println!("    out {}: {}", p.name, p.ty);
        }
        for p in &d.params {
            println!("    param {}: {} = {} ({})", p.name, p.ty.name(), p.default, p.expectation());
        }
    }
}

fn print_summary(stats: &ManagerStats, skills: &[SkillInfo]) {
    println!("robot `{}`: {} cycles, {:.3} s on its clock", stats.robot, stats.cycle, stats.time_s);
    println!(
        "cycle time: mean {:.1} µs, max {:.1} µs; period {:.1} ms; overruns {}; late starts {}",
        stats.mean_cycle_ns / 1e3,
        stats.max_cycle_ns as f64 / 1e3,
        stats.period_s * 1e3,
        stats.overruns,
        stats.late_starts
    );
    println!(
        "{:<16} {:<8} {:>8} {:>10} {:>10} {:>10}  state",
        "skill", "kind", "runs", "mean µs", "max µs", "total ms"
    );
    for s in skills {
        let state = match (&s.faulted, s.active) {
            (Some(cause), _) => format!("faulted: {cause}"),
            (None, true) => "active".to_string(),
            (None, false) => "inactive".to_string(),
        };
        println!(
            "{:<16} {:<8} {:>8} {:>10.2} {:>10.2} {:>10.3}  {state}",
            s.name,
            s.kind.name(),
            s.timing.runs,
            s.timing.mean_ns() / 1e3,
            s.timing.max_ns as f64 / 1e3,
            s.timing.total_ns as f64 / 1e6
        );
    }
}
