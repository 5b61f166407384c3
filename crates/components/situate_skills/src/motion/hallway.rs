//! Following a corridor: `std.follow_hallway`, centred between its walls, along its direction.

use situate::prelude::*;
use situate_robot::{Drive, Odom, SONARS};

use super::clamp_abs;
use crate::perception::Window;
use crate::util::{nearest_in, side_wall, wrap, SideWall, LEFT, RIGHT, ROBOT_RADIUS};

/// A side wall more oblique than this to the heading is no corridor wall, rad.
const MAX_WALL_ANGLE: f64 = 0.5;
/// A lone wall this much farther than its recent distance is not the corridor's, m.
const LONE_WALL_JUMP_M: f64 = 0.4;
/// Both walls' directions agree within this to correct the corridor's axis, rad.
const AXIS_AGREE: f64 = 0.1;
/// … and lie this near the axis, rad.
const AXIS_FOLLOW: f64 = 0.25;

/// Follows a corridor: keeps centred between the two side walls (those
/// within about 30° of the heading), heading along them; when one wall is
/// missing (a door, a side corridor), keeps from the other the half-width
/// last seen since activation, or else (a lobby, a hall: no width seen yet)
/// the distance it had from that wall when it came into view. A wall echo nearer
/// than the corridor's usual width says (by more than `clutter_m`) is a bin
/// or a box against the wall and is not steered by. With odometry (`odom`)
/// the corridor is a direction: the one faced at activation, kept up to date
/// from the walls and held where no wall is seen (a crossing); turned round,
/// the robot turns back to it. Without, it goes straight on where no wall is
/// seen. Slows to a stop when the range ahead
/// falls to `stop_distance`. Writes `drive` every run.
#[derive(Skill, Default)]
#[skill(name = "std.follow_hallway", priority = 25)]
pub struct FollowHallway {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry: holds the corridor's direction across openings.
    #[input]
    odom: Option<Odom>,
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Forward speed, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Side echoes farther than this from the centre are no wall, m.
    #[param(default = 2.0, min = 0.5, max = 5.0, unit = "m")]
    max_wall: f64,
    /// Clearance ahead (rim to echo) at which the robot stops, m.
    #[param(default = 0.4, min = 0.0, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.8, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    /// A side echo this much nearer than the corridor's width says is clutter, m.
    #[param(default = 0.2, min = 0.05, max = 2.0, unit = "m")]
    clutter_m: f64,
    half: Option<f64>,
    /// Recent corridor widths (both walls seen).
    widths: Window,
    /// Recent distances of each wall ([left, right]).
    sides: [Window; 2],
    /// The corridor's direction in the odometry frame, once walls were seen.
    axis: Option<f64>,
    /// The one wall's distance when it alone came into view.
    lone: Option<f64>,
    /// A point of the line followed (odometry frame): where the robot was when it last saw a
    /// wall, or was activated. Held where no wall is seen (a lobby, a crossing).
    line: Option<(f64, f64)>,
}

impl FollowHallway {
    /// A lone wall at `d` is this corridor's, its recent distance being `q`.
    fn lone_ok(&self, d: f64, q: f64) -> bool {
        d >= q - self.clutter_m && d <= q + LONE_WALL_JUMP_M
    }
}

