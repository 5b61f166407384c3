//! Toy skills and an in-memory test device.
//!
//! Enough to run a robot file with no hardware and no simulator: a fake sonar
//! ring and a fake wheel base (dskills), and the paper's `runaway` (with its
//! `safe_distance`) and a `wander` (cskills) that both write the `drive`
//! resource. [`MemDevice`] and [`gate`] are for tests of the manager's
//! promises about devices: a dskill whose device hangs must not delay the
//! cycle.

use std::f64::consts::PI;

use situate::manager::Registry;
use situate::prelude::*;

/// A velocity command for a differential-drive base.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Drive {
    /// Forward speed, m/s.
    pub v: f64,
    /// Turn rate, rad/s.
    pub w: f64,
}

/// A planar pose from odometry.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

/// A ring of 24 sonars around a robot in a round room whose walls sit
/// `room_m` away from its centre, with a box drifting around it.
#[derive(Skill, Default)]
#[skill(name = "toy.sonar", kind = "device")]
pub struct FakeSonar {
    /// Ranges in metres, sonar 0 facing forward, counter-clockwise.
    #[output(signal = "sonar.range")]
    range: [f32; 24],
    /// Radius of the room, metres.
    #[param(default = 2.0, min = 0.5, max = 20.0, unit = "m")]
    room_m: f64,
    /// Period of the drifting box's orbit, seconds.
    #[param(default = 8.0, min = 0.1, max = 1000.0, unit = "s")]
    orbit_s: f64,
    t: f64,
}

impl Body for FakeSonar {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.t = cx.time_s();
        let bearing = 2.0 * PI * self.t / self.orbit_s;
        for (i, r) in self.range.iter_mut().enumerate() {
            let a = 2.0 * PI * i as f64 / 24.0;
            let off = (a - bearing).sin().abs();
            // The box is 0.2 m + 1 m·|sin| away in the sonar's direction.
            let boxed = if (a - bearing).cos() > 0.9 { 0.2 + off } else { f64::INFINITY };
            *r = self.room_m.min(boxed) as f32;
        }
        Ok(())
    }
}

/// A wheel base that integrates the latest drive command into a pose.
#[derive(Skill, Default)]
#[skill(name = "toy.wheels", kind = "device")]
pub struct FakeWheels {
    /// The command; without a new one the base keeps the last for `hold_s`.
    #[input]
    drive: Option<Drive>,
    #[output]
    odom: Pose,
    /// How long a command holds before the base stops, seconds.
    #[param(default = 0.5, min = 0.0, max = 10.0, unit = "s")]
    hold_s: f64,
    last: Drive,
    last_at: f64,
    t: f64,
}

impl Body for FakeWheels {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let now = cx.time_s();
        let dt = (now - self.t).max(0.0);
        self.t = now;
        if let Some(cmd) = self.drive.take() {
            self.last = cmd;
            self.last_at = now;
        } else if now - self.last_at > self.hold_s {
            self.last = Drive::default();
        }
        self.odom.theta += self.last.w * dt;
        self.odom.x += self.last.v * self.odom.theta.cos() * dt;
        self.odom.y += self.last.v * self.odom.theta.sin() * dt;
        Ok(())
    }
}

/// Turns away from the nearest obstacle closer than `safe_distance`
/// (paper 3.1); silent when nothing is that close.
#[derive(Skill, Default)]
#[skill(name = "toy.runaway", priority = 20)]
pub struct Runaway {
    /// Sonar ranges, metres.
    #[input(signal = "sonar.range")]
    sonar_range: Arc<[f32]>,
    #[output]
    drive: Option<Drive>,
    /// Obstacles nearer than this make the robot run away, metres.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    safe_distance: f64,
    /// Speed while running away, m/s.
    #[param(default = 0.3, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
}

impl Body for Runaway {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let n = self.sonar_range.len();
        let Some((i, r)) =
            self.sonar_range.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).map(|(i, r)| (i, f64::from(*r)))
        else {
            return Ok(());
        };
        if r < self.safe_distance {
            let bearing = 2.0 * PI * i as f64 / n as f64;
            // Turn so the obstacle ends up behind, and back off if it's in front.
            let w = -bearing.sin().signum() * 1.0;
            let v = if bearing.cos() > 0.0 { -self.speed } else { self.speed };
            self.drive = Some(Drive { v, w });
            sprint!(cx, "obstacle at {:.2} m, bearing {:.0}°: running away", r, bearing.to_degrees());
        }
        Ok(())
    }
}

/// Drives forward, changing heading now and then (a seeded random walk).
#[derive(Skill, Default)]
#[skill(name = "toy.wander", priority = 10)]
pub struct Wander {
    #[output]
    drive: Drive,
    /// Cruising speed, m/s.
    #[param(default = 0.2, min = 0.0, max = 1.0, unit = "m/s")]
    speed: f64,
    /// Seed of the random walk.
    #[param(default = 1)]
    seed: i64,
    state: u64,
}

