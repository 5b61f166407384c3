//! The simulated world: robot physics, sensors, elevator, all advanced in
//! fixed steps by time (never by calls), so the result does not depend on
//! which device asks first or how often.

use std::f64::consts::PI;
use std::sync::Arc;

use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};
use situate_robot::{sonar_bearing, SONARS};

use crate::elevator::{Button, Cars, RobotAt};
pub use crate::elevator::{CarPhase, CarState};
use crate::geom::{cast, ray_circle, wrap, Aabb, RayFan, Seg, P2};
use crate::map::{Barcode, Map};
use crate::people::{Person, Walkable, PERSON_RADIUS};
use crate::traffic::{RobotDisc, Traffic};

/// Settings of the physics that are not a device's parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldConfig {
    /// Fixed physics step, s.
    pub dt: f64,
    /// Odometry: relative noise of each step's travelled distance (std dev).
    pub odom_dist_noise: f64,
    /// Odometry: relative noise of each step's turn (std dev).
    pub odom_turn_noise: f64,
    /// Odometry: heading drift per metre travelled, rad/m (std dev).
    pub odom_drift: f64,
    /// People walking on every floor (this many per floor).
    pub people: usize,
    /// Whether the map's doors (not the cars') close now and then.
    pub door_closures: bool,
    /// Sonars (indexes 0–23) that never hear an echo: they read `max_range`.
    pub dead_sonars: Vec<usize>,
}

impl Default for WorldConfig {
    fn default() -> Self {
        WorldConfig {
            dt: 0.01,
            odom_dist_noise: 0.02,
            odom_turn_noise: 0.02,
            odom_drift: 0.01,
            people: 0,
            door_closures: false,
            dead_sonars: Vec::new(),
        }
    }
}

pub use crate::traffic::{Closure, CLOSED_S, DOOR_MARGIN, OPEN_GAP_S};

/// Speed and acceleration limits of the base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BaseLimits {
    /// m/s
    pub max_v: f64,
    /// rad/s
    pub max_w: f64,
    /// m/s²
    pub acc_v: f64,
    /// rad/s²
    pub acc_w: f64,
}

impl Default for BaseLimits {
    fn default() -> Self {
        BaseLimits { max_v: 0.8, max_w: 2.0, acc_v: 1.0, acc_w: 3.0 }
    }
}

/// The sonar ring's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SonarSettings {
    pub min_range: f64,
    pub max_range: f64,
    /// Cone width, rad.
    pub cone: f64,
    /// Rays per cone (≥ 1).
    pub rays: usize,
    /// Gaussian noise, m (std dev).
    pub noise: f64,
    /// Probability of a missed echo (reads `max_range`).
    pub dropout: f64,
}

impl Default for SonarSettings {
    fn default() -> Self {
        SonarSettings { min_range: 0.1, max_range: 4.0, cone: 15f64.to_radians(), rays: 5, noise: 0.02, dropout: 0.01 }
    }
}

/// The robot's true state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotState {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
    pub v: f64,
    pub w: f64,
    pub floor: i64,
}

#[derive(Debug, Clone, PartialEq)]
enum Pending {
    Call(i64),
    Panel { car: usize, floor: i64 },
    Say { text: String, at: f64 },
}

/// Streams of the per-reading random numbers, so sensors never share one.
const SONAR_STREAM: u64 = 1;
/// Slack added to every distance beyond which a segment is skipped, m: far
/// more than the rounding of the distances compared, far less than anything
/// the simulation resolves.
const CULL_SLACK: f64 = 1e-6;

/// A bound on `|gauss()|`: with `u1 ≥ 2⁻⁵³`, Box–Muller's radius
/// `sqrt(-2 ln u1)` is at most `sqrt(106 ln 2) ≈ 8.57`.
const GAUSS_BOUND: f64 = 9.0;

