//! This program's own skill types: `ext.nearest` finds the nearest obstacle in the sonar ring,
//! `ext.brake` turns the robot on the spot while one is closer than `stop_distance`, and holds it
//! still while the program's emergency stop is pressed.

use std::sync::atomic::{AtomicBool, Ordering};

use situate::prelude::*;

/// A velocity command: forward m/s, turn rad/s (the toy wheels' `drive`; records match by their
/// fields, so this one is the same signal type).
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Drive {
    pub v: f64,
    pub w: f64,
}

/// The nearest obstacle the sonar ring sees: its range and bearing.
#[derive(Skill, Default)]
#[skill(name = "ext.nearest")]
pub struct Nearest {
    /// Sonar ranges in metres, sonar 0 forward, counter-clockwise, evenly spread.
    #[input(signal = "sonar.range")]
    sonar: Arc<[f32]>,
    /// The shortest range, metres (infinite with no sonar).
    #[output(signal = "obstacle.range")]
    range: f64,
    /// Its bearing, radians in (-π, π], 0 forward, counter-clockwise.
    #[output(signal = "obstacle.bearing")]
    bearing: f64,
}

impl Body for Nearest {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let n = self.sonar.len();
        let nearest = self.sonar.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1));
        (self.range, self.bearing) = match nearest {
            Some((i, &r)) => {
                let a = std::f64::consts::TAU * i as f64 / n as f64;
                (f64::from(r), if a > std::f64::consts::PI { a - std::f64::consts::TAU } else { a })
            }
            None => (f64::INFINITY, 0.0),
        };
        Ok(())
    }
}

/// Turns on the spot, away from the nearest obstacle, while it is closer than `stop_distance`;
/// otherwise writes nothing (so a lower-priority writer of `drive` wins). While the emergency stop
/// is pressed, it holds the robot still instead: zero velocity, every cycle.
#[derive(Skill)]
#[skill(name = "ext.brake", priority = 30)]
pub struct Brake {
    #[input(signal = "obstacle.range")]
    range: f64,
    #[input(signal = "obstacle.bearing")]
    bearing: f64,
    /// Written only when something is too near.
    #[output]
    drive: Option<Drive>,
    /// Obstacles nearer than this stop the robot.
    #[param(default = 0.3, min = 0.05, max = 3.0, unit = "m")]
    stop_distance: f64,
    /// Turn rate while stopped.
    #[param(default = 1.0, min = 0.0, max = 3.0, unit = "rad/s")]
    turn: f64,
    /// The program's emergency stop, set while it is pressed (a resource: `src/main.rs` provides
    /// it, and every skill made with it shares it).
    #[resource]
    estop: Arc<AtomicBool>,
    /// Cycles braked since the skill was last switched on.
    braked: u64,
    /// Whether the emergency stop held the robot in the last run (said once per press).
    held: bool,
}

impl Body for Brake {
    /// Switched on: counts afresh (the body, and this field, live across activations).
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.braked = 0;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.estop.load(Ordering::Acquire) {
            self.drive = Some(Drive { v: 0.0, w: 0.0 });
            if !self.held {
                sprint!(cx, "emergency stop pressed: holding still");
            }
            self.held = true;
            return Ok(());
        }
        if std::mem::take(&mut self.held) {
            sprint!(cx, "emergency stop released");
        }
        if self.range < self.stop_distance {
            let away = if self.bearing >= 0.0 { -self.turn } else { self.turn };
            self.drive = Some(Drive { v: 0.0, w: away });
            self.braked += 1;
            sprint!(cx, "obstacle at {:.2} m: braking", self.range);
        }
        Ok(())
    }

    /// Switched off: says how long it braked while on.
    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        sprint!(cx, "switched off after braking {} cycles", self.braked);
        Ok(())
    }
}
