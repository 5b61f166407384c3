//! Homing: driving to a goal, the tracked barcode (`std.home`) or a point of the odometry frame
//! (`std.home_position`).

use std::f64::consts::{FRAC_PI_2, PI};

use situate::prelude::*;
use situate_robot::{Drive, Odom, Target};

use super::clamp_abs;
use crate::util::wrap;

/// Drives towards a bearing and distance: turns in place while the bearing
/// exceeds `turn_angle` (until it is under half of it), else drives with a
/// proportional turn, slowing over the last `slow_m`.
#[derive(Clone, Copy, Debug, Default)]
struct Approach {
    turning: bool,
}

impl Approach {
    fn command(&mut self, bearing: f64, to_go: f64, speed: f64, turn_angle: f64, max_turn: f64) -> Drive {
        const SLOW_M: f64 = 0.5;
        if bearing.abs() > turn_angle {
            self.turning = true;
        } else if bearing.abs() < turn_angle / 2.0 {
            self.turning = false;
        }
        let w = clamp_abs(1.5 * bearing, max_turn);
        if self.turning {
            return Drive { v: 0.0, w: if w.abs() < 0.2 { 0.2f64.copysign(bearing) } else { w } };
        }
        let v = speed * (to_go / SLOW_M).clamp(0.15, 1.0);
        Drive { v, w }
    }
}

/// Homes on the tracked barcode (`target`): turns in place first when its
/// bearing exceeds `turn_angle`, then drives towards it until it is
/// `stop_distance` away, then stops facing it. Writes `drive` while the
/// target is seen (a stop once there); silent when it is not.
#[derive(Skill, Default)]
#[skill(name = "std.home", priority = 30)]
pub struct Home {
    /// The tracked barcode (from `std.track_barcode`).
    #[input]
    target: Target,
    /// The velocity command, written while the target is seen.
    #[output]
    drive: Option<Drive>,
    /// Forward speed, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Distance from the robot's centre to the barcode at which it stops, m.
    #[param(default = 0.5, min = 0.0, max = 5.0, unit = "m")]
    stop_distance: f64,
    /// Bearing above which the robot turns in place first, rad.
    #[param(default = 0.4, min = 0.05, max = 3.2, unit = "rad")]
    turn_angle: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 1.0, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    approach: Approach,
}

impl Body for Home {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let t = self.target;
        if !t.seen || !t.bearing.is_finite() || !t.distance.is_finite() {
            return Ok(());
        }
        let bearing = wrap(t.bearing);
        self.drive = Some(if t.distance <= self.stop_distance {
            Drive { v: 0.0, w: if bearing.abs() < 0.05 { 0.0 } else { clamp_abs(1.5 * bearing, self.max_turn) } }
        } else {
            self.approach.command(bearing, t.distance - self.stop_distance, self.speed, self.turn_angle, self.max_turn)
        });
        Ok(())
    }
}

/// Drives to the point (`x`, `y`) of the odometry frame: turns in place
/// first when it lies more than `turn_angle` off the heading, then drives to
/// it and stops within `stop_distance`. A goal just behind (within
/// `reverse_within`) is backed up to instead. Writes `drive` every run (a
/// stop once there).
#[derive(Skill, Default)]
#[skill(name = "std.home_position", priority = 30)]
pub struct HomePosition {
    /// Odometry.
    #[input]
    odom: Odom,
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Goal x in the odometry frame, m.
    #[param(default = 0.0, min = -1000.0, max = 1000.0, unit = "m")]
    x: f64,
    /// Goal y in the odometry frame, m.
    #[param(default = 0.0, min = -1000.0, max = 1000.0, unit = "m")]
    y: f64,
    /// Forward speed, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Distance to the goal at which the robot stops, m.
    #[param(default = 0.1, min = 0.01, max = 5.0, unit = "m")]
    stop_distance: f64,
    /// Bearing above which the robot turns in place first, rad.
    #[param(default = 0.4, min = 0.05, max = 3.2, unit = "rad")]
    turn_angle: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 1.0, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    /// A goal behind the robot (more than 90° off its heading) and at most this far is
    /// driven to backwards, without turning round first (0: never), m.
    #[param(default = 0.0, min = 0.0, max = 10.0, unit = "m")]
    reverse_within: f64,
    approach: Approach,
    arrived: bool,
    /// The goal `arrived` is about (`None` after a switch on: not there yet).
    goal: Option<(f64, f64)>,
}

impl Body for HomePosition {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.goal = None;
        Ok(())
    }

    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        // A new activation or a new goal: not there yet (a goal just beside the last one,
        // within twice `stop_distance`, would otherwise count as reached).
        if self.goal != Some((self.x, self.y)) {
            self.arrived = false;
            self.approach = Approach::default();
            self.goal = Some((self.x, self.y));
        }
        let o = self.odom;
        let (dx, dy) = (self.x - o.x, self.y - o.y);
        let to_go = dx.hypot(dy);
        // Arrive within stop_distance; leave again only when pushed well beyond it.
        if to_go <= self.stop_distance {
            self.arrived = true;
        } else if to_go > 2.0 * self.stop_distance {
            self.arrived = false;
        }
        self.drive = if self.arrived || !to_go.is_finite() {
            Drive::default()
        } else {
            let bearing = wrap(dy.atan2(dx) - o.theta);
            if bearing.abs() > FRAC_PI_2 && to_go <= self.reverse_within {
                // Backwards: the robot's back steers as its front would (the back turns
                // with the heading, so the same turn rate closes the same angle).
                let back = wrap(bearing - PI);
                let d =
                    self.approach.command(back, to_go - self.stop_distance, self.speed, self.turn_angle, self.max_turn);
                Drive { v: -d.v, w: d.w }
            } else {
                self.approach.command(bearing, to_go - self.stop_distance, self.speed, self.turn_angle, self.max_turn)
            }
        };
        Ok(())
    }
}
