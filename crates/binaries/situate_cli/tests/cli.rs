//! The `situate` program end to end: the real binary on real files.
//!
//! Tests marked `#[ignore]` describe the behaviour we want where the current
//! one is wrong or unhelpful; each reason names the problem.

mod common;

use common::*;
use std::ffi::OsStr;
use std::path::Path;
use std::process::Command;

fn lines(text: &str) -> Vec<&str> {
    text.lines().collect()
}

fn shown(path: &Path) -> String {
    path.display().to_string()
}

/// Two errors found by the manager's checks (the file itself reads cleanly).
const BROKEN: &str = "\
robot: broken
devices:
  - name: sonar
    type: toy.sonar
skills:
  - name: runaway
    type: toy.runaway
    params: {safe_distance: 4.5}
  - name: wander
    type: toy.wandr
";

/// Two errors found while reading the file.
const UNREADABLE: &str = "\
robot: r
cycle: {rate_hz: 0}
skills:
  - name: w
    type: toy.wander
    actve: true
";

// --- situate check ---------------------------------------------------------

#[test]
fn check_accepts_the_toybot_example() {
    let out = situate(["check", TOYBOT]);
    assert!(out.status.success(), "status {:?}, stderr:\n{}", out.status, stderr(&out));
    let text = stdout(&out);
    assert!(text.starts_with(&format!("{TOYBOT}: ok")), "{text}");
    assert!(text.contains("robot `toybot`, 4 skills"), "{text}");
    assert_eq!(stderr(&out), "", "no warnings expected for toybot");
}

#[test]
fn check_reports_every_error_with_its_position_and_a_count() {
    let (_dir, path) = robot_file("broken.yaml", BROKEN);
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file");
    assert_eq!(stdout(&out), "");
    let p = shown(&path);
    assert_eq!(
        lines(&stderr(&out)),
        [
            format!(
                "{p}:8:29: error: skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got 4.5"
            ),
            format!("{p}:10:11: error: skill `wander`: unknown skill type `toy.wandr` — did you mean `toy.wander`?"),
            format!("{p}: 2 errors"),
        ]
    );
}

#[test]
fn check_reports_every_error_of_a_file_that_does_not_read() {
    let (_dir, path) = robot_file("unreadable.yaml", UNREADABLE);
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file");
    assert_eq!(stdout(&out), "");
    let p = shown(&path);
    let err = stderr(&out);
    let errors: Vec<&str> = lines(&err).into_iter().filter(|l| l.contains(": error: ")).collect();
    assert_eq!(
        errors,
        [
            format!("{p}:2:18: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0"),
            format!("{p}:6:5: error: unknown key `actve` in skill `w` — did you mean `active`?"),
        ]
    );
}

#[test]
fn check_counts_the_errors_of_a_file_that_does_not_read() {
    let (_dir, path) = robot_file("unreadable.yaml", UNREADABLE);
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    let p = shown(&path);
    assert_eq!(lines(&stderr(&out)).last().copied(), Some(format!("{p}: 2 errors").as_str()));
}

#[test]
fn check_prints_warnings_and_still_succeeds() {
    // The wheels' optional `drive` input has no producer.
    let (_dir, path) = robot_file("wheels.yaml", "robot: r\ndevices:\n  - name: wheels\n    type: toy.wheels\n");
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    assert!(out.status.success(), "status {:?}, stderr:\n{}", out.status, stderr(&out));
    let p = shown(&path);
    assert!(stdout(&out).starts_with(&format!("{p}: ok")), "{}", stdout(&out));
    let err = stderr(&out);
    assert!(!err.is_empty());
    for line in lines(&err) {
        assert!(line.starts_with(&format!("{p}:3:11: warning: `wheels` (optional input `drive`)")), "{line}");
    }
}

#[test]
fn check_of_a_missing_file_names_it_without_panicking() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-such-robot.yaml");
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file");
    assert_eq!(stdout(&out), "");
    let err = stderr(&out);
    let first = lines(&err).first().copied().unwrap_or_default().to_string();
    assert!(first.starts_with(&shown(&path)), "{err}");
    assert!(first.contains("error: cannot read robot file: "), "{err}");
}

#[test]
fn check_of_a_missing_file_has_no_position() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-such-robot.yaml");
    let out = situate([OsStr::new("check"), path.as_os_str()]);
    // Today: "PATH:1:1: error: cannot read robot file: No such file or directory (os error 2)"
    let err = stderr(&out);
    assert!(err.starts_with(&format!("{}: error: cannot read robot file: ", shown(&path))), "{err}");
}

