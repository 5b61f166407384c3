//! A robot file as a whole: several errors in one file, all reported in file order, and a
//! valid robot built with its leaves, resources and records.

use super::*;

// --- several errors --------------------------------------------------------

const MANY: &str = "\
robot: r
skills:
  - name: k
    type: test.sink
  - name: g
    type: test.gain
    params:
      max_sped: 1
  - name: t
    type: test.sourse
devices:
  - name: g2
    type: test.gain
";

// `k`'s input `level` is not reported: `t`, whose type is unknown, may be its
// provider once the typo is fixed (no cascade of errors from one typo).
const MANY_IN_FILE_ORDER: [&str; 3] = [
    "robot.yaml:8:7: error: skill `g`: unknown parameter `max_sped` — did you mean `max_speed`?",
    "robot.yaml:10:11: error: skill `t`: unknown skill type `test.sourse` — did you mean `test.source`?",
    "robot.yaml:13:11: error: device `g2`: `test.gain` is a computational skill (cskill); list it under `skills:`, not `devices:`",
];

#[test]
fn several_errors_in_one_file_are_all_reported() {
    let mut got = errors(MANY);
    got.sort();
    let mut want = MANY_IN_FILE_ORDER.map(String::from).to_vec();
    want.sort();
    assert_eq!(got, want);
}

#[test]

fn several_errors_in_one_file_come_in_file_order() {
    assert_eq!(errors(MANY), MANY_IN_FILE_ORDER);
}

// --- a valid robot ---------------------------------------------------------

#[test]
fn a_valid_robot_builds_with_its_leaves_resources_and_records() {
    let src = "\
robot: r
cycle: {rate_hz: 50}
devices:
  - name: wheels
    type: test.wheels
skills:
  - name: px
    type: test.pose_x
    remap: {x: pose.x}
  - name: py
    type: test.pose_y
    remap: {y: pose.y}
  - name: user
    type: test.pose_user
  - name: steer
    type: test.steer
  - name: dodge
    type: test.dodge
    priority: 7
";
    let g = graph(src);
    assert_eq!(g.robot, "r");
    assert!(g.warnings.is_empty(), "{:?}", g.warnings);

    let names: Vec<&str> = g.instances.iter().map(|i| i.name.as_str()).collect();
    assert_eq!(names, ["wheels", "px", "py", "user", "steer", "dodge"]);
    assert_eq!(g.instances[0].kind, SkillKind::Device);
    assert_eq!(g.instances[g.instance("steer").unwrap()].priority, 5);
    assert_eq!(g.instances[g.instance("dodge").unwrap()].priority, 7);

    let mut leaves: Vec<(&str, String, bool)> =
        g.leaves.iter().map(|l| (l.path.as_str(), l.ty.to_string(), l.is_resource())).collect();
    leaves.sort();
    assert_eq!(
        leaves,
        [
            ("drive.v", "f64".to_string(), true),
            ("drive.w", "f64".to_string(), true),
            ("odom.x", "f64".to_string(), false),
            ("odom.y", "f64".to_string(), false),
            ("pose.x", "f64".to_string(), false),
            ("pose.y", "f64".to_string(), false),
        ]
    );
    let drive_v = &g.leaves[g.leaf_index["drive.v"]];
    assert_eq!(drive_v.writers.len(), 2);
    assert_eq!(drive_v.readers.len(), 1);

    // `pose` is assembled from two producers, one field each.
    assert_eq!(g.records.get("pose"), Some(&ty("{x: f64, y: f64}")));
    assert_eq!(g.signal_type("pose"), Some(ty("{x: f64, y: f64}")));
    assert_eq!(g.leaves_under("pose").len(), 2);
    assert_eq!(g.records.get("drive"), Some(&ty("{v: f64, w: f64}")));
    assert_eq!(g.records.get("odom"), Some(&ty("{x: f64, y: f64}")));
    assert_eq!(g.records.len(), 3);
    let user = &g.instances[g.instance("user").unwrap()];
    assert_eq!(user.inputs[0].leaves, [g.leaf_index["pose.x"], g.leaf_index["pose.y"]]);
}
