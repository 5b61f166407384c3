//! The signals of a Denning-like mobile robot: one definition shared by the
//! simulator's dskills (`situate_sim`), any real-hardware dskills that
//! replace them, and the standard skill library (`situate_skills`).
//!
//! Units are SI; angles are radians, counter-clockwise; the robot frame has
//! x ahead and y to the left. The table of which skill writes which signal
//! is in `docs/robot-signals.md`.

use std::sync::Arc;

use situate::prelude::*;

/// Number of sonars in the ring.
pub const SONARS: usize = 24;

/// The bearing of sonar `i` in the robot frame: sonar 0 looks ahead, 6 to
/// the left, 12 behind, 18 to the right.
pub fn sonar_bearing(i: usize) -> f64 {
    let a = (i % SONARS) as f64 * std::f64::consts::TAU / SONARS as f64;
    if a > std::f64::consts::PI {
        a - std::f64::consts::TAU
    } else {
        a
    }
}

/// `drive`: a velocity command for the differential-drive base (a resource:
/// the skills that write it are arbitrated by priority).
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Drive {
    /// Forward speed, m/s.
    pub v: f64,
    /// Turn rate, rad/s (counter-clockwise).
    pub w: f64,
}

/// `odom`: odometry, with drift, in the frame of the pose the base started at.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Odom {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
    /// Measured forward speed, m/s.
    pub v: f64,
    /// Measured turn rate, rad/s.
    pub w: f64,
}

/// `barcodes`: the barcodes the reader sees now (three arrays of one length).
#[derive(Record, Clone, Debug, PartialEq)]
pub struct Barcodes {
    pub ids: Arc<[i64]>,
    /// Bearing in the robot frame, rad.
    pub bearing: Arc<[f64]>,
    /// Distance from the robot's centre, m.
    pub distance: Arc<[f64]>,
}

impl Default for Barcodes {
    fn default() -> Self {
        Barcodes { ids: Arc::from([]), bearing: Arc::from([]), distance: Arc::from([]) }
    }
}

impl Barcodes {
    /// `(bearing, distance)` of barcode `id`, if seen.
    pub fn find(&self, id: i64) -> Option<(f64, f64)> {
        let k = self.ids.iter().position(|&x| x == id)?;
        Some((*self.bearing.get(k)?, *self.distance.get(k)?))
    }
}

/// `arm`: the button arm's counters.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Arm {
    /// Pushes tried.
    pub attempts: i64,
    /// Pushes that hit a button.
    pub presses: i64,
}

/// `speaker`: what the speaker has done.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Speaker {
    /// Utterances said so far.
    pub count: i64,
}

/// `truth.pose`: the simulator's ground truth (for displays, tests and
/// experiments; skills must not read it).
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct TruthPose {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
    pub floor: i64,
}

/// `truth.cars`: per elevator car, its position (a fractional floor while
/// it moves) and its door opening (0 closed … 1 open).
#[derive(Record, Clone, Debug, PartialEq)]
pub struct TruthCars {
    pub floor: Arc<[f64]>,
    pub door: Arc<[f64]>,
}

impl Default for TruthCars {
    fn default() -> Self {
        TruthCars { floor: Arc::from([]), door: Arc::from([]) }
    }
}

/// `truth.people`: the simulator's people (ground truth), one entry per
/// person: position and floor.
#[derive(Record, Clone, Debug, PartialEq)]
pub struct TruthPeople {
    pub x: Arc<[f64]>,
    pub y: Arc<[f64]>,
    pub floor: Arc<[i64]>,
}

impl Default for TruthPeople {
    fn default() -> Self {
        TruthPeople { x: Arc::from([]), y: Arc::from([]), floor: Arc::from([]) }
    }
}

/// `truth.mission`: whether the message was delivered inside the goal office.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct TruthMission {
    pub delivered: bool,
    /// Simulated time of the delivery, s (0 until delivered).
    pub delivered_at_s: f64,
}

/// `target`: the tracked barcode.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Target {
    pub seen: bool,
    pub id: i64,
    /// Bearing in the robot frame, rad.
    pub bearing: f64,
    /// Distance, m.
    pub distance: f64,
}

/// `door`: an opening in a side wall.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Door {
    pub left: bool,
    pub right: bool,
    /// Bearing of the opening's centre in the robot frame, rad.
    pub bearing: f64,
}

/// `opened`: a way that opened near the robot (a car's door, a door that was
/// closed), seen as a sonar whose reading jumped from near to far and stayed.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Opened {
    pub seen: bool,
    /// Bearing of the sonar that saw it, in the robot frame, rad.
    pub bearing: f64,
    /// That sonar's reading before (the farthest of the last second), m.
    pub before: f64,
    /// Its reading now, m.
    pub range: f64,
}

/// `junction`: which ways are open at an intersection.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Junction {
    pub left: bool,
    pub right: bool,
    pub ahead: bool,
    /// How far ahead (negative: behind) the centre of the side opening last
    /// seen lies, along the heading, m.
    pub centre: f64,
}

/// `wall`: the wall ahead, the line through most echoes of the front half
/// of the sonar ring.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Wall {
    pub seen: bool,
    /// Direction from the robot to the wall, perpendicular to it, in the
    /// robot frame, rad (0: the robot faces the wall squarely).
    pub normal: f64,
    /// Perpendicular distance from the robot's centre to the wall, m.
    pub distance: f64,
    /// Echoes on the line.
    pub inliers: i64,
}

/// `opening`: a door opening in the wall ahead, in the robot frame.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Opening {
    pub seen: bool,
    /// Direction from the robot to the wall, perpendicular to it, rad.
    pub normal: f64,
    /// Perpendicular distance from the robot's centre to the wall, m.
    pub wall: f64,
    /// The opening's centre on the wall line (x ahead, y to the left), m.
    pub x: f64,
    pub y: f64,
    /// Width between the jambs, m.
    pub width: f64,
}

/// `sonar.health`: which sonars are taken to be dead (they read no echo
/// however the robot moves, while their neighbours see things).
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct SonarHealth {
    /// Number of dead sonars.
    pub dead: i64,
    /// Bit i set: sonar i is dead.
    pub mask: i64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sonar_bearings_go_counter_clockwise_from_ahead() {
        assert_eq!(sonar_bearing(0), 0.0);
        assert!((sonar_bearing(6) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        assert!((sonar_bearing(12) - std::f64::consts::PI).abs() < 1e-12);
        assert!((sonar_bearing(18) + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn barcodes_find_by_id() {
        let b = Barcodes { ids: Arc::from([3, 7]), bearing: Arc::from([0.1, -0.2]), distance: Arc::from([1.0, 2.0]) };
        assert_eq!(b.find(7), Some((-0.2, 2.0)));
        assert_eq!(b.find(4), None);
    }

    #[test]
    fn records_have_the_contract_types() {
        assert_eq!(Drive::signal_type().to_string(), "{v: f64, w: f64}");
        assert_eq!(Barcodes::signal_type().to_string(), "{ids: i64[], bearing: f64[], distance: f64[]}");
        assert_eq!(TruthPeople::signal_type().to_string(), "{x: f64[], y: f64[], floor: i64[]}");
    }
}
