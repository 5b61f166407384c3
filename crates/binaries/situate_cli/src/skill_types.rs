//! The skill types a robot can name: the program's own (the toys, the standard
//! library `std.*`, and a host's Rust types, [`Extensions::skills`], whose names
//! must be new), the simulator's devices for a robot file with a `simulator:`,
//! and those of `--library`/`--python` files or of a robot file's `libraries:`
//! and `python:` (errors at their line).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use situate::manager::Registry;
use situate_core::SkillType;
use situate_robotfile::config::RobotFile;

use crate::output::{problem, Exit};
use crate::sim::{simulation, SimOverrides, Simulation};
use crate::Extensions;

/// Where each skill type came from, so that a file that brings a name again is refused
/// (it used to replace the first silently), naming both. A file loaded twice (the same path,
/// say through two `include:`d robot files) adds nothing the second time.
pub struct Origins {
    by_name: BTreeMap<String, String>,
    files: BTreeSet<PathBuf>,
}

impl Origins {
    /// The registry's types so far, all from `origin`.
    pub fn of(registry: &Registry, origin: &str) -> Origins {
        let by_name = registry.names().map(|n| (n.to_string(), origin.to_string())).collect();
        Origins { by_name, files: BTreeSet::new() }
    }

    /// Whether `path` is new (and from now on known).
    pub fn first_load(&mut self, path: &Path) -> bool {
        self.files.insert(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()))
    }

    /// Adds a file's types (`from`: how it is named), all or none: none when one of them has a
    /// name taken already.
    pub fn add(&mut self, registry: &mut Registry, types: Vec<SkillType>, from: &str) -> Result<(), String> {
        let mut names = BTreeSet::new();
        for t in &types {
            let name = &t.decl.type_name;
            if let Some(origin) = self.by_name.get(name) {
                return Err(format!(
                    "skill type `{name}` is defined already by {origin}; a file cannot replace it: give the \
                     type in {from} a name of its own"
                ));
            }
            if !names.insert(name.clone()) {
                return Err(format!("{from} defines skill type `{name}` twice"));
            }
        }
        for t in types {
            self.by_name.insert(t.decl.type_name.clone(), from.to_string());
            registry.add(t);
        }
        Ok(())
    }
}

/// How the program's own skill types are named in a clash.
pub const THE_PROGRAM: &str = "the program (a built-in or the program's own Rust type)";

/// The program's skill types and those of `--library` and `--python` files.
pub(crate) fn registry_with(libraries: &[PathBuf], python: &[PathBuf], ext: &Extensions) -> anyhow::Result<Registry> {
    let mut registry = program_registry(ext)?;
    let mut origins = Origins::of(&registry, THE_PROGRAM);
    for path in libraries {
        let from = format!("--library {}", path.display());
        let types = load_library(path).map_err(|e| problem(Exit::BadFile, format!("{from}: {e}")))?;
        if origins.first_load(path) {
            origins.add(&mut registry, types, &from).map_err(|e| problem(Exit::BadFile, format!("{from}: {e}")))?;
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
        let from = format!("--python {}", path.display());
        let types = loader(path).map_err(|e| problem(Exit::BadFile, format!("{from}: {e}")))?;
        if origins.first_load(path) {
            origins.add(&mut registry, types, &from).map_err(|e| problem(Exit::BadFile, format!("{from}: {e}")))?;
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
    let mut origins = Origins::of(&registry, THE_PROGRAM);
    if let Some(sim) = &sim {
        let mut devices = Registry::new();
        situate_sim::register(&mut devices, sim.world.clone());
        for name in devices.names() {
            if let Some(t) = devices.get(name) {
                origins.by_name.insert(name.to_string(), "the simulator (its devices)".to_string());
                registry.add(t.clone());
            }
        }
        // The world they are made with.
        registry.provide_all(devices.resources());
    }
    let mut errors = Vec::new();
    for lib in &robot_file.libraries {
        let path = robot_file.resolve_at(lib.pos, &lib.value);
        let from = format!("`{}`", lib.value);
        let added = load_library(&path).and_then(|types| match origins.first_load(&path) {
            true => origins.add(&mut registry, types, &from),
            false => Ok(()),
        });
        if let Err(e) = added {
            errors.push(robot_file.error(lib.pos, e).to_string());
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
        let from = format!("`{}`", py.value);
        let added = result.and_then(|types| match origins.first_load(&path) {
            true => origins.add(&mut registry, types, &from),
            false => Ok(()),
        });
        if let Err(e) = added {
            errors.push(robot_file.error(py.pos, e).to_string());
        }
    }
    if errors.is_empty() {
        Ok((registry, sim))
    } else {
        Err(errors)
    }
}

/// The skill types `situate run` gives a robot file, for a host that runs the robot in its own
/// process (the Python package's `situate.LocalRobot`): the built-ins (`toy.*`, `std.*`), the
/// host's Rust types, the simulator's devices over a world of their own when the file has a
/// `simulator:` section (its map and seed), and the types of the file's `libraries:` and
/// `python:` files. Each error names the file and line it is about.
pub fn robot_registry(robot_file: &RobotFile, ext: &Extensions) -> Result<Registry, Vec<String>> {
    let registry = program_registry(ext).map_err(|e| vec![format!("{e:#}")])?;
    registry_for(robot_file, registry, ext, &SimOverrides::default()).map(|(registry, _sim)| registry)
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
        // And the resources its types are made with.
        registry.provide_all(added.resources());
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

    #[test]
    fn a_file_that_brings_a_type_name_again_is_refused_naming_both_and_adds_nothing() {
        let mut registry = builtin_registry();
        let mut origins = Origins::of(&registry, THE_PROGRAM);
        // A file's types join when their names are new.
        origins.add(&mut registry, vec![SkillType::of::<Own>()], "`a.py`").expect("a new name");
        assert!(registry.get("mine.own").is_some());
        // Another file with a taken name: refused, naming where the name came from; its other
        // types are not added either.
        let clash = origins.add(&mut registry, vec![SkillType::of::<UnderSim>(), SkillType::of::<Own>()], "`b.py`");
        let text = clash.expect_err("a taken name");
        assert!(text.contains("skill type `mine.own` is defined already by `a.py`"), "{text}");
        assert!(text.contains("give the type in `b.py` a name of its own"), "{text}");
        assert!(registry.get("sim.mine").is_none(), "all or nothing");
        // A built-in name: the program's.
        let text = origins.add(&mut registry, vec![SkillType::of::<LikeWander>()], "`c.py`").expect_err("built in");
        assert!(text.contains("`toy.wander` is defined already by the program"), "{text}");
        // One file with a name twice.
        let text = origins
            .add(&mut registry, vec![SkillType::of::<UnderSim>(), SkillType::of::<UnderSim>()], "`d.py`")
            .expect_err("twice");
        assert!(text.contains("`d.py` defines skill type `sim.mine` twice"), "{text}");
        // The same file again (two included robot files list it): loaded once.
        let here = std::env::current_dir().expect("a working directory");
        assert!(origins.first_load(&here.join("Cargo.toml")));
        assert!(!origins.first_load(Path::new("Cargo.toml")), "the same file by another path");
    }
}
