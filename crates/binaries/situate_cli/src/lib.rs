//! The `situate` program: check and run robot files, and talk to a running
//! skill manager over the link. The same program is installed by the Rust
//! build (`situate` binary) and by the Python wheel (which calls
//! [`main_with`] with its [`Extensions`]).
//!
//! The modules, by concern:
//! - [`args`](crate::args): the command line (clap), nothing run;
//! - `output`: the output contract: results, notes, errors (text or JSON) and exit codes;
//! - `robot`: robot files loaded, checked, started and run; `serve-skill`;
//! - `skill_types`: the skill types a robot can name (the program's, a host's Rust
//!   ones, the simulator's, libraries and Python files);
//! - `client`: the verbs that drive a running robot over the link, and
//!   introspection (`signals`, `graph`, `winners`, `monitors`, `param dump|load`);
//! - `demo`: the delivery demo; `gen`: `types`, `gen` and `cmake-dir`; `map`: maps; `schema`:
//!   the JSON Schemas of the file formats; `sim`: the simulated world;
//!   `signals`: stopping on SIGINT/SIGTERM/SIGHUP; `telemetry`: `echo` and `hz`.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use clap::Parser as _;

/// `print!` for the program's results: see [`output::write_stdout`] (a closed pipe ends quietly).
macro_rules! stdout {
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!($($arg)*)) };
}

/// `println!` for the program's results: see [`output::write_stdout`] (a closed pipe ends quietly).
macro_rules! stdoutln {
    ($($arg:tt)*) => { $crate::output::write_stdout(format_args!("{}\n", format_args!($($arg)*))) };
}

mod args;
mod client;
mod complete;
mod demo;
mod gen;
mod link_record;
mod map;
mod output;
mod replay;
mod robot;
mod ros2;
mod schema;
mod signals;
mod sim;
mod skill_types;
mod telemetry;

use args::{Cli, Command, Global};
pub use output::Exit;
use output::{Out, Problem};
pub use sim::Simulation;
pub use skill_types::robot_registry;

/// The building of a map file as JSON (`situate map show`: its shape in `docs/maps.md`), or
/// the loader's error, naming the file and line.
pub fn building_json(path: &Path) -> Result<String, String> {
    situate_sim::load_map(path).map(|m| m.building_json().to_string()).map_err(|e| e.to_string())
}

/// Loads the skill types of one `python:` file of a robot file.
pub type PythonLoader = Arc<dyn Fn(&Path) -> Result<Vec<situate_core::SkillType>, String> + Send + Sync>;

/// Adds Rust skill types to a [`Registry`](situate::manager::Registry): what
/// [`Extensions::skills`] takes.
pub type RustSkills = Arc<dyn Fn(&mut situate::manager::Registry) + Send + Sync>;

/// What a host adds to the program. The Python package's `situate` passes a
/// [`PythonLoader`], so robot files run from it can hold in-process Python
/// skills, its interpreter (the demo's sequencer runs with it) and where its
/// package data is (the demo, maps and examples); the Rust binary has none
/// of these and says where to get them. A Rust program adds its own skill
/// types with [`Extensions::skills`].
///
/// ```no_run
/// use situate::prelude::*;
///
/// #[derive(Skill, Default)]
/// #[skill(name = "mine.hello")]
/// struct Hello {
///     #[output]
///     greeting: f64,
/// }
///
/// impl Body for Hello {
///     fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
///         self.greeting = 1.0;
///         Ok(())
///     }
/// }
///
/// fn main() -> std::process::ExitCode {
///     let ext = situate_cli::Extensions::default().skills(|r| {
///         r.register::<Hello>();
///     });
///     std::process::ExitCode::from(situate_cli::main_with(std::env::args_os(), ext))
/// }
/// ```
#[derive(Default, Clone)]
pub struct Extensions {
    pub python: Option<PythonLoader>,
    /// Rust skill types added to the built-in ones wherever the program
    /// builds its registry (`run`, `check`, `types`, `signals`/`graph` of a
    /// file, `serve-skill`, `demo`): see [`Extensions::skills`].
    pub rust: Vec<RustSkills>,
    /// The Python interpreter the host runs in (`sys.executable`).
    pub interpreter: Option<PathBuf>,
    /// A directory holding `demo/`, `maps/`, `examples/`, `cmake/` and `include/` (the wheel's
    /// package data).
    pub data_dir: Option<PathBuf>,
}

impl Extensions {
    /// Adds Rust skill types: `register` is given an empty
    /// [`Registry`](situate::manager::Registry) to `register::<T>()` (or
    /// `add`) them in, each time the program builds its registry, and robot
    /// files can then name them like the built-in ones; `situate types` lists
    /// them.
    ///
    /// Their names must be new: a type named like a built-in one, one under
    /// `std.` or `sim.` (the standard library's and the simulator's), or one
    /// registered by two calls is refused with an error naming it, and the
    /// command fails (exit code 1) instead of running with the wrong type.
    #[must_use]
    pub fn skills(mut self, register: impl Fn(&mut situate::manager::Registry) + Send + Sync + 'static) -> Self {
        self.rust.push(Arc::new(register));
        self
    }
}

