//! Skills that write the `drive` resource.
//!
//! Every one of them claims `drive` and is arbitrated by priority (runaway
//! 50, avoid 40, pass_door/enter_car/leave_car 35, home/home_position 30,
//! follow_hallway/turn 25, wander 10). A skill with nothing to say this cycle
//! leaves `drive` unset, so a lower-priority writer's command stands.

use std::f64::consts::{FRAC_PI_2, PI};

use situate::prelude::*;
use situate_robot::{sonar_bearing, Drive, Odom, Target, SONARS};

use crate::perception::Window;
use crate::util::{
    centre_range, echo_point, nearest_in, side_wall, wrap, Activation, SideWall, LEFT, RIGHT, ROBOT_RADIUS,
};

fn clamp_abs(x: f64, limit: f64) -> f64 {
    let limit = limit.abs();
    x.clamp(-limit, limit)
}

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

/// Smooth random exploration: drives at `speed` while the turn rate drifts
/// towards a new random value in ±`max_turn` every `change_s` seconds (a
/// random walk fixed by `seed`). Writes `drive` every run.
#[derive(Skill, Default)]
#[skill(name = "std.wander", priority = 10)]
pub struct Wander {
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Forward speed, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Seed of the random walk: the same seed gives the same walk.
    #[param(default = 1)]
    seed: i64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.5, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    /// Time between new turn rates, s.
    #[param(default = 2.0, min = 0.1, max = 60.0, unit = "s")]
    change_s: f64,
    rng: u64,
    seeded: Option<i64>,
    goal: f64,
    w: f64,
    last_t: Option<f64>,
    next_change: f64,
}

impl Wander {
    /// A uniform number in [−1, 1) (splitmix64).
    fn uniform(&mut self) -> f64 {
        self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.rng;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

impl Body for Wander {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let now = cx.time_s();
        if self.seeded != Some(self.seed) {
            self.seeded = Some(self.seed);
            self.rng = self.seed as u64;
            self.next_change = now;
            self.w = 0.0;
        }
        let dt = self.last_t.map_or(0.0, |t| (now - t).clamp(0.0, 0.5));
        self.last_t = Some(now);
        if now >= self.next_change {
            self.goal = self.uniform() * self.max_turn;
            self.next_change = now + self.change_s;
        }
        // First-order approach to the goal turn rate (time constant 0.5 s).
        self.w += (self.goal - self.w) * (dt / 0.5).min(1.0);
        self.drive = Drive { v: self.speed, w: clamp_abs(self.w, self.max_turn) };
        Ok(())
    }
}

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
    activation: Activation,
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
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.activation.fresh(cx.cycle()) {
            self.half = None;
            self.widths = Window::default();
            self.sides = [Window::default(); 2];
            self.axis = None;
            self.lone = None;
            self.line = None;
        }
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
    activation: Activation,
    /// The goal `arrived` is about.
    goal: Option<(f64, f64)>,
}

