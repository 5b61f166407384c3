//! People walking the building: discs that walk straight between random
//! free points of their floor, pause there, keep out of the elevator shafts
//! and never walk into the robot. The free points are worked out once per
//! floor; a step allocates nothing.

use rand_chacha::ChaCha8Rng;
use rand_core::RngCore;

use crate::geom::{in_polygon, Seg, P2};
use crate::map::Map;
use crate::world::uniform;

/// A person's radius, m.
pub const PERSON_RADIUS: f64 = 0.25;
/// Clearance of a person's start and waypoints from walls, obstacles and
/// shafts (centre to segment), m.
pub const FREE_CLEARANCE: f64 = 0.5;
/// Clearance of a person's centre from every wall along its way, m: its
/// radius and a margin.
pub const PATH_CLEARANCE: f64 = PERSON_RADIUS + 0.05;
/// A person stops while the robot is ahead of it with less than this
/// between their rims, m.
pub const STOP_GAP: f64 = 0.6;
/// People start at least this far from the robot's start (on its floor), m.
pub const START_AWAY: f64 = 3.0;
/// Walking speeds, m/s (each person's from the seed).
pub const SPEED: (f64, f64) = (0.3, 0.7);
/// Pauses at waypoints, s.
pub const PAUSE: (f64, f64) = (0.5, 2.5);
/// A person walks past the robot with at least this between their rims
/// (it stops only for a robot that would come nearer), m.
pub const PASS_GAP: f64 = 0.15;
/// How long a person waits for the robot before walking somewhere else, s.
const WAIT_FOR_ROBOT: f64 = 3.0;
/// The grid of candidate free points, m (coarser on floors that would need
/// more than [`MAX_CELLS`]).
const GRID: f64 = 0.25;
/// The most grid cells worked out per floor.
const MAX_CELLS: f64 = 250_000.0;
/// Random draws when picking a start or a waypoint.
const DRAWS: usize = 24;
/// The nearest waypoint picked, m.
const MIN_LEG: f64 = 1.0;

/// One person.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Person {
    pub floor: i64,
    pub pos: P2,
    /// Walking speed, m/s.
    pub speed: f64,
    /// Where it walks to; `None`: it pauses until `pause_until`, then picks a waypoint.
    pub goal: Option<P2>,
    pub pause_until: f64,
    /// How long it has been waiting for the robot, s.
    pub waited: f64,
}

/// Where people may be on one floor.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Walkable {
    /// What people never cross: walls, obstacles, shafts, and the cars'
    /// doors (always closed for people).
    pub segs: Vec<Seg>,
    /// Free points (a 0.25 m grid, coarser on huge floors) at least [`FREE_CLEARANCE`] from every
    /// segment, outside every obstacle and shaft, connected to the floor's
    /// known rooms (lobby, doors, barcodes, the start, the office).
    pub free: Vec<P2>,
}

/// The walkable space of every floor, in `map.floors` order.
pub fn walkable(map: &Map) -> Vec<Walkable> {
    map.floors.iter().map(|f| walkable_floor(map, f)).collect()
}

