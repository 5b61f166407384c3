//! `std.sonar_filter`: the sonar ring as the other skills should see it,
//! with dead sonars found and filled in.

use situate::prelude::*;
use situate_robot::{Odom, SonarHealth, SONARS};

use crate::util::wrap;

/// Finds dead sonars and fills them in. A sonar is taken to be dead when,
/// over `evidence` observations made while the robot moved (at least 5 cm
/// or 3° since the last one), it read no echo (≥ `max_range`) every time
/// while a neighbour saw something nearer than `neighbour_m`; one echo
/// brings it back. A dead sonar's range is written as the nearer of its
/// neighbours' (the careful guess for avoiding obstacles, and no false
/// "seeing through" for the door and junction detectors). Reads the ring
/// as the device writes it (`sonar.raw`, the device's `range` remapped)
/// and writes `sonar.range` and `sonar.health` every run.
#[derive(Skill, Default)]
#[skill(name = "std.sonar_filter")]
pub struct SonarFilter {
    /// The ring as the device measures it, m.
    #[input(signal = "sonar.raw")]
    raw: [f32; SONARS],
    /// Odometry: evidence counts only while the robot moves.
    #[input]
    odom: Option<Odom>,
    /// The ring with dead sonars filled in, m.
    #[output(signal = "sonar.range")]
    range: [f32; SONARS],
    /// Which sonars are dead.
    #[output(signal = "sonar.health")]
    health: SonarHealth,
    /// The device's no-echo reading (or less), m.
    #[param(default = 3.95, min = 0.5, max = 100.0, unit = "m")]
    max_range: f64,
    /// A neighbour nearer than this makes a no-echo reading suspicious, m.
    #[param(default = 2.0, min = 0.1, max = 100.0, unit = "m")]
    neighbour_m: f64,
    /// Suspicious observations (while moving) before a sonar is dead.
    #[param(default = 40, min = 1, max = 100000)]
    evidence: i64,
    suspicion: [i64; SONARS],
    dead: [bool; SONARS],
    last_pose: Option<(f64, f64, f64)>,
}

impl Body for SonarFilter {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let moved = match (self.odom, self.last_pose) {
            (Some(o), Some((x, y, th))) => {
                (o.x - x).hypot(o.y - y) >= 0.05 || wrap(o.theta - th).abs() >= 3f64.to_radians()
            }
            (Some(_), None) => true,
            (None, _) => true, // without odometry every scan counts
        };
        if moved {
            self.last_pose = self.odom.map(|o| (o.x, o.y, o.theta));
        }
        for i in 0..SONARS {
            let r = f64::from(self.raw[i]);
            let no_echo = !r.is_finite() || r >= self.max_range;
            if !no_echo {
                if self.dead[i] {
                    sprint!(cx, "sonar {i} answers again");
                }
                self.suspicion[i] = 0;
                self.dead[i] = false;
                continue;
            }
            let near = |k: usize| f64::from(self.raw[k]) < self.neighbour_m;
            if moved && (near((i + 1) % SONARS) || near((i + SONARS - 1) % SONARS)) {
                self.suspicion[i] += 1;
                if self.suspicion[i] >= self.evidence && !self.dead[i] {
                    self.dead[i] = true;
                    sprint!(
                        cx,
                        "sonar {i} reads no echo however the robot moves: taken as dead, filled in from its neighbours"
                    );
                }
            }
        }
        let mut out = self.raw;
        let mut mask = 0i64;
        for i in (0..SONARS).filter(|&i| self.dead[i]) {
            mask |= 1 << i;
            // The nearer live neighbour on either side (up to three sonars away).
            let fill = (1..=3)
                .flat_map(|k| [(i + k) % SONARS, (i + SONARS - k) % SONARS])
                .filter(|&k| !self.dead[k])
                .map(|k| self.raw[k])
                .take(2)
                .fold(f32::INFINITY, f32::min);
            if fill.is_finite() {
                out[i] = fill;
            }
        }
        self.range = out;
        self.health = SonarHealth { dead: i64::from(mask.count_ones()), mask };
        Ok(())
    }
}
