//! The simulator's dskills, one per device, sharing one [`World`].
//!
//! Each body first advances the world to its cycle time, so the physics
//! advances by time whoever calls first, under the simulated clock
//! (lockstep) as on device threads under the wall clock. The ports are the
//! robot's signal contract (`situate_robot`): real-hardware dskills with the
//! same ports can replace these without changing anything else.

use std::sync::{Arc, Mutex, MutexGuard};

use situate::manager::Registry;
use situate::prelude::*;
use situate_robot::{Arm, Barcodes, Drive, Odom, Speaker, TruthCars, TruthMission, TruthPeople, TruthPose, SONARS};

use crate::world::{BaseLimits, SonarSettings, World};

/// The world the sim dskills share.
pub type SharedWorld = Arc<Mutex<World>>;

/// The name of the resource every sim dskill is made with: the [`SharedWorld`].
pub const WORLD: &str = "world";

/// Locks the world (a poisoned lock is recovered: the world has no
/// invariant a panicking reader could break).
fn lock(world: &SharedWorld) -> MutexGuard<'_, World> {
    world.lock().unwrap_or_else(|p| p.into_inner())
}

/// The ring of 24 sonars: range along bearing i·15°, measured from the
/// robot's centre; no echo reads `max_range`.
#[derive(Skill)]
#[skill(name = "sim.sonar", kind = "device")]
pub struct SimSonar {
    /// Ranges, m: sonar 0 ahead, counter-clockwise.
    #[output(signal = "sonar.range")]
    range: [f32; SONARS],
    /// Reading when there is no echo, m.
    #[param(default = 4.0, min = 0.2, max = 20.0, unit = "m")]
    max_range: f64,
    /// Shortest reading, m.
    #[param(default = 0.1, min = 0.0, max = 1.0, unit = "m")]
    min_range: f64,
    /// Width of each sonar's cone.
    #[param(default = 15.0, min = 0.0, max = 60.0, unit = "deg")]
    cone_deg: f64,
    /// Rays cast per cone (the reading is their minimum).
    #[param(default = 5, min = 1.0, max = 31.0)]
    rays: i64,
    /// Gaussian range noise (standard deviation).
    #[param(default = 0.02, min = 0.0, max = 1.0, unit = "m")]
    noise_m: f64,
    /// Probability of a missed echo per reading.
    #[param(default = 0.01, min = 0.0, max = 1.0)]
    dropout: f64,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimSonar {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        let s = SonarSettings {
            min_range: self.min_range,
            max_range: self.max_range,
            cone: self.cone_deg.to_radians(),
            rays: self.rays.max(1) as usize,
            noise: self.noise_m,
            dropout: self.dropout,
        };
        self.range = w.sonar(&s);
        Ok(())
    }
}

/// The differential-drive base: obeys the latest `drive` within its limits
/// (no command for `hold_s` = stop, decelerating) and reports odometry, with
/// drift, in the frame of the pose it started at.
#[derive(Skill)]
#[skill(name = "sim.base", kind = "device")]
pub struct SimBase {
    /// Velocity command.
    #[input]
    drive: Option<Drive>,
    /// Odometry.
    #[output]
    odom: Odom,
    /// Top forward speed.
    #[param(default = 0.8, min = 0.0, max = 3.0, unit = "m/s")]
    max_v: f64,
    /// Top turn rate.
    #[param(default = 2.0, min = 0.0, max = 10.0, unit = "rad/s")]
    max_w: f64,
    /// Forward acceleration limit.
    #[param(default = 1.0, min = 0.01, max = 20.0, unit = "m/s^2")]
    acc_v: f64,
    /// Turn acceleration limit.
    #[param(default = 3.0, min = 0.01, max = 50.0, unit = "rad/s^2")]
    acc_w: f64,
    /// How long a command holds without a new one (0: stop in the first run without one).
    #[param(default = 0.0, min = 0.0, max = 10.0, unit = "s")]
    hold_s: f64,
    last: Drive,
    last_at: f64,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimBase {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let now = cx.time_s();
        if let Some(d) = self.drive.take() {
            if !d.v.is_finite() || !d.w.is_finite() {
                return Err(SkillError::new(format!("sim.base: drive command is not finite: v {} w {}", d.v, d.w)));
            }
            self.last = d;
            self.last_at = now;
        } else if now - self.last_at >= self.hold_s {
            self.last = Drive::default();
        }
        let limits = BaseLimits { max_v: self.max_v, max_w: self.max_w, acc_v: self.acc_v, acc_w: self.acc_w };
        let mut w = lock(&self.world);
        w.advance_to(now);
        w.set_drive(self.last.v, self.last.w, limits);
        let (x, y, theta, v, wr) = w.odom();
        self.odom = Odom { x, y, theta, v, w: wr };
        Ok(())
    }
}