fn walkable_floor(map: &Map, floor: &crate::map::Floor) -> Walkable {
    let mut segs = map.static_segments(floor);
    segs.extend(map.elevator.cars.iter().map(|c| c.door()));
    let Some((lo, hi)) = bounds(&segs) else {
        return Walkable { segs, free: Vec::new() };
    };
    // Whatever the grid, a person's every leg is checked against the walls
    // (`clear_way`): a coarse grid only makes the free points fewer.
    let grid = GRID.max(((hi.x - lo.x) * (hi.y - lo.y) / MAX_CELLS).sqrt());
    let nx = (((hi.x - lo.x) / grid).ceil() as usize).clamp(1, 4000);
    let ny = (((hi.y - lo.y) / grid).ceil() as usize).clamp(1, 4000);
    let centre = |i: usize, j: usize| P2::new(lo.x + (i as f64 + 0.5) * grid, lo.y + (j as f64 + 0.5) * grid);
    let open: Vec<bool> = (0..nx * ny)
        .map(|k| {
            let p = centre(k % nx, k / nx);
            segs.iter().all(|s| s.dist_to(p) >= FREE_CLEARANCE)
                && !map.elevator.cars.iter().any(|c| c.contains(p))
                && !floor.obstacles.iter().any(|o| in_polygon(p, o))
        })
        .collect();
    // Seeds: points in front of what the robot is meant to reach.
    let mut seeds: Vec<P2> = Vec::new();
    if floor.level == map.mission.start_floor {
        seeds.push(P2::new(map.mission.start.0, map.mission.start.1));
    }
    if let Some(l) = &floor.lobby {
        seeds.push(l.button.plus(P2::dir(l.facing).scale(1.0)));
    }
    for d in &floor.doors {
        let mid = d.seg.at(0.5);
        let e = d.seg.b.minus(d.seg.a);
        let n = P2::new(-e.y, e.x).scale(0.8 / e.norm().max(1e-9));
        seeds.push(mid.plus(n));
        seeds.push(mid.minus(n));
    }
    for b in &floor.barcodes {
        if let Some(f) = b.facing {
            seeds.push(b.at.plus(P2::dir(f).scale(0.8)));
        }
    }
    if let Some(o) = &floor.office {
        let n = o.polygon.len().max(1) as f64;
        let c = o.polygon.iter().fold(P2::default(), |a, p| a.plus(*p)).scale(1.0 / n);
        seeds.push(c);
    }
    let mut reached = vec![false; nx * ny];
    let mut queue: Vec<usize> = Vec::new();
    for s in seeds {
        // The nearest open cell, on the seed's side of every wall.
        let best = (0..nx * ny)
            .filter(|&k| open[k])
            .map(|k| (k, centre(k % nx, k / nx).dist(s)))
            .filter(|&(k, d)| {
                d <= 0.6 && {
                    let path = Seg::new(s, centre(k % nx, k / nx));
                    !segs.iter().any(|w| w.intersects(&path))
                }
            })
            .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        if let Some((k, _)) = best {
            if !reached[k] {
                reached[k] = true;
                queue.push(k);
            }
        }
    }
    // Flood over 4-neighbours: two open cells under 1 m apart, each ≥ 0.5 m
    // from every segment, have no segment between them.
    while let Some(k) = queue.pop() {
        let (i, j) = (k % nx, k / nx);
        let mut visit = |k2: usize| {
            if open[k2] && !reached[k2] {
                reached[k2] = true;
                queue.push(k2);
            }
        };
        if i > 0 {
            visit(k - 1);
        }
        if i + 1 < nx {
            visit(k + 1);
        }
        if j > 0 {
            visit(k - nx);
        }
        if j + 1 < ny {
            visit(k + nx);
        }
    }
    let free = (0..nx * ny).filter(|&k| reached[k]).map(|k| centre(k % nx, k / nx)).collect();
    Walkable { segs, free }
}

fn bounds(segs: &[Seg]) -> Option<(P2, P2)> {
    let mut it = segs.iter().flat_map(|s| [s.a, s.b]).filter(|p| p.x.is_finite() && p.y.is_finite());
    let first = it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| {
        (P2::new(lo.x.min(p.x), lo.y.min(p.y)), P2::new(hi.x.max(p.x), hi.y.max(p.y)))
    }))
}

/// `n` people per floor at random free points (on the robot's start floor
/// at least [`START_AWAY`] from the start), each with its speed.
pub fn place(map: &Map, walk: &[Walkable], n: usize, rng: &mut ChaCha8Rng) -> Vec<Person> {
    let start = P2::new(map.mission.start.0, map.mission.start.1);
    let mut out = Vec::new();
    for (f, w) in map.floors.iter().zip(walk) {
        if w.free.is_empty() {
            continue;
        }
        for _ in 0..n {
            for _ in 0..DRAWS * 4 {
                let p = w.free[(rng.next_u64() % w.free.len() as u64) as usize];
                if f.level == map.mission.start_floor && p.dist(start) < START_AWAY {
                    continue;
                }
                let speed = SPEED.0 + uniform(rng) * (SPEED.1 - SPEED.0);
                let pause_until = uniform(rng) * PAUSE.1;
                out.push(Person { floor: f.level, pos: p, speed, goal: None, pause_until, waited: 0.0 });
                break;
            }
        }
    }
    out
}