/// The simulated building and robot.
#[derive(Debug, Clone)]
pub struct World {
    map: Arc<Map>,
    seed: u64,
    cfg: WorldConfig,
    step: u64,
    rng: ChaCha8Rng,
    robot: RobotState,
    target: (f64, f64),
    limits: BaseLimits,
    odom: (f64, f64, f64, f64, f64),
    elevator: Cars,
    pending: Vec<Pending>,
    pending_drive: Option<((f64, f64), BaseLimits)>,
    said: Vec<crate::task::Utterance>,
    delivered_at: Option<f64>,
    arm_attempts: i64,
    arm_presses: i64,
    /// Fixed segments per floor (same order as `map.floors`).
    statics: Vec<Vec<Seg>>,
    /// People walking and the map's doors closing.
    traffic: Traffic,
}

/// A uniform number in [0, 1).
pub(crate) fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A standard normal number (Box–Muller).
/// The ring's readings: for each sonar, `nearest(axis, ray directions)`
/// gives the nearest echo of its cone's rays (infinity for none); noise and
/// missed echoes are drawn from `rng` in sonar order.
fn sonar_ring(
    theta: f64,
    s: &SonarSettings,
    rng: &mut ChaCha8Rng,
    mut nearest: impl FnMut(f64, &mut dyn Iterator<Item = f64>) -> f64,
) -> [f32; SONARS] {
    let mut out = [0f32; SONARS];
    let rays = s.rays.max(1);
    for (i, o) in out.iter_mut().enumerate() {
        let axis = theta + sonar_bearing(i);
        let mut dirs =
            (0..rays).map(|k| axis + if rays == 1 { 0.0 } else { s.cone * (k as f64 / (rays - 1) as f64 - 0.5) });
        let best = nearest(axis, &mut dirs);
        let noisy = best + s.noise * gauss(rng);
        let missed = uniform(rng) < s.dropout;
        let r = if missed || !noisy.is_finite() || noisy > s.max_range { s.max_range } else { noisy.max(s.min_range) };
        *o = r as f32;
    }
    out
}