impl Body for FollowHallway {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.half = None;
        self.widths = Window::default();
        self.sides = [Window::default(); 2];
        self.axis = None;
        self.lone = None;
        self.line = None;
        Ok(())
    }

    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        // Only walls roughly along the corridor are the corridor's: at a junction the side
        // sonars see the side corridor's walls, across it, and steering by them would turn
        // the robot into it. Along the corridor's direction once it is known (odometry),
        // not the robot's heading: a robot turned a little (round clutter, at a corner)
        // would otherwise take the crossing corridor's walls for its own and turn on.
        let (odom, axis) = (self.odom, self.axis);
        let along = |w: Option<SideWall>| {
            w.filter(|w| match (odom, axis) {
                (Some(o), Some(axis)) => {
                    let off = wrap(o.theta + w.angle - axis);
                    off.abs() < MAX_WALL_ANGLE || (std::f64::consts::PI - off.abs()) < MAX_WALL_ANGLE
                }
                _ => w.angle.abs() < MAX_WALL_ANGLE,
            })
        };
        let mut left = along(side_wall(&self.sonar, LEFT, self.max_wall, 0.15));
        let mut right = along(side_wall(&self.sonar, RIGHT, self.max_wall, 0.15));
        // Clutter: a wall nearer than the corridor's width (both seen) or than the wall's own
        // recent distance (one seen) allows; the side that moved in most is the clutter.
        match (left, right) {
            (Some(l), Some(r)) => {
                if let Some(width) = self.widths.quantile() {
                    if l.distance + r.distance < width - self.clutter_m {
                        let drop_l = self.sides[0].quantile().map_or(0.0, |q| q - l.distance);
                        let drop_r = self.sides[1].quantile().map_or(0.0, |q| q - r.distance);
                        if drop_l >= drop_r {
                            left = None;
                        } else {
                            right = None;
                        }
                    }
                }
            }
            // One wall: nearer than it was is clutter; much farther is not this corridor's wall
            // but something beyond an opening (a bin in a junction's far corner, an alcove's
            // wall), which steering by would turn the robot into the opening.
            (Some(l), None) if self.sides[0].quantile().is_some_and(|q| !self.lone_ok(l.distance, q)) => left = None,
            (None, Some(r)) if self.sides[1].quantile().is_some_and(|q| !self.lone_ok(r.distance, q)) => right = None,
            _ => {}
        }
        if let Some(l) = left {
            self.sides[0].push(l.distance);
        }
        if let Some(r) = right {
            self.sides[1].push(r.distance);
        }
        // Half the corridor's width while both walls are seen, remembered past openings.
        if let (Some(l), Some(r)) = (left, right) {
            let width = self.widths.push(l.distance + r.distance);
            self.half = Some(width / 2.0);
        }
        // With one wall only: keep the half-width last seen, or with no width seen yet (a
        // lobby, a hall) the distance it had from that wall when it came into view.
        let lone = match (left, right) {
            (Some(w), None) | (None, Some(w)) => self.half.unwrap_or(*self.lone.get_or_insert(w.distance)),
            _ => {
                self.lone = None;
                0.0
            }
        };
        // Offset to the left of where the robot should be, and the walls' direction.
        let seen = match (left, right) {
            (Some(l), Some(r)) => Some(((l.distance - r.distance) / 2.0, (l.angle + r.angle) / 2.0)),
            (Some(l), None) => Some((l.distance - lone, l.angle)),
            (None, Some(r)) => Some((lone - r.distance, r.angle)),
            (None, None) => None,
        };
        // With odometry the corridor is a direction, not just a line: the one the robot
        // faced when activated, kept up to date from the walls. Turned round (avoiding
        // someone, say), the robot turns back to it instead of following the corridor back.
        if let Some(o) = self.odom {
            let axis = *self.axis.get_or_insert(o.theta);
            // Corrected only by both walls agreeing, near it: a lone fit (a wall's end and a
            // bin beyond it, say) tilts a little each cycle and would drag the axis after it.
            let both = match (left, right) {
                (Some(l), Some(r)) if (l.angle - r.angle).abs() < AXIS_AGREE => seen,
                _ => None,
            };
            if let Some((_, angle)) = both.filter(|&(_, a)| wrap(o.theta + a - axis).abs() < AXIS_FOLLOW) {
                let mut along = wrap(o.theta + angle);
                if wrap(along - axis).abs() > std::f64::consts::FRAC_PI_2 {
                    along = wrap(along + std::f64::consts::PI);
                }
                self.axis = Some(wrap(axis + 0.1 * wrap(along - axis)));
            }
        }
        // Where no wall is seen, back to the line the robot was on: pushed aside in a lobby
        // (going round someone), it would otherwise go on parallel to its way, and miss the
        // corridor it was heading for or clip its jamb.
        if let Some(o) = self.odom {
            if seen.is_some() || self.line.is_none() {
                self.line = Some((o.x, o.y));
            }
        }
        let (offset, angle) = match (seen, self.odom, self.axis) {
            (seen, Some(o), Some(axis)) => {
                let angle = wrap(axis - o.theta);
                // The walls' left and right are the corridor's only while facing its way.
                let offset = match (seen, self.line) {
                    (Some((off, _)), _) => {
                        if angle.abs() > std::f64::consts::FRAC_PI_2 {
                            -off
                        } else {
                            off
                        }
                    }
                    // Left of the line (along the axis) by `c`: the way is to the right.
                    (None, Some((lx, ly))) => (o.x - lx) * axis.sin() - (o.y - ly) * axis.cos(),
                    (None, None) => 0.0,
                };
                (offset, angle)
            }
            (Some((offset, angle)), _, _) => (offset, angle),
            (None, _, _) => (0.0, 0.0),
        };
        // Heading wanted relative to the corridor, then relative to the robot.
        let wanted = clamp_abs(1.2 * offset, 0.5);
        let error = wrap(wanted + angle);
        let w = clamp_abs(1.5 * error, self.max_turn);
        let ahead = nearest_in(&self.sonar, 0.0, 16f64.to_radians()).map_or(f64::INFINITY, |(_, r)| r - ROBOT_RADIUS);
        let slow = ((ahead - self.stop_distance) / 1.0).clamp(0.0, 1.0);
        let v = self.speed * slow * error.cos().max(0.3);
        self.drive = Drive { v, w };
        Ok(())
    }
}
