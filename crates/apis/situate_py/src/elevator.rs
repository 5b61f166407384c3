//! `situate._native.Elevator`: the 2-D simulator's elevator logic ([`situate_sim::elevator`])
//! for the physics robot, which moves its MuJoCo cars and doors by it (one logic, two
//! simulators).

use std::path::PathBuf;
use std::sync::Arc;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use situate_sim::elevator::{Bank, CarPhase, RobotAt};
use situate_sim::geom::P2;

/// The elevator bank of a map file's building: calls, cars travelling, doors, floor panels.
#[pyclass(module = "situate._native", name = "Elevator")]
pub struct Elevator {
    bank: Bank,
}

fn robot(floor: i64, x: f64, y: f64, theta: f64) -> RobotAt {
    RobotAt { floor, pos: P2::new(x, y), theta }
}

#[pymethods]
impl Elevator {
    /// The bank of the building in the map file `path`, every car closed on the lowest floor;
    /// `seed` seeds the cars' random times. Raises `ValueError` with the loader's message.
    #[new]
    fn new(py: Python<'_>, path: PathBuf, seed: u64) -> PyResult<Self> {
        let map = py.detach(|| situate_sim::load_map(&path)).map_err(|e| PyValueError::new_err(e.to_string()))?;
        Ok(Elevator { bank: Bank::new(Arc::new(map), seed) })
    }

    /// Each car's `(position, door, phase, from, to)`: its floor position (fractional while it
    /// moves), its door's opening (0 closed … 1 open), what it does (`idle`, `travel`,
    /// `opening`, `open`, `closing`) and the floors it travels from and to (its position
    /// twice when it does not travel). Car 1 first.
    fn cars(&self) -> Vec<(f64, f64, &'static str, f64, f64)> {
        self.bank
            .states()
            .iter()
            .map(|c| {
                let (from, to) = match c.phase {
                    CarPhase::Travel { from, to, .. } => (from, to as f64),
                    _ => (c.pos, c.pos),
                };
                (c.pos, c.door, c.phase.name(), from, to)
            })
            .collect()
    }

    /// The arm pushes the button for `label` from the robot's pose at time `now`, within
    /// `reach` m and `fov` rad of ahead: whether it hit a button (the lobby's call button, or
    /// the panel of the car the robot is in).
    #[allow(clippy::too_many_arguments)]
    fn press(&mut self, label: i64, floor: i64, x: f64, y: f64, theta: f64, reach: f64, fov: f64, now: f64) -> bool {
        self.bank.press(&robot(floor, x, y, theta), label, reach, fov, now)
    }

    /// One step of `dt` s at time `now`, the robot at its pose.
    fn step(&mut self, now: f64, dt: f64, floor: i64, x: f64, y: f64, theta: f64) {
        self.bank.step(&robot(floor, x, y, theta), now, dt);
    }
}
