//! The command line: the global options and every command's arguments
//! (parsed by clap, nothing run here).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

use crate::client::ClientCommand;
use crate::demo::DemoOptions;
use crate::map::MapCommand;
use crate::sim::WorldArgs;

#[derive(Parser)]
#[command(
    name = "situate",
    version,
    about = "The reactive layer of a robot: check and run robot files, drive a running one",
    after_help = "Exit codes: 0 done, 1 failed, 2 bad usage, 3 bad file, 4 no robot answering, 5 request \
                  refused (docs/cli.md).\nLogs: -v/-vv/-vvv, or RUST_LOG (e.g. RUST_LOG=situate_link=debug), \
                  which wins when set."
)]
pub(crate) struct Cli {
    #[command(flatten)]
    pub(crate) global: Global,
    #[command(subcommand)]
    pub(crate) command: Command,
}

/// Options every command takes.
#[derive(Args, Clone, Copy, Debug, Default)]
pub(crate) struct Global {
    /// Results as JSON on stdout (one value, or one per line for streams), errors as one JSON
    /// object `{"error": {"kind", "exit", "message", "lines"}}` on stdout.
    #[arg(long, global = true)]
    pub(crate) json: bool,
    /// More log lines on stderr: -v info, -vv debug, -vvv trace (RUST_LOG, when set, wins).
    #[arg(short, long, global = true, action = clap::ArgAction::Count, conflicts_with = "quiet")]
    pub(crate) verbose: u8,
    /// No progress notes and warnings on stderr, errors only.
    #[arg(short, long, global = true)]
    pub(crate) quiet: bool,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Check a robot file statically; every problem is reported as FILE:LINE:COL.
    Check {
        file: PathBuf,
        #[command(flatten)]
        compose: Compose,
    },
    /// Run a robot file, serving the link, and print a summary at the end.
    Run(RunArgs),
    /// The delivery demo: the simulated robot, the skill manager and the Python sequencer of
    /// demo/deliver.py (and the GUI unless --headless). Prints one line per phase and the outcome.
    Demo(DemoOptions),
    /// Replay a recording through the robot rebuilt from its robot file: devices (and skills
    /// not given with --live) play from the recording, the live skills run their code now, and
    /// every cycle is compared with the recording; the first difference is named
    /// (docs/recording.md). Exit 0: identical; 1: it differs.
    Replay(crate::replay::ReplayArgs),
    /// Generate a C or C++ skill's typed I/O (structs and the glue) from its YAML manifest
    /// (docs/manifests.md).
    Gen {
        /// `c` or `cpp`.
        #[arg(value_parser = gen_languages())]
        lang: String,
        manifest: PathBuf,
        /// The directory to write into.
        #[arg(short, long, default_value = ".")]
        out: PathBuf,
    },
    /// Print the directory of the CMake package for C/C++ skills (`situateConfig.cmake`; the
    /// headers `situate.h`, `situate.hpp` are in its `../include`):
    /// `cmake -Dsituate_DIR="$(situate cmake-dir)"`.
    #[command(name = "cmake-dir", long_flag = "cmake-dir")]
    CmakeDir,
    /// Print the directory holding the demo, the maps and the examples (`demo/`, `maps/`,
    /// `examples/`): the installed package's copy, or the checkout this program was built from:
    /// `cp -r "$(situate data-dir)/examples/toybot.yaml" .`
    #[command(name = "data-dir", long_flag = "data-dir")]
    DataDir,
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
        remote: crate::client::Remote,
    },

    /// Building maps for the simulator (docs/maps.md): generate one, check one.
    #[command(subcommand)]
    Map(MapCommand),

    /// The JSON Schema of a file format (robot files, skill manifests, maps), for editors
    /// (`# yaml-language-server: $schema=…`) and checkers.
    Schema {
        /// Which format.
        #[arg(value_parser = ["robot", "manifest", "map"])]
        format: String,
        /// Write it here instead of stdout.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },

    /// Print a shell's completion script: `situate completions bash > /etc/bash_completion.d/situate`.
    Completions {
        /// bash, zsh, fish, elvish or powershell.
        shell: clap_complete::Shell,
    },

    #[command(flatten)]
    Client(ClientCommand),
}

