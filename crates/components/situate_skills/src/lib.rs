//! The standard skill library of a Denning-like mobile robot (round, radius
//! 0.25 m, differential drive, a ring of 24 sonars, a barcode reader, a
//! button arm, a speaker), over the signals of [`situate_robot`].
//!
//! Type names start with `std.`. The skills that drive claim the `drive`
//! resource and are arbitrated by priority: `std.runaway` 50, `std.avoid`
//! 40, `std.pass_door`/`std.enter_car`/`std.leave_car` 35,
//! `std.home`/`std.home_position` 30, `std.follow_hallway`/`std.turn` 25,
//! `std.wander` 10. A skill with nothing to say this cycle leaves its
//! output unset.
//!
//! Sonar ranges and barcode distances are measured from the robot's centre
//! (as the simulator's `sim.sonar` and `sim.barcode` do); distance
//! parameters called clearances are from the robot's rim (range − 0.25 m).
//!
//! | skill | reads | writes |
//! |---|---|---|
//! | `std.runaway` | `sonar.range` | `drive` (only when something is within `safe_distance`) |
//! | `std.avoid` | `sonar.range` | `drive` (only when an obstacle is in the path within `distance`) |
//! | `std.wander` | — | `drive` (every cycle) |
//! | `std.follow_hallway` | `sonar.range`, `odom` (optional) | `drive` (every cycle) |
//! | `std.detect_door` | `sonar.range` | `door` (every cycle) |
//! | `std.detect_intersection` | `sonar.range`, `odom` (optional) | `junction` (every cycle) |
//! | `std.watch_openings` | `sonar.range`, `odom` (optional) | `opened` (every cycle) |
//! | `std.sonar_filter` | `sonar.raw`, `odom` (optional) | `sonar.range`, `sonar.health` (every cycle) |
//! | `std.fit_wall` | `sonar.range` | `wall`, `barcode_wall` (every cycle) |
//! | `std.locate_door` | `sonar.range` | `opening` (every cycle) |
//! | `std.track_barcode` | `barcodes` | `target` (every cycle) |
//! | `std.identify_car` | `barcodes` | `car` (every cycle) |
//! | `std.home` | `target` | `drive` (while `target.seen`) |
//! | `std.home_position` | `odom` | `drive` (every cycle) |
//! | `std.turn` | `odom` | `drive` (until turned) |
//! | `std.pass_door` | `sonar.range`, `odom` | `drive`, `door_passed` (every cycle) |
//! | `std.enter_car` | `sonar.range`, `odom` | `drive`, `car_entered` (every cycle) |
//! | `std.leave_car` | `sonar.range`, `odom` | `drive`, `car_exited` (every cycle) |
//! | `std.push_button` | `target`, `arm` (optional) | `arm.press` (when a push is tried) |
//! | `std.say` | — | `speaker.say` (once per activation) |
//!
//! Skills whose behaviour depends on "since activation" (`std.turn`,
//! `std.say`, `std.push_button`, `std.pass_door`, `std.enter_car`,
//! `std.leave_car`, `std.home_position`, the corridor width
//! `std.follow_hallway` remembers, and the detectors' and trackers' state)
//! start afresh in their `Body::activate`, which the manager calls when the
//! skill is switched on. (They once guessed a switch on from a gap between
//! two runs, and so also started afresh when an input skipped a cycle.)

mod actions;
mod health;
mod motion;
mod perception;
mod scan;
pub mod util;

use situate::manager::Registry;

pub use actions::{PushButton, Say};
pub use health::SonarFilter;
pub use motion::{Avoid, EnterCar, FollowHallway, Home, HomePosition, LeaveCar, PassDoor, Runaway, Turn, Wander};
pub use perception::{DetectDoor, DetectIntersection, IdentifyCar, TrackBarcode, WatchOpenings};
pub use scan::{barcode_wall, door_in_wall, fit_wall, fit_wall_through, locate_door, FitWall, LocateDoor, ScanModel};

/// Adds every standard skill type to `registry`.
pub fn register(registry: &mut Registry) {
    registry
        .register::<Runaway>()
        .register::<Avoid>()
        .register::<Wander>()
        .register::<FollowHallway>()
        .register::<DetectDoor>()
        .register::<WatchOpenings>()
        .register::<DetectIntersection>()
        .register::<FitWall>()
        .register::<SonarFilter>()
        .register::<LocateDoor>()
        .register::<TrackBarcode>()
        .register::<Home>()
        .register::<HomePosition>()
        .register::<Turn>()
        .register::<PassDoor>()
        .register::<PushButton>()
        .register::<IdentifyCar>()
        .register::<EnterCar>()
        .register::<LeaveCar>()
        .register::<Say>();
}

/// A registry holding the standard skills.
pub fn registry() -> Registry {
    let mut r = Registry::new();
    register(&mut r);
    r
}
