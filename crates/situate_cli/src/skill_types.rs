//! The skill types a robot can name: the program's own (the toys, the standard
//! library `std.*`, and a host's Rust types, [`Extensions::skills`], whose names
//! must be new), the simulator's devices for a robot file with a `simulator:`,
//! and those of `--library`/`--python` files or of a robot file's `libraries:`
//! and `python:` (errors at their line).

use std::path::{Path, PathBuf};

use situate::manager::{Registry, RobotFile};

use crate::output::{problem, Exit};
use crate::sim::{simulation, SimOverrides, Simulation};
use crate::Extensions;

/// The program's skill types and those of `--library` and `--python` files.
pub(crate) fn registry_with(libraries: &[PathBuf], python: &[PathBuf], ext: &Extensions) -> anyhow::Result<Registry> {
    let mut registry = program_registry(ext)?;
    for path in libraries {
        for t in load_library(path).map_err(|e| problem(Exit::BadFile, format!("--library {}: {e}", path.display())))? {
            registry.add(t);
        }
    }
    for path in python {
        let loader = ext.python.as_ref().ok_or_else(|| {
            problem(
                Exit::Usage,
                format!(
                    "--python {}: Python skills run in the Python package's `situate` (`make python`, then \
                     `.venv/bin/situate`); this binary has no Python inside",
                    path.display()
                ),
            )
        })?;
        for t in loader(path).map_err(|e| problem(Exit::BadFile, format!("--python {}: {e}", path.display())))? {
            registry.add(t);
        }
    }
    Ok(registry)
}

/// The skill types a robot file can name: the program's ([`program_registry`]), the
/// simulator's devices when it has a `simulator:` section, then the file's
/// own `libraries:` and `python:` files. Errors name the file's line.
pub(crate) fn registry_for(
    robot_file: &RobotFile,
    mut registry: Registry,
    ext: &Extensions,
    over: &SimOverrides,
) -> Result<(Registry, Option<Simulation>), Vec<String>> {
    let sim = simulation(robot_file, over)?;
    if let Some(sim) = &sim {
        situate_sim::register(&mut registry, sim.world.clone());
    }
    let mut errors = Vec::new();
    for lib in &robot_file.libraries {
        let path = robot_file.resolve_at(lib.pos, &lib.value);
        match load_library(&path) {
            Ok(types) => {
                for t in types {
                    registry.add(t);
                }
            }
            Err(e) => errors.push(robot_file.error(lib.pos, e).to_string()),
        }
    }
    for py in &robot_file.python {
        let path = robot_file.resolve_at(py.pos, &py.value);
        let result = match &ext.python {
            Some(loader) => loader(&path),
            None => Err(format!(
                "`{}`: Python skills run in the Python package's `situate` (install the wheel: `make python`, \
                 then `.venv/bin/situate`); this binary has no Python inside",
                py.value
            )),
        };
        match result {
            Ok(types) => {
                for t in types {
                    registry.add(t);
                }
            }
            Err(e) => errors.push(robot_file.error(py.pos, e).to_string()),
        }
    }
    if errors.is_empty() {
        Ok((registry, sim))
    } else {
        Err(errors)
    }
}

/// The skill types every robot file can name: the toys and the standard
/// skill library (`std.*`).
fn builtin_registry() -> Registry {
    let mut registry = situate_toys::registry();
    situate_skills::register(&mut registry);
    registry
}

/// Type-name prefixes that belong to the program: the standard library's and
/// the simulator's (whose devices are registered only for a robot file with
/// a `simulator:`, so a host's type is refused there even when none is named so yet).
const RESERVED_PREFIXES: [&str; 2] = ["std.", "sim."];