// --- situate run -----------------------------------------------------------

#[test]
fn run_toybot_for_twenty_simulated_cycles_prints_a_summary() {
    let out = situate(["run", TOYBOT, "--cycles", "20", "--clock", "simulated", "--no-link"]);
    assert!(out.status.success(), "status {:?}, stderr:\n{}", out.status, stderr(&out));
    let text = stdout(&out);
    let summary = lines(&text);
    assert!(summary[0].starts_with("robot `toybot`: 20 cycles"), "{text}");
    assert!(text.contains("overruns"), "{text}");
    let header = summary.iter().position(|l| l.starts_with("skill ")).expect("a table header");
    let columns: Vec<&str> = summary[header].split_whitespace().collect();
    assert_eq!(&columns[..3], ["skill", "kind", "runs"]);
    let mut runs = std::collections::BTreeMap::new();
    for line in &summary[header + 1..] {
        let cells: Vec<&str> = line.split_whitespace().collect();
        let n: u64 = cells[2].parse().unwrap_or_else(|_| panic!("runs of `{}`: {line}", cells[0]));
        assert!(n <= 20, "{line}");
        assert_eq!(cells.last(), Some(&"active"), "{line}");
        runs.insert(cells[0], (cells[1], n));
    }
    assert_eq!(runs.keys().copied().collect::<Vec<_>>(), ["runaway", "sonar", "wander", "wheels"]);
    assert_eq!(runs["sonar"].0, "device");
    assert_eq!(runs["wheels"].0, "device");
    assert_eq!(runs["runaway"].0, "sync");
    // `wander` reads nothing, so it runs in every cycle.
    assert_eq!(runs["wander"], ("sync", 20));
}

