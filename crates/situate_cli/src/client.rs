//! The client verbs of `situate`: drive a running robot over the link
//! (`skills`, `activate`, `param`, `query`, `monitor`, `events`, `stats`,
//! `cycle`). Every failure is one sentence on stderr and exit status 1.

use super::*;

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
    /// Print the protocol's JSON instead of text.
    #[arg(long, global = true)]
    pub(crate) json: bool,
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
    /// Start, stop or step a running robot's cycle: `cycle run`, `cycle stop`, `cycle step 5`.
    Cycle {
        #[arg(value_parser = ["run", "stop", "step"])]
        action: String,
        cycles: Option<u64>,
        #[command(flatten)]
        remote: Remote,
    },
}

pub(crate) fn run(command: ClientCommand) -> anyhow::Result<ExitCode> {
    match command {
        ClientCommand::Skills(remote) => client_verb(&remote, |c, robot| {
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
        ClientCommand::Activate { names, with_providers, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "activate", &json!({"skills": names, "with_providers": with_providers}))?;
            print_change(&remote, &r, "activated");
            Ok(())
        }),
        ClientCommand::Deactivate { names, remote } => client_verb(&remote, |c, robot| {
            let r = c.request(robot, "deactivate", &json!({"skills": names}))?;
            print_change(&remote, &r, "deactivated");
            Ok(())
        }),
        ClientCommand::Param { action, skill, param, value, remote } => client_verb(&remote, |c, robot| {
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
        ClientCommand::Query { signal, remote } => client_verb(&remote, |c, robot| {
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
        ClientCommand::Monitor { condition, any, mode, count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/monitor_fired")?;
            let (args, shown) = match &condition {
                Some(condition) => (json!({"condition": condition, "mode": mode}), condition.clone()),
                None => (
                    json!({"any": any, "mode": mode}),
                    any.iter().enumerate().map(|(i, c)| format!("[{i}] {c}")).collect::<Vec<_>>().join("; "),
                ),
            };
            let r = c.request(robot, "monitor_add", &args)?;
            let id = r["monitor"].as_u64().unwrap_or(0);
            eprintln!("monitor {id} registered ({mode}): {shown}");
            let limit = count.or(if mode == "once" { Some(1) } else { None });
            let mut seen = 0;
            let interrupted = interrupt_flag()?;
            while limit.is_none_or(|n| seen < n) && !interrupted.flag().load(Ordering::SeqCst) {
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
                                held_text(condition.as_deref(), &any, &e["held"]),
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
        ClientCommand::Events { count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/**")?;
            let interrupted = interrupt_flag()?;
            let mut seen = 0;
            while count.is_none_or(|n| seen < n) && !interrupted.flag().load(Ordering::SeqCst) {
                if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
                    println!("{e}");
                    seen += 1;
                }
            }
            Ok(())
        }),
        ClientCommand::Stats(remote) => client_verb(&remote, |c, robot| {
            let s = c.request(robot, "stats", &json!({}))?;
            if remote.json {
                println!("{s}");
            } else {
                println!(
                    "robot `{}`: cycle {}, {} s, {}; cycle time mean {:.1} µs, max {:.1} µs; overruns {}; late starts {}; active: {}",
                    s["robot"].as_str().unwrap_or(""),
                    s["cycle"],
                    s["time_s"],
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
                );
            }
            Ok(())
        }),
        ClientCommand::Cycle { action, cycles, remote } => client_verb(&remote, |c, robot| {
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

pub(crate) fn client_verb(
    remote: &Remote,
    f: impl FnOnce(&Client, &str) -> anyhow::Result<()>,
) -> anyhow::Result<ExitCode> {
    let extra = match &remote.zenoh {
        None => None,
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
            Some(json5::from_str::<Json>(&text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?)
        }
    };
    let mut client = match Client::connect_with(&remote.connect, extra.as_ref()) {
        Ok(c) => c,
        Err(e) => return Ok(client_failure(&e)),
    };
    // Clamped: `--timeout inf` or `nan` must not panic.
    client.timeout = Duration::from_secs_f64(if remote.timeout.is_finite() {
        remote.timeout.clamp(0.1, 86_400.0)
    } else {
        86_400.0
    });
    let robot = match client.resolve_robot(remote.robot.as_deref()) {
        Ok(r) => r,
        Err(e) => return Ok(client_failure(&e)),
    };
    match f(&client, &robot) {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(e) => match (e.downcast_ref::<ClientError>(), e.downcast_ref::<situate_link::LinkError>()) {
            (Some(c), _) => Ok(client_failure(c)),
            (None, Some(l)) => {
                eprintln!("situate: {l}");
                Ok(ExitCode::FAILURE)
            }
            (None, None) => Err(e),
        },
    }
}

/// A client error, said as a sentence (`situate: …`): a manager's refusal
/// with its pointer line if any, never the link's raw data.
fn client_failure(e: &ClientError) -> ExitCode {
    match e {
        ClientError::Remote(r) => {
            eprintln!("situate: {}", r.message);
            if let Some(p) = r.detail.get("pointer").and_then(Json::as_str) {
                eprintln!("{p}");
            }
        }
        other => eprintln!("situate: {other}"),
    }
    ExitCode::FAILURE
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

    #[derive(clap::Parser)]
    struct Cli {
        #[command(subcommand)]
        command: ClientCommand,
    }

    fn monitor(args: &[&str]) -> Result<(Option<String>, Vec<String>), String> {
        let argv = ["situate", "monitor"].iter().chain(args);
        match Cli::try_parse_from(argv).map_err(|e| e.kind().to_string())?.command {
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
