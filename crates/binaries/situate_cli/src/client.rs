//! The client verbs of `situate`: drive a running robot over the link
//! (`skills`, `activate`, `param`, `query`, `monitor`, `events`, `stats`,
//! `cycle`; `echo` and `hz` in `telemetry`) and look into it (`signals`, `graph`, `winners`, `monitors`,
//! `param dump|load`); `signals` and `graph` also read a robot file
//! statically. Every failure is one sentence (`situate: …`) with its exit
//! code: 4 when no robot answered, 5 when the robot refused the request.
//!
//! By file: `command` is the verbs' command line (clap), `connect` the connection to a
//! robot ([`client_verb`]) and its errors as sentences, `param` the `param` verbs, `graph` the
//! signals and the data-flow graph (`signals`, `graph`); this file runs each verb.

use std::sync::atomic::Ordering;
use std::time::Duration;

use serde_json::{json, Value as Json};

use crate::output::Out;
use crate::signals;
use crate::Extensions;

mod command;
mod connect;
mod graph;
mod param;

use command::RecordAction;
pub(crate) use command::{ClientCommand, Remote};
pub(crate) use connect::client_verb;
use graph::{graph_dot, graph_json, graph_text, signals_text};
use param::param;

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

fn change_text(r: &Json, what: &str) -> String {
    let changed: Vec<&str> = r["changed"].as_array().into_iter().flatten().filter_map(Json::as_str).collect();
    if changed.is_empty() {
        format!("nothing {what} (already so)")
    } else {
        format!("{what} {} from cycle {}", changed.join(", "), r["at_cycle"])
    }
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

    #[test]
    fn an_any_event_shows_the_conditions_that_held() {
        let any = ["target.seen".to_string(), "x > 1".to_string(), "time > 120".to_string()];
        assert_eq!(held_text(None, &any, &json!([0, 2])), "[0] target.seen; [2] time > 120");
        assert_eq!(held_text(Some("cycle > 1"), &[], &json!([0])), "cycle > 1");
        // An index this client did not send (a newer manager?) is still shown.
        assert_eq!(held_text(None, &any, &json!([7])), "[7]");
    }
}