impl Body for HomePosition {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        // A new activation or a new goal: not there yet (a goal just beside the last one,
        // within twice `stop_distance`, would otherwise count as reached).
        if self.activation.fresh(cx.cycle()) || self.goal != Some((self.x, self.y)) {
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

/// Turns in place by `angle` relative to the heading at activation
/// (measured with odometry, so any angle, even beyond a half turn), then
/// falls silent. Writes `drive` until the turn is done within `tolerance`.
#[derive(Skill, Default)]
#[skill(name = "std.turn", priority = 25)]
pub struct Turn {
    /// Odometry.
    #[input]
    odom: Odom,
    /// The velocity command, written until the turn is done.
    #[output]
    drive: Option<Drive>,
    /// Angle to turn, rad (positive: left).
    #[param(default = FRAC_PI_2, min = -12.6, max = 12.6, unit = "rad")]
    angle: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.8, min = 0.05, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    /// The turn is done when this close to `angle`, rad.
    #[param(default = 0.03, min = 0.001, max = 0.5, unit = "rad")]
    tolerance: f64,
    activation: Activation,
    turned: f64,
    last_theta: f64,
    done: bool,
}

impl Body for Turn {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let theta = self.odom.theta;
        if !theta.is_finite() {
            tracing::warn!(skill = "std.turn", theta, "odometry heading is not finite: silent this cycle");
            return Ok(());
        }
        if self.activation.fresh(cx.cycle()) {
            self.turned = 0.0;
            self.done = false;
        } else {
            self.turned += wrap(theta - self.last_theta);
        }
        self.last_theta = theta;
        let remaining = self.angle - self.turned;
        if !self.done && remaining.abs() <= self.tolerance {
            self.done = true;
            sprint!(cx, "turned {:.1}°", self.turned.to_degrees());
        }
        if self.done {
            return Ok(());
        }
        let w = clamp_abs(2.0 * remaining, self.max_turn);
        let w = if w.abs() < 0.1 { 0.1f64.copysign(remaining) } else { w };
        self.drive = Some(Drive { v: 0.0, w });
        Ok(())
    }
}

/// Echoes farther than this from the centre are no jamb, m.
const JAMB_RANGE: f64 = 1.5;

/// The parameters of a [`Passage`].
#[derive(Clone, Copy, Debug)]
struct PassageLimits {
    speed: f64,
    distance: f64,
    stop_distance: f64,
    max_turn: f64,
}

/// Drives through a narrow opening straight ahead, centred between its
/// jambs by sonar, until `distance` travelled (odometry) since activation;
/// shared by `std.pass_door`, `std.enter_car` and `std.leave_car`.
#[derive(Clone, Copy, Debug, Default)]
struct Passage {
    activation: Activation,
    start: (f64, f64),
    heading: f64,
    done: bool,
}

impl Passage {
    /// The command this cycle; `self.done` tells whether the passage is over.
    fn step(&mut self, cycle: u64, sonar: &[f32; SONARS], odom: &Odom, limits: PassageLimits) -> Drive {
        let PassageLimits { speed, distance, stop_distance, max_turn } = limits;
        if !(odom.x.is_finite() && odom.y.is_finite() && odom.theta.is_finite()) {
            tracing::warn!(?odom, "passage: odometry is not finite: stopping this cycle");
            return Drive::default();
        }
        if self.activation.fresh(cycle) {
            *self = Passage { activation: self.activation, start: (odom.x, odom.y), heading: odom.theta, done: false };
        }
        let travelled = (odom.x - self.start.0).hypot(odom.y - self.start.1);
        let ahead = nearest_in(sonar, 0.0, 16f64.to_radians()).map_or(f64::INFINITY, |(_, r)| r - ROBOT_RADIUS);
        if travelled >= distance || ahead <= stop_distance {
            self.done = true;
        }
        if self.done {
            return Drive::default();
        }
        // The jambs: the echoes nearest the robot's line on either side, near and not behind.
        let (mut left, mut right) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..SONARS {
            let (x, y) = echo_point(sonar, i);
            let b = sonar_bearing(i).abs();
            let near = x.hypot(y) <= JAMB_RANGE;
            if !near
                || !(15f64.to_radians() - 1e-9..=120f64.to_radians() + 1e-9).contains(&b)
                || !(-0.3..=1.2).contains(&x)
            {
                continue;
            }
            if y > 0.0 {
                left = left.min(y);
            } else {
                right = right.max(y);
            }
        }
        let wanted = if left.is_finite() && right.is_finite() {
            // Aim at the middle between the jambs, a little ahead.
            ((left + right) / 2.0).atan2(0.8)
        } else {
            // Hold the heading of activation.
            wrap(self.heading - odom.theta)
        };
        let w = clamp_abs(2.0 * wanted, max_turn);
        let slow = ((ahead - stop_distance) / 0.5).clamp(0.2, 1.0);
        Drive { v: speed * slow * wanted.cos().max(0.0), w }
    }
}

/// Goes through the door opening straight ahead (turn to face it first,
/// e.g. with `std.turn` by `door.bearing`), centred between the jambs by
/// sonar; stops after `distance` travelled since activation (odometry), or
/// when something is `stop_distance` ahead. Writes `drive` every run (a stop
/// once done) and `door_passed` (false until done).
#[derive(Skill, Default)]
#[skill(name = "std.pass_door", priority = 35)]
pub struct PassDoor {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry.
    #[input]
    odom: Odom,
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Whether the robot has gone `distance` since activation.
    #[output(signal = "door_passed")]
    passed: bool,
    /// Forward speed, m/s.
    #[param(default = 0.2, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Distance to travel from activation, m.
    #[param(default = 1.5, min = 0.0, max = 20.0, unit = "m")]
    distance: f64,
    /// Clearance ahead (rim to echo) at which the robot stops early, m.
    #[param(default = 0.3, min = 0.0, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.6, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    passage: Passage,
}

impl Body for PassDoor {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(cx.cycle(), &self.sonar, &self.odom, limits);
        self.passed = p.done;
        Ok(())
    }
}

/// Enters the elevator car whose open door is straight ahead: drives through
/// the opening centred by sonar until `distance` travelled since activation
/// (odometry) or the back wall is `stop_distance` ahead, then stops. Writes
/// `drive` every run (a stop once inside) and `car_entered`.
#[derive(Skill, Default)]
#[skill(name = "std.enter_car", priority = 35)]
pub struct EnterCar {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry.
    #[input]
    odom: Odom,
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Whether the robot is inside (done).
    #[output(signal = "car_entered")]
    entered: bool,
    /// Forward speed, m/s.
    #[param(default = 0.2, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Distance to travel from activation, m.
    #[param(default = 1.7, min = 0.0, max = 10.0, unit = "m")]
    distance: f64,
    /// Clearance ahead (rim to echo) at which the robot stops early, m.
    #[param(default = 0.3, min = 0.0, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.6, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    passage: Passage,
}

impl Body for EnterCar {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(cx.cycle(), &self.sonar, &self.odom, limits);
        self.entered = p.done;
        Ok(())
    }
}

/// Leaves the elevator car through its open door straight ahead (turn to
/// face it first): drives out centred by sonar until `distance` travelled
/// since activation (odometry) or something is `stop_distance` ahead, then
/// stops. Writes `drive` every run (a stop once outside) and `car_exited`.
#[derive(Skill, Default)]
#[skill(name = "std.leave_car", priority = 35)]
pub struct LeaveCar {
    /// Sonar ranges, m.
    #[input(signal = "sonar.range")]
    sonar: [f32; SONARS],
    /// Odometry.
    #[input]
    odom: Odom,
    /// The velocity command, written every run.
    #[output]
    drive: Drive,
    /// Whether the robot is outside (done).
    #[output(signal = "car_exited")]
    exited: bool,
    /// Forward speed, m/s.
    #[param(default = 0.2, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Distance to travel from activation, m.
    #[param(default = 1.6, min = 0.0, max = 10.0, unit = "m")]
    distance: f64,
    /// Clearance ahead (rim to echo) at which the robot stops early, m.
    #[param(default = 0.3, min = 0.0, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Largest turn rate, rad/s.
    #[param(default = 0.6, min = 0.0, max = 3.0, unit = "rad/s")]
    max_turn: f64,
    passage: Passage,
}

impl Body for LeaveCar {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(cx.cycle(), &self.sonar, &self.odom, limits);
        self.exited = p.done;
        Ok(())
    }
}
