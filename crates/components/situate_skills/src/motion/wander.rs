//! Exploring: `std.wander`, a smooth random walk.

use situate::prelude::*;
use situate_robot::Drive;

use super::clamp_abs;

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