#[test]
fn run_reports_a_yaml_syntax_error_with_its_position() {
    let (_dir, path) = robot_file("syntax.yaml", "robot: r\nskills: [a, b\n");
    let out = situate([
        OsStr::new("run"),
        path.as_os_str(),
        OsStr::new("--cycles"),
        OsStr::new("1"),
        OsStr::new("--no-link"),
    ]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file");
    assert_eq!(stdout(&out), "");
    assert_eq!(
        lines(&stderr(&out)),
        [
            format!(
                "{}:2:9: error: missing `]` to close the `[` at line 2, column 9 (the YAML parser stopped at line 3, \
                 column 1: while parsing a flow sequence, expected ',' or ']')",
                shown(&path)
            ),
            format!("{}: 1 error", shown(&path))
        ]
    );
}

#[test]
fn run_refuses_a_robot_that_does_not_check() {
    let (_dir, path) = robot_file("broken.yaml", BROKEN);
    let out = situate([
        OsStr::new("run"),
        path.as_os_str(),
        OsStr::new("--cycles"),
        OsStr::new("1"),
        OsStr::new("--no-link"),
    ]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file");
    assert_eq!(stdout(&out), "", "no summary for a robot that did not build");
    let p = shown(&path);
    let err = stderr(&out);
    assert!(err.contains(&format!("{p}:8:29: error: ")), "{err}");
    assert!(err.contains(&format!("{p}:10:11: error: ")), "{err}");
}

// --- situate types ---------------------------------------------------------

#[test]
fn types_lists_runaway_with_its_safe_distance_and_range() {
    let out = situate(["types"]);
    assert!(out.status.success(), "status {:?}, stderr:\n{}", out.status, stderr(&out));
    let text = stdout(&out);
    let all = lines(&text);
    let start = all.iter().position(|l| l.starts_with("toy.runaway ")).unwrap_or_else(|| panic!("{text}"));
    assert_eq!(all[start], "toy.runaway (sync, priority 20)");
    let block: Vec<&str> = all[start + 1..].iter().copied().take_while(|l| l.starts_with(' ')).collect();
    assert!(block.contains(&"    param safe_distance: f64 = 0.5 (a number in [0.1, 3.0])"), "{block:#?}");
    assert!(block.contains(&"    in  sonar_range: f32[]"), "{block:#?}");
    for name in ["toy.sonar", "toy.wheels", "toy.wander", "toy.memdev"] {
        assert!(all.iter().any(|l| l.starts_with(&format!("{name} ("))), "{name} missing:\n{text}");
    }
}

const MAPS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../maps");

/// A simulated robot: the default building, the sim's devices, two standard skills.
fn sim_robot(extra: &str) -> String {
    format!(
        "robot: simbot\ncycle: {{rate_hz: 10, clock: simulated}}\nsimulator: {{map: {MAPS}/default.yaml, seed: 4}}\n\
         devices:\n  - {{name: sonar, type: sim.sonar}}\n  - {{name: base, type: sim.base}}\n  - {{name: truth, type: sim.truth}}\n\
         skills:\n  - {{name: runaway, type: std.runaway}}\n  - {{name: wander, type: std.wander}}\n{extra}"
    )
}

#[test]
fn a_simulated_robot_checks_and_runs_with_the_standard_skills() {
    let (_dir, path) = robot_file("sim.yaml", sim_robot(""));
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = situate(["run".as_ref(), path.as_os_str(), "--no-link".as_ref(), "--cycles".as_ref(), "50".as_ref()]);
    assert_no_panic(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = stdout(&out);
    assert!(text.contains("robot `simbot`: 50 cycles, 5.000 s on its clock"), "{text}");
    assert!(text.lines().any(|l| l.starts_with("wander ") && l.contains("active")), "{text}");
}

#[test]
fn a_simulator_section_with_a_bad_map_or_key_names_the_place() {
    let source = "robot: s\nsimulator: {map: nowhere.yaml, sed: 3}\n";
    let (_dir, path) = robot_file("s.yaml", source);
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains(&format!(
            "{}:2:32: error: unknown key `sed` in `simulator` — did you mean `seed`?",
            shown(&path)
        )),
        "{}",
        stderr(&out)
    );

    let (_dir, path) = robot_file("s.yaml", "robot: s\nsimulator: {map: nowhere.yaml}\n");
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("nowhere.yaml"), "{}", stderr(&out));
}

#[test]
fn a_broken_map_is_reported_in_the_map_and_at_the_robot_files_map_line() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("broken.yaml"), "floors: [\n").unwrap();
    let path = dir.path().join("r.yaml");
    std::fs::write(&path, "robot: s\nsimulator:\n  map: broken.yaml\n  seed: 1\n").unwrap();
    for verb in ["check", "run"] {
        let out =
            situate([verb.as_ref(), path.as_os_str(), "--no-link".as_ref()].into_iter().take(if verb == "check" {
                2
            } else {
                3
            }));
        assert_no_panic(&out);
        assert!(!out.status.success());
        let err = stderr(&out);
        let map = shown(&dir.path().join("broken.yaml"));
        assert!(
            err.lines()
                .any(|l| l.starts_with(&format!("{map}:1:9: error: missing `]` to close the `[` at line 1, column 9"))),
            "{verb}: the map's own place: {err}"
        );
        assert!(
            err.contains(&format!("{}:3:8: error: the map `{map}` named here cannot be used", shown(&path))),
            "{verb}: the robot file's `map:` line: {err}"
        );
    }
}

#[test]
fn check_validates_the_gui_and_link_sections_as_run_does() {
    let cases = [
        ("gui: {listen: nonsense}\n", "5:15: error: `gui.listen`: `nonsense` is not an address"),
        ("gui: {port: 8080, colour: red}\n", "5:19: error: unknown key `colour` in `gui`"),
        ("link:\n  zenoh:\n    mode: bogus\n", "7:5: error: `link`: Zenoh refuses this configuration:"),
        ("link:\n  listen: [nonsense]\n", "6:12: error: `link.listen` expects endpoints"),
    ];
    for (section, expected) in cases {
        let source =
            format!("robot: t\ncycle: {{clock: simulated}}\ndevices:\n  - {{name: sonar, type: toy.sonar}}\n{section}");
        let (_dir, path) = robot_file("t.yaml", &source);
        for verb in ["check", "run"] {
            let out = situate(
                [verb.as_ref(), path.as_os_str(), "--cycles".as_ref(), "1".as_ref()]
                    .into_iter()
                    .take(if verb == "check" { 2 } else { 4 }),
            );
            assert_no_panic(&out);
            let err = stderr(&out);
            assert!(!out.status.success(), "{verb} accepted {section:?}: {err}");
            assert!(err.contains(&format!("{}:{expected}", shown(&path))), "{verb} {section:?}: {err}");
        }
    }
}