/// The barcode reader: barcodes in range and field of view, facing the
/// robot, not hidden by a wall or a closed door; nearest first.
#[derive(Skill)]
#[skill(name = "sim.barcode", kind = "device")]
pub struct SimBarcode {
    /// What the reader sees now.
    #[output]
    barcodes: Barcodes,
    /// Reading range.
    #[param(default = 5.0, min = 0.1, max = 50.0, unit = "m")]
    range: f64,
    /// Half the field of view (either side of ahead).
    #[param(default = 60.0, min = 0.0, max = 180.0, unit = "deg")]
    fov_deg: f64,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimBarcode {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        let seen = w.barcodes(self.range, self.fov_deg.to_radians());
        self.barcodes = Barcodes {
            ids: seen.iter().map(|s| s.0).collect(),
            bearing: seen.iter().map(|s| s.1).collect(),
            distance: seen.iter().map(|s| s.2).collect(),
        };
        Ok(())
    }
}

/// The button arm: `arm.press` pushes the button with that label (a car
/// panel: the floor; a call button: any) if one is within `reach` of the
/// robot's centre and `fov_deg` of ahead.
#[derive(Skill)]
#[skill(name = "sim.arm", kind = "device")]
pub struct SimArm {
    /// Button to push.
    #[input(signal = "arm.press")]
    press: Option<i64>,
    /// Pushes tried and pushes that hit a button.
    #[output]
    arm: Arm,
    /// Reach from the robot's centre.
    #[param(default = 0.6, min = 0.0, max = 3.0, unit = "m")]
    reach: f64,
    /// How far off ahead a button may be.
    #[param(default = 25.0, min = 0.0, max = 180.0, unit = "deg")]
    fov_deg: f64,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimArm {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        if let Some(label) = self.press.take() {
            let hit = w.press(label, self.reach, self.fov_deg.to_radians());
            sprint!(cx, "press {label}: {}", if hit { "hit" } else { "nothing in reach" });
        }
        let (attempts, presses) = w.arm_counts();
        self.arm = Arm { attempts, presses };
        Ok(())
    }
}

/// The speaker: says `speaker.say`.
#[derive(Skill)]
#[skill(name = "sim.speaker", kind = "device")]
pub struct SimSpeaker {
    /// Text to say.
    #[input(signal = "speaker.say")]
    say: Option<String>,
    /// Utterances so far.
    #[output]
    speaker: Speaker,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimSpeaker {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        if let Some(text) = self.say.take() {
            sprint!(cx, "says: {text}");
            w.say(&text);
        }
        self.speaker = Speaker { count: w.speaker_count() };
        Ok(())
    }
}

/// The altimeter: the floor the robot is on (nearest floor while a car moves).
#[derive(Skill)]
#[skill(name = "sim.altimeter", kind = "device")]
pub struct SimAltimeter {
    /// Floor level.
    #[output]
    floor: i64,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimAltimeter {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        self.floor = w.robot().floor;
        Ok(())
    }
}

/// Ground truth for displays, tests and experiments (skills must not read it).
#[derive(Skill)]
#[skill(name = "sim.truth", kind = "device")]
pub struct SimTruth {
    /// The robot's true pose and floor.
    #[output(signal = "truth.pose")]
    pose: TruthPose,
    /// Each car's floor position and door opening.
    #[output(signal = "truth.cars")]
    cars: TruthCars,
    /// Whether the message was delivered in the office.
    #[output(signal = "truth.mission")]
    mission: TruthMission,
    /// The people: positions and floors (empty without people).
    #[output(signal = "truth.people")]
    people: TruthPeople,
    /// The world it senses and acts in (the resource `world`).
    #[resource]
    world: SharedWorld,
}

impl Body for SimTruth {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let mut w = lock(&self.world);
        w.advance_to(cx.time_s());
        let r = w.robot();
        self.pose = TruthPose { x: r.x, y: r.y, theta: r.theta, floor: r.floor };
        self.cars = TruthCars {
            floor: w.cars().iter().map(|c| c.pos).collect(),
            door: w.cars().iter().map(|c| c.door).collect(),
        };
        let at = w.delivered_at();
        self.mission = TruthMission { delivered: at.is_some(), delivered_at_s: at.unwrap_or(0.0) };
        let people = w.people();
        if people.len() != self.people.x.len() || !people.is_empty() {
            self.people = TruthPeople {
                x: people.iter().map(|p| p.pos.x).collect(),
                y: people.iter().map(|p| p.pos.y).collect(),
                floor: people.iter().map(|p| p.floor).collect(),
            };
        }
        Ok(())
    }
}

/// Adds every sim dskill type to `registry`, and `world` as the resource they are all made
/// with ([`WORLD`]).
pub fn register(registry: &mut Registry, world: SharedWorld) {
    registry
        .provide(WORLD, world)
        .register::<SimSonar>()
        .register::<SimBase>()
        .register::<SimBarcode>()
        .register::<SimArm>()
        .register::<SimSpeaker>()
        .register::<SimAltimeter>()
        .register::<SimTruth>();
}

/// The sim dskill types' declarations (ports, parameters, documentation), without a world: what
/// `situate types` lists. They run only in a robot file with a `simulator:` section.
pub fn declarations() -> Vec<situate::SkillDecl> {
    vec![
        SimSonar::declaration(),
        SimBase::declaration(),
        SimBarcode::declaration(),
        SimArm::declaration(),
        SimSpeaker::declaration(),
        SimAltimeter::declaration(),
        SimTruth::declaration(),
    ]
}

/// A registry holding the sim dskills over `world`.
pub fn registry(world: SharedWorld) -> Registry {
    let mut r = Registry::new();
    register(&mut r, world);
    r
}
