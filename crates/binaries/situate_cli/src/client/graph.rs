//! The signals and the data-flow graph of a robot (`signals`, `graph`): of a robot file,
//! built without running anything, or asked of the running robot; as text, or as
//! Graphviz's dot language.

use std::path::Path;

use serde_json::{json, Value as Json};

use super::command::Remote;
use super::connect::client_verb;
use crate::args::Compose;
use crate::output::{problem, Exit};
use crate::Extensions;

/// The protocol's `graph` object: of a robot file, built here without
/// running anything, or asked of the running robot.
pub(super) fn graph_json(
    file: Option<&Path>,
    compose: &Compose,
    remote: &Remote,
    ext: &Extensions,
) -> anyhow::Result<Json> {
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

/// One line a signal: `sonar.range  f32[24]  written by sonar  read by runaway, wander`.
pub(super) fn signals_text(signals: &Json) -> String {
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
pub(super) fn graph_text(graph: &Json) -> String {
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
pub(super) fn graph_dot(graph: &Json) -> String {
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
