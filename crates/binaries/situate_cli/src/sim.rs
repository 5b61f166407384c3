//! The simulated world a robot file runs in: its `simulator:` section, with
//! the command line's overrides (`--map`, `--seed`, `--people`,
//! `--door-closures`, `--dead-sonar`).

use std::path::PathBuf;
use std::sync::Arc;

use situate_robotfile::config::{ConfigError, RobotFile};
use situate_robotfile::yaml::{Node, Spanned};

/// The simulated building a robot file runs in (its `simulator:` section).
pub struct Simulation {
    pub map_path: PathBuf,
    pub map: situate_sim::Map,
    pub world: situate_sim::SharedWorld,
    pub seed: u64,
}

/// Overrides of a robot file's `simulator:` section from the command line.
#[derive(Default, Clone)]
pub(crate) struct SimOverrides {
    pub map: Option<PathBuf>,
    pub seed: Option<u64>,
    pub world: WorldArgs,
}

/// Most people per floor (`simulator: {people: N}`, `--people N`).
const MAX_PEOPLE: u64 = 100;

/// What real buildings have, on the command line (`run`, `demo`): each
/// overrides the robot file's `simulator:` key.
#[derive(clap::Args, Default, Clone, Debug)]
pub(crate) struct WorldArgs {
    /// People walking on every floor of the simulated building (this many per floor).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(0..=MAX_PEOPLE))]
    people: Option<u64>,
    /// The map's doors close now and then (one at a time, 20-60 s).
    #[arg(long)]
    door_closures: bool,
    /// A dead sonar (0-23): it always reads max_range. Repeatable; replaces the file's list.
    #[arg(long = "dead-sonar", value_name = "I", value_parser = clap::value_parser!(u8).range(0..24))]
    dead_sonars: Vec<u8>,
}

impl WorldArgs {
    pub(crate) fn any(&self) -> bool {
        self.people.is_some() || self.door_closures || !self.dead_sonars.is_empty()
    }

    /// The same settings as command-line arguments (for the physics robot's program, which
    /// takes them as `situate demo` does).
    pub(crate) fn to_args(&self) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(n) = self.people {
            out.extend(["--people".to_string(), n.to_string()]);
        }
        if self.door_closures {
            out.push("--door-closures".to_string());
        }
        for k in &self.dead_sonars {
            out.extend(["--dead-sonar".to_string(), k.to_string()]);
        }
        out
    }
}

/// The building a robot that simulates none is shown in: `--map` given with a robot file
/// without `simulator:` (a ROS 2 robot whose simulator is a program of its own, such as the
/// physics robot). The GUI's world view and a recording's `world` show it there; nothing of
/// the 2-D simulator runs. `None` when no `--map` was given or the file has a simulator.
pub(crate) fn shown_building(
    robot_file: &RobotFile,
    over: &SimOverrides,
) -> Result<Option<(PathBuf, situate_sim::Map)>, Vec<String>> {
    let (None, Some(path)) = (&robot_file.simulator, &over.map) else { return Ok(None) };
    let map = situate_sim::load_map(path).map_err(|e| vec![format!("--map: {e}")])?;
    Ok(Some((path.clone(), map)))
}

