//! Small noise-free worlds for the skills: walls as line segments, the 24
//! sonar ranges of a pose among them (exact ray–segment intersection over
//! rays spread across each sonar's cone), barcodes, and a kinematic
//! integrator to close the loop.

use situate_robot::{sonar_bearing, Barcodes, Drive, Odom, SONARS};
use std::sync::Arc;

/// The robot's radius, m.
pub const RADIUS: f64 = 0.25;
/// Range reported without an echo, m.
pub const MAX_RANGE: f64 = 4.0;
/// Half the opening of a sonar's cone, rad.
pub const HALF_CONE: f64 = 7.5 * std::f64::consts::PI / 180.0;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

impl Pose {
    pub fn new(x: f64, y: f64, theta: f64) -> Self {
        Pose { x, y, theta }
    }

    /// Moves by `drive` for `dt` seconds (unicycle kinematics).
    pub fn step(self, drive: Drive, dt: f64) -> Pose {
        let theta = self.theta + drive.w * dt;
        Pose { x: self.x + drive.v * theta.cos() * dt, y: self.y + drive.v * theta.sin() * dt, theta }
    }

    /// Odometry of this pose relative to the frame `origin` (no drift).
    pub fn odom(self, drive: Drive) -> Odom {
        Odom { x: self.x, y: self.y, theta: self.theta, v: drive.v, w: drive.w }
    }
}

#[derive(Clone, Debug, Default)]
pub struct Scene {
    walls: Vec<((f64, f64), (f64, f64))>,
    /// (id, x, y)
    barcodes: Vec<(i64, f64, f64)>,
}

impl Scene {
    pub fn new() -> Self {
        Scene::default()
    }

    pub fn wall(mut self, x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        self.walls.push(((x0, y0), (x1, y1)));
        self
    }

    /// A box (a bin, a table) with corners `(x0, y0)` and `(x1, y1)`: its four walls.
    pub fn rect(self, x0: f64, y0: f64, x1: f64, y1: f64) -> Self {
        self.wall(x0, y0, x1, y0).wall(x1, y0, x1, y1).wall(x1, y1, x0, y1).wall(x0, y1, x0, y0)
    }

    pub fn barcode(mut self, id: i64, x: f64, y: f64) -> Self {
        self.barcodes.push((id, x, y));
        self
    }

    /// Distance along the ray from `o` in direction `a` to the nearest wall.
    pub fn ray(&self, o: (f64, f64), a: f64) -> f64 {
        let d = (a.cos(), a.sin());
        let mut best = f64::INFINITY;
        for &(p, q) in &self.walls {
            let e = (q.0 - p.0, q.1 - p.1);
            let den = d.0 * e.1 - d.1 * e.0;
            if den.abs() < 1e-12 {
                continue;
            }
            let w = (p.0 - o.0, p.1 - o.1);
            let t = (w.0 * e.1 - w.1 * e.0) / den;
            let s = (w.0 * d.1 - w.1 * d.0) / den;
            if t >= 0.0 && (-1e-9..=1.0 + 1e-9).contains(&s) {
                best = best.min(t);
            }
        }
        best
    }

    /// The 24 ranges at `pose`, from the centre (as `sim.sonar`), each the nearest echo over its cone.
    pub fn sonar(&self, pose: Pose) -> [f32; SONARS] {
        let mut out = [0f32; SONARS];
        for (i, r) in out.iter_mut().enumerate() {
            let a = pose.theta + sonar_bearing(i);
            let o = (pose.x, pose.y);
            let mut best = f64::INFINITY;
            // Five rays across the cone, as `sim.sonar` casts by default.
            for k in -2..=2 {
                best = best.min(self.ray(o, a + HALF_CONE * f64::from(k) / 2.0));
            }
            *r = best.clamp(0.1, MAX_RANGE) as f32;
        }
        out
    }