impl Body for Wander {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.state == 0 {
            self.state = (self.seed as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        }
        // xorshift64
        self.state ^= self.state << 13;
        self.state ^= self.state >> 7;
        self.state ^= self.state << 17;
        let turn = ((self.state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.8;
        if cx.cycle().is_multiple_of(50) {
            sprint!(cx, "new heading change {turn:.2} rad/s");
        }
        self.drive = Drive { v: self.speed, w: turn };
        Ok(())
    }
}

pub mod gate {
    //! Named gates for tests: a body that waits on a closed gate blocks
    //! until the test opens it, standing in for a hung device or a slow
    //! computation without timing anything.

    use std::collections::HashMap;
    use std::sync::{Condvar, Mutex, OnceLock};

    struct Gates {
        open: Mutex<HashMap<String, bool>>,
        changed: Condvar,
    }

    fn gates() -> &'static Gates {
        static GATES: OnceLock<Gates> = OnceLock::new();
        GATES.get_or_init(|| Gates { open: Mutex::new(HashMap::new()), changed: Condvar::new() })
    }

    pub fn close(name: &str) {
        gates().open.lock().unwrap_or_else(|p| p.into_inner()).insert(name.to_string(), false);
    }

    pub fn open(name: &str) {
        gates().open.lock().unwrap_or_else(|p| p.into_inner()).insert(name.to_string(), true);
        gates().changed.notify_all();
    }

    /// Waits until the gate is open (an unknown gate is open).
    pub fn pass(name: &str) {
        let g = gates();
        let mut open = g.open.lock().unwrap_or_else(|p| p.into_inner());
        while open.get(name) == Some(&false) {
            open = g.changed.wait(open).unwrap_or_else(|p| p.into_inner());
        }
    }
}

/// An in-memory test device: a register the commands write and the readings
/// report, counting its exchanges. With `gate` set, each exchange first waits
/// for that [`gate`] to be open — a device that hangs.
#[derive(Skill, Default)]
#[skill(name = "toy.memdev", kind = "device")]
pub struct MemDevice {
    #[input]
    command: Option<f64>,
    /// The last command written, or 0.
    #[output]
    reading: f64,
    /// How many exchanges the device has done.
    #[output]
    exchanges: i64,
    /// Name of the gate each exchange waits on (empty: none).
    #[param(default = "")]
    gate: String,
}

impl Body for MemDevice {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        if !self.gate.is_empty() {
            gate::pass(&self.gate);
        }
        if let Some(c) = self.command.take() {
            self.reading = c;
        }
        self.exchanges += 1;
        Ok(())
    }
}

/// Every toy skill type.
pub fn register(registry: &mut Registry) {
    registry
        .register::<FakeSonar>()
        .register::<FakeWheels>()
        .register::<Runaway>()
        .register::<Wander>()
        .register::<MemDevice>()
        .register::<example::Runaway>()
        .register::<Agree>();
}

/// The Rust one of the four runaway examples (`examples/{rust,c,cpp,python}/runaway`), built in so
/// robot files can name `rust.runaway` next to the others. `rust_runaway.rs` is a link to the
/// example's file, so the packaged crate carries the file itself.
#[path = "rust_runaway.rs"]
pub mod example;

/// Checks that up to four writers of a `drive` command agree exactly: every
/// cycle, either none of `a`, `b`, `c`, `d` was written or all were, with
/// bit-identical values (an absent input counts as silence).
#[derive(Skill, Default)]
#[skill(name = "toy.agree")]
pub struct Agree {
    #[input]
    a: Option<Drive>,
    #[input]
    b: Option<Drive>,
    #[input]
    c: Option<Drive>,
    #[input]
    d: Option<Drive>,
    /// Cycles checked so far.
    #[output(signal = "agree.cycles")]
    cycles: i64,
    /// Cycles in which all four wrote (and agreed).
    #[output(signal = "agree.commands")]
    commands: i64,
    /// Cycles in which they did not agree.
    #[output(signal = "agree.mismatches")]
    mismatches: i64,
}

impl Body for Agree {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let bits = |d: &Option<Drive>| d.map(|d| (d.v.to_bits(), d.w.to_bits()));
        let all = [bits(&self.a), bits(&self.b), bits(&self.c), bits(&self.d)];
        self.cycles += 1;
        if all.iter().all(|x| *x == all[0]) {
            if all[0].is_some() {
                self.commands += 1;
            }
        } else {
            self.mismatches += 1;
            sprint!(
                cx,
                "cycle {}: the writers disagree: {:?} {:?} {:?} {:?}",
                cx.cycle(),
                self.a,
                self.b,
                self.c,
                self.d
            );
        }
        Ok(())
    }
}

/// A registry holding the toy skills.
pub fn registry() -> Registry {
    let mut r = Registry::new();
    register(&mut r);
    r
}