/// Reads `simulator: {map: FILE, seed: N}` and builds the world.
pub(crate) fn simulation(robot_file: &RobotFile, over: &SimOverrides) -> Result<Option<Simulation>, Vec<String>> {
    let Some(node) = &robot_file.simulator else {
        // `--map` alone names the building the robot is shown in (`shown_building`).
        if over.seed.is_some() {
            return Err(vec![format!("{}: --seed needs a robot file with a `simulator:` section", robot_file.file)]);
        }
        if over.world.any() {
            return Err(vec![format!(
                "{}: --people, --door-closures and --dead-sonar need a robot file with a `simulator:` section",
                robot_file.file
            )]);
        }
        return Ok(None);
    };
    let mut errors = Vec::new();
    let mut map_path = None;
    // Where the robot file names the map: a map's error is reported there too.
    let mut map_at = None;
    let mut seed = 1u64;
    let mut cfg = situate_sim::WorldConfig::default();
    match node.value.as_map() {
        Some(entries) => {
            for (key, value) in entries {
                match key.value.as_str() {
                    "map" => match value.value.as_text() {
                        Some(p) => {
                            map_path = Some(robot_file.resolve_at(value.pos, p));
                            map_at = Some(value.pos);
                        }
                        None => errors.push(robot_file.error(value.pos, "`map` expects the path of a map file")),
                    },
                    "seed" => match value.value.as_i64().filter(|s| *s >= 0) {
                        Some(n) => seed = n as u64,
                        None => errors.push(robot_file.error(value.pos, "`seed` expects a whole number ≥ 0")),
                    },
                    "people" => match value.value.as_i64().filter(|n| (0..=MAX_PEOPLE as i64).contains(n)) {
                        Some(n) => cfg.people = n as usize,
                        None => errors.push(robot_file.error(
                            value.pos,
                            format!("`people` expects a whole number of people per floor, 0 to {MAX_PEOPLE}"),
                        )),
                    },
                    "door_closures" => match value.value.as_bool() {
                        Some(b) => cfg.door_closures = b,
                        None => errors.push(robot_file.error(value.pos, "`door_closures` expects `true` or `false`")),
                    },
                    "dead_sonars" => match dead_sonars(robot_file, value) {
                        Ok(list) => cfg.dead_sonars = list,
                        Err(e) => errors.push(e),
                    },
                    other => errors.push(robot_file.error(
                        key.pos,
                        format!(
                            "unknown key `{other}` in `simulator`{}",
                            situate_core::suggestion(other, ["map", "seed", "people", "door_closures", "dead_sonars"])
                        ),
                    )),
                }
            }
        }
        None => errors.push(robot_file.error(node.pos, "`simulator` expects a mapping with `map:` and `seed:`")),
    }
    if let Some(m) = &over.map {
        map_path = Some(m.clone());
        map_at = None;
    }
    if let Some(s) = over.seed {
        seed = s;
    }
    if let Some(n) = over.world.people {
        cfg.people = n as usize;
    }
    if over.world.door_closures {
        cfg.door_closures = true;
    }
    if !over.world.dead_sonars.is_empty() {
        cfg.dead_sonars = over.world.dead_sonars.iter().map(|&i| usize::from(i)).collect();
    }
    if map_path.is_none() && errors.is_empty() {
        errors.push(robot_file.error(node.pos, "`simulator` needs `map:` (the building's map file)"));
    }
    if !errors.is_empty() {
        return Err(errors.into_iter().map(|e| e.to_string()).collect());
    }
    let map_path = map_path.unwrap_or_default();
    let map = situate_sim::load_map(&map_path).map_err(|e| {
        // Both places: the map's own (file:line:col), then the robot file's `map:`.
        let named = match map_at {
            Some(pos) => robot_file.error(pos, format!("the map `{}` named here cannot be used", map_path.display())),
            None => {
                robot_file.error(node.pos, format!("the map `{}` given by --map cannot be used", map_path.display()))
            }
        };
        vec![format!("{e}\n{named}")]
    })?;
    let world = Arc::new(std::sync::Mutex::new(situate_sim::World::with_config(map.clone(), seed, cfg)));
    Ok(Some(Simulation { map_path, map, world, seed }))
}

/// `dead_sonars: [i, …]`: sonar indexes 0 to 23.
fn dead_sonars(robot_file: &RobotFile, value: &Spanned<Node>) -> Result<Vec<usize>, ConfigError> {
    let Some(items) = value.value.as_seq() else {
        return Err(robot_file.error(value.pos, "`dead_sonars` expects a list of sonar indexes, e.g. [3, 17]"));
    };
    let mut out = Vec::new();
    for item in items {
        match item.value.as_i64().filter(|i| (0..24).contains(i)) {
            Some(i) => out.push(i as usize),
            None => {
                return Err(robot_file.error(item.pos, "a dead sonar is a sonar index, a whole number from 0 to 23"))
            }
        }
    }
    Ok(out)
}
