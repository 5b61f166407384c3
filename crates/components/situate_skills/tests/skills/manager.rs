//! The skills in a real manager, built from a robot file, with a device
//! that feeds sonar from a scene and moves by the winning `drive`.

use situate::manager::{Control, Manager, Registry, RobotFile, RobotSpec};
use situate::prelude::*;
use situate_robot::{Arm, Barcodes, Drive, SONARS};

use crate::scene::{Pose, Scene};

/// A base in front of a wall at x = `wall_x`: reports the scene's sonar and
/// its x, and integrates the latest `drive` (none: stands still).
#[derive(Skill, Default)]
#[skill(name = "test.scene_base", kind = "device")]
struct SceneBase {
    #[input]
    drive: Option<Drive>,
    #[output(signal = "sonar.range")]
    range: [f32; SONARS],
    #[output(signal = "test.x")]
    x: f64,
    #[param(default = 0.5, min = 0.0, max = 10.0, unit = "m")]
    wall_x: f64,
    pose: Option<Pose>,
    t: f64,
}

impl Body for SceneBase {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let dt = (cx.time_s() - self.t).max(0.0);
        self.t = cx.time_s();
        let pose = self.pose.unwrap_or(Pose::new(0.0, 0.0, 0.0));
        let pose = pose.step(self.drive.take().unwrap_or_default(), dt);
        self.pose = Some(pose);
        self.range = Scene::new().wall(self.wall_x, -5.0, self.wall_x, 5.0).sonar(pose);
        self.x = pose.x;
        Ok(())
    }
}

const ROBOT: &str = "\
robot: scene
cycle:
  period_ms: 50
  clock: simulated
devices:
  - name: base
    type: test.scene_base
skills:
  - name: wander
    type: std.wander
    params: {speed: 0.3, max_turn: 0.0}
  - name: runaway
    type: std.runaway
";

fn manager() -> Manager {
    let mut registry = Registry::new();
    situate_skills::register(&mut registry);
    registry.register::<SceneBase>();
    let file = RobotFile::parse("scene.yaml", ROBOT).unwrap_or_else(|e| panic!("{e:?}"));
    Manager::build(&RobotSpec::from_file(&file), &registry).unwrap_or_else(|e| panic!("{e}"))
}

fn winner(m: &mut Manager) -> Option<String> {
    m.query("drive").unwrap().writer
}

#[test]
fn runaway_beats_wander_near_a_wall_and_leaves_the_drive_to_it_when_clear() {
    let mut m = manager();
    m.step(3).unwrap();
    assert_eq!(winner(&mut m).as_deref(), Some("runaway"), "a wall 0.25 m ahead");
    let v = m.query("drive.v").unwrap().value.and_then(|v| v.as_f64()).unwrap();
    assert!(v < 0.0, "backing off: {v}");
    m.step(100).unwrap();
    // Clear of the wall, runaway is silent: wander drives forward until runaway takes over again.
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..100 {
        m.step(1).unwrap();
        seen.insert(winner(&mut m).unwrap());
        let x = m.query("test.x").unwrap().value.and_then(|v| v.as_f64()).unwrap();
        assert!(x < 0.5 - 0.25, "never hits the wall: x {x}");
    }
    assert_eq!(seen.into_iter().collect::<Vec<_>>(), ["runaway", "wander"]);
    m.deactivate(&["runaway"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(winner(&mut m).as_deref(), Some("wander"));
}

#[test]
fn every_standard_skill_is_registered_under_std() {
    let r = situate_skills::registry();
    let names: Vec<&str> = r.names().collect();
    assert_eq!(names.len(), 20, "{names:?}");
    assert!(names.iter().all(|n| n.starts_with("std.")), "{names:?}");
    for (name, priority) in [("std.runaway", 50), ("std.avoid", 40), ("std.pass_door", 35), ("std.home", 30)] {
        assert_eq!(r.get(name).unwrap().decl.priority, priority, "{name}");
    }
    // Every parameter is documented.
    for n in &names {
        let d = &r.get(n).unwrap().decl;
        assert!(!d.doc.is_empty(), "{n}");
        assert!(d.params.iter().all(|p| !p.doc.is_empty()), "{n}: {:?}", d.params);
    }
}

/// An arm that hits whatever button it is told to push, and a barcode
/// reader that sees barcode 5 half a metre ahead.
#[derive(Skill, Default)]
#[skill(name = "test.arm", kind = "device")]
struct TestArm {
    #[input(signal = "arm.press")]
    press: Option<i64>,
    #[output]
    arm: Arm,
    #[output]
    barcodes: Barcodes,
    #[output(signal = "test.pressed")]
    pressed: i64,
}

impl Body for TestArm {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        if let Some(b) = self.press.take() {
            self.arm.attempts += 1;
            self.arm.presses += 1;
            self.pressed = b;
        }
        self.barcodes = Barcodes { ids: Arc::from([5]), bearing: Arc::from([0.05]), distance: Arc::from([0.5]) };
        Ok(())
    }
}

#[test]
fn push_button_drives_an_arm_through_the_contract_signals() {
    let mut registry = Registry::new();
    situate_skills::register(&mut registry);
    registry.register::<TestArm>();
    let text = "\
robot: arm
cycle:
  period_ms: 50
  clock: simulated
devices:
  - name: arm
    type: test.arm
skills:
  - name: track
    type: std.track_barcode
    params: {id: 5}
  - name: push
    type: std.push_button
    params: {button: 3, retry_s: 0.2}
";
    let file = RobotFile::parse("arm.yaml", text).unwrap_or_else(|e| panic!("{e:?}"));
    let mut m = Manager::build(&RobotSpec::from_file(&file), &registry).unwrap_or_else(|e| panic!("{e}"));
    m.step(40).unwrap();
    let int = |m: &mut Manager, s: &str| m.query(s).unwrap().value.and_then(|v| v.as_f64());
    assert_eq!(int(&mut m, "test.pressed"), Some(3.0));
    assert_eq!(int(&mut m, "arm.presses"), Some(1.0), "one hit, no retries after it");
    assert_eq!(int(&mut m, "target.distance"), Some(0.5));
}
