//! The building's own life: people walking and the map's doors closing now
//! and then. Written once for both simulators: the 2-D [`World`](crate::world::World)
//! steps it on its streams 2 and 3, and the physics robot (MuJoCo) steps the
//! same logic through `situate._native.Traffic` and moves its bodies by it.

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

use crate::geom::{Seg, P2};
use crate::map::Map;
use crate::people::{self, Around, Person, Walkable, PATH_CLEARANCE};
use crate::world::uniform;

/// Door closures: how long a door stays closed, s.
pub const CLOSED_S: (f64, f64) = (20.0, 60.0);
/// Door closures: the gap between two closures, s.
pub const OPEN_GAP_S: (f64, f64) = (60.0, 180.0);
/// A door due to close waits until the robot's rim is this far from its opening, m.
pub const DOOR_MARGIN: f64 = 0.3;

/// The people's stream (their own, so people change no other random number).
pub const PEOPLE_STREAM: u64 = 2;
/// The door closures' stream.
pub const DOORS_STREAM: u64 = 3;

/// Where the map's doors are in their closures (with door closures on).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Closure {
    /// Every door open; the next closure is due at `next`.
    Open { next: f64 },
    /// Door `door` of floor `floor` (indexes into `map.floors` and its
    /// `doors`) is due to close for `for_s`, once its doorway is clear.
    Due { floor: usize, door: usize, for_s: f64 },
    /// That door is closed until `until`.
    Closed { floor: usize, door: usize, until: f64 },
}

/// The robot as people and doors see it: a disc on a floor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotDisc {
    pub floor: i64,
    pub pos: P2,
    pub radius: f64,
}

/// People and door closures in one building.
#[derive(Debug, Clone)]
pub struct Traffic {
    /// Where people may walk, per floor (empty without people).
    walk: std::sync::Arc<Vec<Walkable>>,
    people: Vec<Person>,
    people_rng: ChaCha8Rng,
    closure: Option<Closure>,
    doors_rng: ChaCha8Rng,
}

impl Traffic {
    /// `people` people on every floor of `map` (placed now, away from the
    /// robot's start) and, with `door_closures`, the map's doors closing now
    /// and then; `seed` seeds both on streams of their own.
    pub fn new(map: &Map, seed: u64, people: usize, door_closures: bool) -> Traffic {
        let mut people_rng = ChaCha8Rng::seed_from_u64(seed);
        people_rng.set_stream(PEOPLE_STREAM);
        let mut doors_rng = ChaCha8Rng::seed_from_u64(seed);
        doors_rng.set_stream(DOORS_STREAM);
        let (walk, people) = if people > 0 {
            let walk = people::walkable(map);
            let placed = people::place(map, &walk, people, &mut people_rng);
            (walk, placed)
        } else {
            (Vec::new(), Vec::new())
        };
        let any_door = map.floors.iter().any(|f| !f.doors.is_empty());
        let closure = (door_closures && any_door).then(|| Closure::Open { next: gap(&mut doors_rng) });
        Traffic { walk: std::sync::Arc::new(walk), people, people_rng, closure, doors_rng }
    }

    /// The people, floor by floor.
    pub fn people(&self) -> &[Person] {
        &self.people
    }

    /// Where people may walk on each floor (empty without people).
    pub fn walkable(&self) -> &[Walkable] {
        &self.walk
    }

    /// Moves person `k` (tests, scenarios): it stands at `(x, y)` on
    /// `floor` until time `until` (s), then walks on. False: no such person.
    pub fn place_person(&mut self, k: usize, floor: i64, x: f64, y: f64, until: f64) -> bool {
        let Some(p) = self.people.get_mut(k) else { return false };
        *p = Person { floor, pos: P2::new(x, y), goal: None, pause_until: until, waited: 0.0, ..*p };
        true
    }

    /// The door closures' state (`None` when off or the map has no doors).
    pub fn closure(&self) -> Option<Closure> {
        self.closure
    }

    /// The map's door closed now: its floor, opening and the time it opens.
    pub fn closed_door(&self, map: &Map) -> Option<(i64, Seg, f64)> {
        match self.closure {
            Some(Closure::Closed { floor, door, until }) => {
                let f = map.floors.get(floor)?;
                Some((f.level, f.doors.get(door)?.seg, until))
            }
            _ => None,
        }
    }

    /// One step of `dt` s at time `now`: the door closures, then the people.
    pub fn step(&mut self, map: &Map, robot: &RobotDisc, now: f64, dt: f64) {
        self.step_doors(map, robot, now);
        self.step_people(map, robot, now, dt);
    }

    /// Door closures: a random door closes after a random gap, once its
    /// doorway is clear of the robot and of people, and opens again later.
    fn step_doors(&mut self, map: &Map, robot: &RobotDisc, now: f64) {
        let Some(state) = self.closure else { return };
        self.closure = Some(match state {
            Closure::Open { next } if now >= next => {
                let total: usize = map.floors.iter().map(|f| f.doors.len()).sum();
                let mut k = (self.doors_rng.next_u64() % total.max(1) as u64) as usize;
                let for_s = CLOSED_S.0 + uniform(&mut self.doors_rng) * (CLOSED_S.1 - CLOSED_S.0);
                let mut due = Closure::Open { next: now + gap(&mut self.doors_rng) };
                for (fi, f) in map.floors.iter().enumerate() {
                    if k < f.doors.len() {
                        due = Closure::Due { floor: fi, door: k, for_s };
                        break;
                    }
                    k -= f.doors.len();
                }
                due
            }
            Closure::Due { floor, door, for_s } => {
                let f = &map.floors[floor];
                let seg = f.doors[door].seg;
                let robot_in = robot.floor == f.level && seg.dist_to(robot.pos) < robot.radius + DOOR_MARGIN;
                let person_in =
                    self.people.iter().any(|p| p.floor == f.level && seg.dist_to(p.pos) < PATH_CLEARANCE + 0.05);
                if robot_in || person_in {
                    state
                } else {
                    tracing::debug!(floor = f.level, door = door, for_s, "door closed");
                    Closure::Closed { floor, door, until: now + for_s }
                }
            }
            Closure::Closed { until, .. } if now >= until => Closure::Open { next: now + gap(&mut self.doors_rng) },
            other => other,
        });
    }

    fn step_people(&mut self, map: &Map, robot: &RobotDisc, now: f64, dt: f64) {
        if self.people.is_empty() {
            return;
        }
        let closed = self.closed_door(map);
        for p in self.people.iter_mut() {
            let Some(fi) = map.floors.iter().position(|f| f.level == p.floor) else { continue };
            let around = Around {
                walk: &self.walk[fi],
                closed: closed.filter(|d| d.0 == p.floor).map(|d| d.1),
                robot: (robot.floor == p.floor).then_some((robot.pos, robot.radius)),
            };
            p.step(now, dt, &around, &mut self.people_rng);
        }
    }
}

/// A random gap between door closures, s.
fn gap(rng: &mut ChaCha8Rng) -> f64 {
    OPEN_GAP_S.0 + uniform(rng) * (OPEN_GAP_S.1 - OPEN_GAP_S.0)
}
