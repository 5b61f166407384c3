//! The paper's runaway skill in Rust (type `rust.runaway`): when the nearest
//! of the 24 sonars is closer than `safe_distance`, back away from it and turn
//! away; otherwise write nothing (so a lower-priority writer of `drive` wins).
//!
//! The same algorithm as `examples/{c,cpp,python}/runaway`, step for step
//! (`-a.sin()` is `-1.0 * sin(a)` bit for bit), so the four agree bit for bit
//! (`examples/mixed/robot.yaml`). Like them, it counts the cycles it ran away
//! from each switch on (`activate`) and says the count when switched off
//! (`deactivate`), in the same words.

use situate::prelude::*;

/// A velocity command: forward m/s, turn rad/s.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Drive {
    pub v: f64,
    pub w: f64,
}

/// Backs away from the nearest sonar obstacle closer than `safe_distance`.
#[derive(Skill, Default)]
#[skill(name = "rust.runaway", priority = 50)]
pub struct Runaway {
    /// 24 ranges in metres, sonar 0 forward, counter-clockwise.
    #[input(signal = "sonar.range")]
    sonar: [f32; 24],
    /// Written only when something is too near.
    #[output]
    drive: Option<Drive>,
    /// Obstacles nearer than this repel.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    safe_distance: f64,
    /// Cycles it ran away since it was last switched on.
    ran: u64,
}

impl Body for Runaway {
    /// Switched on: counts afresh (the body, and this field, live across activations).
    fn activate(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.ran = 0;
        Ok(())
    }

    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        let two_pi = 2.0 * std::f64::consts::PI;
        let (mut k, mut r_min) = (0usize, f64::from(self.sonar[0]));
        for (i, &r) in self.sonar.iter().enumerate().skip(1) {
            // Ties: the lowest index wins.
            if f64::from(r) < r_min {
                (k, r_min) = (i, f64::from(r));
            }
        }
        if r_min >= self.safe_distance {
            return Ok(());
        }
        let a = if k <= 12 { k as f64 * two_pi / 24.0 } else { k as f64 * two_pi / 24.0 - two_pi };
        self.drive = Some(Drive { v: -0.3 * a.cos() * (1.0 - r_min / self.safe_distance), w: -a.sin() });
        self.ran += 1;
        Ok(())
    }

    /// Switched off: says how long it ran away while on.
    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        sprint!(cx, "switched off after running away {} cycles", self.ran);
        Ok(())
    }
}