    /// The barcodes within 5 m and ±60° of the heading, not behind a wall.
    pub fn barcodes(&self, pose: Pose) -> Barcodes {
        let (mut ids, mut bearing, mut distance) = (Vec::new(), Vec::new(), Vec::new());
        for &(id, x, y) in &self.barcodes {
            let (dx, dy) = (x - pose.x, y - pose.y);
            let d = dx.hypot(dy);
            let b = wrap(dy.atan2(dx) - pose.theta);
            let hidden = self.ray((pose.x, pose.y), dy.atan2(dx)) < d - 0.05;
            if d <= 5.0 && b.abs() <= 60f64.to_radians() && !hidden {
                ids.push(id);
                bearing.push(b);
                distance.push(d);
            }
        }
        Barcodes { ids: Arc::from(ids), bearing: Arc::from(bearing), distance: Arc::from(distance) }
    }

    /// Distance from the point to the nearest wall.
    pub fn clearance(&self, x: f64, y: f64) -> f64 {
        self.walls
            .iter()
            .map(|&(p, q)| {
                let e = (q.0 - p.0, q.1 - p.1);
                let l2 = e.0 * e.0 + e.1 * e.1;
                let s = if l2 > 0.0 { (((x - p.0) * e.0 + (y - p.1) * e.1) / l2).clamp(0.0, 1.0) } else { 0.0 };
                (x - p.0 - s * e.0).hypot(y - p.1 - s * e.1)
            })
            .fold(f64::INFINITY, f64::min)
    }
}

pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let a = a.rem_euclid(t);
    if a > std::f64::consts::PI {
        a - t
    } else {
        a
    }
}

#[test]
fn a_wall_ahead_is_seen_by_the_front_sonar_from_the_centre() {
    let s = Scene::new().wall(2.0, -5.0, 2.0, 5.0);
    let r = s.sonar(Pose::new(0.0, 0.0, 0.0));
    assert!((f64::from(r[0]) - 2.0).abs() < 1e-4, "{r:?}");
    assert_eq!(f64::from(r[12]), MAX_RANGE);
    // Turned left by 90°, the wall is on the right.
    let r = s.sonar(Pose::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
    assert!((f64::from(r[18]) - 2.0).abs() < 1e-4, "{r:?}");
}

/// Deterministic sonar noise: uniform ±`amp` m on every range, and a missed
/// echo (reads [`MAX_RANGE`]) with probability `miss`.
pub struct Noise {
    state: u64,
    pub amp: f64,
    pub miss: f64,
}

impl Noise {
    pub fn new(seed: u64, amp: f64, miss: f64) -> Self {
        Noise { state: seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1, amp, miss }
    }

    /// Uniform in [0, 1).
    fn next(&mut self) -> f64 {
        self.state ^= self.state << 13;
        self.state ^= self.state >> 7;
        self.state ^= self.state << 17;
        (self.state >> 11) as f64 / (1u64 << 53) as f64
    }

    pub fn apply(&mut self, mut r: [f32; SONARS]) -> [f32; SONARS] {
        for x in &mut r {
            let n = (self.next() * 2.0 - 1.0) * self.amp;
            *x = if self.next() < self.miss {
                MAX_RANGE as f32
            } else {
                (f64::from(*x) + n).clamp(0.1, MAX_RANGE) as f32
            };
        }
        r
    }
}

/// A base with acceleration limits: the velocities follow the command at
/// most `accel` m/s² and `alpha` rad/s² (no command: towards a stop).
pub struct Base {
    pub pose: Pose,
    pub v: f64,
    pub w: f64,
    pub accel: f64,
    pub alpha: f64,
}

impl Base {
    pub fn new(pose: Pose) -> Self {
        Base { pose, v: 0.0, w: 0.0, accel: 0.6, alpha: 2.0 }
    }

    pub fn step(&mut self, cmd: Option<Drive>, dt: f64) {
        let cmd = cmd.unwrap_or_default();
        self.v += (cmd.v - self.v).clamp(-self.accel * dt, self.accel * dt);
        self.w += (cmd.w - self.w).clamp(-self.alpha * dt, self.alpha * dt);
        self.pose = self.pose.step(Drive { v: self.v, w: self.w }, dt);
    }
}
