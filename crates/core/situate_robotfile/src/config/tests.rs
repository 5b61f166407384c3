//! The robot file's tests as a whole, and the helpers the tests of its
//! sections share.

use situate_core::value::Value;

use super::*;
use crate::limits::MAX_ROBOT_FILE_BYTES;

pub(super) const FULL: &str = "\
# toybot: a sonar and two behaviours
robot: toybot
cycle:
  rate_hz: 50
  clock: simulated
  executor: parallel
  threads: 2
devices:
  - name: sonar
    type: toy.sonar
    period_ms: 20
    params: {noise_m: 0.01, beams: [0.1, 0.2, 3]}
    remap: {range: sonar.range}
skills:
  - name: wander
    type: toy.wander
    active: false
    priority: -5
  - name: runaway
    type: toy.runaway
    priority: 10
    params:
      safe_distance: 0.5
      label: \"near\"
      verbose: true
      retries: 3
    remap:
      sonar_range: sonar.range
link:
  peers: [a]
gui: {port: 8080}
";

pub(super) fn p(line: usize, col: usize) -> Pos {
    Pos::new(line, col)
}

pub(super) fn s<T>(value: T, line: usize, col: usize) -> Spanned<T> {
    Spanned::new(value, p(line, col))
}

/// The error lines for `source`, parsed as `robot.yaml`.
pub(super) fn errors(source: &str) -> Vec<String> {
    match RobotFile::parse("robot.yaml", source) {
        Ok(r) => panic!("expected errors, got {r:?}"),
        Err(errors) => errors.iter().map(ToString::to_string).collect(),
    }
}

/// The only error for `source`.
pub(super) fn error(source: &str) -> String {
    let errors = errors(source);
    assert_eq!(errors.len(), 1, "{errors:#?}");
    errors.into_iter().next().unwrap()
}

/// A valid file whose one skill entry gets `extra` lines.
pub(super) fn skill(extra: &str) -> String {
    format!("robot: r\nskills:\n  - name: runaway\n    type: toy.runaway\n{extra}")
}

#[test]
fn a_full_file_reads_into_the_model_with_positions() {
    let r = RobotFile::parse("toybot.yaml", FULL).unwrap();
    assert_eq!(r.file, "toybot.yaml");
    assert_eq!(r.robot, s("toybot".to_string(), 2, 8));
    assert_eq!(
        r.cycle,
        CycleConfig {
            period_s: 0.02,
            clock: ClockKind::Simulated,
            executor: ExecutorKind::Parallel,
            threads: Some(2),
            budget_ms: None,
            liveness_ms: None,
            pos: p(3, 1),
        }
    );
    assert_eq!(r.skills.len(), 3);

    let sonar = &r.skills[0];
    assert_eq!(sonar.section, Section::Devices);
    assert_eq!(sonar.pos, p(9, 5));
    assert_eq!(sonar.name, s("sonar".to_string(), 9, 11));
    assert_eq!(sonar.type_name, s("toy.sonar".to_string(), 10, 11));
    assert!(sonar.active);
    assert_eq!(sonar.priority, None);
    assert_eq!(sonar.period_ms, Some(s(20.0, 11, 16)));
    assert_eq!(
        sonar.params,
        vec![
            Param {
                name: s("noise_m".to_string(), 12, 14),
                value: s(Value::F64(0.01), 12, 23),
                written: Some("0.01".into())
            },
            Param {
                name: s("beams".to_string(), 12, 29),
                value: s(Value::F64s(vec![0.1, 0.2, 3.0].into()), 12, 36),
                written: None
            },
        ]
    );
    assert_eq!(sonar.remap, vec![(s("range".to_string(), 13, 13), s("sonar.range".to_string(), 13, 20))]);
    assert_eq!(sonar.label(), "device `sonar`");

    let wander = &r.skills[1];
    assert_eq!(wander.section, Section::Skills);
    assert_eq!((wander.pos, wander.active), (p(15, 5), false));
    assert_eq!(wander.priority, Some(s(-5, 18, 15)));
    assert!(wander.params.is_empty() && wander.remap.is_empty());

    let runaway = &r.skills[2];
    assert_eq!(runaway.pos, p(19, 5));
    assert_eq!(runaway.priority, Some(s(10, 21, 15)));
    let params: Vec<_> = runaway
        .params
        .iter()
        .map(|p| (p.name.value.as_str(), p.name.pos, p.value.value.clone(), p.value.pos))
        .collect();
    assert_eq!(
        params,
        vec![
            ("safe_distance", p(23, 7), Value::F64(0.5), p(23, 22)),
            ("label", p(24, 7), Value::Str("near".into()), p(24, 14)),
            ("verbose", p(25, 7), Value::Bool(true), p(25, 16)),
            ("retries", p(26, 7), Value::I64(3), p(26, 16)),
        ]
    );
    assert_eq!(runaway.param("retries").unwrap().value, Value::I64(3));
    assert_eq!(runaway.remap, vec![(s("sonar_range".to_string(), 28, 7), s("sonar.range".to_string(), 28, 20))]);
    assert_eq!(r.link.as_ref().unwrap().pos, p(30, 3));
    let gui = r.gui.as_ref().unwrap();
    assert_eq!(gui.pos, p(31, 6));
    assert_eq!(gui.value.get("port").unwrap().value.as_i64(), Some(8080));
    assert_eq!(r.section(Section::Skills).count(), 2);
    assert_eq!(r.error(runaway.name.pos, "no such thing").to_string(), "toybot.yaml:19:11: error: no such thing");
}

