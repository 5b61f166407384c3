//! Passing a narrow opening centred between its jambs: `std.pass_door`, `std.enter_car` and
//! `std.leave_car`, over one `Passage`.

use situate::prelude::*;
use situate_robot::{sonar_bearing, Drive, Odom, SONARS};

use super::clamp_abs;
use crate::util::{echo_point, nearest_in, wrap, ROBOT_RADIUS};

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
    /// Begun: `start` and `heading` hold (a skill's switch on makes a fresh `Passage`).
    begun: bool,
    start: (f64, f64),
    heading: f64,
    done: bool,
}

impl Passage {
    /// The command this cycle; `self.done` tells whether the passage is over.
    fn step(&mut self, sonar: &[f32; SONARS], odom: &Odom, limits: PassageLimits) -> Drive {
        let PassageLimits { speed, distance, stop_distance, max_turn } = limits;
        if !(odom.x.is_finite() && odom.y.is_finite() && odom.theta.is_finite()) {
            tracing::warn!(?odom, "passage: odometry is not finite: stopping this cycle");
            return Drive::default();
        }
        if !self.begun {
            *self = Passage { begun: true, start: (odom.x, odom.y), heading: odom.theta, done: false };
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
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.passage = Passage::default();
        Ok(())
    }

    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(&self.sonar, &self.odom, limits);
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
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.passage = Passage::default();
        Ok(())
    }

    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(&self.sonar, &self.odom, limits);
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
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.passage = Passage::default();
        Ok(())
    }

    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        let limits = PassageLimits {
            speed: self.speed,
            distance: self.distance,
            stop_distance: self.stop_distance,
            max_turn: self.max_turn,
        };
        let p = &mut self.passage;
        self.drive = p.step(&self.sonar, &self.odom, limits);
        self.exited = p.done;
        Ok(())
    }
}
