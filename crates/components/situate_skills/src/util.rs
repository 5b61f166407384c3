//! Helpers shared by the skills: sonar geometry, angles, activation.

use std::f64::consts::{PI, TAU};

use situate_robot::{sonar_bearing, SONARS};

/// The robot's radius, m. Sonar ranges are measured from the robot's centre
/// (as `sim.sonar` does); clearances (range − radius) are from the rim.
pub const ROBOT_RADIUS: f64 = 0.25;

/// Sonar index of the sonar looking to the left (90°).
pub const LEFT: usize = 6;
/// Sonar index of the sonar looking to the right (−90°).
pub const RIGHT: usize = 18;

/// `a` wrapped into (−π, π].
pub fn wrap(a: f64) -> f64 {
    let mut a = a % TAU;
    if a > PI {
        a -= TAU;
    } else if a <= -PI {
        a += TAU;
    }
    a
}

/// Sonar `i` (taken modulo 24) as a distance from the robot's centre, m.
/// A NaN or negative reading counts as no echo (infinitely far).
pub fn centre_range(range: &[f32; SONARS], i: usize) -> f64 {
    let r = f64::from(range[i % SONARS]);
    if r.is_nan() || r < 0.0 {
        f64::INFINITY
    } else {
        r
    }
}

/// The echo of sonar `i` as a point in the robot frame (from the centre).
pub fn echo_point(range: &[f32; SONARS], i: usize) -> (f64, f64) {
    let rho = centre_range(range, i);
    let b = sonar_bearing(i);
    (rho * b.cos(), rho * b.sin())
}

/// Sonar index `i` offset by `k` around the ring (negative: clockwise).
pub fn ring(i: usize, k: i64) -> usize {
    (i as i64 + k).rem_euclid(SONARS as i64) as usize
}

/// A wall beside the robot seen by three adjacent side sonars.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SideWall {
    /// Perpendicular distance from the robot's centre, m.
    pub distance: f64,
    /// The wall's direction in the robot frame, rad (0: parallel to the
    /// robot's heading).
    pub angle: f64,
}

/// The side wall seen by sonars `side − 1`, `side`, `side + 1` (`side`:
/// [`LEFT`] or [`RIGHT`]) when all three see echoes nearer than `max_m`
/// (from the centre) lying on one line within `tolerance_m`; `None` otherwise
/// (an opening, a corner or no wall).
pub fn side_wall(range: &[f32; SONARS], side: usize, max_m: f64, tolerance_m: f64) -> Option<SideWall> {
    let (a, m, b) = (ring(side, -1), side, ring(side, 1));
    if [a, m, b].iter().any(|&i| centre_range(range, i) > max_m) {
        return None;
    }
    // The line through the two outer echoes; the middle one must lie on it.
    let (p, q, c) = (echo_point(range, a), echo_point(range, b), echo_point(range, m));
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let len = dx.hypot(dy);
    if len < 1e-6 {
        return None;
    }
    let dist_of = |pt: (f64, f64)| ((pt.0 - p.0) * dy - (pt.1 - p.1) * dx).abs() / len;
    let distance = (p.0 * dy - p.1 * dx).abs() / len;
    if dist_of(c) > tolerance_m {
        return None;
    }
    // Direction from the rear echo to the front echo.
    let angle = if side == LEFT { (p.1 - q.1).atan2(p.0 - q.0) } else { (q.1 - p.1).atan2(q.0 - p.0) };
    Some(SideWall { distance, angle: wrap(angle) })
}

/// The nearest echo (from the centre) among the sonars whose bearing lies
/// within `half_width` of `bearing`, with its sonar index.
pub fn nearest_in(range: &[f32; SONARS], bearing: f64, half_width: f64) -> Option<(usize, f64)> {
    (0..SONARS)
        .filter(|&i| wrap(sonar_bearing(i) - bearing).abs() <= half_width + 1e-9)
        .map(|i| (i, centre_range(range, i)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// Counts consecutive agreeing observations before flipping a flag: the
/// flag turns on after `on` cycles of `true` and off after `off` cycles of
/// `false`.
#[derive(Clone, Copy, Debug, Default)]
pub struct Hysteresis {
    state: bool,
    count: i64,
}

impl Hysteresis {
    /// Feeds one observation; returns the (possibly new) state.
    pub fn update(&mut self, observed: bool, on: i64, off: i64) -> bool {
        if observed == self.state {
            self.count = 0;
        } else {
            self.count += 1;
            let need = if observed { on } else { off };
            if self.count >= need.max(1) {
                self.state = observed;
                self.count = 0;
            }
        }
        self.state
    }

    /// The current state.
    pub fn state(&self) -> bool {
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_keeps_angles_in_the_half_open_circle() {
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
        assert!((wrap(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-12);
        assert!((wrap(PI) - PI).abs() < 1e-12);
        assert!((wrap(0.3) - 0.3).abs() < 1e-12);
    }

    #[test]
    fn hysteresis_needs_consecutive_observations() {
        let mut h = Hysteresis::default();
        assert!(!h.update(true, 3, 2));
        assert!(!h.update(true, 3, 2));
        assert!(!h.update(false, 3, 2));
        assert!(!h.update(true, 3, 2));
        assert!(!h.update(true, 3, 2));
        assert!(h.update(true, 3, 2));
        assert!(h.update(false, 3, 2));
        assert!(!h.update(false, 3, 2));
    }

    #[test]
    fn a_parallel_wall_at_one_metre() {
        // A wall along y = 1: sonar i at bearing b reads 1/sin b.
        let mut r = [4.0f32; SONARS];
        for (i, x) in r.iter_mut().enumerate().take(8).skip(5) {
            *x = (1.0 / sonar_bearing(i).sin()) as f32;
        }
        let w = side_wall(&r, LEFT, 2.5, 0.1).expect("a wall");
        assert!((w.distance - 1.0).abs() < 1e-4, "{w:?}");
        assert!(w.angle.abs() < 1e-4, "{w:?}");
        assert_eq!(side_wall(&r, RIGHT, 2.5, 0.1), None);
    }
}