#[test]
fn defaults_and_section_order() {
    let r = RobotFile::parse(
        "r.yaml",
        "robot: my-bot_2\nskills:\n  - {name: b, type: t.b}\ndevices:\n  - {name: a, type: t.a}\n",
    )
    .unwrap();
    assert_eq!(r.cycle, CycleConfig::default());
    assert_eq!(r.cycle.rate_hz(), 20.0);
    let names: Vec<_> = r.skills.iter().map(|e| e.name.value.as_str()).collect();
    assert_eq!(names, ["a", "b"]);
    assert_eq!(r.skills[0].pos, p(5, 5));
    assert!(r.link.is_none() && r.gui.is_none());
    let r = RobotFile::parse("r.yaml", "robot: r\ncycle:\n  period_ms: 4\ndevices:\n").unwrap();
    assert_eq!(r.cycle.period_s, 0.004);
    assert!(r.skills.is_empty());
}

#[test]
fn empty_file_misses_robot_at_the_start() {
    assert_eq!(error(""), "robot.yaml:1:1: error: missing required key `robot`");
    assert_eq!(error("# nothing yet\n"), "robot.yaml:1:1: error: missing required key `robot`");
    assert_eq!(error("\ncycle: {rate_hz: 5}\n"), "robot.yaml:2:1: error: missing required key `robot`");
}

#[test]
fn yaml_syntax_errors_are_reported_alone() {
    assert_eq!(
        error("robot: r\nskills: [a, b\n"),
        "robot.yaml:2:9: error: missing `]` to close the `[` at line 2, column 9 (the YAML parser stopped at line 3, \
             column 1: while parsing a flow sequence, expected ',' or ']')"
    );
    assert_eq!(
        error("robot: r\ncycle:\n\trate_hz: 5\n"),
        "robot.yaml:3:1: error: tab character in indentation; indent YAML with spaces"
    );
    assert_eq!(
        error("robot: r\ncycle:\n  rate_hz: 5\n  rate_hz: 6\n"),
        "robot.yaml:4:3: error: duplicate key `rate_hz` (first given on line 3)"
    );
    assert_eq!(
        error("robot: &name r\n"),
        "robot.yaml:1:8: error: anchors and aliases (`&name`, `*name`) are not supported in robot files"
    );
}

#[test]
fn a_control_character_is_an_error_at_its_place_not_the_end_of_the_file() {
    // Before, the NUL ended the file: `robot: r` alone read cleanly.
    assert_eq!(
        error("robot: r\n\0skills:\n  - {name: w, type: toy.wander}\n"),
        "robot.yaml:2:1: error: control character U+0000 (NUL): a robot file is UTF-8 text (is this one UTF-16, \
             or binary?)"
    );
    assert!(
        error("robot: r\ncycle: {rate_hz: 5\u{c}}\n").starts_with("robot.yaml:2:19: error: control character U+000C")
    );
    assert!(RobotFile::parse("r.yaml", "robot: r\r\ncycle: {rate_hz: 5}\r\n").is_ok(), "CRLF is fine");
}

#[test]
fn tabs_and_fullwidth_colons_are_errors_at_their_own_place() {
    let indent = "error: tab character in indentation; indent YAML with spaces";
    // Accepted before: the tab after `-` silently set the mapping's column.
    assert_eq!(error("robot: r\nskills:\n-\tname: w\n  type: toy.wander\n"), format!("robot.yaml:3:2: {indent}"));
    // Blamed on line 4 before.
    assert_eq!(error("robot: r\nskills:\n  -\tname: w\n    type: toy.wander\n"), format!("robot.yaml:3:4: {indent}"));
    // Blamed on line 1 before.
    assert_eq!(error("robot: r\n\tskills: []\n"), format!("robot.yaml:2:1: {indent}"));
    // Blamed on line 5 before.
    assert_eq!(
        error("robot: r\nskills:\n  - name: w\n    type： toy.wander\n"),
        "robot.yaml:4:9: error: fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)"
    );
}