#[test]
fn a_library_named_bare_next_to_the_robot_file_is_found_there() {
    // `situate check robot.yaml` from the file's own folder: `libfoo.so` once went to dlopen as
    // a bare name, which searches the system's library path and not the folder.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("libfoo.so"), b"not a shared library").unwrap();
    std::fs::write(dir.path().join("robot.yaml"), "robot: l\nlibraries: [libfoo.so]\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["check", "robot.yaml"])
        .current_dir(dir.path())
        .output()
        .expect("the situate binary runs");
    assert_no_panic(&out);
    let err = stderr(&out);
    assert!(!out.status.success(), "{err}");
    let next_to_it = format!("robot.yaml:2:13: error: {}: not a loadable", dir.path().join("libfoo.so").display());
    assert!(err.contains(&next_to_it), "the file next to the robot file: {err}");
    assert!(!err.to_lowercase().contains("no such file"), "it was found: {err}");
}

#[test]
fn a_nul_byte_an_oversized_file_and_bytes_that_are_not_utf8_are_refused_with_a_place() {
    let (_d, nul) = robot_file("nul.yaml", "robot: t\0\ndevices: [x]\n");
    let out = situate(["check".as_ref(), nul.as_os_str()]);
    assert_no_panic(&out);
    assert!(!out.status.success(), "a NUL once ended the file and it checked ok");
    assert!(
        stderr(&out).contains(&format!("{}:1:9: error: control character U+0000 (NUL)", shown(&nul))),
        "{}",
        stderr(&out)
    );

    let (_d, big) = robot_file("big.yaml", format!("robot: t\n# {}\n", "x".repeat(3 << 20)));
    let out = situate(["check".as_ref(), big.as_os_str()]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("a robot file may be at most 1048576 bytes (1 MiB)"), "{}", stderr(&out));

    let dir = tempfile::tempdir().unwrap();
    let latin1 = dir.path().join("latin1.yaml");
    std::fs::write(&latin1, b"robot: t\ndoc: caf\xe9\n").unwrap();
    let out = situate(["check".as_ref(), latin1.as_os_str()]);
    assert_no_panic(&out);
    assert!(
        stderr(&out).contains(&format!("{}:2:9: error: invalid UTF-8 (byte 0xE9)", shown(&latin1))),
        "{}",
        stderr(&out)
    );
}

#[test]
fn a_device_under_skills_is_reported_as_that_and_not_as_a_priority_clash() {
    let source = "robot: t\ndevices:\n  - {name: sonar, type: toy.sonar}\nskills:\n  - {name: w1, type: toy.wheels}\n  - {name: w2, type: toy.wheels}\n";
    let (_dir, path) = robot_file("t.yaml", source);
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert_no_panic(&out);
    let err = stderr(&out);
    let errors: Vec<&str> = err.lines().filter(|l| l.contains(": error: ")).collect();
    assert_eq!(errors.len(), 2, "{err}");
    assert!(
        errors[0]
            .ends_with("error: skill `w1`: `toy.wheels` is a device (dskill); list it under `devices:`, not `skills:`"),
        "{err}"
    );
    assert!(!err.contains("priorit"), "no priority clash: {err}");

    let source = "robot: t\ndevices:\n  - {name: sonar, type: toy.sonar}\n  - {name: sonar2, type: toy.sonar}\n";
    let (_dir, path) = robot_file("t.yaml", source);
    let out = situate(["check".as_ref(), path.as_os_str()]);
    let err = stderr(&out);
    assert!(err.contains("4:12: error: devices `sonar` and `sonar2` both write signal `sonar.range` with priority 0; give each its own signal (e.g. `remap: {range: sonar2.range}` on `sonar2`)"), "{err}");
}

#[test]
fn a_seed_needs_a_simulator_and_a_map_alone_is_the_building_a_robot_is_shown_in() {
    let out = situate(["run", TOYBOT, "--no-link", "--cycles", "2", "--seed", "3"]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--seed needs a robot file with a `simulator:` section"), "{}", stderr(&out));
    // Without a simulator, `--map` is the building the GUI and a recording show the robot in
    // (a ROS 2 robot in a simulator of its own): read, and refused with the map's error.
    let map = format!("{}/../../../maps/default.yaml", env!("CARGO_MANIFEST_DIR"));
    let out = situate(["run", TOYBOT, "--no-link", "--no-gui", "--cycles", "2", "--map", &map]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = situate(["run", TOYBOT, "--no-link", "--no-gui", "--cycles", "2", "--map", "no/such/map.yaml"]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--map: ") && stderr(&out).contains("no/such/map.yaml"), "{}", stderr(&out));
}

#[test]
fn a_missing_library_or_a_python_file_in_the_rust_binary_is_an_error_at_its_line() {
    let source = "robot: l\nlibraries: [no/such/lib.so]\npython: [skills.py]\n";
    let (_dir, path) = robot_file("l.yaml", source);
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains(&format!("{}:2:13: error:", shown(&path))) && err.contains("lib.so"), "{err}");
    assert!(err.contains(&format!("{}:3:10: error:", shown(&path))) && err.contains("Python package"), "{err}");
}

#[test]
fn gen_writes_the_typed_io_of_a_manifest_and_refuses_a_bad_one() {
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../examples/c/runaway/runaway.yaml");
    let dir = tempfile::tempdir().unwrap();
    let out = situate(["gen".as_ref(), "c".as_ref(), manifest.as_ref(), "-o".as_ref(), dir.path().as_os_str()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let written: Vec<String> = stdout(&out).lines().map(str::to_string).collect();
    assert!(!written.is_empty());
    let header = std::fs::read_to_string(&written[0]).unwrap();
    assert!(header.contains("safe_distance"), "{header}");

    // Unchanged: not written again (a build system would rebuild).
    let modified = std::fs::metadata(&written[0]).unwrap().modified().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    let again = situate(["gen".as_ref(), "c".as_ref(), manifest.as_ref(), "-o".as_ref(), dir.path().as_os_str()]);
    assert!(again.status.success(), "{}", stderr(&again));
    assert_eq!(std::fs::metadata(&written[0]).unwrap().modified().unwrap(), modified);

    let (_d, bad) = robot_file("bad.yaml", "name: c.bad\ninputs: {x: f99}\n");
    let out = situate(["gen".as_ref(), "c".as_ref(), bad.as_os_str(), "-o".as_ref(), dir.path().as_os_str()]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "{}", stderr(&out));
    assert!(
        stderr(&out).contains(&format!("{}:2:13: error: port `x`: unknown type `f99`", shown(&bad))),
        "{}",
        stderr(&out)
    );

    // Nothing is generated for Python, and the program says why.
    let out = situate(["gen".as_ref(), "python".as_ref(), manifest.as_ref(), "-o".as_ref(), dir.path().as_os_str()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("@situate.skill"), "{}", stderr(&out));
}

#[test]
fn a_gui_address_that_is_not_one_is_refused_before_anything_runs() {
    let out = situate(["run", TOYBOT, "--no-link", "--cycles", "2", "--gui", "somewhere"]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--gui: `somewhere` is not an address"), "{}", stderr(&out));
}

#[test]
fn the_demo_without_its_files_says_where_it_looked() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["demo", "--headless"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("no demo found (looked in ./demo)"), "{}", stderr(&out));
}

// --- situate map generate / map check --------------------------------------

#[test]
fn map_generate_then_map_check_round_trips() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    for seed in [3u64, 11, 29] {
        let path = dir.path().join(format!("g{seed}.yaml"));
        let out = situate(["map", "generate", "--seed", &seed.to_string(), "--cars", "2..3", "-o", &shown(&path)]);
        assert_no_panic(&out);
        assert!(out.status.success(), "{}", stderr(&out));
        let first = std::fs::read_to_string(&path).expect("the map is written");
        // The same seed and options: the same bytes.
        let again = situate(["map", "generate", "--seed", &seed.to_string(), "--cars", "2..3", "-o", "-"]);
        assert_eq!(stdout(&again), first);
        let out = situate(["map", "check", &shown(&path)]);
        assert!(out.status.success(), "{}{}", stdout(&out), stderr(&out));
        assert_eq!(stdout(&out).trim(), format!("{}: ok", shown(&path)));
        let out = situate(["map", "check", "--json", &shown(&path)]);
        let j: serde_json::Value = serde_json::from_str(&stdout(&out)).expect("JSON");
        assert_eq!(j["ok"], true);
        // With --json, what the building drew: the same as the file's comment block.
        let out =
            situate(["--json", "map", "generate", "--seed", &seed.to_string(), "--cars", "2..3", "-o", &shown(&path)]);
        assert!(out.status.success(), "{}", stderr(&out));
        let j: serde_json::Value = serde_json::from_str(stdout(&out).trim()).expect("JSON");
        let walls = j["features"]["car_walls"].as_array().map(Vec::len);
        assert!(matches!(walls, Some(2..=3)), "{j}");
        let lobby = j["features"]["lobby"].as_str().unwrap_or_default().to_string();
        assert!(first.contains(&format!("\n#   lobby: {lobby}\n")), "{j}\n{first}");
    }
    // The family before issue 37, frozen: another building for the same seed, no car across
    // from the call button; a family that does not exist is refused.
    let one = situate(["map", "generate", "--seed", "3", "--family", "1", "-o", "-"]);
    assert!(one.status.success(), "{}", stderr(&one));
    assert!(stdout(&one).contains("\n#   lobby: facing\n"), "{}", stdout(&one));
    assert_ne!(stdout(&one), stdout(&situate(["map", "generate", "--seed", "3", "-o", "-"])));
    let out = situate(["map", "generate", "--seed", "1", "--family", "3", "-o", "-"]);
    assert!(stderr(&out).contains("--family"), "{}", stderr(&out));
    // Options out of range: refused, naming the option.
    let out = situate(["map", "generate", "--seed", "1", "--cars", "7", "-o", "-"]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("--cars"), "{}", stderr(&out));
}

#[test]
fn a_failing_map_check_exits_non_zero_with_every_finding_and_its_line() {
    let small = std::fs::read_to_string(repo().join("maps/small.yaml")).expect("small.yaml");
    let broken = small.replacen("door: south, barcode: 202", "door: south, door_width: 0.6, barcode: 202", 1).replacen(
        "at: [4.25, 0.02], facing_deg: 90}",
        "at: [4.25, 0.02], facing_deg: -90}",
        1,
    );
    let (_dir, path) = robot_file("broken-map.yaml", &broken);
    let out = situate(["map", "check", &shown(&path)]);
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(1));
    let err = stderr(&out);
    let line = |needle: &str| broken.lines().position(|l| l.contains(needle)).map(|i| i + 1).unwrap_or(0);
    let car = format!("{}:{}: error: elevator, car 2: door 0.60 m wide", shown(&path), line("door_width: 0.6"));
    let code = format!(
        "{}:{}: error: floor 0, door 1 (lab), barcode: barcode 10 faces the wall it is on (0.02 m ahead of it): it cannot be \
         read; turn it round (facing_deg: 90)",
        shown(&path),
        line("name: lab")
    );
    assert_eq!(
        lines(&err),
        [car + ": the robot (0.50 m) needs 0.80 m to board", code, format!("{}: 2 findings", shown(&path))]
    );
    let out = situate(["map", "check", "--json", &shown(&path)]);
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).expect("JSON");
    assert_eq!(j["ok"], false);
    assert_eq!(j["findings"].as_array().map(Vec::len), Some(2));
    assert_eq!(j["findings"][0]["element"], "elevator, car 2");
    assert_eq!(j["findings"][0]["line"], line("door_width: 0.6"));
    assert_eq!(j["findings"][0]["message"], "door 0.60 m wide: the robot (0.50 m) needs 0.80 m to board");
    // A loader error: the file, line and element.
    let (_dir2, path2) = robot_file("missing.yaml", small.replacen("{home: 40}", "{home: 99}", 1));
    let out = situate(["map", "check", &shown(&path2)]);
    assert_eq!(out.status.code(), Some(1));
    let want =
        format!("{}:{}: error: mission, route car_to_office, step 1: no barcode 99", shown(&path2), line("{home: 40}"));
    assert!(stderr(&out).contains(&want), "{}", stderr(&out));
    let out = situate(["map", "check", "--json", &shown(&path2)]);
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).expect("JSON");
    assert_eq!(j["findings"][0]["element"], "mission, route car_to_office, step 1");
    // A file that is not YAML: about the map, with its line and column.
    let (_dir3, path3) = robot_file("unclosed.yaml", small.replacen("[4.25, 0.02]", "[4.25, 0.02", 1));
    let out = situate(["map", "check", "--json", &shown(&path3)]);
    assert_eq!(out.status.code(), Some(1));
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).expect("JSON");
    assert_eq!(j["findings"][0]["element"], "map");
    let text = j["findings"][0]["text"].as_str().unwrap_or_default();
    assert!(text.starts_with(&format!("{}:", shown(&path3))) && text.contains(": error: missing `]`"), "{text}");
}

#[test]
fn check_on_a_map_file_says_to_use_map_check() {
    let out = situate(["check", &shown(&repo().join("maps/small.yaml"))]);
    assert_no_panic(&out);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("this is a map file: use `situate map check"), "{}", stderr(&out));
}
