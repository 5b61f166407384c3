//! The static checks of `situate check`, end to end from YAML text:
//! `RobotFile::parse` → `RobotSpec::from_file` → `Graph::build`, asserting
//! the full `FILE:LINE:COL: error: …` line of every diagnostic.
//!
//! Tests marked `#[ignore]` describe the behaviour we want where the current
//! one is wrong or unhelpful; each reason names the problem.
//!
//! The robot files' skill types and the helpers that check them are here; the tests are
//! grouped by concern in the modules: `entries`, what one entry of a file gets wrong (its
//! skill type and section, its name, its parameters, its remaps); `wiring`, how the skills
//! connect (inputs nobody provides, types, resources, data-flow loops); `whole_file`, several
//! errors in one file, and a valid robot.

#[path = "../common/mod.rs"]
mod common;
mod entries;
mod whole_file;
mod wiring;

use common::*;
use situate_core::{SkillDecl, SkillKind, SkillType};
use situate_manager::{Graph, Registry, RobotFile, RobotSpec, Severity, SkillSpec};

/// A skill type that does nothing: these tests only wire and check.
fn idle(d: SkillDecl) -> SkillType {
    fn_type(d, |_, _| Ok(()))
}

fn sync(name: &str, inputs: &[(&str, &str)], outputs: &[(&str, &str)]) -> SkillDecl {
    decl(name, SkillKind::Sync, inputs, outputs)
}

/// The skill types the robot files below name.
fn registry() -> Registry {
    let mut r = Registry::new();
    let drive = "{v: f64, w: f64}";
    for d in [
        // Scalars on one signal, `level`.
        sync("test.source", &[], &[("level", "f64")]),
        sync("test.sink", &[("level", "f64")], &[]),
        sync("test.monitor", &[("level", "f64?")], &[]),
        sync("test.label", &[("label", "string")], &[]),
        with_priority(sync("test.count", &[], &[("level", "i64")]), 1),
        sync("test.pass", &[("x", "f64")], &[("y", "f64")]),
        with_param(sync("test.gain", &[], &[]), "max_speed", 1.0, 0.0, 2.0),
        // Arrays.
        decl("test.ranger", SkillKind::Device, &[], &[("range", "f32[24]")]),
        sync("test.scan_src", &[], &[("scan", "f32[]")]),
        sync("test.scan_any", &[("scan", "f32[]")], &[]),
        sync("test.scan_fixed", &[("scan", "f32[24]")], &[]),
        // Records and their fields.
        sync("test.pose_x", &[], &[("x", "f64")]),
        sync("test.pose_y", &[], &[("y", "f64")]),
        sync("test.pose_value", &[], &[("pose", "f64")]),
        sync("test.pose_user", &[("pose", "{x: f64, y: f64}")], &[]),
        // Resources: `speed` (a scalar) and `drive` (a record).
        with_priority(sync("test.cruise", &[], &[("speed", "f64")]), 5),
        with_priority(sync("test.avoid", &[], &[("speed", "f64")]), 5),
        with_priority(sync("test.stop", &[], &[("speed", "f64")]), 9),
        with_priority(sync("test.steer", &[], &[("drive", drive)]), 5),
        with_priority(sync("test.dodge", &[], &[("drive", drive)]), 5),
        decl("test.wheels", SkillKind::Device, &[("drive", "{v: f64, w: f64}?")], &[("odom", "{x: f64, y: f64}")]),
        // A device with a command in and a reading out.
        decl("test.servo", SkillKind::Device, &[("command", "f64?")], &[("reading", "f64")]),
    ] {
        r.add(idle(d));
    }
    r
}

/// Reads, lifts and builds `src` as `robot.yaml`; every diagnostic as text.
fn check(src: &str) -> Result<Graph, Vec<String>> {
    let file =
        RobotFile::parse("robot.yaml", src).map_err(|es| es.iter().map(ToString::to_string).collect::<Vec<_>>())?;
    let spec = RobotSpec::from_file(&file);
    Graph::build(&spec, &registry()).map_err(|e| e.diagnostics.iter().map(ToString::to_string).collect())
}

fn errors(src: &str) -> Vec<String> {
    match check(src) {
        Ok(g) => panic!("expected errors, the robot built with {} instances", g.instances.len()),
        Err(errors) => errors,
    }
}

/// The only diagnostic for `src`.
fn error(src: &str) -> String {
    let errors = errors(src);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    errors.into_iter().next().unwrap()
}

fn graph(src: &str) -> Graph {
    match check(src) {
        Ok(g) => g,
        Err(errors) => panic!("expected a valid robot, got:\n{}", errors.join("\n")),
    }
}
