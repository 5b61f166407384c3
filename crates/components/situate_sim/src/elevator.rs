//! The elevator bank's logic: calls, cars sent and travelling, doors opening, held open and
//! closing, the floor panel, the buttons the robot's arm can push.
//!
//! One logic for both simulators: the 2-D [`World`](crate::World) steps it with its physics,
//! and the physics robot (`situate.physics`, through `situate._native.Elevator`) moves its
//! MuJoCo cars and doors by it. It knows the building ([`Map`]) and where the robot is
//! ([`RobotAt`]), nothing of how the robot moves.

use rand_chacha::ChaCha8Rng;
use rand_core::RngCore;

use crate::geom::{wrap, P2};
use crate::map::Map;
use crate::world::uniform;

/// What an elevator car is doing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CarPhase {
    /// Doors closed, standing.
    Idle,
    /// Moving (or waiting, when `from` is `to`) to floor `to`, arriving at `until`.
    Travel { from: f64, to: i64, start: f64, until: f64 },
    /// Doors opening.
    Opening,
    /// Doors open until the time given.
    Open { until: f64 },
    /// Doors closing (they open again for the robot in the doorway or a call).
    Closing,
}

impl CarPhase {
    /// The phase's name, as `truth.cars` and the physics robot show it.
    pub fn name(&self) -> &'static str {
        match self {
            CarPhase::Idle => "idle",
            CarPhase::Travel { .. } => "travel",
            CarPhase::Opening => "opening",
            CarPhase::Open { .. } => "open",
            CarPhase::Closing => "closing",
        }
    }
}

/// One car's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarState {
    /// Floor position (fractional while moving).
    pub pos: f64,
    /// Door opening, 0 closed … 1 open.
    pub door: f64,
    pub phase: CarPhase,
    /// A floor pressed on the panel, not yet served.
    pub target: Option<i64>,
}

impl CarState {
    /// The floor the car is at or nearest to.
    pub fn floor(&self) -> i64 {
        self.pos.round() as i64
    }

    /// How much of the car's door blocks its doorway on `level`, 0 … 1: all of it on other
    /// floors and while the car travels; what is not open when it stands at `level`.
    pub fn closed_on(&self, level: i64) -> f64 {
        if self.floor() == level && !matches!(self.phase, CarPhase::Travel { .. }) {
            1.0 - self.door
        } else {
            1.0
        }
    }
}

/// Where the robot is, as the elevator sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotAt {
    /// The floor it is on (the nearest one while a car carries it).
    pub floor: i64,
    /// Its centre.
    pub pos: P2,
    /// Its heading, rad.
    pub theta: f64,
}

/// A button the robot's arm can push.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Button {
    /// The call button of the lobby on the robot's floor.
    Call,
    /// The floor panel of the car the robot is in (its index).
    Panel(usize),
}

/// The cars of the building's elevator and the calls not yet served.
#[derive(Debug, Clone, PartialEq)]
pub struct Cars {
    cars: Vec<CarState>,
    calls: Vec<i64>,
}

impl Cars {
    /// Every car of `map` standing closed on the lowest floor.
    pub fn new(map: &Map) -> Cars {
        let lowest = map.floors.iter().map(|f| f.level).min().unwrap_or(0);
        let car = CarState { pos: lowest as f64, door: 0.0, phase: CarPhase::Idle, target: None };
        Cars { cars: vec![car; map.elevator.cars.len()], calls: Vec::new() }
    }

    /// The cars' states, car 1 first.
    pub fn states(&self) -> &[CarState] {
        &self.cars
    }

    /// The cars' states, to set by hand (the crate's tests).
    #[cfg(test)]
    pub(crate) fn states_mut(&mut self) -> &mut [CarState] {
        &mut self.cars
    }

    /// A call from `floor`'s lobby (once: a call waiting is not made twice).
    pub fn call(&mut self, floor: i64) {
        if !self.calls.contains(&floor) {
            self.calls.push(floor);
        }
    }

