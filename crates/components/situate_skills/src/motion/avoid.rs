//! Keeping clear of obstacles: `std.runaway` (from anything too near) and `std.avoid` (round an
//! obstacle in the robot's path).

use situate::prelude::*;
use situate_robot::{sonar_bearing, Drive, SONARS};

use super::clamp_abs;
use crate::util::{centre_range, echo_point, wrap, ROBOT_RADIUS};

/// Runs away from anything nearer than `safe_distance` (the paper's
/// runaway): sums a push away from every such echo and drives along it —
/// forward when the push points ahead, backing up when it points behind,
/// turning so the robot's front (or back) follows the push. Writes `drive`
/// only while something is that near; silent otherwise.
#[derive(Skill, Default)]
#[skill(name = "std.runaway", priority = 50)]
pub struct Runaway {
    /// Sonar ranges, m (sonar i looks at bearing i·15°).
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The velocity command, written only while an obstacle is too near.
    #[output]
    drive: Option<Drive>,
    /// Clearance (rim to echo) under which the robot runs away, m.
    #[param(default = 0.4, min = 0.1, max = 3.0, unit = "m")]
    safe_distance: f64,
    /// Speed while running away, m/s.
    #[param(default = 0.25, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 1.0, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
}

impl Body for Runaway {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let (mut fx, mut fy, mut near) = (0.0, 0.0, f64::INFINITY);
        for i in 0..SONARS {
            let r = centre_range(&self.sonar, i) - ROBOT_RADIUS;
            if r < self.safe_distance {
                let push = (self.safe_distance - r) / self.safe_distance;
                let b = sonar_bearing(i);
                fx -= push * b.cos();
                fy -= push * b.sin();
                near = near.min(r);
            }
        }
        if near.is_infinite() {
            return Ok(());
        }
        if fx.hypot(fy) < 1e-6 {
            // Pushed equally from all sides: turn in place to find a way out.
            self.drive = Some(Drive { v: 0.0, w: self.max_turn });
            return Ok(());
        }
        let psi = fy.atan2(fx);
        // Turn the front towards the push, or the back when it points well behind.
        let turn = if psi.cos() >= -0.2 { psi } else { wrap(psi - std::f64::consts::PI) };
        self.drive = Some(Drive { v: self.speed * psi.cos(), w: clamp_abs(2.0 * turn, self.max_turn) });
        sprint!(cx, "obstacle at {near:.2} m: running towards {:.0}°", psi.to_degrees());
        Ok(())
    }
}

/// How far beyond the robot's sides `std.avoid` looks for obstacles in its path, m.
const LANE_MARGIN: f64 = 0.2;

/// Obstacle avoidance: when an echo in the robot's path (within ±60° and
/// 0.2 m beyond its sides) is nearer than `distance` along the heading, slows down (to a stop at `stop_distance`) and turns towards
/// the freer side. Writes `drive` only then; silent when the way is clear.
#[derive(Skill, Default)]
#[skill(name = "std.avoid", priority = 40)]
pub struct Avoid {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// The velocity command, written only while an obstacle is near ahead.
    #[output]
    drive: Option<Drive>,
    /// Clearance ahead (rim to echo) under which the robot avoids, m.
    #[param(default = 0.7, min = 0.1, max = 3.0, unit = "m")]
    distance: f64,
    /// Clearance ahead at which forward speed reaches zero, m.
    #[param(default = 0.25, min = 0.0, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Forward speed when the obstacle is at `distance`, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Turn rate when the obstacle is at `stop_distance`, rad/s.
    #[param(default = 0.8, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    /// The side last turned to (+1 left, −1 right), kept while the sides are alike.
    side: f64,
}

impl Body for Avoid {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        // The nearest echo in the robot's path (a lane a little wider than the robot), along the heading.
        let near = (0..SONARS)
            .filter(|&i| sonar_bearing(i).abs() <= 60f64.to_radians() + 1e-9)
            .map(|i| echo_point(&self.sonar, i))
            .filter(|&(x, y)| x > 0.0 && y.abs() < ROBOT_RADIUS + LANE_MARGIN)
            .map(|(x, _)| x - ROBOT_RADIUS)
            .fold(f64::INFINITY, f64::min);
        if near >= self.distance {
            return Ok(());
        }
        let cap = 2.0 * self.distance + ROBOT_RADIUS;
        let space = |idx: &[usize]| idx.iter().map(|&i| centre_range(&self.sonar, i).min(cap)).sum::<f64>();
        let (left, right) = (space(&[1, 2, 3, 4, 5]), space(&[19, 20, 21, 22, 23]));
        if self.side == 0.0 || (left - right).abs() > 0.3 {
            self.side = if left >= right { 1.0 } else { -1.0 };
        }
        let span = (self.distance - self.stop_distance).max(1e-3);
        let urgency = ((self.distance - near) / span).clamp(0.0, 1.0);
        self.drive =
            Some(Drive { v: self.speed * (1.0 - urgency), w: self.side * self.max_turn * (0.3 + 0.7 * urgency) });
        Ok(())
    }
}
