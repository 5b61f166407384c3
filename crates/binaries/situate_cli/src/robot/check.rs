//! A robot file's graph, built without starting anything: `situate check`, and the
//! `signals FILE` and `graph FILE` of the client verbs; the same checks `run` makes.

use std::path::Path;

use serde_json::json;

use super::start::{gui_address, RunOptions};
use super::{bad_file, load, Loaded};
use crate::args::Compose;
use crate::map;
use crate::output::{Out, Problem};
use crate::sim::SimOverrides;
use crate::skill_types::{program_registry, registry_for};
use crate::Extensions;

/// A robot file's graph, built without starting anything (`check`,
/// `signals FILE`, `graph FILE`): the same checks `run` makes.
pub(crate) fn static_graph(
    file: &Path,
    compose: &Compose,
    ext: &Extensions,
) -> anyhow::Result<(Loaded, situate::manager::Graph)> {
    if map::looks_like_map(file) {
        return Err(Problem::file_problem(format!(
            "{}: this is a map file: use `situate map check {}`",
            file.display(),
            file.display()
        ))
        .into());
    }
    let mut loaded = load(file, compose)?;
    let (mut registry, _sim) = registry_for(&loaded.file, program_registry(ext)?, ext, &SimOverrides::default())
        .map_err(|errors| bad_file(file, &errors))?;
    crate::ros2::add_devices(&mut loaded.spec, &mut registry, loaded.ros2.as_ref());
    // Every section `run` reads is checked by the code `run` uses.
    gui_address(&loaded.file, &RunOptions::default()).map_err(|e| bad_file(file, &[e]))?;
    for (_, decl) in &loaded.remote {
        // Checking needs the declaration only; nothing is created.
        registry.add(situate_core::SkillType::new(decl.clone(), || Err("not created by `check`".into())));
    }
    match situate::manager::Graph::build(&loaded.spec, &registry) {
        Ok(graph) => Ok((loaded, graph)),
        Err(e) => Err(build_failure(file, &e)),
    }
}

/// The manager's diagnostics (errors and warnings), then the count of errors.
pub(super) fn build_failure(file: &Path, e: &situate_robotfile::spec::BuildError) -> anyhow::Error {
    let n = e.diagnostics.iter().filter(|d| d.is_error()).count();
    let mut p = Problem::bad_file(file, e.diagnostics.iter().map(ToString::to_string).collect());
    p.message = format!("{}: {n} error{}", file.display(), if n == 1 { "" } else { "s" });
    p.into()
}

/// `situate check`.
pub(crate) fn check(file: &Path, compose: &Compose, ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let (_loaded, graph) = static_graph(file, compose, ext)?;
    let warnings: Vec<String> = graph.warnings.iter().map(ToString::to_string).collect();
    if !out.json {
        for w in &warnings {
            out.warn(w);
        }
    }
    let n = graph.instances.len();
    let result = json!({
        "file": file.display().to_string(),
        "ok": true,
        "robot": graph.robot,
        "skills": n,
        "signal_leaves": graph.leaves.len(),
        "warnings": warnings,
    });
    out.result(&result, || {
        format!(
            "{}: ok — robot `{}`, {n} skill{}, {} signal leaves",
            file.display(),
            graph.robot,
            if n == 1 { "" } else { "s" },
            graph.leaves.len()
        )
    });
    Ok(())
}