    /// Car `car`'s panel pressed for `floor` at time `now`: its doors close within 2 s and it
    /// goes there. A floor the building lacks, or a car it lacks, does nothing.
    pub fn select(&mut self, map: &Map, car: usize, floor: i64, now: f64) {
        let Some(c) = self.cars.get_mut(car) else { return };
        if map.floor(floor).is_some() {
            c.target = Some(floor);
            if let CarPhase::Open { until } = c.phase {
                c.phase = CarPhase::Open { until: until.min(now + 2.0) };
            }
        }
    }

    /// The car whose inside holds `p` (on any floor).
    pub fn inside(map: &Map, p: P2) -> Option<usize> {
        map.elevator.cars.iter().position(|c| c.contains(p))
    }

    /// The buttons the robot could push where it is: the call button of its floor's lobby, the
    /// panel of the car it is in while that car is at its floor. Each with where it is and the
    /// way it faces.
    pub fn buttons(&self, map: &Map, robot: &RobotAt) -> Vec<(P2, f64, Button)> {
        let mut out = Vec::new();
        if let Some(l) = map.floor(robot.floor).and_then(|f| f.lobby.as_ref()) {
            out.push((l.button, l.facing, Button::Call));
        }
        for (k, (c, s)) in map.elevator.cars.iter().zip(&self.cars).enumerate() {
            if s.floor() == robot.floor && c.contains(robot.pos) {
                let (p, facing) = c.panel();
                out.push((p, facing, Button::Panel(k)));
            }
        }
        out
    }

    /// The button that a push for `label` hits: one within `reach` (m, from the robot's
    /// centre) and `fov` (rad, either side of the heading), the robot on the side it faces,
    /// that takes the label (a car's panel: a floor of the building; a call button: any).
    pub fn reachable(&self, map: &Map, robot: &RobotAt, label: i64, reach: f64, fov: f64) -> Option<Button> {
        self.buttons(map, robot).into_iter().find_map(|(p, facing, b)| {
            let rel = p.minus(robot.pos);
            let in_front = wrap(rel.y.atan2(rel.x) - robot.theta).abs() <= fov;
            // The robot must be on the button's side.
            let facing_ok = P2::dir(facing).dot(rel.scale(-1.0)) > 0.0;
            let accepts = match b {
                Button::Call => true,
                Button::Panel(_) => map.floor(label).is_some(),
            };
            (rel.norm() <= reach && in_front && facing_ok && accepts).then_some(b)
        })
    }

    /// Whether the robot's disc is in car `k`'s doorway on the car's floor.
    fn in_doorway(map: &Map, car: &CarState, k: usize, robot: &RobotAt) -> bool {
        let c = &map.elevator.cars[k];
        car.floor() == robot.floor && c.door().dist_to(robot.pos) < map.robot_radius + 0.05
    }