#[test]
fn unknown_keys_suggest_the_closest() {
    assert_eq!(
        error(&skill("    actve: false\n")),
        "robot.yaml:5:5: error: unknown key `actve` in skill `runaway` — did you mean `active`?"
    );
    assert_eq!(
        errors("robt: r\n"),
        [
            "robot.yaml:1:1: error: unknown key `robt` at the top level — did you mean `robot`?",
            "robot.yaml:1:1: error: missing required key `robot`",
        ]
    );
    assert_eq!(
        errors("robot: r\nskils: []\ncycle: {rate_hz: 5, frobnicate: 1}\n"),
        [
            "robot.yaml:2:1: error: unknown key `skils` at the top level — did you mean `skills`?",
            "robot.yaml:3:21: error: unknown key `frobnicate` in `cycle`",
        ]
    );
    assert_eq!(
            error("robot: r\ndevices:\n  - name: 1sonar\n    type: t\n"),
            "robot.yaml:3:11: error: device name `1sonar` is not an identifier (letters, digits and `_`, not starting with a digit)"
        );
}

#[test]
fn wrong_value_types() {
    assert_eq!(
        error("robot: r\ncycle:\n  rate_hz: fast\n"),
        "robot.yaml:3:12: error: `rate_hz` expects a number > 0, got \"fast\""
    );
    assert_eq!(
        error(&skill("    active: yes\n")),
        "robot.yaml:5:13: error: `active` expects true or false, got \"yes\""
    );
    assert_eq!(error(&skill("    priority: 1.5\n")), "robot.yaml:5:15: error: `priority` expects an integer, got 1.5");
    assert_eq!(
            error(&skill("    priority: 3000000000\n")),
            "robot.yaml:5:15: error: `priority` is out of range: expects an integer from -2147483648 to 2147483647, got 3000000000"
        );
    assert_eq!(
        error("robot: r\ncycle: {clock: wal}\n"),
        "robot.yaml:2:16: error: `clock` expects `wall` or `simulated`, got \"wal\" — did you mean `wall`?"
    );
    assert_eq!(
        error("robot: r\ncycle: {executor: [serial]}\n"),
        "robot.yaml:2:19: error: `executor` expects `serial` or `parallel`, got a list"
    );
    assert_eq!(
        error("robot: r\ncycle: {threads: 0}\n"),
        "robot.yaml:2:18: error: `threads` is out of range: expects an integer from 1 to 64, got 0"
    );
    assert_eq!(error("robot: [a]\n"), "robot.yaml:1:8: error: `robot` expects a name, got a list");
    assert_eq!(
        error("robot: r\ncycle: fast\n"),
        "robot.yaml:2:8: error: `cycle` expects a mapping (`rate_hz:`, `clock:`, `executor:`, …), got \"fast\""
    );
    assert_eq!(
            error("- robot: r\n"),
            "robot.yaml:1:1: error: a robot file is a mapping with keys `robot:`, `cycle:`, `devices:` and `skills:`, got a list"
        );
}

#[test]
fn missing_required_keys() {
    assert_eq!(
        error("robot: r\nskills:\n  - name: runaway\n    active: true\n"),
        "robot.yaml:3:5: error: missing required key `type` in skill `runaway`"
    );
    assert_eq!(error("cycle: {}\n"), "robot.yaml:1:1: error: missing required key `robot`");
}

#[test]
fn bad_names() {
    assert_eq!(
        error("robot: my bot\n"),
        "robot.yaml:1:8: error: robot name `my bot` may only contain letters, digits, `_` and `-`"
    );
    assert_eq!(
            error("robot: r\nskills:\n  - name: run-away\n    type: t\n"),
            "robot.yaml:3:11: error: skill name `run-away` is not an identifier (letters, digits and `_`, not starting with a digit)"
        );
    assert_eq!(
        error("robot: r\nskills:\n  - name: {a: 1}\n    type: t\n"),
        "robot.yaml:3:11: error: `name` expects a name, got a mapping"
    );
    assert_eq!(
        error("robot: r\nskills:\n  - name: a\n    type: \"\"\n"),
        "robot.yaml:4:11: error: `type` expects a skill type name, got \"\""
    );
}

#[test]
fn many_errors_come_together_in_file_order() {
    let src = "\
robot: r
skills:
  - name: runaway
    type: toy.runaway
    actve: true
    priority: high
  - name: b@d
    type: t
devices:
  - sonar
cycle:
  rate_hz: 0
  clock: sundial
";
    assert_eq!(
            errors(src),
            [
                "robot.yaml:5:5: error: unknown key `actve` in skill `runaway` — did you mean `active`?",
                "robot.yaml:6:15: error: `priority` expects an integer, got \"high\"",
                "robot.yaml:7:11: error: skill name `b@d` is not an identifier (letters, digits and `_`, not starting with a digit)",
                "robot.yaml:10:5: error: each entry of `devices` must be a mapping with `name:` and `type:`, got \"sonar\"",
                "robot.yaml:12:12: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0",
                "robot.yaml:13:10: error: `clock` expects `wall` or `simulated`, got \"sundial\"",
            ]
        );
}

