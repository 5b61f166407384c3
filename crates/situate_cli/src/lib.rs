//! The `situate` program: check and run robot files, and talk to a running
//! skill manager over the link. The same program is installed by the Rust
//! build (`situate` binary) and by the Python wheel (which calls [`main`]).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::{Args, Parser, Subcommand};
use serde_json::{json, Value as Json};
use situate::manager::{
    ClockKind, Control, Event, ExecutorKind, Manager, ManagerStats, Registry, RobotFile, RobotSpec, SkillInfo,
};
use situate_link::{Client, ClientError, Link, LinkConfig};

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

#[derive(Args, Clone)]
struct Remote {
    /// The robot to talk to (default: the only one answering).
    #[arg(long, global = true)]
    robot: Option<String>,
    /// The manager's endpoint.
    #[arg(long, global = true, env = "SITUATE_CONNECT", default_value = situate_link::DEFAULT_ENDPOINT)]
    connect: Vec<String>,
    /// Seconds to wait for an answer.
    #[arg(long, global = true, default_value_t = 5.0)]
    timeout: f64,
    /// Print the protocol's JSON instead of text.
    #[arg(long, global = true)]
    json: bool,
    /// A JSON5 file merged into the client's Zenoh configuration (credentials, TLS).
    #[arg(long, global = true, env = "SITUATE_ZENOH_CONFIG")]
    zenoh: Option<PathBuf>,
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
    },
    /// List the skill types this program knows, with their declarations.
    Types,
    /// List the skills of a running robot.
    Skills(#[command(flatten)] Remote),
    /// Activate skills of a running robot (from its next cycle on).
    Activate {
        #[arg(required = true)]
        names: Vec<String>,
        /// Also activate providers of inputs nobody active provides.
        #[arg(long)]
        with_providers: bool,
        #[command(flatten)]
        remote: Remote,
    },
    /// Deactivate skills of a running robot.
    Deactivate {
        #[arg(required = true)]
        names: Vec<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Get or set a parameter: `param get SKILL PARAM`, `param set SKILL PARAM VALUE`.
    Param {
        #[arg(value_parser = ["get", "set"])]
        action: String,
        skill: String,
        param: String,
        value: Option<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// The current value of a signal (`sonar.range`, or a whole record such as `odom`).
    Query {
        signal: String,
        #[command(flatten)]
        remote: Remote,
    },
    /// Register a monitor and print its events: `monitor "sonar.range[0] < 0.25"`.
    Monitor {
        condition: String,
        /// once: the first time it holds; edge: each time it becomes true; level: every cycle it holds.
        #[arg(long, default_value = "once", value_parser = ["once", "edge", "level"])]
        mode: String,
        /// Stop after this many events (default: 1 for once, else until interrupted).
        #[arg(long)]
        count: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Print events as they come (one JSON object per line).
    Events {
        /// Stop after this many events.
        #[arg(long)]
        count: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Cycle statistics of a running robot.
    Stats(#[command(flatten)] Remote),
    /// Serve a Python remote skill (`module:function`); provided by the Python package's `situate`.
    #[command(name = "serve-skill", disable_help_flag = true)]
    ServeSkill {
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<String>,
    },
    /// Start, stop or step a running robot's cycle: `cycle run`, `cycle stop`, `cycle step 5`.
    Cycle {
        #[arg(value_parser = ["run", "stop", "step"])]
        action: String,
        cycles: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
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
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            count_line(file, errors.len());
            return Err(ExitCode::FAILURE);
        }
    };
    let link = match &robot_file.link {
        None => LinkConfig::default(),
        Some(node) => match LinkConfig::from_node(node) {
            Ok(l) => l,
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
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            count_line(file, errors.len());
            return Err(ExitCode::FAILURE);
        }
    };
    Ok(Loaded { spec: RobotSpec::from_file(&robot_file), link, remote, file: robot_file })
}

fn count_line(file: &Path, n: usize) {
    eprintln!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" });
}

fn run(cli: Cli, ext: &Extensions) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Check { file } => check(&file, ext),
        Command::Run { file, cycles, executor, clock, no_link, listen } => {
            run_robot(&file, cycles, executor, clock, no_link, listen, ext)
        }
        Command::Types => {
            types();
            Ok(ExitCode::SUCCESS)
        }
        Command::Skills(remote) => client_verb(&remote, |c, robot| {
            let skills = c.request(robot, "skills", &json!({}))?;
            if remote.json {
                println!("{skills}");
            } else {
                for s in skills.as_array().into_iter().flatten() {
                    let state = match (s["faulted"].as_str(), s["active"].as_bool()) {
                        (Some(f), _) => format!("faulted: {f}"),
                        (None, Some(true)) => "active".into(),
                        _ => "inactive".into(),
                    };
                    println!(
                        "{:<16} {:<18} {:<6} priority {:<4} {state}",
                        s["name"].as_str().unwrap_or(""),
                        s["type_name"].as_str().unwrap_or(""),
                        s["kind"].as_str().unwrap_or(""),
                        s["priority"]
                    );
                }
            }
            Ok(())
        }),
        Command::Activate { names, with_providers, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "activate", &json!({"skills": names, "with_providers": with_providers}))?;
            print_change(&remote, &r, "activated");
            Ok(())
        }),
        Command::Deactivate { names, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "deactivate", &json!({"skills": names}))?;
            print_change(&remote, &r, "deactivated");
            Ok(())
        }),
        Command::Param { action, skill, param, value, remote } => client_verb(&remote, |c, robot| {
            if action == "set" {
                let Some(text) = &value else {
                    anyhow::bail!("`param set` needs a VALUE: situate param set {skill} {param} VALUE");
                };
                // A number, true/false, or a JSON string; anything else is taken as text.
                let v: Json = serde_json::from_str(text).unwrap_or_else(|_| Json::String(text.clone()));
                c.request(robot, "set_param", &json!({"skill": skill, "param": param, "value": v}))?;
                if !remote.json {
                    println!("{skill}.{param} = {v} (from the next cycle)");
                }
            } else {
                let v = c.request(robot, "get_param", &json!({"skill": skill, "param": param}))?;
                println!("{v}");
            }
            Ok(())
        }),
        Command::Query { signal, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "query", &json!({"signal": signal}))?;
            if remote.json {
                println!("{r}");
            } else {
                println!(
                    "{} = {} ({}, cycle {}, by {})",
                    r["signal"].as_str().unwrap_or(""),
                    r["value"],
                    r["type"].as_str().unwrap_or(""),
                    r["cycle"],
                    r["writer"]
                );
            }
            Ok(())
        }),
        Command::Monitor { condition, mode, count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/monitor_fired")?;
            let r = c.request(robot, "monitor_add", &json!({"condition": condition, "mode": mode}))?;
            let id = r["monitor"].as_u64().unwrap_or(0);
            eprintln!("monitor {id} registered ({mode}): {condition}");
            let limit = count.or(if mode == "once" { Some(1) } else { None });
            let mut seen = 0;
            let interrupted = interrupt_flag()?;
            while limit.is_none_or(|n| seen < n) && !interrupted.load(Ordering::SeqCst) {
                if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
                    if e["monitor"].as_u64() == Some(id) {
                        seen += 1;
                        if remote.json {
                            println!("{e}");
                        } else {
                            println!(
                                "cycle {} (t = {:.3} s): {} — {}",
                                e["cycle"],
                                e["time_s"].as_f64().unwrap_or(0.0),
                                condition,
                                e["values"]
                            );
                        }
                    }
                }
            }
            if mode != "once" || seen == 0 {
                let _ = c.request(robot, "monitor_cancel", &json!({"monitor": id}));
            }
            Ok(())
        }),
        Command::Events { count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/**")?;
            let interrupted = interrupt_flag()?;
            let mut seen = 0;
            while count.is_none_or(|n| seen < n) && !interrupted.load(Ordering::SeqCst) {
                if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
                    println!("{e}");
                    seen += 1;
                }
            }
            Ok(())
        }),
        Command::Stats(remote) => {
            client_verb(&remote, |c, robot| {
                let s = c.request(robot, "stats", &json!({}))?;
                if remote.json {
                    println!("{s}");
                } else {
                    println!(
                    "robot `{}`: cycle {}, {} s, {}; cycle time mean {:.1} µs, max {:.1} µs; overruns {}; active: {}",
                    s["robot"].as_str().unwrap_or(""),
                    s["cycle"],
                    s["time_s"],
                    if s["running"].as_bool() == Some(true) { "running" } else { "stopped" },
                    s["mean_cycle_ns"].as_f64().unwrap_or(0.0) / 1e3,
                    s["max_cycle_ns"].as_f64().unwrap_or(0.0) / 1e3,
                    s["overruns"],
                    s["active"].as_array().map(|a| a.iter().filter_map(Json::as_str).collect::<Vec<_>>().join(", ")).unwrap_or_default()
                );
                }
                Ok(())
            })
        }
        Command::ServeSkill { .. } => {
            anyhow::bail!(
                "`serve-skill` serves Python skills: run it with the `situate` that the Python package installs \
                 (scripts/python.sh, then .venv/bin/situate serve-skill MODULE:FUNCTION --robot ROBOT)"
            )
        }
        Command::Cycle { action, cycles, remote } => client_verb(&remote, |c, robot| {
            match action.as_str() {
                "step" => c.request(robot, "step", &json!({"cycles": cycles.unwrap_or(1)}))?,
                other => c.request(robot, other, &json!({}))?,
            };
            Ok(())
        }),
    }
}

fn print_change(remote: &Remote, r: &Json, what: &str) {
    if remote.json {
        println!("{r}");
        return;
    }
    let changed: Vec<&str> = r["changed"].as_array().into_iter().flatten().filter_map(Json::as_str).collect();
    if changed.is_empty() {
        println!("nothing {what} (already so)");
    } else {
        println!("{what} {} from cycle {}", changed.join(", "), r["at_cycle"]);
    }
}

fn interrupt_flag() -> anyhow::Result<Arc<AtomicBool>> {
    let flag = Arc::new(AtomicBool::new(false));
    let f = Arc::clone(&flag);
    // A second handler (in one process) is refused: then Ctrl-C just ends the process.
    let _ = ctrlc::set_handler(move || f.store(true, Ordering::SeqCst));
    Ok(flag)
}

fn client_verb(remote: &Remote, f: impl FnOnce(&Client, &str) -> anyhow::Result<()>) -> anyhow::Result<ExitCode> {
    let extra = match &remote.zenoh {
        None => None,
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            Some(json5::from_str::<Json>(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?)
        }
    };
    let mut client = Client::connect_with(&remote.connect, extra.as_ref())?;
    // Clamped: `--timeout inf` or `nan` must not panic.
    client.timeout = Duration::from_secs_f64(if remote.timeout.is_finite() {
        remote.timeout.clamp(0.1, 86_400.0)
    } else {
        86_400.0
    });
    let robot = match client.resolve_robot(remote.robot.as_deref()) {
        Ok(r) => r,
        Err(e) => return Err(anyhow::Error::new(e)),
    };
    match f(&client, &robot) {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(e) => match e.downcast_ref::<ClientError>() {
            Some(ClientError::Remote(r)) => {
                eprintln!("error: {}", r.message);
                if let Some(p) = r.detail.get("pointer").and_then(Json::as_str) {
                    eprintln!("{p}");
                }
                Ok(ExitCode::FAILURE)
            }
            _ => Err(e),
        },
    }
}

/// The skill types a robot file can name: the built-in libraries, then the
/// file's own `libraries:` and `python:` files. Errors name the file's line.
fn registry_for(robot_file: &RobotFile, ext: &Extensions) -> Result<Registry, Vec<String>> {
    let mut registry = situate_toys::registry();
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
        Ok(registry)
    } else {
        Err(errors)
    }
}

fn load_library(path: &Path) -> Result<Vec<situate_core::SkillType>, String> {
    Err(format!("cannot load `{}`: C/C++ skill libraries are not supported by this build", path.display()))
}

fn check(file: &Path, ext: &Extensions) -> anyhow::Result<ExitCode> {
    let loaded = match load(file) {
        Ok(s) => s,
        Err(code) => return Ok(code),
    };
    let mut registry = match registry_for(&loaded.file, ext) {
        Ok(r) => r,
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            count_line(file, errors.len());
            return Ok(ExitCode::FAILURE);
        }
    };
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

fn run_robot(
    file: &Path,
    cycles: Option<u64>,
    executor: Option<String>,
    clock: Option<String>,
    no_link: bool,
    listen: Vec<String>,
    ext: &Extensions,
) -> anyhow::Result<ExitCode> {
    let Loaded { mut spec, mut link, remote, file: robot_file } = match load(file) {
        Ok(s) => s,
        Err(code) => return Ok(code),
    };
    let mut registry = match registry_for(&robot_file, ext) {
        Ok(r) => r,
        Err(errors) => {
            for e in &errors {
                eprintln!("{e}");
            }
            count_line(file, errors.len());
            return Ok(ExitCode::FAILURE);
        }
    };
    if no_link && !remote.is_empty() {
        let names: Vec<&str> = remote.iter().map(|(n, _)| n.as_str()).collect();
        anyhow::bail!("remote skills ({}) need the link; drop --no-link", names.join(", "));
    }
    if let Some(e) = executor {
        spec.executor = if e == "parallel" { ExecutorKind::Parallel } else { ExecutorKind::Serial };
    }
    if let Some(c) = clock {
        spec.clock = if c == "simulated" { ClockKind::Simulated } else { ClockKind::Wall };
    }
    if !listen.is_empty() {
        link.listen = listen;
    }
    let session = if no_link {
        None
    } else {
        Some(Link::open(&link).with_context(|| {
            format!(
                "opening the link on {} (is another robot using it? try --listen or --no-link)",
                link.listen.join(", ")
            )
        })?)
    };
    if let Some(session) = &session {
        for (name, decl) in remote {
            registry.add(situate_link::RemoteSkill::skill_type(session, &robot_file.robot.value, &name, decl));
        }
    }
    let mut manager = match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => {
            eprintln!("{e}");
            count_line(file, e.diagnostics.iter().filter(|d| d.is_error()).count());
            return Ok(ExitCode::FAILURE);
        }
    };
    for w in &manager.graph().warnings {
        eprintln!("{w}");
    }
    manager.stop_after(cycles);
    let events = manager.events();
    let (mut handle, join) = manager.spawn(true);
    let served = match session {
        None => None,
        Some(session) => match Link::serve(&spec.robot, handle.clone(), session, &link).context("serving the link") {
            Ok(l) => {
                eprintln!(
                    "situate: robot `{}` serving situate/{}/** on {}",
                    spec.robot,
                    spec.robot,
                    link.listen.join(", ")
                );
                Some(l)
            }
            Err(e) => {
                let _ = handle.request(situate::manager::Request::Shutdown);
                let _ = join.join();
                return Err(e);
            }
        },
    };
    let interrupted = interrupt_flag()?;
    let started = Instant::now();
    loop {
        if interrupted.load(Ordering::SeqCst) {
            break;
        }
        match events.recv_timeout(Duration::from_millis(100)) {
            Ok(Event::SkillFaulted { skill, cause, cycle }) => {
                eprintln!("cycle {cycle}: skill `{skill}` faulted: {cause}")
            }
            Ok(Event::ManagerStopped { cycle }) if cycles.is_some_and(|n| cycle >= n) => break,
            _ => {}
        }
        if cycles.is_some() && started.elapsed() > Duration::from_secs(1) {
            // A stop requested over the link also ends a bounded run.
            if let Ok(s) = handle.stats() {
                if cycles.is_some_and(|n| s.cycle >= n) && !s.running {
                    break;
                }
            }
        }
    }
    let stats = handle.stats().map_err(anyhow::Error::msg)?;
    let skills = handle.skills().map_err(anyhow::Error::msg)?;
    drop(served);
    let _ = handle.request(situate::manager::Request::Shutdown);
    let _ = join.join();
    print_summary(&stats, &skills);
    Ok(ExitCode::SUCCESS)
}

fn types() {
    let registry = situate_toys::registry();
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
        "cycle time: mean {:.1} µs, max {:.1} µs; period {:.1} ms; overruns {}",
        stats.mean_cycle_ns / 1e3,
        stats.max_cycle_ns as f64 / 1e3,
        stats.period_s * 1e3,
        stats.overruns
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