/// Runs the program with these arguments (the first is the program name).
pub fn main<I, T>(args: I) -> std::process::ExitCode
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    std::process::ExitCode::from(main_with(args, Extensions::default()))
}

/// [`main`] with a host's [`Extensions`]; returns the exit code (see [`Exit`]:
/// 0 done, 1 failed, 2 bad usage, 3 bad file, 4 no robot answering, 5
/// request refused; 128 + N after a second signal N).
pub fn main_with<I, T>(args: I, ext: Extensions) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let args: Vec<OsString> = args.into_iter().map(Into::into).collect();
    // `COMPLETE=bash situate` prints the shell's registration, and the shell then asks for each
    // completion the same way (names of the running robot: `complete.rs`); nothing else runs.
    let cwd = std::env::current_dir().ok();
    match clap_complete::CompleteEnv::with_factory(<Cli as clap::CommandFactory>::command)
        .try_complete(args.clone(), cwd.as_deref())
    {
        Ok(true) => return 0,
        Ok(false) => {}
        Err(e) => {
            let _ = e.print();
            return Exit::Usage.code();
        }
    }
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        Err(e) => {
            // Before parsing succeeds the flags are unknown: `--json` anywhere asks for JSON.
            let json = args.iter().skip(1).any(|a| a == "--json");
            if !e.use_stderr() {
                let _ = e.print(); // --help, --version
                return 0;
            }
            if json {
                let message = e.render().to_string();
                let message = message.trim().trim_start_matches("error: ").to_string();
                stdoutln!("{}", Problem::new(Exit::Usage, message).to_json());
            } else {
                let _ = e.print();
            }
            return Exit::Usage.code();
        }
    };
    init_logging(&cli.global);
    // The GUI's and the link's connections each take a file descriptor: the soft limit (often
    // 1024) would be reached long before the hard one.
    if let Err(e) = situate_gui::raise_open_files_limit() {
        tracing::debug!(error = %e, "could not raise the open files limit");
    }
    let out = Out { json: cli.global.json, quiet: cli.global.quiet };
    match run(cli.command, &ext, out) {
        Ok(code) => code,
        Err(e) => out.fail(&e),
    }
}

/// Log lines on stderr: `RUST_LOG` when set, else by `-v`/`-q`; colour only
/// at a terminal (and never with `NO_COLOR` set).
fn init_logging(global: &Global) {
    use std::io::IsTerminal as _;
    let default = match (global.quiet, global.verbose) {
        (true, _) => "error,zenoh=off",
        (false, 0) => "warn,zenoh=error",
        (false, 1) => "info,zenoh=warn",
        (false, 2) => "debug,zenoh=info",
        (false, _) => "trace",
    };
    let ansi = std::io::stderr().is_terminal() && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty());
    let _ = tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| default.into()))
        .with_ansi(ansi)
        .with_writer(std::io::stderr)
        .try_init();
}

/// The data a published `situate_cli` crate carries (`data/`: demo, maps,
/// examples, the CMake package), where `cargo install` left its sources.
pub(crate) fn packaged_data() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

fn run(command: Command, ext: &Extensions, out: Out) -> anyhow::Result<u8> {
    match command {
        Command::Check { file, compose } => robot::check(&file, &compose, ext, out)?,
        Command::Run(args) => robot::run_robot(args, ext, out)?,
        Command::Demo(demo) => return demo::run_demo(&demo, ext, out),
        Command::Replay(args) => return replay::replay_command(args, ext, out),
        Command::Gen { lang, manifest, out: dir } => gen::generate(&lang, &manifest, &dir, out)?,
        Command::CmakeDir => gen::print_cmake_dir(ext, out)?,
        Command::DataDir => gen::print_data_dir(ext, out)?,
        Command::Types { library, python } => gen::types(&skill_types::registry_with(&library, &python, ext)?, out),
        Command::Client(command) => client::run(command, ext, out)?,
        Command::Map(command) => return map::map_command(command, out),
        Command::ServeSkill { skill, name, library, python, remote } => {
            robot::serve_skill(&skill, name, &library, &python, &remote, ext, out)?
        }
        Command::Schema { format, output } => schema::schema_command(&format, output.as_deref(), out)?,
        Command::Completions { shell } => {
            use clap::CommandFactory as _;
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut Cli::command(), "situate", &mut script);
            stdout!("{}", String::from_utf8_lossy(&script));
        }
    }
    Ok(Exit::Ok.code())
}
