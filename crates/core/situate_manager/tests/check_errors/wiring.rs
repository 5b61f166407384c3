//! How the skills of a robot file connect: inputs nobody provides, types that disagree,
//! resources (signals several skills write) and data-flow loops.

use super::*;

// --- inputs nobody provides ------------------------------------------------

#[test]
fn a_required_input_nobody_provides_is_an_error() {
    // At the skill's name when the port is not remapped…
    let src = "\
robot: r
skills:
  - name: k
    type: test.sink
";
    assert_eq!(
        error(src),
        "robot.yaml:3:11: error: `k` (input `level`) reads signal `level`, which no skill or device provides"
    );
    // …and at the remap's target, with the closest provided signal, when it is.
    let src = "\
robot: r
skills:
  - name: s
    type: test.source
  - name: k
    type: test.sink
    remap: {level: lvel}
";
    assert_eq!(
        error(src),
        "robot.yaml:7:20: error: `k` (input `level`) reads signal `lvel`, which no skill or device provides — did you mean `level`?"
    );
}

#[test]

fn a_transposed_signal_name_gets_a_suggestion() {
    let src = "\
robot: r
skills:
  - name: s
    type: test.source
  - name: k
    type: test.sink
    remap: {level: levle}
";
    // Today: the same message without the suggestion.
    assert_eq!(
        error(src),
        "robot.yaml:7:20: error: `k` (input `level`) reads signal `levle`, which no skill or device provides — did you mean `level`?"
    );
}

#[test]
fn an_optional_input_nobody_provides_is_a_warning_and_the_build_succeeds() {
    let src = "\
robot: r
skills:
  - name: m
    type: test.monitor
";
    let g = graph(src);
    let warnings: Vec<String> = g.warnings.iter().map(ToString::to_string).collect();
    assert_eq!(
        warnings,
        ["robot.yaml:3:11: warning: `m` (optional input `level`) reads signal `level`, which no skill or device provides"]
    );
    assert_eq!(g.warnings[0].severity, Severity::Warning);
}

#[test]
fn a_warning_rides_along_with_the_errors_of_a_failed_build() {
    let src = "\
robot: r
skills:
  - name: m
    type: test.monitor
  - name: k
    type: test.sink
    remap: {level: other}
";
    assert_eq!(
        errors(src),
        [
            "robot.yaml:7:20: error: `k` (input `level`) reads signal `other`, which no skill or device provides",
            "robot.yaml:3:11: warning: `m` (optional input `level`) reads signal `level`, which no skill or device provides",
        ]
    );
}

#[test]

fn a_record_input_nobody_provides_is_one_error() {
    let src = "\
robot: r
skills:
  - name: user
    type: test.pose_user
";
    // Today: two errors at 3:11, "… reads signal `pose.x`, …" and "… reads signal `pose.y`, …".
    assert_eq!(
        error(src),
        "robot.yaml:3:11: error: `user` (input `pose`) reads signal `pose`, which no skill or device provides"
    );
}

#[test]
fn a_record_input_missing_one_field_names_the_field() {
    let src = "\
robot: r
skills:
  - name: px
    type: test.pose_x
    remap: {x: pose.x}
  - name: user
    type: test.pose_user
";
    assert_eq!(
        error(src),
        "robot.yaml:6:11: error: `user` (input `pose`) reads signal `pose.y`, which no skill or device provides — did you mean `pose.x`?"
    );
}

// --- types -----------------------------------------------------------------

#[test]
fn producer_and_consumer_disagreeing_on_the_type_is_an_error_at_the_consumer() {
    let src = "\
robot: r
skills:
  - name: s
    type: test.source
  - name: l
    type: test.label
    remap: {label: level}
";
    assert_eq!(
        error(src),
        "robot.yaml:7:20: error: type mismatch on signal `level`: `s` (output `level`) produces f64, `l` (input `label`) expects string"
    );
}

#[test]
fn a_variable_array_does_not_feed_a_fixed_one_but_the_reverse_is_fine() {
    let src = "\
robot: r
skills:
  - name: v
    type: test.scan_src
  - name: f
    type: test.scan_fixed
";
    assert_eq!(
        error(src),
        "robot.yaml:5:11: error: type mismatch on signal `scan`: `v` (output `scan`) produces f32[], `f` (input `scan`) expects f32[24]"
    );
    let src = "\
robot: r
devices:
  - name: ranger
    type: test.ranger
skills:
  - name: any
    type: test.scan_any
    remap: {scan: range}
  - name: fixed
    type: test.scan_fixed
    remap: {scan: range}
";
    let g = graph(src);
    assert_eq!(g.signal_type("range"), Some(ty("f32[24]")));
    assert_eq!(g.leaves[g.leaf_index["range"]].readers.len(), 2);
}

#[test]
fn two_writers_disagreeing_on_a_type_is_an_error_at_the_second() {
    let src = "\
robot: r
skills:
  - name: s
    type: test.source
  - name: c
    type: test.count
";
    assert_eq!(
        error(src),
        "robot.yaml:5:11: error: type mismatch on signal `level`: `s` (output `level`) writes f64, `c` (output `level`) writes i64"
    );
}

