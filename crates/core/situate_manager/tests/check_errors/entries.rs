//! What one entry of a robot file gets wrong: its skill type (and the section it is listed
//! under), its name, its parameters, its remaps.

use super::*;

// --- skill types -----------------------------------------------------------

#[test]
fn unknown_skill_type_suggests_the_closest_registered_one() {
    let src = "\
robot: r
skills:
  - name: a
    type: test.sourse
";
    assert_eq!(
        error(src),
        "robot.yaml:4:11: error: skill `a`: unknown skill type `test.sourse` — did you mean `test.source`?"
    );
}

#[test]
fn unknown_skill_type_without_a_close_name_has_no_suggestion() {
    let src = "\
robot: r
skills:
  - name: a
    type: lidar
";
    assert_eq!(error(src), "robot.yaml:4:11: error: skill `a`: unknown skill type `lidar`");
}

#[test]

fn an_unknown_type_does_not_cascade_into_missing_inputs() {
    let src = "\
robot: r
skills:
  - name: s
    type: test.sourse
  - name: k
    type: test.sink
";
    // Today a second error follows, at 5:11: "`k` (input `level`) reads
    // signal `level`, which no skill or device provides".
    assert_eq!(
        errors(src),
        ["robot.yaml:4:11: error: skill `s`: unknown skill type `test.sourse` — did you mean `test.source`?"]
    );
}

#[test]
fn dskills_belong_under_devices_and_cskills_under_skills() {
    let src = "\
robot: r
skills:
  - name: ranger
    type: test.ranger
";
    assert_eq!(
        error(src),
        "robot.yaml:4:11: error: skill `ranger`: `test.ranger` is a device (dskill); list it under `devices:`, not `skills:`"
    );
    let src = "\
robot: r
devices:
  - name: src
    type: test.source
";
    assert_eq!(
        error(src),
        "robot.yaml:4:11: error: device `src`: `test.source` is a computational skill (cskill); list it under `skills:`, not `devices:`"
    );
}

#[test]
fn a_device_under_skills_is_reported_before_the_conflicts_it_causes() {
    // Before: first "skills `ranger` and `ranger2` both write resource
    // `range` with priority 0", a consequence of the real mistake.
    let src = "\
robot: r
devices:
  - {name: ranger, type: test.ranger}
skills:
  - {name: ranger2, type: test.ranger}
  - {name: servo, type: test.servo, params: {x: 1}}
";
    assert_eq!(
        errors(src),
        [
            "robot.yaml:5:27: error: skill `ranger2`: `test.ranger` is a device (dskill); list it under `devices:`, not `skills:`",
            "robot.yaml:6:25: error: skill `servo`: `test.servo` is a device (dskill); list it under `devices:`, not `skills:`",
            "robot.yaml:6:46: error: skill `servo`: unknown parameter `x` (it has no parameters)",
        ]
    );
}

// --- names -----------------------------------------------------------------

#[test]
fn duplicate_skill_names_point_back_at_the_first() {
    let src = "\
robot: r
skills:
  - name: a
    type: test.source
    priority: 1
  - name: a
    type: test.source
";
    assert_eq!(error(src), "robot.yaml:6:11: error: duplicate skill name `a` (first defined at line 3)");
}

#[test]

fn duplicate_names_across_sections_point_back_at_the_earlier_line() {
    let src = "\
robot: r
skills:
  - name: a
    type: test.sink
devices:
  - name: a
    type: test.ranger
";
    // Today: "robot.yaml:3:11: error: duplicate skill name `a` (first defined at line 6)",
    // and it is the earlier entry, the skill, that is dropped from the graph.
    assert_eq!(error(src), "robot.yaml:6:11: error: duplicate skill name `a` (first defined at line 3)");
}

// --- parameters ------------------------------------------------------------

#[test]
fn unknown_parameter_suggests_the_closest() {
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params:
      max_sped: 1.5
";
    assert_eq!(
        error(src),
        "robot.yaml:6:7: error: skill `g`: unknown parameter `max_sped` — did you mean `max_speed`?"
    );
}

#[test]
fn parameter_of_the_wrong_type_is_reported_at_its_value() {
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params:
      max_speed: fast
";
    assert_eq!(
        error(src),
        "robot.yaml:6:18: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got \"fast\""
    );
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params: {max_speed: true}
";
    assert_eq!(
        error(src),
        "robot.yaml:5:25: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got true"
    );
}

#[test]

fn a_list_for_a_scalar_parameter_is_called_a_list() {
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params: {max_speed: [1, 2]}
";
    // Today: "… expects a number in [0.0, 2.0], got a f64 array"
    assert_eq!(
        error(src),
        "robot.yaml:5:25: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got a list of numbers"
    );
}

#[test]
fn a_parameter_out_of_range_is_quoted_as_written() {
    // Before: "got 1000000…" (301 digits), and 16 for `0x10`.
    for (written, col) in [("1e300", 25), ("0x10", 25), ("-1.5E+2", 25), ("99999999999999999999", 25)] {
        let src =
            format!("robot: r\nskills:\n  - name: g\n    type: test.gain\n    params: {{max_speed: {written}}}\n");
        assert_eq!(
            error(&src),
            format!(
                "robot.yaml:5:{col}: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got {written}"
            )
        );
    }
}

#[test]
fn parameter_out_of_range_is_reported_at_its_value() {
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params:
      max_speed: 2.5
";
    assert_eq!(
        error(src),
        "robot.yaml:6:18: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got 2.5"
    );
    // An integer for a number parameter is range-checked the same way.
    let src = "\
robot: r
skills:
  - name: g
    type: test.gain
    params: {max_speed: -3}
";
    assert_eq!(
        error(src),
        "robot.yaml:5:25: error: skill `g`: parameter `max_speed` expects a number in [0.0, 2.0], got -3"
    );
}

// --- remaps ----------------------------------------------------------------

#[test]
fn remap_of_an_unknown_port_suggests_the_closest() {
    let src = "\
robot: r
skills:
  - name: s
    type: test.source
  - name: k
    type: test.sink
    remap: {levl: level}
";
    assert_eq!(error(src), "robot.yaml:7:13: error: skill `k`: remap of unknown port `levl` — did you mean `level`?");
}

#[test]
fn remap_target_that_is_not_a_signal_name() {
    // The robot file's reader rejects it before the graph is built…
    let src = "\
robot: r
skills:
  - name: k
    type: test.sink
    remap: {level: sonar..range}
";
    assert_eq!(
        error(src),
        "robot.yaml:5:20: error: remap target `sonar..range` of port `level` is not a signal name (identifiers joined by `.`, like `sonar.range`)"
    );
    // …and the graph rejects it in a robot assembled in code.
    let spec = simulated("r").skill(SkillSpec::new("k", "test.sink").remap("level", "sonar..range"));
    let diags = Graph::build(&spec, &registry()).err().expect("the build must fail").diagnostics;
    let texts: Vec<String> = diags.iter().map(ToString::to_string).collect();
    assert_eq!(
        texts,
        [
            "error: skill `k`: remap target `sonar..range` is not a signal name (identifiers joined by `.`)",
            "error: `k` (input `level`) reads signal `level`, which no skill or device provides",
        ]
    );
}
