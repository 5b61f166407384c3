//! Robot files: loading one (with what composes it at launch: `include:`,
//! `${ENV}` substitution and `--set`), checking it, starting it, running it until it
//! is told to stop, and serving one skill type out of process.
//!
//! This file loads a robot file; by file: `check` builds its graph without starting anything
//! (`check`, and `signals`/`graph` of a file), `start` starts it (the link, the ROS 2 bridge,
//! the GUI) with the command line's [`RunOptions`], `running` is a started robot and how it
//! stops, `run` is `situate run`, `recording` what a recording keeps and says of itself, and
//! `serve` is `situate serve-skill`.

use std::path::Path;

use situate_link::LinkConfig;
use situate_robotfile::config::RobotFile;
use situate_robotfile::spec::RobotSpec;
use situate_robotfile::yaml::Spanned;

use crate::args::Compose;
use crate::output::{problem, Exit, Problem};

mod check;
mod recording;
mod run;
mod running;
mod serve;
mod start;

pub(crate) use check::{check, static_graph};
pub(crate) use recording::{recording_json, recording_metadata, recording_text};
pub(crate) use run::run_robot;
pub(crate) use serve::serve_skill;
pub(crate) use start::{free_loopback_endpoint, parse_gui_address, start_robot, RunOptions};

/// A robot file read and lifted into what the manager builds from.
pub(crate) struct Loaded {
    pub(crate) file: RobotFile,
    pub(crate) spec: RobotSpec,
    pub(crate) link: LinkConfig,
    /// The `ros2:` bridge's configuration, when the file has one.
    pub(crate) ros2: Option<situate_ros2::Ros2Config>,
    pub(crate) remote: Vec<(String, situate_core::SkillDecl)>,
}

/// Reads a robot file and those it includes (their `${NAME}`s replaced from the environment),
/// applies `--set`, and checks its `link:` and remote skills. Every problem
/// is a [`Problem`] of kind [`Exit::BadFile`] (or [`Exit::Usage`] for a bad `--set`).
pub(crate) fn load(path: &Path, compose: &Compose) -> anyhow::Result<Loaded> {
    let env = |name: &str| std::env::var(name).ok();
    let options = situate_robotfile::config::LoadOptions { env: Some(&env) };
    let mut robot_file = RobotFile::load_with(path, options).map_err(|errors| bad_file(path, &errors))?;
    apply_sets(&mut robot_file, &compose.set)?;
    let link = match &robot_file.link {
        None => LinkConfig::default(),
        Some(node) => match LinkConfig::from_node(node) {
            // What `run` gives Zenoh is checked here too, so `check` and `run` agree.
            Ok(l) => match l.zenoh_config() {
                Ok(_) => l,
                Err(e) => {
                    let at = node
                        .value
                        .as_map()
                        .and_then(|m| m.iter().find(|(k, _)| k.value == "zenoh").map(|(_, v)| v.pos))
                        .unwrap_or(node.pos);
                    let e = crate::output::clean(&e.to_string());
                    return Err(bad_file(
                        path,
                        &[robot_file.error(at, format!("`link`: Zenoh refuses this configuration: {e}"))],
                    ));
                }
            },
            Err(errors) => {
                let lines: Vec<_> = errors.into_iter().map(|e| robot_file.locate(e, node.pos)).collect();
                return Err(bad_file(path, &lines));
            }
        },
    };
    let ros2 = match &robot_file.ros2 {
        None => None,
        Some(node) => match situate_ros2::Ros2Config::from_node(node) {
            Ok(c) => Some(c),
            Err(e) => return Err(bad_file(path, &[robot_file.locate(e, node.pos)])),
        },
    };
    let remote = robot_file.remote_decls().map_err(|errors| bad_file(path, &errors))?;
    Ok(Loaded { spec: RobotSpec::from_file(&robot_file), link, ros2, remote, file: robot_file })
}

/// A file's problems, each on its line, then the count.
pub(crate) fn bad_file(path: &Path, errors: &[impl std::fmt::Display]) -> anyhow::Error {
    Problem::bad_file(path, errors.iter().map(ToString::to_string).collect()).into()
}

/// `--set SKILL.PARAM=VALUE`: the value (YAML: a scalar or a list of
/// numbers) replaces the file's, or is added; the manager then checks it
/// against the parameter's declaration like a value written in the file.
fn apply_sets(robot_file: &mut RobotFile, sets: &[String]) -> anyhow::Result<()> {
    for set in sets {
        let usage = |why: String| problem(Exit::Usage, format!("--set {set}: {why}"));
        let Some((target, text)) = set.split_once('=') else {
            return Err(usage("expected SKILL.PARAM=VALUE, e.g. runaway.safe_distance=0.3".into()));
        };
        let Some((skill, param)) = target.trim().split_once('.') else {
            return Err(usage(format!("`{target}` is not SKILL.PARAM")));
        };
        let node = situate_robotfile::yaml::parse(text).map_err(|e| usage(format!("the value: {}", e.message)))?;
        let value = node
            .value
            .to_value()
            .or_else(|| node.value.to_f64s())
            .ok_or_else(|| usage("the value is not a scalar or a list of numbers".into()))?;
        let names: Vec<String> = robot_file.skills.iter().map(|e| e.name.value.clone()).collect();
        let Some(entry) = robot_file.skills.iter_mut().find(|e| e.name.value == skill) else {
            return Err(usage(format!(
                "no skill or device `{skill}` in {}{}",
                robot_file.file,
                situate_core::suggestion(skill, names.iter().map(String::as_str))
            )));
        };
        let written = Some(text.trim().to_string());
        match entry.params.iter_mut().find(|p| p.name.value == param) {
            Some(p) => {
                p.value = Spanned::new(value, p.value.pos);
                p.written = written;
            }
            None => entry.params.push(situate_robotfile::config::Param {
                name: Spanned::new(param.to_string(), entry.pos),
                value: Spanned::new(value, entry.pos),
                written,
            }),
        }
    }
    Ok(())
}
