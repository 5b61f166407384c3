//! The command line of the client verbs (clap), nothing run: the robot to talk to
//! ([`Remote`]), each verb's arguments ([`ClientCommand`]), and those of `record …` and `param …`.

use std::path::PathBuf;

use clap::{Args, Subcommand};
use clap_complete::ArgValueCandidates;

use crate::args::Compose;
use crate::complete;

#[derive(Args, Clone)]
pub(crate) struct Remote {
    /// The robot to talk to (default: the only one answering).
    #[arg(long, global = true)]
    pub(crate) robot: Option<String>,
    /// The manager's endpoint.
    #[arg(long, global = true, env = "SITUATE_CONNECT", default_value = situate_link::DEFAULT_ENDPOINT)]
    pub(crate) connect: Vec<String>,
    /// Seconds to wait for an answer.
    #[arg(long, global = true, default_value_t = 5.0)]
    pub(crate) timeout: f64,
    /// A JSON5 file merged into the client's Zenoh configuration (credentials, TLS).
    #[arg(long, global = true, env = "SITUATE_ZENOH_CONFIG")]
    pub(crate) zenoh: Option<PathBuf>,
}

#[derive(Subcommand)]
pub(crate) enum ClientCommand {
    /// List the skills of a running robot.
    Skills(#[command(flatten)] Remote),
    /// Activate skills of a running robot (from its next cycle on).
    Activate {
        #[arg(required = true, add = ArgValueCandidates::new(complete::skills))]
        names: Vec<String>,
        /// Also activate providers of inputs nobody active provides.
        #[arg(long)]
        with_providers: bool,
        #[command(flatten)]
        remote: Remote,
    },
    /// Deactivate skills of a running robot.
    Deactivate {
        #[arg(required = true, add = ArgValueCandidates::new(complete::skills))]
        names: Vec<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Say which phase of its mission a sequencer is in (`phase "leaving the lab"`): shown on the
    /// GUI's timeline, recorded, and sent as a `phase` event (for shell sequencers and tests).
    Phase {
        /// One line, 1 to 200 characters.
        text: String,
        /// The name the sequencer gives itself, shown with the phase.
        #[arg(long)]
        client: Option<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// A running robot's parameters: `param get SKILL PARAM`, `param set SKILL PARAM VALUE`,
    /// `param dump` (every value, as a file `param load` reads), `param load FILE`.
    Param {
        #[command(subcommand)]
        action: ParamAction,
    },
    /// The signals, with their types, writers and readers: of a robot file, statically
    /// (`signals robot.yaml`), or of a running robot.
    Signals {
        /// A robot file to read instead of asking a running robot.
        file: Option<PathBuf>,
        #[command(flatten)]
        compose: Compose,
        #[command(flatten)]
        remote: Remote,
    },
    /// The data-flow graph (skills and the signals between them): of a robot file, statically,
    /// or of a running robot; `--dot` for Graphviz (`situate graph robot.yaml --dot | dot -Tsvg`).
    Graph {
        /// A robot file to read instead of asking a running robot.
        file: Option<PathBuf>,
        /// Graphviz's dot language instead of text.
        #[arg(long, conflicts_with = "json")]
        dot: bool,
        #[command(flatten)]
        compose: Compose,
        #[command(flatten)]
        remote: Remote,
    },
    /// Which skill won each resource (a signal several skills write) in the last cycle.
    Winners(#[command(flatten)] Remote),
    /// Record a running robot to MCAP: `record start NAME.mcap` (into the robot's
    /// --record-dir), `record stop` (prints what the file holds), `record status`.
    Record {
        #[command(subcommand)]
        action: RecordAction,
    },
    /// The monitors registered on a running robot.
    Monitors(#[command(flatten)] Remote),
    /// The current value of a signal (`sonar.range`, or a whole record such as `odom`); of
    /// several, all at the end of the same cycle (`query odom sonar.range`, one `query_many`).
    Query {
        #[arg(required = true, add = ArgValueCandidates::new(complete::signals))]
        signals: Vec<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Register a monitor and print its events: `monitor "sonar.range[0] < 0.25"`, or on any of
    /// several conditions, each event saying which held: `monitor --any "target.seen" --any "time > 120"`.
    Monitor {
        /// The condition (or give `--any` instead).
        #[arg(required_unless_present = "any", conflicts_with = "any")]
        condition: Option<String>,
        /// One of several conditions (repeat it, up to 64): the monitor holds when any does, and
        /// each event lists those that held.
        #[arg(long, value_name = "CONDITION")]
        any: Vec<String>,
        /// once: the first time it holds; edge: each time it becomes true; level: every cycle it holds.
        #[arg(long, default_value = "once", value_parser = ["once", "edge", "level"])]
        mode: String,
        /// Stop after this many events (default: 1 for once, else until interrupted).
        #[arg(long)]
        count: Option<u64>,
        /// Also stop the cycle at the end of each cycle the monitor fires in (`cycle run`
        /// resumes it), as a sequencer's pausing monitor does.
        #[arg(long)]
        pause: bool,
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
    /// Print signals' values as the robot's telemetry brings them, one line per sample (`--json`:
    /// one object per line), like `ros2 topic echo`: `echo sonar.range odom.x --count 10`.
    Echo {
        /// Signals (`sonar.range`) or whole records (`odom`).
        #[arg(required = true, add = ArgValueCandidates::new(complete::signals))]
        signals: Vec<String>,
        /// Print at most this many lines a second (the robot's telemetry rate, `link.telemetry_hz`,
        /// default 10, is the most there are).
        #[arg(long, value_name = "HZ")]
        rate: Option<f64>,
        /// Stop after this many lines (default: until interrupted).
        #[arg(long)]
        count: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
    /// How often a signal is written, like `ros2 topic hz`: a report each window (of all seen
    /// since the start).
    #[command(alias = "rate")]
    Hz {
        #[arg(add = ArgValueCandidates::new(complete::signals))]
        signal: String,
        /// Seconds between reports.
        #[arg(long, default_value_t = 1.0, value_name = "S")]
        window: f64,
        /// Stop after this many reports (default: until interrupted).
        #[arg(long)]
        count: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Cycle statistics of a running robot.
    Stats(#[command(flatten)] Remote),
    /// Start, stop or step a running robot's cycle: `cycle run`, `cycle stop`, `cycle step 5`.
    Cycle {
        #[arg(value_parser = ["run", "stop", "step"])]
        action: String,
        cycles: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
}

/// `situate record …`.
#[derive(Subcommand)]
pub(crate) enum RecordAction {
    /// Start recording, from the robot's next cycle, to NAME (a file name ending .mcap,
    /// written into the robot's --record-dir; an existing file is refused).
    Start {
        name: String,
        #[command(flatten)]
        remote: Remote,
    },
    /// Stop the recording and print what it holds.
    Stop {
        #[command(flatten)]
        remote: Remote,
    },
    /// Whether the robot is recording, and where.
    Status {
        #[command(flatten)]
        remote: Remote,
    },
}

/// `situate param …`.
#[derive(Subcommand)]
pub(crate) enum ParamAction {
    /// One parameter's value.
    Get {
        #[arg(add = ArgValueCandidates::new(complete::skills))]
        skill: String,
        #[arg(add = ArgValueCandidates::new(complete::params))]
        param: String,
        #[command(flatten)]
        remote: Remote,
    },
    /// Set one parameter (from the next cycle): the value is JSON (a number, true/false, a list,
    /// a quoted string), anything else is taken as text.
    Set {
        #[arg(add = ArgValueCandidates::new(complete::skills))]
        skill: String,
        #[arg(add = ArgValueCandidates::new(complete::params))]
        param: String,
        value: String,
        #[command(flatten)]
        remote: Remote,
    },
    /// Every parameter's value, as one JSON object `{skill: {param: value}}` (what `param load` reads).
    Dump {
        /// Only these skills (repeatable).
        #[arg(long)]
        skill: Vec<String>,
        #[command(flatten)]
        remote: Remote,
    },
    /// Set the parameters of a file `{skill: {param: value}}` (JSON or JSON5, as `param dump` writes).
    Load {
        file: PathBuf,
        #[command(flatten)]
        remote: Remote,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser)]
    struct Cli {
        #[command(subcommand)]
        command: ClientCommand,
    }

    fn monitor(args: &[&str]) -> Result<(Option<String>, Vec<String>), String> {
        let argv = ["situate", "monitor"].iter().chain(args);
        match <Cli as clap::Parser>::try_parse_from(argv).map_err(|e| e.kind().to_string())?.command {
            ClientCommand::Monitor { condition, any, .. } => Ok((condition, any)),
            _ => Err("not monitor".into()),
        }
    }

    #[test]
    fn monitor_takes_one_condition_or_several_any() {
        assert_eq!(monitor(&["cycle > 1"]).unwrap(), (Some("cycle > 1".into()), vec![]));
        assert_eq!(
            monitor(&["--any", "target.seen", "--any", "time > 120", "--mode", "edge"]).unwrap(),
            (None, vec!["target.seen".to_string(), "time > 120".to_string()])
        );
        assert!(monitor(&[]).is_err(), "a condition or --any is needed");
        assert!(monitor(&["cycle > 1", "--any", "cycle > 2"]).is_err(), "not both");
    }
}