#[test]
fn load_reads_files_and_reports_read_errors() {
    let dir = std::env::temp_dir().join(format!("situate-config-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("toybot.yaml");
    std::fs::write(&path, FULL).unwrap();
    let r = RobotFile::load(&path).unwrap();
    assert_eq!(r.file, path.display().to_string());
    let missing = dir.join("nope.yaml");
    let errors = RobotFile::load(&missing).unwrap_err();
    assert_eq!(errors.len(), 1);
    let text = errors[0].to_string();
    // A file that does not read has no line and column.
    let prefix = format!("{}: error: cannot read robot file: ", missing.display());
    assert!(text.starts_with(&prefix), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_file_over_the_size_cap_is_refused_by_its_size_before_it_is_read() {
    let dir = std::env::temp_dir().join(format!("situate-config-cap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // 50 MiB, sparse: refused from its size, not read (it took ~3 s and
    // 2 GB to parse such a file).
    let big = dir.join("big.yaml");
    std::fs::File::create(&big).unwrap().set_len(50 << 20).unwrap();
    let started = std::time::Instant::now();
    let errors = RobotFile::load(&big).unwrap_err();
    assert!(started.elapsed() < std::time::Duration::from_secs(1));
    assert_eq!(
        errors[0].to_string(),
        format!(
            "{}: error: the file is 52428800 bytes (50 MiB); a robot file may be at most 1048576 bytes (1 MiB)",
            big.display()
        )
    );
    // Exactly at the cap is fine (a comment, then a valid robot).
    let at_cap = dir.join("at_cap.yaml");
    let head = "robot: r\n#";
    let text = format!("{head}{}\n", "x".repeat(MAX_ROBOT_FILE_BYTES as usize - head.len() - 1));
    std::fs::write(&at_cap, &text).unwrap();
    assert!(RobotFile::load(&at_cap).is_ok());
    std::fs::write(&at_cap, text + "\n").unwrap();
    assert!(RobotFile::load(&at_cap).unwrap_err()[0].message.starts_with("the file is 1048577 bytes (1.0 MiB);"));
    // Invalid UTF-8 is an error at its place; UTF-16 is named.
    let latin1 = dir.join("latin1.yaml");
    std::fs::write(&latin1, b"robot: r\n# caf\xe9\n").unwrap();
    assert_eq!(
        RobotFile::load(&latin1).unwrap_err()[0].to_string(),
        format!(
            "{}:2:6: error: invalid UTF-8 (byte 0xE9): a robot file is UTF-8 text; save it as UTF-8",
            latin1.display()
        )
    );
    let utf16 = dir.join("utf16.yaml");
    std::fs::write(&utf16, b"\xff\xfer\0o\0").unwrap();
    assert!(RobotFile::load(&utf16).unwrap_err()[0].message.starts_with("the file is UTF-16 text"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn no_input_panics() {
    for (i, _) in FULL.char_indices() {
        let _ = RobotFile::parse("t.yaml", &FULL[..i]);
    }
    // Random edits of the full file: replace one character at a time
    // with YAML-significant ones, and random lines of keys and values.
    let chars: Vec<char> = FULL.chars().collect();
    let alphabet: Vec<char> = " \n\t-:?,[]{}#&*!|>'\".~0a1é：\0\r".chars().collect();
    let words = [
        "robot:",
        "cycle:",
        "rate_hz:",
        "period_ms:",
        "skills:",
        "devices:",
        "- ",
        "name:",
        "type:",
        "params:",
        "remap:",
        "[",
        "]",
        "{",
        "}",
        "0",
        "-1",
        "1e9",
        "x.y",
        "\n  ",
        "\n",
        "priority:",
        "threads:",
        ".nan",
        "\"\"",
        "~",
        "active:",
        ", ",
    ];
    let mut seed: u64 = 0x2545_f491_4f6c_dd1d;
    let mut next = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed
    };
    for _ in 0..3000 {
        let mut edited = chars.clone();
        for _ in 0..3 {
            let at = next() as usize % edited.len();
            edited[at] = alphabet[next() as usize % alphabet.len()];
        }
        let text: String = edited.into_iter().collect();
        let _ = RobotFile::parse("t.yaml", &text);
    }
    for _ in 0..5000 {
        let n = next() as usize % 16;
        let text: String = (0..n).map(|_| words[next() as usize % words.len()]).collect();
        let _ = RobotFile::parse("t.yaml", &text);
    }
}
