//! `situate._native.Traffic`: the 2-D simulator's people and door closures
//! ([`situate_sim::traffic`]) for the physics robot, which moves its MuJoCo people and door
//! panels by them (one logic, two simulators).

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use situate_sim::geom::P2;
use situate_sim::map::Map;
use situate_sim::traffic::{Closure, RobotDisc, Traffic as Logic};

/// People walking and the map's doors closing in a map file's building.
#[pyclass(module = "situate._native", name = "Traffic")]
pub struct Traffic {
    map: Map,
    traffic: Logic,
}

#[pymethods]
impl Traffic {
    /// `people` people on every floor of the building in the map file `path` and, with
    /// `door_closures`, its doors closing now and then; `seed` seeds both (as the 2-D
    /// simulator's `people` and `door_closures` settings). Raises `ValueError` with the
    /// loader's message.
    #[new]
    fn new(py: Python<'_>, path: PathBuf, seed: u64, people: usize, door_closures: bool) -> PyResult<Self> {
        let map = py.detach(|| situate_sim::load_map(&path)).map_err(|e| PyValueError::new_err(e.to_string()))?;
        let traffic = py.detach(|| Logic::new(&map, seed, people, door_closures));
        Ok(Traffic { map, traffic })
    }

    /// Each person's `(floor, x, y)`, floor by floor.
    fn people(&self) -> Vec<(i64, f64, f64)> {
        self.traffic.people().iter().map(|p| (p.floor, p.pos.x, p.pos.y)).collect()
    }

    /// The map's door closed now, as `(floor, door)`: its floor's level and its index in that
    /// floor's `doors`; `None` when every door is open.
    fn closed_door(&self) -> Option<(i64, usize)> {
        match self.traffic.closure()? {
            Closure::Closed { floor, door, .. } => Some((self.map.floors.get(floor)?.level, door)),
            _ => None,
        }
    }

    /// Moves person `k` (tests, scenarios): it stands at `(x, y)` on `floor` until time
    /// `until` (s), then walks on. False: no such person.
    fn place_person(&mut self, k: usize, floor: i64, x: f64, y: f64, until: f64) -> bool {
        self.traffic.place_person(k, floor, x, y, until)
    }

    /// One step of `dt` s at time `now`, the robot's centre at `(x, y)` on `floor`.
    fn step(&mut self, now: f64, dt: f64, floor: i64, x: f64, y: f64) {
        let robot = RobotDisc { floor, pos: P2::new(x, y), radius: self.map.robot_radius };
        self.traffic.step(&self.map, &robot, now, dt);
    }
}