/// Whether a person can walk straight from `a` to `b`.
pub fn clear_way(a: P2, b: P2, segs: &[Seg], closed: Option<Seg>) -> bool {
    let path = Seg::new(a, b);
    segs.iter().chain(closed.as_ref()).all(|s| s.dist_to_seg(&path) >= PATH_CLEARANCE)
}

/// What a person's step depends on besides itself.
pub(crate) struct Around<'a> {
    pub walk: &'a Walkable,
    /// The map's closed door on the person's floor.
    pub closed: Option<Seg>,
    /// The robot's centre and radius, when on the person's floor.
    pub robot: Option<(P2, f64)>,
}

impl Person {
    /// One physics step of `dt` at time `now`.
    pub(crate) fn step(&mut self, now: f64, dt: f64, around: &Around<'_>, rng: &mut ChaCha8Rng) {
        let Some(goal) = self.goal else {
            if now >= self.pause_until {
                match self.pick(around, rng) {
                    Some(g) => self.goal = Some(g),
                    None => self.pause_until = now + 1.0,
                }
            }
            return;
        };
        let to = goal.minus(self.pos);
        let d = to.norm();
        if d > 1e-12 {
            let u = to.scale(1.0 / d);
            if let Some((rp, rr)) = around.robot {
                let rel = rp.minus(self.pos);
                // Only a step towards the robot's half-plane brings them closer, and only a
                // way that passes it by less than `PASS_GAP` runs into it.
                let into = Seg::new(self.pos, goal).dist_to(rp) < PERSON_RADIUS + rr + PASS_GAP;
                if rel.norm() - PERSON_RADIUS - rr < STOP_GAP && rel.dot(u) > 0.0 && into {
                    self.waited += dt;
                    if self.waited >= WAIT_FOR_ROBOT {
                        self.waited = 0.0;
                        self.goal = None;
                        self.pause_until = now;
                    }
                    return;
                }
            }
            let next = if self.speed * dt >= d { goal } else { self.pos.plus(u.scale(self.speed * dt)) };
            if around.closed.is_some_and(|c| c.dist_to(next) < PATH_CLEARANCE) {
                // A door closed across the way: go somewhere else.
                self.goal = None;
                self.pause_until = now + PAUSE.0;
                return;
            }
            self.waited = 0.0;
            self.pos = next;
        }
        if self.pos == goal {
            self.goal = None;
            self.pause_until = now + PAUSE.0 + uniform(rng) * (PAUSE.1 - PAUSE.0);
        }
    }

    /// A random free point at least [`MIN_LEG`] away that is reachable in a
    /// straight line passing the robot by [`PASS_GAP`] or more, if one of a
    /// few draws is (someone the robot keeps in a dead end walks out past it
    /// where there is room, as people do).
    fn pick(&self, around: &Around<'_>, rng: &mut ChaCha8Rng) -> Option<P2> {
        let free = &around.walk.free;
        if free.is_empty() {
            return None;
        }
        let past_robot = |p: P2| {
            around.robot.is_none_or(|(rp, rr)| Seg::new(self.pos, p).dist_to(rp) >= PERSON_RADIUS + rr + PASS_GAP)
        };
        (0..DRAWS).find_map(|_| {
            let p = free[(rng.next_u64() % free.len() as u64) as usize];
            (p.dist(self.pos) >= MIN_LEG && clear_way(self.pos, p, &around.walk.segs, around.closed) && past_robot(p))
                .then_some(p)
        })
    }
}
