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
        ClientCommand::Monitor { condition, mode, count, remote } => client_verb(&remote, |c, robot| {
            let (_sub, events) = c.subscribe(robot, "events/monitor_fired")?;
            let r = c.request(robot, "monitor_add", &json!({"condition": condition, "mode": mode}))?;
            let id = r["monitor"].as_u64().unwrap_or(0);
            eprintln!("monitor {id} registered ({mode}): {condition}");
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