fn gauss(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - uniform(rng);
    let u2 = uniform(rng);
    (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
}

impl World {
    /// A world on `map` with the robot at the mission's start, cars idle on
    /// the lowest floor; `seed` drives every random number.
    pub fn new(map: Map, seed: u64) -> World {
        World::with_config(map, seed, WorldConfig::default())
    }

    /// [`World::new`] with physics settings.
    pub fn with_config(map: Map, seed: u64, cfg: WorldConfig) -> World {
        let m = &map.mission;
        let robot = RobotState { x: m.start.0, y: m.start.1, theta: m.start.2, v: 0.0, w: 0.0, floor: m.start_floor };
        let elevator = Cars::new(&map);
        let statics = map.floors.iter().map(|f| map.static_segments(f)).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(0);
        let traffic = Traffic::new(&map, seed, cfg.people, cfg.door_closures);
        World {
            map: Arc::new(map),
            seed,
            cfg,
            step: 0,
            rng,
            robot,
            target: (0.0, 0.0),
            limits: BaseLimits::default(),
            odom: (0.0, 0.0, 0.0, 0.0, 0.0),
            elevator,
            pending: Vec::new(),
            pending_drive: None,
            said: Vec::new(),
            delivered_at: None,
            arm_attempts: 0,
            arm_presses: 0,
            statics,
            traffic,
        }
    }

    /// The physics settings.
    pub fn config(&self) -> &WorldConfig {
        &self.cfg
    }

    /// The people, floor by floor.
    pub fn people(&self) -> &[Person] {
        self.traffic.people()
    }

    /// Where people may walk on each floor (empty without people).
    pub fn walkable(&self) -> &[Walkable] {
        self.traffic.walkable()
    }

    /// Moves person `k` (tests, scenarios): it stands at `(x, y)` on
    /// `floor` until time `until` (s), then walks on. False: no such person.
    pub fn place_person(&mut self, k: usize, floor: i64, x: f64, y: f64, until: f64) -> bool {
        self.traffic.place_person(k, floor, x, y, until)
    }

    /// The door closures' state (`None` when off or the map has no doors).
    pub fn closure(&self) -> Option<Closure> {
        self.traffic.closure()
    }

    /// The map's door closed now: its floor, opening and the time it opens.
    pub fn closed_door(&self) -> Option<(i64, Seg, f64)> {
        self.traffic.closed_door(&self.map)
    }

    /// The closed door's opening on `level`.
    fn closed_on(&self, level: i64) -> Option<Seg> {
        self.closed_door().filter(|d| d.0 == level).map(|d| d.1)
    }

    /// The building.
    pub fn map(&self) -> &Map {
        &self.map
    }

    /// Simulated time, s.
    pub fn time_s(&self) -> f64 {
        self.step as f64 * self.cfg.dt
    }

    /// Physics steps done.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// The robot's true state.
    pub fn robot(&self) -> RobotState {
        self.robot
    }

    /// Moves the robot (tests, scenarios); its speed drops to zero.
    pub fn place_robot(&mut self, floor: i64, x: f64, y: f64, theta: f64) {
        self.robot = RobotState { x, y, theta, v: 0.0, w: 0.0, floor };
    }

    /// The cars' states, car 1 first.
    pub fn cars(&self) -> &[CarState] {
        self.elevator.states()
    }

    /// Odometry: `(x, y, theta, v, w)` in the start frame.
    pub fn odom(&self) -> (f64, f64, f64, f64, f64) {
        self.odom
    }

    /// Utterances said so far: what, when and where (ground truth).
    pub fn said(&self) -> &[crate::task::Utterance] {
        &self.said
    }

    /// When the message was said inside the goal office.
    pub fn delivered_at(&self) -> Option<f64> {
        self.delivered_at
    }

    /// The arm's counters: `(attempts, presses)`.
    pub fn arm_counts(&self) -> (i64, i64) {
        (self.arm_attempts, self.arm_presses)
    }

    /// Steps the physics in fixed steps up to time `t` (no-op when there
    /// already). Every device calls this first with its cycle time.
    pub fn advance_to(&mut self, t: f64) {
        let target = (t / self.cfg.dt + 1e-6).floor().max(0.0) as u64;
        while self.step < target {
            self.step_once();
        }
    }

    /// Sets the velocity command, applied from the next physics step.
    pub fn set_drive(&mut self, v: f64, w: f64, limits: BaseLimits) {
        self.pending_drive = Some(((v, w), limits));
    }

    /// Tries to push the button labelled `label` within `reach` (m, from the
    /// robot's centre) and `fov` (rad, either side of the heading). Returns
    /// whether a button was hit; its effect starts at the next physics step.
    pub fn press(&mut self, label: i64, reach: f64, fov: f64) -> bool {
        self.arm_attempts += 1;
        match self.elevator.reachable(&self.map, &self.robot_at(), label, reach, fov) {
            Some(Button::Call) => self.pending.push(Pending::Call(self.robot.floor)),
            Some(Button::Panel(car)) => self.pending.push(Pending::Panel { car, floor: label }),
            None => return false,
        }
        self.arm_presses += 1;
        true
    }

    /// Says `text`; counts as the delivery when the robot is in the office.
    pub fn say(&mut self, text: &str) {
        let at = self.time_s();
        self.pending.push(Pending::Say { text: text.to_string(), at });
    }

    /// Utterances said or about to be (the speaker's counter).
    pub fn speaker_count(&self) -> i64 {
        (self.said.len() + self.pending.iter().filter(|p| matches!(p, Pending::Say { .. })).count()) as i64
    }

    fn pos(&self) -> P2 {
        P2::new(self.robot.x, self.robot.y)
    }

    /// The robot as the elevator sees it.
    fn robot_at(&self) -> RobotAt {
        RobotAt { floor: self.robot.floor, pos: self.pos(), theta: self.robot.theta }
    }

    fn floor_index(&self, level: i64) -> Option<usize> {
        self.map.floors.iter().position(|f| f.level == level)
    }

    /// The robot's car, if it is inside one.
    pub fn robot_car(&self) -> Option<usize> {
        Cars::inside(&self.map, self.pos())
    }

    /// Every segment that blocks motion and sensing on `level` now: walls,
    /// obstacles, shafts, closed (or closing) car doors, the closed door.
    pub fn segments(&self, level: i64) -> Vec<Seg> {
        let mut segs = self.floor_index(level).map(|i| self.statics[i].clone()).unwrap_or_default();
        segs.extend(self.door_segments(level));
        segs
    }

    /// The segments of [`World::segments`] whose box meets `region`, in the
    /// same order: a query that cannot be affected by a segment outside
    /// `region` gives the same result on these.
    fn segments_in(&self, level: i64, region: &Aabb) -> Vec<Seg> {
        let statics = self.floor_index(level).map(|i| self.statics[i].as_slice()).unwrap_or_default();
        statics.iter().copied().chain(self.door_segments(level)).filter(|s| region.meets(s)).collect()
    }

    /// The closed (or closing) part of each car door on `level`, then the
    /// map's closed door if it is on `level`.
    fn door_segments(&self, level: i64) -> impl Iterator<Item = Seg> + '_ {
        let cars = self.map.elevator.cars.iter().zip(self.elevator.states()).filter_map(move |(c, s)| {
            let closed = s.closed_on(level);
            (closed > 1e-6).then(|| {
                let d = c.door();
                Seg::new(d.a, d.at(closed))
            })
        });
        cars.chain(self.closed_on(level))
    }

    /// The nearest hit of a ray from the robot on the people of its floor.
    fn ray_people(&self, origin: P2, dir: P2) -> Option<f64> {
        let level = self.robot.floor;
        self.traffic
            .people()
            .iter()
            .filter(|p| p.floor == level)
            .filter_map(|p| ray_circle(origin, dir, p.pos, PERSON_RADIUS))
            .min_by(f64::total_cmp)
    }

    /// Barcodes present on `level` now (cars' only when the car is there).
    fn barcodes_on(&self, level: i64) -> Vec<Barcode> {
        let mut out: Vec<Barcode> = Vec::new();
        if let Some(f) = self.map.floor(level) {
            out.extend(f.barcodes.iter().cloned());
            out.extend(f.doors.iter().filter_map(|d| d.barcode.clone()));
            if let Some(l) = &f.lobby {
                out.push(Barcode { id: l.barcode, at: l.button, facing: Some(l.facing), line: l.line });
            }
            if let Some(o) = &f.office {
                out.push(o.barcode.clone());
            }
        }
        for (c, s) in self.map.elevator.cars.iter().zip(self.elevator.states()) {
            if s.floor() == level {
                let (at, facing) = c.panel();
                out.push(Barcode { id: c.barcode, at, facing: Some(facing), line: c.line });
            }
        }
        out
    }

    fn step_once(&mut self) {
        let dt = self.cfg.dt;
        let now = self.time_s();
        if let Some((t, l)) = self.pending_drive.take() {
            self.target = t;
            self.limits = l;
        }
        for p in std::mem::take(&mut self.pending) {
            match p {
                Pending::Call(f) => self.elevator.call(f),
                Pending::Panel { car, floor } => self.elevator.select(&self.map, car, floor, now),
                Pending::Say { text, at } => {
                    if self.delivered_at.is_none() && self.map.in_office(self.robot.floor, self.pos()) {
                        self.delivered_at = Some(at);
                        tracing::info!(at, "message delivered");
                    }
                    let floor = self.robot.floor;
                    self.said.push(crate::task::Utterance { time_s: at, floor, at: self.pos(), text });
                }
            }
        }
        self.step_elevator(now, dt);
        let robot = RobotDisc { floor: self.robot.floor, pos: self.pos(), radius: self.map.robot_radius };
        self.traffic.step(&self.map, &robot, now, dt);
        self.step_robot(dt);
        self.step += 1;
    }

    fn step_elevator(&mut self, now: f64, dt: f64) {
        let robot = self.robot_at();
        self.elevator.step(&self.map, &robot, now, dt, &mut self.rng);
        if let Some(k) = Cars::inside(&self.map, robot.pos) {
            self.robot.floor = self.elevator.states()[k].floor();
        }
    }

    fn step_robot(&mut self, dt: f64) {
        let l = self.limits;
        let approach = |cur: f64, want: f64, acc: f64| cur + (want - cur).clamp(-acc * dt, acc * dt);
        let (tv, tw) = (self.target.0.clamp(-l.max_v, l.max_v), self.target.1.clamp(-l.max_w, l.max_w));
        let mut v = approach(self.robot.v, tv, l.acc_v);
        let w = approach(self.robot.w, tw, l.acc_w);
        let dth = w * dt;
        let mid = self.robot.theta + dth / 2.0;
        let from = self.pos();
        let want = from.plus(P2::dir(mid).scale(v * dt));
        let r = self.map.robot_radius;
        // Only segments within `r` of the move can block it (see `blocked`).
        let segs = self.segments_in(self.robot.floor, &Aabb::spanning(from, want).grown(r + CULL_SLACK));
        let level = self.robot.floor;
        let people = self.traffic.people();
        let hit = |to: P2| {
            blocked(from, to, &segs, r)
                || people.iter().any(|p| p.floor == level && blocked_disc(from, to, p.pos, r + PERSON_RADIUS))
        };
        let frac = if hit(want) {
            // The largest part of the move that stays clear.
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..20 {
                let m = (lo + hi) / 2.0;
                if hit(from.plus(want.minus(from).scale(m))) {
                    hi = m;
                } else {
                    lo = m;
                }
            }
            v = 0.0;
            lo
        } else {
            1.0
        };
        let to = from.plus(want.minus(from).scale(frac));
        let ds = to.minus(from).norm() * if self.robot.v + v < 0.0 { -1.0 } else { 1.0 };
        self.robot.x = to.x;
        self.robot.y = to.y;
        self.robot.theta = wrap(self.robot.theta + dth);
        self.robot.v = v;
        self.robot.w = w;
        // Odometry from the true motion, with noise.
        let c = &self.cfg;
        let ds_m = ds * (1.0 + c.odom_dist_noise * gauss(&mut self.rng));
        let dth_m =
            dth * (1.0 + c.odom_turn_noise * gauss(&mut self.rng)) + c.odom_drift * ds.abs() * gauss(&mut self.rng);
        let (ox, oy, ot, _, _) = self.odom;
        let om = ot + dth_m / 2.0;
        self.odom = (ox + ds_m * om.cos(), oy + ds_m * om.sin(), wrap(ot + dth_m), ds_m / dt, dth_m / dt);
    }

    /// The 24 sonar ranges now (from the robot's centre), with noise and
    /// missed echoes from a random stream tied to the seed and the step.
    pub fn sonar(&self, s: &SonarSettings) -> [f32; SONARS] {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(SONAR_STREAM);
        rng.set_word_pos(u128::from(self.step) * 1024);
        let p = self.pos();
        // An echo from farther than `reach` reads `max_range` whatever the
        // noise adds to it, as does no echo at all: such segments can be left out.
        let reach = s.max_range + GAUSS_BOUND * s.noise.abs() + CULL_SLACK;
        let reach = if reach.is_nan() { f64::INFINITY } else { reach };
        // Each sonar's rays are within half its cone of its axis.
        let fan = RayFan::new(p, &self.segments_in(self.robot.floor, &Aabb::around(p, reach)), s.cone / 2.0);
        let mut among = Vec::new();
        let mut out = sonar_ring(self.robot.theta, s, &mut rng, |axis, rays| {
            fan.select(P2::dir(axis), &mut among);
            rays.map(|dir| {
                let wall = fan.cast_among(P2::dir(dir), &among).unwrap_or(f64::INFINITY);
                if self.traffic.people().is_empty() {
                    wall
                } else {
                    wall.min(self.ray_people(p, P2::dir(dir)).unwrap_or(f64::INFINITY))
                }
            })
            .fold(f64::INFINITY, f64::min)
        });
        for &i in &self.cfg.dead_sonars {
            if let Some(o) = out.get_mut(i) {
                *o = s.max_range as f32;
            }
        }
        out
    }

    /// Barcodes within `range` (m) and `fov` (rad either side of the
    /// heading), facing the robot and not hidden: `(id, bearing, distance)`,
    /// nearest first.
    pub fn barcodes(&self, range: f64, fov: f64) -> Vec<(i64, f64, f64)> {
        let p = self.pos();
        // A barcode is hidden only by a segment nearer than it, so within `range`.
        let reach = if range.is_nan() { f64::INFINITY } else { range + CULL_SLACK };
        let segs = self.segments_in(self.robot.floor, &Aabb::around(p, reach));
        let mut seen: Vec<(i64, f64, f64)> = self
            .barcodes_on(self.robot.floor)
            .into_iter()
            .filter_map(|b| {
                let rel = b.at.minus(p);
                let d = rel.norm();
                let bearing = wrap(rel.y.atan2(rel.x) - self.robot.theta);
                if d > range || bearing.abs() > fov || d < 1e-9 {
                    return None;
                }
                if let Some(f) = b.facing {
                    // Readable only from in front of the label (within 80°).
                    if P2::dir(f).dot(rel.scale(-1.0 / d)) < 10f64.to_radians().sin() {
                        return None;
                    }
                }
                let dir = rel.scale(1.0 / d);
                let hidden = cast(p, dir, &segs).is_some_and(|h| h < d - 0.01)
                    || self.ray_people(p, dir).is_some_and(|h| h < d - 0.01);
                (!hidden).then_some((b.id, bearing, d))
            })
            .collect();
        seen.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
        seen
    }
}

