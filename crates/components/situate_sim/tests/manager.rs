//! The sim dskills under a real manager, built from a robot file.

use std::sync::{Arc, Mutex};

use situate::manager::{Control, Manager, RobotFile, RobotSpec};
use situate::prelude::*;
use situate_robot::{Drive, Odom, TruthCars, TruthMission, TruthPose};
use situate_sim::{load_map, registry, World};

/// Drives forward, turning slowly.
#[derive(Skill, Default)]
#[skill(name = "test.forward")]
struct Forward {
    #[output]
    drive: Drive,
}

impl Body for Forward {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.drive = Drive { v: 0.4, w: 0.1 };
        Ok(())
    }
}

const ROBOT: &str = "\
robot: simbot
cycle:
  rate_hz: 20
  clock: simulated
  executor: serial
devices:
  - {name: sonar, type: sim.sonar}
  - {name: base, type: sim.base, params: {max_v: 0.5}}
  - {name: barcode, type: sim.barcode}
  - {name: arm, type: sim.arm}
  - {name: speaker, type: sim.speaker}
  - {name: altimeter, type: sim.altimeter}
  - {name: truth, type: sim.truth}
skills:
  - {name: forward, type: test.forward}
";

fn manager(seed: u64) -> (Manager, Arc<Mutex<World>>) {
    let path = format!("{}/../../../maps/default.yaml", env!("CARGO_MANIFEST_DIR"));
    let map = load_map(&path).unwrap_or_else(|e| panic!("{e}"));
    let world = Arc::new(Mutex::new(World::new(map, seed)));
    let mut reg = registry(Arc::clone(&world));
    reg.register::<Forward>();
    let file = RobotFile::parse("robot.yaml", ROBOT)
        .unwrap_or_else(|es| panic!("{}", es.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n")));
    let spec = RobotSpec::from_file(&file);
    let m = Manager::build(&spec, &reg).unwrap_or_else(|e| panic!("build failed:\n{e}"));
    (m, world)
}

fn read<T: SignalValue>(m: &mut Manager, signal: &str) -> T {
    let reading = m.query(signal).unwrap_or_else(|e| panic!("{signal}: {e}"));
    let value = reading.value.unwrap_or_else(|| panic!("{signal}: never written"));
    T::from_value(&value).unwrap_or_else(|| panic!("{signal}: wrong type"))
}

#[test]
fn a_cskill_drives_the_simulated_base_for_100_cycles() {
    let (mut m, world) = manager(3);
    m.step(100).unwrap_or_else(|e| panic!("{e}"));
    let pose: TruthPose = read(&mut m, "truth.pose");
    let odom: Odom = read(&mut m, "odom");
    // 5 s at up to 0.4 m/s from (1.5, 1.5) heading east, turning left.
    assert_eq!(pose.floor, -1);
    assert!(pose.x > 2.5 && pose.x < 3.6, "x {}", pose.x);
    assert!(pose.theta > 0.3 && pose.theta < 0.6, "theta {}", pose.theta);
    assert!((odom.x - (pose.x - 1.5)).abs() < 0.2, "odom x {} vs truth {}", odom.x, pose.x - 1.5);
    assert!(odom.v > 0.3, "odom v {}", odom.v);
    let sonar: [f32; 24] = read(&mut m, "sonar.range");
    assert!(sonar.iter().all(|r| (0.1..=4.0).contains(r)), "{sonar:?}");
    let floor: i64 = read(&mut m, "floor");
    assert_eq!(floor, -1);
    let cars: TruthCars = read(&mut m, "truth.cars");
    assert_eq!(cars.floor.len(), 4);
    let mission: TruthMission = read(&mut m, "truth.mission");
    assert!(!mission.delivered);
    // The world was advanced by time: 100 cycles of 50 ms, 10 ms steps.
    let w = world.lock().unwrap_or_else(|p| p.into_inner());
    assert_eq!(w.steps(), 500);
}

#[test]
fn two_managers_with_the_same_seed_agree() {
    let (mut a, _) = manager(9);
    let (mut b, _) = manager(9);
    a.step(60).unwrap_or_else(|e| panic!("{e}"));
    b.step(60).unwrap_or_else(|e| panic!("{e}"));
    let (pa, pb): (TruthPose, TruthPose) = (read(&mut a, "truth.pose"), read(&mut b, "truth.pose"));
    assert_eq!(pa, pb);
    let (sa, sb): ([f32; 24], [f32; 24]) = (read(&mut a, "sonar.range"), read(&mut b, "sonar.range"));
    assert_eq!(sa, sb);
}

/// The ports are the robot's signal contract (docs: `situate_robot`), so
/// real-hardware dskills with the same ports can replace these.
/// A skill type, its inputs (signal, type, optional) and outputs (signal, type).
type Ports = (&'static str, &'static [(&'static str, &'static str, bool)], &'static [(&'static str, &'static str)]);

#[test]
fn the_dskills_have_the_contract_ports() {
    let path = format!("{}/../../../maps/small.yaml", env!("CARGO_MANIFEST_DIR"));
    let map = load_map(&path).unwrap_or_else(|e| panic!("{e}"));
    let reg = registry(Arc::new(Mutex::new(World::new(map, 1))));
    let want: [Ports; 7] = [
        ("sim.sonar", &[], &[("sonar.range", "f32[24]")]),
        (
            "sim.base",
            &[("drive", "{v: f64, w: f64}", true)],
            &[("odom", "{x: f64, y: f64, theta: f64, v: f64, w: f64}")],
        ),
        ("sim.barcode", &[], &[("barcodes", "{ids: i64[], bearing: f64[], distance: f64[]}")]),
        ("sim.arm", &[("arm.press", "i64", true)], &[("arm", "{attempts: i64, presses: i64}")]),
        ("sim.speaker", &[("speaker.say", "string", true)], &[("speaker", "{count: i64}")]),
        ("sim.altimeter", &[], &[("floor", "i64")]),
        (
            "sim.truth",
            &[],
            &[
                ("truth.pose", "{x: f64, y: f64, theta: f64, floor: i64}"),
                ("truth.cars", "{floor: f64[], door: f64[]}"),
                ("truth.mission", "{delivered: bool, delivered_at_s: f64}"),
                ("truth.people", "{x: f64[], y: f64[], floor: i64[]}"),
            ],
        ),
    ];
    for (name, inputs, outputs) in want {
        let t = reg.get(name).unwrap_or_else(|| panic!("{name} not registered"));
        assert_eq!(t.decl.kind, SkillKind::Device, "{name}");
        let got_in: Vec<(String, String, bool)> =
            t.decl.inputs.iter().map(|p| (p.signal.clone(), p.ty.to_string(), p.optional)).collect();
        let want_in: Vec<(String, String, bool)> =
            inputs.iter().map(|(s, ty, o)| (s.to_string(), ty.to_string(), *o)).collect();
        assert_eq!(got_in, want_in, "{name} inputs");
        let got_out: Vec<(String, String)> =
            t.decl.outputs.iter().map(|p| (p.signal.clone(), p.ty.to_string())).collect();
        let want_out: Vec<(String, String)> = outputs.iter().map(|(s, ty)| (s.to_string(), ty.to_string())).collect();
        assert_eq!(got_out, want_out, "{name} outputs");
    }
    let names: Vec<&str> = reg.names().collect();
    assert_eq!(names.len(), 7, "{names:?}");
}