/// A host's Rust skill type ([`Extensions::skills`]) whose name is taken.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub(crate) enum NameClash {
    #[error(
        "the program's Rust skill type `{0}` has the name of a built-in skill type; give it a name of its own \
         in its #[skill(name = ...)]"
    )]
    BuiltIn(String),
    #[error(
        "the program's Rust skill type `{0}`: names starting with `{1}` belong to {2}; give it a name of its own \
         in its #[skill(name = ...)]"
    )]
    Reserved(String, &'static str, &'static str),
    #[error("the program's Rust skill type `{0}` is registered by two `Extensions::skills` calls")]
    Twice(String),
}

/// The built-in skill types and the host's Rust ones ([`Extensions::skills`]),
/// whose names must be new ([`NameClash`]).
pub(crate) fn program_registry(ext: &Extensions) -> anyhow::Result<Registry> {
    with_rust_skills(builtin_registry(), ext).map_err(|e| problem(Exit::Failure, e.to_string()))
}

fn with_rust_skills(mut registry: Registry, ext: &Extensions) -> Result<Registry, NameClash> {
    let builtin: std::collections::BTreeSet<String> = registry.names().map(str::to_string).collect();
    for register in &ext.rust {
        let mut added = Registry::new();
        register(&mut added);
        for name in added.names() {
            if builtin.contains(name) {
                return Err(NameClash::BuiltIn(name.to_string()));
            }
            if let Some(prefix) = RESERVED_PREFIXES.iter().find(|p| name.starts_with(*p)) {
                let owner = if *prefix == "std." { "the standard skill library" } else { "the simulator's devices" };
                return Err(NameClash::Reserved(name.to_string(), prefix, owner));
            }
            if registry.get(name).is_some() {
                return Err(NameClash::Twice(name.to_string()));
            }
        }
        for name in added.names() {
            if let Some(t) = added.get(name) {
                registry.add(t.clone());
            }
        }
    }
    Ok(registry)
}

fn load_library(path: &Path) -> Result<Vec<situate_core::SkillType>, String> {
    situate_cabi::load_library(path).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate::prelude::*;

    #[derive(Skill, Default)]
    #[skill(name = "toy.wander")]
    struct LikeWander {
        #[output]
        x: f64,
    }

    #[derive(Skill, Default)]
    #[skill(name = "sim.mine")]
    struct UnderSim {
        #[output]
        x: f64,
    }

    #[derive(Skill, Default)]
    #[skill(name = "mine.own")]
    struct Own {
        #[output]
        x: f64,
    }

    impl Body for LikeWander {
        fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
            Ok(())
        }
    }

    impl Body for UnderSim {
        fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
            Ok(())
        }
    }

    impl Body for Own {
        fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
            Ok(())
        }
    }

    fn with(register: impl Fn(&mut Registry) + Send + Sync + 'static) -> Result<Registry, NameClash> {
        with_rust_skills(builtin_registry(), &Extensions::default().skills(register))
    }

    #[test]
    fn a_hosts_own_type_joins_the_built_in_ones() {
        let registry = with(|r| {
            r.register::<Own>();
        })
        .expect("a new name");
        assert!(registry.get("mine.own").is_some());
        assert!(registry.get("toy.wander").is_some() && registry.get("std.wander").is_some());
    }

    #[test]
    fn a_taken_name_is_an_error_naming_the_type() {
        let built_in = with(|r| {
            r.register::<LikeWander>();
        });
        assert_eq!(built_in.as_ref().err(), Some(&NameClash::BuiltIn("toy.wander".into())));
        let text = built_in.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(text.contains("`toy.wander` has the name of a built-in skill type"), "{text}");
        let reserved = with(|r| {
            r.register::<UnderSim>();
        });
        let text = reserved.err().map(|e| e.to_string()).unwrap_or_default();
        assert!(text.contains("`sim.mine`: names starting with `sim.` belong to the simulator's devices"), "{text}");
        let ext = Extensions::default()
            .skills(|r| {
                r.register::<Own>();
            })
            .skills(|r| {
                r.register::<Own>();
            });
        let twice = with_rust_skills(builtin_registry(), &ext);
        assert_eq!(twice.err(), Some(NameClash::Twice("mine.own".into())));
    }
}
