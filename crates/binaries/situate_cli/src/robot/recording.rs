//! What a recording keeps of how the robot was built (its metadata, for `situate replay`),
//! and a finished recording said (in JSON and in one line).

use std::path::Path;

use serde_json::{json, Value as Json};
use situate_robotfile::config::ClockKind;

use crate::sim::Simulation;

/// What a recording keeps of how the robot was built, for `situate replay`:
/// the robot file (absolute), the `--set`s given, the clock, and the
/// simulator's building and seed (for the GUI's world view of a replay).
pub(crate) fn recording_metadata(
    file: &Path,
    sets: &[String],
    clock: ClockKind,
    sim: Option<&Simulation>,
) -> std::collections::BTreeMap<String, String> {
    let file = std::fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
    let mut meta = std::collections::BTreeMap::new();
    meta.insert("robot_file".to_string(), file.display().to_string());
    meta.insert("sets".to_string(), serde_json::to_string(sets).unwrap_or_default());
    let clock = match clock {
        ClockKind::Simulated => "simulated",
        ClockKind::Wall => "wall",
    };
    meta.insert("clock".to_string(), clock.to_string());
    if let Some(sim) = sim {
        meta.insert("world".to_string(), sim.map.world_json().to_string());
        meta.insert("seed".to_string(), sim.seed.to_string());
        meta.insert("map_file".to_string(), sim.map_path.display().to_string());
    }
    meta
}

/// A finished recording in JSON (`"recording"` of `run` and `demo`).
pub(crate) fn recording_json(r: &situate_record::Summary) -> Json {
    json!({
        "path": r.path.display().to_string(),
        "cycles": r.frames,
        "first_cycle": r.cycles.map(|c| c.0),
        "last_cycle": r.cycles.map(|c| c.1),
        "messages": r.messages,
        "channels": r.channels,
        "dropped_cycles": r.dropped,
        "bytes": r.bytes,
    })
}

/// A finished recording, one line.
pub(crate) fn recording_text(r: &situate_record::Summary) -> String {
    let size = if r.bytes >= 1_000_000 {
        format!("{:.1} MB", r.bytes as f64 / 1e6)
    } else {
        format!("{:.1} kB", r.bytes as f64 / 1e3)
    };
    format!(
        "recorded {} cycles ({} messages on {} channels, {size}{}) to {}\n",
        r.frames,
        r.messages,
        r.channels,
        if r.dropped > 0 { format!("; {} cycles dropped: the disk did not keep up", r.dropped) } else { String::new() },
        r.path.display()
    )
}