/// `gen`'s languages; `python` is accepted only to say why nothing is generated for it.
fn gen_languages() -> clap::builder::PossibleValuesParser {
    use clap::builder::PossibleValue;
    clap::builder::PossibleValuesParser::new([
        PossibleValue::new("c"),
        PossibleValue::new("cpp").alias("c++"),
        PossibleValue::new("python").alias("py").hide(true),
    ])
}

/// What composes a robot file at launch (`check`, `run`, `signals`, `graph`).
#[derive(Args, Clone, Default, Debug)]
pub(crate) struct Compose {
    /// Set a skill's parameter, over the file's value: `--set runaway.safe_distance=0.3`
    /// (repeatable; the value is YAML: a number, true/false, text, or a list `[1, 2]`).
    #[arg(long = "set", value_name = "SKILL.PARAM=VALUE", add = clap_complete::ArgValueCandidates::new(crate::complete::settable))]
    pub(crate) set: Vec<String>,
}

/// `situate run`'s arguments.
#[derive(Args)]
pub(crate) struct RunArgs {
    pub(crate) file: PathBuf,
    /// Stop after this many cycles (default: run until interrupted).
    #[arg(long)]
    pub(crate) cycles: Option<u64>,
    /// Override the file's executor.
    #[arg(long, value_parser = ["serial", "parallel"])]
    pub(crate) executor: Option<String>,
    /// Override the file's clock.
    #[arg(long, value_parser = ["wall", "simulated"])]
    pub(crate) clock: Option<String>,
    /// Do not open the link (no network at all).
    #[arg(long)]
    pub(crate) no_link: bool,
    /// Override the link's listen endpoints (e.g. tcp/127.0.0.1:7448).
    #[arg(long)]
    pub(crate) listen: Vec<String>,
    /// Override the simulator's map file (robot files with `simulator:`); for a robot file
    /// without one (a ROS 2 robot in a simulator of its own), the building the GUI's world view
    /// and the recording show it in.
    #[arg(long)]
    pub(crate) map: Option<PathBuf>,
    /// Override the simulator's seed.
    #[arg(long)]
    pub(crate) seed: Option<u64>,
    #[command(flatten)]
    pub(crate) world: WorldArgs,
    /// On the simulated clock, run at this many times real time (default: as fast as possible).
    #[arg(long)]
    pub(crate) speed: Option<f64>,
    /// Start with the cycle stopped: a sequencer (or `situate cycle run`) starts it. With ROS
    /// time, the robot's clock waits for it too (lock-step).
    #[arg(long)]
    pub(crate) stopped: bool,
    /// Serve the debugging GUI at this address (e.g. 127.0.0.1:8080, or a port).
    #[arg(long)]
    pub(crate) gui: Option<String>,
    /// No GUI, even if the robot file has a `gui:` section.
    #[arg(long, conflicts_with = "gui")]
    pub(crate) no_gui: bool,
    /// Let the GUI answer to this host name too, besides localhost and its own address (e.g.
    /// robot.lan, without a port; repeat for several). Requests naming any other host are
    /// refused, a guard against DNS rebinding (docs/gui.md).
    #[arg(long, value_name = "NAME", conflicts_with = "no_gui")]
    pub(crate) gui_allow_host: Vec<String>,
    /// Record the run to this MCAP file: every signal, event, print and resource winner
    /// (docs/recording.md).
    #[arg(long, value_name = "FILE")]
    pub(crate) record: Option<PathBuf>,
    /// Where a recording started over the link (the `record` request, `situate record start
    /// NAME`) is written (default: the directory the robot was started in).
    #[arg(long, value_name = "DIR")]
    pub(crate) record_dir: Option<PathBuf>,
    #[command(flatten)]
    pub(crate) compose: Compose,
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory as _;

    #[test]
    fn the_command_line_is_consistent() {
        Cli::command().debug_assert();
    }
}