/// Whether moving the robot's disc (radius `r`) from `a` to `b` hits a
/// segment. A disc already overlapping a segment may move away from it.
fn blocked(a: P2, b: P2, segs: &[Seg], r: f64) -> bool {
    let path = Seg::new(a, b);
    segs.iter().any(|s| {
        let d0 = s.dist_to(a);
        if d0 >= r {
            s.dist_to_seg(&path) < r
        } else {
            s.dist_to(b) < d0
        }
    })
}

/// Whether moving the robot's disc from `a` to `b` brings it nearer than
/// `reach` (the sum of the radii) to the disc centred at `c`. A disc already
/// overlapping may move away.
fn blocked_disc(a: P2, b: P2, c: P2, reach: f64) -> bool {
    let d0 = a.dist(c);
    if d0 >= reach {
        Seg::new(a, b).dist_to(c) < reach
    } else {
        b.dist(c) < d0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default_map() -> Map {
        let path = format!("{}/../../../maps/default.yaml", env!("CARGO_MANIFEST_DIR"));
        crate::load_map(path).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The sonar ring as computed before segments were culled: every ray
    /// against every segment.
    fn sonar_every_segment(w: &World, s: &SonarSettings) -> [f32; SONARS] {
        let mut rng = ChaCha8Rng::seed_from_u64(w.seed);
        rng.set_stream(SONAR_STREAM);
        rng.set_word_pos(u128::from(w.step) * 1024);
        let segs = w.segments(w.robot.floor);
        let p = w.pos();
        // Every ray against every segment of the floor: the reference the
        // culled cast must match bit for bit.
        sonar_ring(w.robot.theta, s, &mut rng, |_, rays| {
            rays.filter_map(|dir| cast(p, P2::dir(dir), &segs)).fold(f64::INFINITY, f64::min)
        })
    }

    /// Poses all over every floor (inside walls and obstacles too), with cars
    /// in every door state.
    fn worlds() -> Vec<World> {
        let mut out = Vec::new();
        let mut rng = ChaCha8Rng::seed_from_u64(99);
        let base = World::new(default_map(), 5);
        for k in 0..1500u64 {
            let mut w = base.clone();
            let floor = w.map.floors[(k % w.map.floors.len() as u64) as usize].level;
            let (x, y) = (-1.0 + 23.0 * uniform(&mut rng), -1.0 + 23.0 * uniform(&mut rng));
            w.place_robot(floor, x, y, (uniform(&mut rng) - 0.5) * 7.0);
            w.step = k * 37;
            for c in w.elevator.states_mut() {
                c.pos = floor as f64;
                c.door = [0.0, 0.3, 1.0][(k % 3) as usize];
                c.phase = [CarPhase::Idle, CarPhase::Opening, CarPhase::Open { until: 1e9 }][(k % 3) as usize];
            }
            out.push(w);
        }
        out
    }

    #[test]
    fn culled_sonar_readings_are_bit_for_bit_those_of_every_segment() {
        let settings = [
            SonarSettings::default(),
            SonarSettings { noise: 0.0, dropout: 0.0, ..SonarSettings::default() },
            SonarSettings { max_range: 1.0, noise: 0.5, ..SonarSettings::default() },
            SonarSettings { max_range: 20.0, cone: 60f64.to_radians(), rays: 31, ..SonarSettings::default() },
            SonarSettings { rays: 1, cone: 0.0, ..SonarSettings::default() },
        ];
        for w in worlds() {
            for s in &settings {
                let got = w.sonar(s).map(f32::to_bits);
                assert_eq!(got, sonar_every_segment(&w, s).map(f32::to_bits), "{:?} {s:?}", w.robot());
            }
        }
    }

    #[test]
    fn blocking_on_the_segments_near_a_move_is_blocking_on_all() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for w in worlds() {
            let r = w.map.robot_radius;
            let all = w.segments(w.robot.floor);
            let from = w.pos();
            for _ in 0..4 {
                let step = 0.001 + 0.2 * uniform(&mut rng);
                let to = from.plus(P2::dir(uniform(&mut rng) * 7.0).scale(step));
                let near = w.segments_in(w.robot.floor, &Aabb::spanning(from, to).grown(r + CULL_SLACK));
                for m in [1.0, 0.5, 0.25, 0.001] {
                    let b = from.plus(to.minus(from).scale(m));
                    assert_eq!(blocked(from, b, &near, r), blocked(from, b, &all, r), "{from:?} -> {b:?}");
                }
            }
        }
    }

    #[test]
    fn barcodes_seen_with_culled_walls_are_those_seen_with_all() {
        for w in worlds() {
            let p = w.pos();
            let segs = w.segments(w.robot.floor);
            // The reader's rule with every segment.
            let mut want: Vec<(i64, f64, f64)> = w
                .barcodes_on(w.robot.floor)
                .into_iter()
                .filter_map(|b| {
                    let rel = b.at.minus(p);
                    let d = rel.norm();
                    let bearing = wrap(rel.y.atan2(rel.x) - w.robot.theta);
                    if d > 3.0 || bearing.abs() > 1.0 || d < 1e-9 {
                        return None;
                    }
                    if let Some(f) = b.facing {
                        if P2::dir(f).dot(rel.scale(-1.0 / d)) < 10f64.to_radians().sin() {
                            return None;
                        }
                    }
                    let hidden = cast(p, rel.scale(1.0 / d), &segs).is_some_and(|h| h < d - 0.01);
                    (!hidden).then_some((b.id, bearing, d))
                })
                .collect();
            want.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
            assert_eq!(w.barcodes(3.0, 1.0), want);
        }
    }
}
