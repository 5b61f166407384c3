//! The shell completes the names of the running robot, as the `ros2` CLI completes node and topic
//! names: with `source <(COMPLETE=bash situate)` (clap_complete's completions activated by the
//! environment; zsh, fish, elvish and PowerShell too), `situate activate wa<TAB>` offers the
//! robot's skills, `situate echo od<TAB>` its signals, `situate param set runaway <TAB>` the
//! parameters. The robot is the one the CLI would reach (`SITUATE_CONNECT`, else the default
//! endpoint; the only robot answering there). Nothing answering within half a second
//! (`SITUATE_COMPLETE_TIMEOUT_S`), or several robots: no names, and the shell goes on with what
//! it has. `situate run robot.yaml --set <TAB>` (and `check`, `signals`, `graph`) offers the
//! parameters of the robot file on the line, as `skill.param=`, with no robot running. The
//! static scripts of `situate completions SHELL` still complete the commands and options,
//! without the robot's names.

use std::time::Duration;

use clap_complete::engine::CompletionCandidate;
use serde_json::{json, Value as Json};
use situate_link::Client;

/// How long a completion waits for the robot by default: a shell waiting for names must never
/// hang. `SITUATE_COMPLETE_TIMEOUT_S` sets another (seconds).
const ASK_FOR: Duration = Duration::from_millis(500);

fn ask_for() -> Duration {
    std::env::var("SITUATE_COMPLETE_TIMEOUT_S")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .map_or(ASK_FOR, |s| Duration::from_secs_f64(s.min(60.0)))
}

/// The robot the CLI would reach now: its `graph` (skills and signals) and `skills` (with their
/// parameters), or nothing.
fn ask(verb: &str) -> Option<Json> {
    let endpoints: Vec<String> = match std::env::var("SITUATE_CONNECT") {
        Ok(e) if !e.is_empty() => e.split(',').map(str::to_string).collect(),
        _ => vec![situate_link::DEFAULT_ENDPOINT.to_string()],
    };
    let mut client = Client::connect(&endpoints).ok()?;
    client.timeout = ask_for();
    let robot = client.resolve_robot(None).ok()?;
    client.request(&robot, verb, &json!({})).ok()
}

fn candidates(names: impl IntoIterator<Item = (String, String)>) -> Vec<CompletionCandidate> {
    let mut names: Vec<(String, String)> = names.into_iter().collect();
    names.sort();
    names.dedup_by(|a, b| a.0 == b.0);
    names.into_iter().map(|(name, help)| CompletionCandidate::new(name).help(Some(help.into()))).collect()
}

/// The running robot's skills, each with its type and whether it is active.
pub(crate) fn skills() -> Vec<CompletionCandidate> {
    let Some(Json::Array(skills)) = ask("skills") else { return Vec::new() };
    candidates(skills.iter().filter_map(|s| {
        let name = s["name"].as_str()?.to_string();
        let state = if s["active"].as_bool() == Some(true) { "active" } else { "inactive" };
        Some((name, format!("{} ({state})", s["type_name"].as_str().unwrap_or("?"))))
    }))
}

/// The running robot's parameters, by name (every skill's: the shell does not say which skill
/// the line names), each with the skills that have it.
pub(crate) fn params() -> Vec<CompletionCandidate> {
    let Some(Json::Array(skills)) = ask("skills") else { return Vec::new() };
    let mut by_name = std::collections::BTreeMap::<String, Vec<String>>::new();
    for skill in &skills {
        let Some(owner) = skill["name"].as_str() else { continue };
        for p in skill["params"].as_array().into_iter().flatten() {
            if let Some(name) = p["name"].as_str() {
                by_name.entry(name.to_string()).or_default().push(owner.to_string());
            }
        }
    }
    candidates(by_name.into_iter().map(|(name, owners)| (name, format!("of {}", owners.join(", ")))))
}

/// The robot file on the command line being completed: the first word after the verb that
/// names a file (`situate run robot.yaml --set ru<TAB>`). The shell passes the line's words after
/// a `--` (clap_complete's protocol), which the process's arguments hold whatever runs it (the
/// Rust program, or the Python package's console script).
fn file_on_line() -> Option<std::path::PathBuf> {
    let words: Vec<String> = std::env::args().skip_while(|a| a != "--").skip(1).collect();
    let verb = words.iter().position(|w| ["run", "check", "signals", "graph"].contains(&w.as_str()))?;
    words[verb + 1..].iter().filter(|w| !w.starts_with('-')).map(std::path::PathBuf::from).find(|p| p.is_file())
}

/// `--set` values: the parameters of every skill of the robot file on the line, as
/// `skill.param=`, each with its type and default. The completion loads no Python: a file with
/// `python:` skill files, like one that does not load, gives none.
pub(crate) fn settable() -> Vec<CompletionCandidate> {
    let Some(file) = file_on_line() else { return Vec::new() };
    let ext = crate::Extensions::default();
    let Ok((_, graph)) = crate::robot::static_graph(&file, &crate::args::Compose::default(), &ext) else {
        return Vec::new();
    };
    candidates(graph.instances.iter().flat_map(|inst| {
        inst.skill_type.decl.params.iter().map(move |p| {
            let unit = if p.unit.is_empty() { String::new() } else { format!(" {}", p.unit) };
            let ty = format!("{:?}", p.ty).to_lowercase();
            (format!("{}.{}=", inst.name, p.name), format!("{ty}, default {}{unit}", p.default))
        })
    }))
}

/// The running robot's signals (every leaf, and each record whole), each with its type.
pub(crate) fn signals() -> Vec<CompletionCandidate> {
    let Some(graph) = ask("graph") else { return Vec::new() };
    let mut names = Vec::new();
    for s in graph["signals"].as_array().into_iter().flatten() {
        let (Some(name), Some(ty)) = (s["signal"].as_str(), s["type"].as_str()) else { continue };
        // A record's leaves are signals too (`odom.x`); the record itself (`odom`) is named
        // whole by `echo` and `query`.
        if let Some((record, _)) = name.rsplit_once('.') {
            names.push((record.to_string(), "a record".to_string()));
        }
        names.push((name.to_string(), ty.to_string()));
    }
    candidates(names)
}
