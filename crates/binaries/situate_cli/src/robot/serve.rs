//! `situate serve-skill`: one instance of a skill type, served out of process to a running
//! robot until Ctrl-C.

use std::path::PathBuf;

use serde_json::json;

use crate::client::{client_verb, Remote};
use crate::output::{problem, Exit, Out};
use crate::signals;
use crate::skill_types::registry_with;
use crate::Extensions;

/// `situate serve-skill`: one instance of a skill type, served out of
/// process until Ctrl-C (docs/protocol.md, "Remote skills").
pub(crate) fn serve_skill(
    skill: &str,
    name: Option<String>,
    libraries: &[PathBuf],
    python: &[PathBuf],
    remote: &Remote,
    ext: &Extensions,
    out: Out,
) -> anyhow::Result<()> {
    if skill.contains(':') {
        return Err(problem(
            Exit::Usage,
            format!(
                "`{skill}` names a Python function (MODULE:FUNCTION): serve it with the `situate` that the Python \
                 package installs (scripts/python.sh, then .venv/bin/situate serve-skill {skill} --robot ROBOT)"
            ),
        ));
    }
    let registry = registry_with(libraries, python, ext)?;
    let Some(ty) = registry.get(skill) else {
        let known: Vec<&str> = registry.names().collect();
        return Err(problem(
            Exit::Usage,
            format!(
                "no skill type `{skill}`{}; give the library that defines it with --library (known here: {})",
                situate_core::suggestion(skill, known.iter().copied()),
                known.join(", ")
            ),
        ));
    };
    let name = name.unwrap_or_else(|| skill.rsplit('.').next().unwrap_or(skill).to_string());
    client_verb(remote, |client, robot| {
        let stop = signals::Stop::install()?;
        // The body runs on this thread: one that never returns is left behind.
        let stuck = format!(
            "`{name}`'s body did not return within {} of the stop request; exiting without it",
            signals::bound_text()
        );
        let watchdog = stop.watchdog(move || stuck);
        let stats =
            situate_link::serve_skill(client.session(), robot, &name, ty, registry.resources(), stop.flag(), || {
                out.note(format_args!(
                    "serving `{name}` (type `{skill}`) of robot `{robot}` on situate/{robot}/remote/{name}/inputs; \
                 Ctrl-C stops"
                ));
            });
        drop(watchdog);
        let s = stats.map_err(|e| problem(Exit::Failure, e.to_string()))?;
        let stopped_by = stop.signal().map(signals::name);
        let result = json!({
            "skill": name, "type": skill, "robot": robot, "signal": stopped_by,
            "received": s.received, "computed": s.computed, "dropped": s.dropped, "errors": s.errors,
        });
        if out.json {
            stdoutln!("{result}");
        } else {
            out.note(format_args!(
                "stopped{}; {} inputs received, {} runs, {} dropped as stale, {} errors",
                stopped_by.map(|s| format!(" ({s})")).unwrap_or_default(),
                s.received,
                s.computed,
                s.dropped,
                s.errors
            ));
        }
        Ok(())
    })
}