    /// One step of `dt` s at time `now`: calls served (by a car already there, else a random
    /// idle car, sent after the map's `arrive_s`), cars moved, doors opened (held open for a
    /// random time in `open_s`, 2 s when a floor was chosen) and closed (opening again for the
    /// robot in the doorway). The random numbers come from `rng`.
    pub fn step(&mut self, map: &Map, robot: &RobotAt, now: f64, dt: f64, rng: &mut ChaCha8Rng) {
        let el = &map.elevator;
        let inside = Cars::inside(map, robot.pos);
        let mut calls = std::mem::take(&mut self.calls);
        calls.retain(|&f| {
            let there = self.cars.iter().any(|c| {
                c.floor() == f && matches!(c.phase, CarPhase::Opening | CarPhase::Open { .. })
                    || matches!(c.phase, CarPhase::Travel { to, .. } if to == f)
            });
            if there {
                return false;
            }
            // A car closing its doors here opens them again.
            if let Some(c) = self.cars.iter_mut().find(|c| c.floor() == f && c.phase == CarPhase::Closing) {
                c.phase = CarPhase::Opening;
                return false;
            }
            let idle: Vec<usize> = (0..self.cars.len())
                .filter(|&k| self.cars[k].phase == CarPhase::Idle && self.cars[k].target.is_none() && inside != Some(k))
                .collect();
            if idle.is_empty() {
                return true;
            }
            let k = idle[(rng.next_u64() % idle.len() as u64) as usize];
            let delay = el.arrive_s.0 + uniform(rng) * (el.arrive_s.1 - el.arrive_s.0);
            let from = self.cars[k].pos;
            self.cars[k].phase = CarPhase::Travel { from, to: f, start: now, until: now + delay.max(dt) };
            tracing::debug!(car = k + 1, floor = f, delay, "car dispatched");
            false
        });
        self.calls = calls;
        let door_rate = dt / el.door_move_s;
        for k in 0..self.cars.len() {
            let mut c = self.cars[k];
            match c.phase {
                CarPhase::Idle => {
                    if let Some(t) = c.target.take() {
                        let dur = (t as f64 - c.pos).abs() * el.travel_s_per_floor;
                        c.phase = if dur < 1e-9 {
                            CarPhase::Opening
                        } else {
                            CarPhase::Travel { from: c.pos, to: t, start: now, until: now + dur }
                        };
                    }
                }
                CarPhase::Travel { from, to, start, until } => {
                    if now + dt >= until {
                        c.pos = to as f64;
                        c.phase = CarPhase::Opening;
                    } else {
                        c.pos = from + (to as f64 - from) * ((now + dt - start) / (until - start));
                    }
                }
                CarPhase::Opening => {
                    c.door = (c.door + door_rate).min(1.0);
                    if c.door >= 1.0 {
                        let hold = if c.target.is_some() {
                            2.0
                        } else {
                            el.open_s.0 + uniform(rng) * (el.open_s.1 - el.open_s.0)
                        };
                        c.phase = CarPhase::Open { until: now + hold };
                    }
                }
                CarPhase::Open { until } => {
                    if now + dt >= until {
                        c.phase = CarPhase::Closing;
                    }
                }
                CarPhase::Closing => {
                    if Cars::in_doorway(map, &c, k, robot) {
                        c.phase = CarPhase::Opening;
                    } else {
                        c.door = (c.door - door_rate).max(0.0);
                        if c.door <= 0.0 {
                            c.phase = CarPhase::Idle;
                        }
                    }
                }
            }
            self.cars[k] = c;
        }
    }
}

/// The random stream of a [`Bank`] (the 2-D [`World`](crate::World) steps its [`Cars`] on its
/// own stream 0 instead).
const BANK_STREAM: u64 = 4;

/// The elevator bank on its own: a building's [`Cars`] with their random stream, stepped by a
/// simulator other than the 2-D [`World`](crate::World) (the physics robot's).
#[derive(Debug, Clone)]
pub struct Bank {
    map: std::sync::Arc<Map>,
    cars: Cars,
    rng: ChaCha8Rng,
}

impl Bank {
    /// The bank of `map`'s elevator, every car closed on the lowest floor; `seed` seeds the
    /// cars' random times.
    pub fn new(map: std::sync::Arc<Map>, seed: u64) -> Bank {
        use rand_core::SeedableRng;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(BANK_STREAM);
        Bank { cars: Cars::new(&map), map, rng }
    }

    /// The building.
    pub fn map(&self) -> &Map {
        &self.map
    }

    /// The cars' states, car 1 first.
    pub fn states(&self) -> &[CarState] {
        self.cars.states()
    }

    /// The arm pushes the button for `label` from where the robot is (see [`Cars::reachable`])
    /// at time `now`: a call, or a floor chosen on the panel. Whether it hit a button.
    pub fn press(&mut self, robot: &RobotAt, label: i64, reach: f64, fov: f64, now: f64) -> bool {
        match self.cars.reachable(&self.map, robot, label, reach, fov) {
            Some(Button::Call) => self.cars.call(robot.floor),
            Some(Button::Panel(car)) => self.cars.select(&self.map, car, label, now),
            None => return false,
        }
        true
    }

    /// One step (see [`Cars::step`]).
    pub fn step(&mut self, robot: &RobotAt, now: f64, dt: f64) {
        self.cars.step(&self.map, robot, now, dt, &mut self.rng);
    }
}