#[test]
fn a_signal_cannot_be_both_a_value_and_a_record() {
    let src = "\
robot: r
skills:
  - name: v
    type: test.pose_value
  - name: px
    type: test.pose_x
    remap: {x: pose.x}
";
    assert_eq!(
        error(src),
        "robot.yaml:3:11: error: signal `pose` is used both as a value, by `v` (output `pose`), and as a record with field `x`, by `px` (output `x`)"
    );
}

// --- resources -------------------------------------------------------------

#[test]
fn equal_priority_writers_of_a_resource_with_the_types_priorities() {
    let src = "\
robot: r
skills:
  - name: cruise
    type: test.cruise
  - name: avoid
    type: test.avoid
";
    assert_eq!(
        error(src),
        "robot.yaml:5:11: error: skills `cruise` and `avoid` both write resource `speed` with priority 5; give them different priorities"
    );
}

#[test]
fn equal_priority_from_the_file_is_reported_at_the_priority_value() {
    let src = "\
robot: r
skills:
  - name: cruise
    type: test.cruise
  - name: stop
    type: test.stop
    priority: 5
";
    assert_eq!(
        error(src),
        "robot.yaml:7:15: error: skills `cruise` and `stop` both write resource `speed` with priority 5; give them different priorities"
    );
}

#[test]

fn equal_priority_given_on_the_first_writer_is_reported_there() {
    let src = "\
robot: r
skills:
  - name: stop
    type: test.stop
    priority: 5
  - name: cruise
    type: test.cruise
";
    // Today: "robot.yaml:6:11: error: …" (cruise's name).
    assert_eq!(
        error(src),
        "robot.yaml:5:15: error: skills `stop` and `cruise` both write resource `speed` with priority 5; give them different priorities"
    );
}

#[test]

fn equal_priority_writers_of_a_record_resource_name_the_record() {
    let src = "\
robot: r
skills:
  - name: steer
    type: test.steer
  - name: dodge
    type: test.dodge
";
    // Today: "… both write resource `drive.v` with priority 5; …" (one error: `drive.w` is deduplicated).
    assert_eq!(
        error(src),
        "robot.yaml:5:11: error: skills `steer` and `dodge` both write resource `drive` with priority 5; give them different priorities"
    );
}

#[test]
fn many_equal_priority_writers_are_one_error_not_one_per_pair() {
    // Before: one error per pair — n writers, n²/2 errors (2000 writers took
    // 30 s and 1 GB to report).
    let mut src = String::from("robot: r\nskills:\n");
    for i in 0..40 {
        src.push_str(&format!("  - {{name: c{i}, type: test.cruise}}\n"));
    }
    assert_eq!(
        error(&src),
        "robot.yaml:42:12: error: skills `c0`, `c1`, `c2`, `c3`, `c4`, `c5`, `c6`, `c7`, `c8`, `c9` and 30 more all \
         write resource `speed` with priority 5; give them different priorities"
    );
    let src = "\
robot: r
skills:
  - {name: a, type: test.cruise}
  - {name: b, type: test.avoid}
  - {name: c, type: test.cruise, priority: 5}
  - {name: d, type: test.stop}
";
    assert_eq!(
        error(src),
        "robot.yaml:5:44: error: skills `a`, `b` and `c` all write resource `speed` with priority 5; give them different priorities"
    );
}

#[test]
fn a_record_resource_is_reported_once_not_once_per_field() {
    let src = "\
robot: r
skills:
  - name: steer
    type: test.steer
  - name: dodge
    type: test.dodge
";
    let errors = errors(src);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    assert!(errors[0].starts_with("robot.yaml:5:11: error: skills `steer` and `dodge` both write resource `drive"));
}

// --- loops -----------------------------------------------------------------

#[test]
fn a_data_flow_loop_among_cskills_names_its_skills() {
    let src = "\
robot: r
skills:
  - name: a
    type: test.pass
    remap: {x: b_out, y: a_out}
  - name: b
    type: test.pass
    remap: {x: a_out, y: b_out}
";
    assert_eq!(
        error(src),
        "robot.yaml:3:11: error: data-flow loop among skills `a`, `b`: each waits for another's output in the same cycle"
    );
}

#[test]

fn a_data_flow_loop_names_only_the_skills_on_it() {
    let src = "\
robot: r
skills:
  - name: a
    type: test.pass
    remap: {x: b_out, y: a_out}
  - name: b
    type: test.pass
    remap: {x: a_out, y: b_out}
  - name: c
    type: test.pass
    remap: {x: b_out, y: c_out}
";
    // Today: "… data-flow loop among skills `a`, `b`, `c`: …"
    assert_eq!(
        error(src),
        "robot.yaml:3:11: error: data-flow loop among skills `a`, `b`: each waits for another's output in the same cycle"
    );
}

#[test]
fn a_loop_through_a_dskill_is_not_a_data_flow_loop() {
    // The controller reads the servo's reading and writes its command; the
    // servo's reading is taken before the data flow, its command after it.
    let src = "\
robot: r
devices:
  - name: servo
    type: test.servo
skills:
  - name: ctrl
    type: test.pass
    remap: {x: reading, y: command}
";
    let g = graph(src);
    assert!(g.warnings.is_empty());
    assert_eq!(g.instances.len(), 2);
}
