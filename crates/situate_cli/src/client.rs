//! The client verbs of `situate`: drive a running robot over the link
//! (`skills`, `activate`, `param`, `query`, `monitor`, `events`, `stats`,
//! `cycle`; `echo` and `hz` in `telemetry`) and look into it (`signals`, `graph`, `winners`, `monitors`,
//! `param dump|load`); `signals` and `graph` also read a robot file
//! statically. Every failure is one sentence (`situate: …`) with its exit
//! code: 4 when no robot answered, 5 when the robot refused the request.

use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use std::time::Duration;

use clap::{Args, Subcommand};
use clap_complete::ArgValueCandidates;
use serde_json::{json, Value as Json};
use situate_link::{Client, ClientError};

use crate::args::Compose;
use crate::complete;
use crate::output::{problem, Exit, Out, Problem};
use crate::signals;
use crate::Extensions;

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

pub(crate) fn run(command: ClientCommand, ext: &Extensions, out: Out) -> anyhow::Result<()> {
    match command {
        ClientCommand::Skills(remote) => client_verb(&remote, |c, robot| {
            let skills = c.request(robot, "skills", &json!({}))?;
            out.result(&skills, || {
                let mut lines = Vec::new();
                for s in skills.as_array().into_iter().flatten() {
                    let state = match (s["faulted"].as_str(), s["active"].as_bool()) {
                        (Some(f), _) => format!("faulted: {f}"),
                        (None, Some(true)) => "active".into(),
                        _ => "inactive".into(),
                    };
                    lines.push(format!(
                        "{:<16} {:<18} {:<6} priority {:<4} {state}",
                        s["name"].as_str().unwrap_or(""),
                        s["type_name"].as_str().unwrap_or(""),
                        s["kind"].as_str().unwrap_or(""),
                        s["priority"]
                    ));
                }
                lines.join("\n")
            });
            Ok(())
        }),
        ClientCommand::Activate { names, with_providers, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "activate", &json!({"skills": names, "with_providers": with_providers}))?;
            out.result(&r, || change_text(&r, "activated"));
            Ok(())
        }),
        ClientCommand::Deactivate { names, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "deactivate", &json!({"skills": names}))?;
            out.result(&r, || change_text(&r, "deactivated"));
            Ok(())
        }),
        ClientCommand::Phase { text, client, remote } => client_verb(&remote, |c, robot| {
            let args = match &client {
                Some(name) => json!({"text": text, "client": name}),
                None => json!({"text": text}),
            };
            let r = c.request(robot, "phase", &args)?;
            out.result(&r, || format!("phase: {text}"));
            Ok(())
        }),
        ClientCommand::Param { action } => param(action, out),
        ClientCommand::Record { action } => {
            let (remote, args) = match &action {
                RecordAction::Start { name, remote } => (remote, json!({"start": name})),
                RecordAction::Stop { remote } => (remote, json!({"stop": true})),
                RecordAction::Status { remote } => (remote, json!({})),
            };
            client_verb(remote, |c, robot| {
                let r = c.request(robot, "record", &args)?;
                out.result(&r, || match &action {
                    RecordAction::Start { .. } => format!("recording to {}", r["recording"].as_str().unwrap_or("?")),
                    RecordAction::Stop { .. } => format!(
                        "recorded {} cycles ({} messages on {} channels, {} bytes) to {}",
                        r["cycles"],
                        r["messages"],
                        r["channels"],
                        r["bytes"],
                        r["path"].as_str().unwrap_or("?")
                    ),
                    RecordAction::Status { .. } => match r["recording"].as_str() {
                        Some(p) => format!("recording to {p}"),
                        None => format!("not recording (recordings go into {})", r["dir"].as_str().unwrap_or("?")),
                    },
                });
                Ok(())
            })
        }
        ClientCommand::Query { signals, remote } => client_verb(&remote, |c, robot| {
            let line = |r: &Json| {
                format!(
                    "{} = {} ({}, cycle {}, by {})",
                    r["signal"].as_str().unwrap_or(""),
                    r["value"],
                    r["type"].as_str().unwrap_or(""),
                    r["cycle"],
                    r["writer"]
                )
            };
            // One signal: `query` (its reading, as ever); several: one `query_many` (a list).
            if let [signal] = signals.as_slice() {
                let r = c.request(robot, "query", &json!({ "signal": signal }))?;
                out.result(&r, || line(&r));
            } else {
                let r = c.request(robot, "query_many", &json!({ "signals": signals }))?;
                let readings = r.as_array().map(Vec::as_slice).unwrap_or_default();
                out.result(&r, || readings.iter().map(line).collect::<Vec<_>>().join("\n"));
            }
            Ok(())
        }),
        ClientCommand::Monitor { condition, any, mode, count, pause, remote } => client_verb(&remote, |c, robot| {
            // `monitor_fired`, and `monitor_cancelled`: someone else may cancel it (the GUI, forced).
            let (_sub, events) = c.subscribe(robot, "events/**")?;
            let (args, shown) = match &condition {
                Some(condition) => (json!({"condition": condition, "mode": mode, "pause": pause}), condition.clone()),
                None => (
                    json!({"any": any, "mode": mode, "pause": pause}),
                    any.iter().enumerate().map(|(i, c)| format!("[{i}] {c}")).collect::<Vec<_>>().join("; "),
                ),
            };
            let r = c.request(robot, "monitor_add", &args)?;
            let id = r["monitor"].as_u64().unwrap_or(0);
            if !out.quiet {
                eprintln!("monitor {id} registered ({mode}): {shown}");
            }
            let limit = count.or(if mode == "once" { Some(1) } else { None });
            let mut seen = 0;
            let interrupted = signals::Stop::install()?;
            while limit.is_none_or(|n| seen < n) && !interrupted.flag().load(Ordering::SeqCst) {
                if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
                    if e["monitor"].as_u64() == Some(id) && e["kind"] == "monitor_cancelled" {
                        anyhow::bail!(
                            "monitor {id} was cancelled by {} at cycle {}: it will not fire",
                            match e["reason"].as_str() {
                                Some("forced") => "another session (the GUI's user)",
                                Some("session_ended") => "the robot, as this connection's session ended",
                                _ => "this connection",
                            },
                            e["cycle"]
                        );
                    }
                    if e["monitor"].as_u64() == Some(id) && e["kind"] == "monitor_fired" {
                        seen += 1;
                        out.result(&e, || {
                            format!(
                                "cycle {} (t = {:.3} s): {} — {}",
                                e["cycle"],
                                e["time_s"].as_f64().unwrap_or(0.0),
                                held_text(condition.as_deref(), &any, &e["held"]),
                                e["values"]
                            )
                        });
                    }
                }
            }
            if mode != "once" || seen == 0 {
                let _ = c.request(robot, "monitor_cancel", &json!({"monitor": id}));
            }
            Ok(())
        }),
        ClientCommand::Events { count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/**")?;
            let interrupted = signals::Stop::install()?;
            let mut seen = 0;
            while count.is_none_or(|n| seen < n) && !interrupted.flag().load(Ordering::SeqCst) {
                if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
                    stdoutln!("{e}");
                    seen += 1;
                }
            }
            Ok(())
        }),
        ClientCommand::Echo { signals, rate, count, remote } => {
            crate::telemetry::echo(&signals, rate, count, &remote, out)
        }
        ClientCommand::Hz { signal, window, count, remote } => {
            crate::telemetry::hz(&signal, window, count, &remote, out)
        }
        ClientCommand::Stats(remote) => client_verb(&remote, |c, robot| {
            let s = c.request(robot, "stats", &json!({}))?;
            out.result(&s, || {
                format!(
                    "robot `{}`: cycle {}, {} s, {}; cycle time mean {:.1} µs, max {:.1} µs; overruns {}; late starts {}; active: {}",
                    s["robot"].as_str().unwrap_or(""),
                    s["cycle"],
                    seconds(s["time_s"].as_f64().unwrap_or(0.0)),
                    if s["running"].as_bool() == Some(true) {
                        format!("running at {:.1} Hz", s["rate_hz"].as_f64().unwrap_or(0.0))
                    } else {
                        "stopped".to_string()
                    },
                    s["mean_cycle_ns"].as_f64().unwrap_or(0.0) / 1e3,
                    s["max_cycle_ns"].as_f64().unwrap_or(0.0) / 1e3,
                    s["overruns"],
                    s["late_starts"],
                    s["active"].as_array().map(|a| a.iter().filter_map(Json::as_str).collect::<Vec<_>>().join(", ")).unwrap_or_default()
                )
            });
            Ok(())
        }),
        ClientCommand::Cycle { action, cycles, remote } => client_verb(&remote, |c, robot| {
            let stepped = cycles.unwrap_or(1);
            match action.as_str() {
                "step" => c.request(robot, "step", &json!({"cycles": stepped}))?,
                other => c.request(robot, other, &json!({}))?,
            };
            // Where the cycle is now, and whether it runs: what the command did, said.
            let s = c.request(robot, "stats", &json!({}))?;
            let (at, running) = (s["cycle"].as_u64().unwrap_or(0), s["running"].as_bool() == Some(true));
            let result = json!({"cycle": action, "at_cycle": at, "running": running, "time_s": s["time_s"]});
            out.result(&result, || {
                let time = seconds(s["time_s"].as_f64().unwrap_or(0.0));
                let name = s["robot"].as_str().unwrap_or(robot);
                match (action.as_str(), running) {
                    ("step", _) => format!(
                        "robot `{name}`: stepped {stepped} cycle{}, now at cycle {at} ({time} s), stopped",
                        if stepped == 1 { "" } else { "s" }
                    ),
                    (_, true) => format!("robot `{name}`: running, at cycle {at} ({time} s)"),
                    (_, false) => format!("robot `{name}`: stopped at cycle {at} ({time} s)"),
                }
            });
            Ok(())
        }),
        ClientCommand::Signals { file, compose, remote } => {
            let graph = graph_json(file.as_deref(), &compose, &remote, ext)?;
            let signals = graph["signals"].clone();
            out.result(&signals, || signals_text(&signals));
            Ok(())
        }
        ClientCommand::Graph { file, dot, compose, remote } => {
            let graph = graph_json(file.as_deref(), &compose, &remote, ext)?;
            if dot {
                stdout!("{}", graph_dot(&graph));
            } else {
                out.result(&graph, || graph_text(&graph));
            }
            Ok(())
        }
        ClientCommand::Winners(remote) => client_verb(&remote, |c, robot| {
            let w = c.request(robot, "winners", &json!({}))?;
            out.result(&w, || {
                let mut lines = Vec::new();
                for r in w.as_array().into_iter().flatten() {
                    let writers: Vec<&str> =
                        r["writers"].as_array().into_iter().flatten().filter_map(Json::as_str).collect();
                    lines.push(format!(
                        "{:<20} won by {:<16} (writers: {}; cycle {})",
                        r["signal"].as_str().unwrap_or(""),
                        r["winner"].as_str().unwrap_or("nobody"),
                        writers.join(", "),
                        r["cycle"]
                    ));
                }
                if lines.is_empty() {
                    "no resources (no signal has several writers)".to_string()
                } else {
                    lines.join("\n")
                }
            });
            Ok(())
        }),
        ClientCommand::Monitors(remote) => client_verb(&remote, |c, robot| {
            let list = c.request(robot, "monitor_list", &json!({}))?;
            out.result(&list, || {
                let lines: Vec<String> = list
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|m| {
                        format!(
                            "monitor {} ({}{}): {}; fired {}, holds {}{}{}",
                            m["monitor"],
                            m["mode"].as_str().unwrap_or(""),
                            if m["pause"].as_bool() == Some(true) { ", pause" } else { "" },
                            m["condition"].as_str().unwrap_or(""),
                            m["fired"],
                            m["holds"],
                            m["session"].as_str().map(|s| format!("; session {s}")).unwrap_or_default(),
                            m["client"].as_str().map(|c| format!(" (client {c})")).unwrap_or_default()
                        )
                    })
                    .collect();
                if lines.is_empty() {
                    "no monitors".to_string()
                } else {
                    lines.join("\n")
                }
            });
            Ok(())
        }),
    }
}

/// `situate param …`.
fn param(action: ParamAction, out: Out) -> anyhow::Result<()> {
    match action {
        ParamAction::Get { skill, param, remote } => client_verb(&remote, |c, robot| {
            let v = c.request(robot, "get_param", &json!({"skill": skill, "param": param}))?;
            out.result(&v, || v.to_string());
            Ok(())
        }),
        ParamAction::Set { skill, param, value, remote } => client_verb(&remote, |c, robot| {
            // A number, true/false, or a JSON string; anything else is taken as text.
            let v: Json = serde_json::from_str(&value).unwrap_or_else(|_| Json::String(value.clone()));
            c.request(robot, "set_param", &json!({"skill": skill, "param": param, "value": v}))?;
            out.result(&json!({"skill": skill, "param": param, "value": v}), || {
                format!("{skill}.{param} = {v} (from the next cycle)")
            });
            Ok(())
        }),
        ParamAction::Dump { skill, remote } => client_verb(&remote, |c, robot| {
            let skills = c.request(robot, "skills", &json!({}))?;
            let mut dump = serde_json::Map::new();
            for s in skills.as_array().into_iter().flatten() {
                let name = s["name"].as_str().unwrap_or_default();
                if !skill.is_empty() && !skill.iter().any(|k| k == name) {
                    continue;
                }
                let params: serde_json::Map<String, Json> = s["params"]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|p| (p["name"].as_str().unwrap_or_default().to_string(), p["value"].clone()))
                    .collect();
                if !params.is_empty() {
                    dump.insert(name.to_string(), Json::Object(params));
                }
            }
            for k in &skill {
                if !dump.contains_key(k) && !skills.as_array().into_iter().flatten().any(|s| s["name"] == **k) {
                    return Err(problem(Exit::Refused, format!("no skill `{k}` on robot `{robot}`")));
                }
            }
            let dump = Json::Object(dump);
            // The text form is the file `param load` reads, pretty-printed.
            out.result(&dump, || serde_json::to_string_pretty(&dump).unwrap_or_default());
            Ok(())
        }),
        ParamAction::Load { file, remote } => {
            let values = read_param_file(&file)?;
            client_verb(&remote, |c, robot| {
                let mut set = Vec::new();
                for (skill, params) in &values {
                    for (param, value) in params {
                        c.request(robot, "set_param", &json!({"skill": skill, "param": param, "value": value}))?;
                        set.push(format!("{skill}.{param}"));
                    }
                }
                out.result(&json!({"set": set}), || format!("set {} parameters (from the next cycle)", set.len()));
                Ok(())
            })
        }
    }
}

/// One skill's parameter values, from a parameter file.
type SkillParams = (String, Vec<(String, Json)>);

/// A parameter file `{skill: {param: value}}`, checked whole before anything is set.
fn read_param_file(file: &Path) -> anyhow::Result<Vec<SkillParams>> {
    let shown = file.display();
    let text = std::fs::read_to_string(file)
        .map_err(|e| Problem::file_problem(format!("{shown}: cannot read the parameter file: {e}")))?;
    let root: Json =
        json5::from_str(&text).map_err(|e| Problem::file_problem(format!("{shown}: not JSON or JSON5: {e}")))?;
    let Json::Object(skills) = root else {
        return Err(Problem::file_problem(format!(
            "{shown}: expected an object {{skill: {{param: value}}}} (what `situate param dump` writes)"
        ))
        .into());
    };
    let mut out = Vec::new();
    for (skill, params) in skills {
        let Json::Object(params) = params else {
            return Err(Problem::file_problem(format!(
                "{shown}: `{skill}`: expected an object of parameter values {{param: value}}"
            ))
            .into());
        };
        out.push((skill, params.into_iter().collect()));
    }
    Ok(out)
}

/// The protocol's `graph` object: of a robot file, built here without
/// running anything, or asked of the running robot.
fn graph_json(file: Option<&Path>, compose: &Compose, remote: &Remote, ext: &Extensions) -> anyhow::Result<Json> {
    let Some(file) = file else {
        if !compose.set.is_empty() {
            return Err(problem(Exit::Usage, "--set changes a robot file: give the file"));
        }
        let mut graph = Json::Null;
        client_verb(remote, |c, robot| {
            graph = c.request(robot, "graph", &json!({}))?;
            Ok(())
        })?;
        return Ok(graph);
    };
    let (_loaded, g) = crate::robot::static_graph(file, compose, ext)?;
    let info = situate::manager::control::GraphInfo {
        skills: g
            .instances
            .iter()
            .map(|d| situate::manager::control::GraphSkill {
                name: d.name.clone(),
                kind: d.kind,
                active: d.active,
                priority: d.priority,
                inputs: d.inputs.iter().map(|p| p.signal.clone()).collect(),
                outputs: d.outputs.iter().map(|p| p.signal.clone()).collect(),
            })
            .collect(),
        signals: g
            .leaves
            .iter()
            .map(|l| situate::manager::control::GraphSignal {
                signal: l.path.clone(),
                ty: l.ty.clone(),
                writers: l.writers.iter().map(|&(w, _)| g.instances[w].name.clone()).collect(),
                readers: l.readers.iter().map(|&(r, _)| g.instances[r].name.clone()).collect(),
            })
            .collect(),
    };
    Ok(situate_link::json::reply_to_json(&situate::manager::Reply::Graph(info)))
}

fn names(list: &Json) -> String {
    let names: Vec<&str> = list.as_array().into_iter().flatten().filter_map(Json::as_str).collect();
    if names.is_empty() {
        "-".to_string()
    } else {
        names.join(", ")
    }
}

/// `sonar.range  f32[24]  written by sonar  read by runaway, wander`.
/// Seconds as a person reads them: to the millisecond, without the float's noise or trailing
/// zeros (`21.9`, not `21.900000000000002`; `3`, not `3.000`).
fn seconds(s: f64) -> String {
    let text = format!("{s:.3}");
    let text = text.trim_end_matches('0').trim_end_matches('.');
    if text == "-0" {
        "0".to_string()
    } else {
        text.to_string()
    }
}

fn signals_text(signals: &Json) -> String {
    let rows: Vec<&Json> = signals.as_array().into_iter().flatten().collect();
    let width = rows.iter().filter_map(|s| s["signal"].as_str()).map(str::len).max().unwrap_or(0);
    let type_width = rows.iter().filter_map(|s| s["type"].as_str()).map(str::len).max().unwrap_or(0);
    rows.iter()
        .map(|s| {
            format!(
                "{:<width$}  {:<type_width$}  written by {}; read by {}",
                s["signal"].as_str().unwrap_or(""),
                s["type"].as_str().unwrap_or(""),
                names(&s["writers"]),
                names(&s["readers"])
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The skills with their inputs and outputs, then the signals.
fn graph_text(graph: &Json) -> String {
    let mut lines = Vec::new();
    for s in graph["skills"].as_array().into_iter().flatten() {
        lines.push(format!(
            "{} ({}, priority {}, {}): in {} -> out {}",
            s["name"].as_str().unwrap_or(""),
            s["kind"].as_str().unwrap_or(""),
            s["priority"],
            if s["active"].as_bool() == Some(true) { "active" } else { "inactive" },
            names(&s["inputs"]),
            names(&s["outputs"])
        ));
    }
    lines.push(String::new());
    lines.push(signals_text(&graph["signals"]));
    lines.join("\n")
}

/// Graphviz: skills as boxes (inactive ones dashed), signals as ellipses,
/// an edge from each writer to its signal and from the signal to each reader.
fn graph_dot(graph: &Json) -> String {
    use std::fmt::Write as _;
    let quote = |s: &str| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""));
    let mut dot = String::from("digraph situate {\n  rankdir=LR;\n  node [fontname=\"Helvetica\"];\n");
    for s in graph["skills"].as_array().into_iter().flatten() {
        let name = s["name"].as_str().unwrap_or("");
        let style = if s["active"].as_bool() == Some(true) { "solid" } else { "dashed" };
        let _ = writeln!(
            dot,
            "  {} [shape=box, style={style}, label={}];",
            quote(&format!("skill:{name}")),
            quote(&format!("{name}\\n{}", s["kind"].as_str().unwrap_or("")))
        );
    }
    for s in graph["signals"].as_array().into_iter().flatten() {
        let signal = s["signal"].as_str().unwrap_or("");
        let resource = s["writers"].as_array().is_some_and(|w| w.len() > 1);
        let _ = writeln!(
            dot,
            "  {} [shape=ellipse{}, label={}];",
            quote(&format!("signal:{signal}")),
            if resource { ", peripheries=2" } else { "" },
            quote(&format!("{signal}\\n{}", s["type"].as_str().unwrap_or("")))
        );
        for w in s["writers"].as_array().into_iter().flatten().filter_map(Json::as_str) {
            let _ = writeln!(dot, "  {} -> {};", quote(&format!("skill:{w}")), quote(&format!("signal:{signal}")));
        }
        for r in s["readers"].as_array().into_iter().flatten().filter_map(Json::as_str) {
            let _ = writeln!(dot, "  {} -> {};", quote(&format!("signal:{signal}")), quote(&format!("skill:{r}")));
        }
    }
    dot.push_str("}\n");
    dot
}

fn change_text(r: &Json, what: &str) -> String {
    let changed: Vec<&str> = r["changed"].as_array().into_iter().flatten().filter_map(Json::as_str).collect();
    if changed.is_empty() {
        format!("nothing {what} (already so)")
    } else {
        format!("{what} {} from cycle {}", changed.join(", "), r["at_cycle"])
    }
}

/// Connects, finds the robot and runs `f`; a client error becomes a
/// [`Problem`] of its kind (no robot answering, or the request refused).
pub(crate) fn client_verb(remote: &Remote, f: impl FnOnce(&Client, &str) -> anyhow::Result<()>) -> anyhow::Result<()> {
    let extra = match &remote.zenoh {
        None => None,
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| Problem::file_problem(format!("{}: cannot read: {e}", path.display())))?;
            Some(
                json5::from_str::<Json>(&text)
                    .map_err(|e| Problem::file_problem(format!("{}: {e}", path.display())))?,
            )
        }
    };
    let mut client = Client::connect_with(&remote.connect, extra.as_ref()).map_err(|e| client_problem(&e))?;
    // Clamped: `--timeout inf` or `nan` must not panic.
    client.timeout = Duration::from_secs_f64(if remote.timeout.is_finite() {
        remote.timeout.clamp(0.1, 86_400.0)
    } else {
        86_400.0
    });
    let robot = client.resolve_robot(remote.robot.as_deref()).map_err(|e| client_problem(&e))?;
    f(&client, &robot).map_err(|e| {
        if let Some(c) = e.downcast_ref::<ClientError>() {
            return client_problem(c);
        }
        if let Some(l) = e.downcast_ref::<situate_link::LinkError>() {
            return Problem::new(Exit::Failure, l.to_string()).said_by_situate().into();
        }
        e
    })
}

/// A client error, said as a sentence (`situate: …`): a manager's refusal
/// with its pointer line if any, never the link's raw data.
fn client_problem(e: &ClientError) -> anyhow::Error {
    let p = match e {
        ClientError::Remote(r) => Problem {
            after: r.detail.get("pointer").and_then(Json::as_str).map(str::to_string).into_iter().collect(),
            ..Problem::new(Exit::Refused, r.message.clone()).said_by_situate().with_detail(json!({"remote": r.detail}))
        },
        ClientError::NoAnswer { .. }
        | ClientError::TimedOut { .. }
        | ClientError::NotReachable { .. }
        | ClientError::Ambiguous(_)
        | ClientError::OtherRobots { .. } => Problem::new(Exit::NoRobot, e.to_string()).said_by_situate(),
        other => Problem::new(Exit::Failure, other.to_string()).said_by_situate(),
    };
    p.into()
}

/// What held, for a person: the condition, or the `any` conditions the event
/// lists in `held` (`[0] target.seen; [2] time > 120`).
fn held_text(condition: Option<&str>, any: &[String], held: &serde_json::Value) -> String {
    if let Some(condition) = condition {
        return condition.to_string();
    }
    let held: Vec<String> = held
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(serde_json::Value::as_u64)
        .map(|i| match any.get(i as usize) {
            Some(c) => format!("[{i}] {c}"),
            None => format!("[{i}]"),
        })
        .collect();
    held.join("; ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seconds_read_without_float_noise() {
        assert_eq!(seconds(21.900000000000002), "21.9");
        assert_eq!(seconds(3.0), "3");
        assert_eq!(seconds(0.0), "0");
        assert_eq!(seconds(-0.0001), "0");
        assert_eq!(seconds(0.1234), "0.123");
        assert_eq!(seconds(120.05), "120.05");
    }

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

    #[test]
    fn an_any_event_shows_the_conditions_that_held() {
        let any = ["target.seen".to_string(), "x > 1".to_string(), "time > 120".to_string()];
        assert_eq!(held_text(None, &any, &json!([0, 2])), "[0] target.seen; [2] time > 120");
        assert_eq!(held_text(Some("cycle > 1"), &[], &json!([0])), "cycle > 1");
        // An index this client did not send (a newer manager?) is still shown.
        assert_eq!(held_text(None, &any, &json!([7])), "[7]");
    }
}
