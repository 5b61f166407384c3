//! Skills that write the `drive` resource.
//!
//! Every one of them claims `drive` and is arbitrated by priority (runaway
//! 50, avoid 40, pass_door/enter_car/leave_car 35, home/home_position 30,
//! follow_hallway/turn 25, wander 10). A skill with nothing to say this cycle
//! leaves `drive` unset, so a lower-priority writer's command stands.

mod avoid;
mod hallway;
mod homing;
mod passage;
mod turn;
mod wander;

pub use avoid::{Avoid, Runaway};
pub use hallway::FollowHallway;
pub use homing::{Home, HomePosition};
pub use passage::{EnterCar, LeaveCar, PassDoor};
pub use turn::Turn;
pub use wander::Wander;

fn clamp_abs(x: f64, limit: f64) -> f64 {
    let limit = limit.abs();
    x.clamp(-limit, limit)
}
