//! Turning: `std.turn`, in place by an angle measured with odometry.

use std::f64::consts::FRAC_PI_2;

use situate::prelude::*;
use situate_robot::{Drive, Odom};

use super::clamp_abs;
use crate::util::wrap;

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
    turned: f64,
    /// The heading at the last run since the switch on (`None`: none yet).
    last_theta: Option<f64>,
    done: bool,
}

impl Body for Turn {
    fn activate(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.turned = 0.0;
        self.last_theta = None;
        self.done = false;
        Ok(())
    }

    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let theta = self.odom.theta;
        if !theta.is_finite() {
            tracing::warn!(skill = "std.turn", theta, "odometry heading is not finite: silent this cycle");
            return Ok(());
        }
        if let Some(last) = self.last_theta {
            self.turned += wrap(theta - last);
        }
        self.last_theta = Some(theta);
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
