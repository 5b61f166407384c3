//! The standard skills against small scenes (see `scene`), run through
//! their real glue (see `harness`), and one real manager.

mod actions;
mod barcode_wall;
mod harness;
mod health;
mod manager;
mod motion;
mod perception;
mod scan;
mod scene;

use harness::{val, Harness};
use scene::{Pose, Scene};
use situate_robot::{Drive, Odom, SONARS};

/// Simulated seconds per cycle in the closed loops.
pub const DT: f64 = 0.05;

/// The `drive` a drive skill wrote this run, if any.
pub fn drive_of(h: &mut Harness, inputs: &[(&str, situate::Value)]) -> Option<Drive> {
    h.run(inputs).get::<Drive>("drive")
}

/// Sonar of `pose` in `scene` as the input value.
pub fn sonar(scene: &Scene, pose: Pose) -> situate::Value {
    val::<[f32; SONARS]>(scene.sonar(pose))
}

pub fn odom(pose: Pose) -> situate::Value {
    val(Odom { x: pose.x, y: pose.y, theta: pose.theta, v: 0.0, w: 0.0 })
}
