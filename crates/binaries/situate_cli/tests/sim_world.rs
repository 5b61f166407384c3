//! The robot file's `simulator:` keys for what real buildings have (people,
//! door closures, dead sonars) and their command-line overrides.

mod common;

use common::*;
use std::ffi::OsStr;

const MAPS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../maps");

/// A simulated robot whose `simulator:` section ends with `keys` (block style, one per line).
fn sim_robot(keys: &str) -> String {
    format!(
        "robot: simbot\ncycle: {{rate_hz: 10, clock: simulated}}\nsimulator:\n  map: {MAPS}/default.yaml\n  seed: 4\n{keys}\
         devices:\n  - {{name: sonar, type: sim.sonar}}\n  - {{name: base, type: sim.base}}\n  - {{name: truth, type: sim.truth}}\n\
         skills:\n  - {{name: wander, type: std.wander}}\n"
    )
}

#[test]
fn people_door_closures_and_dead_sonars_are_accepted_and_run() {
    let (_dir, path) =
        robot_file("sim.yaml", sim_robot("  people: 3\n  door_closures: true\n  dead_sonars: [0, 23]\n"));
    let out = situate(["check".as_ref(), path.as_os_str()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let out = situate(["run".as_ref(), path.as_os_str(), "--no-link".as_ref(), "--cycles".as_ref(), "30".as_ref()]);
    assert_no_panic(&out);
    assert!(out.status.success(), "{}", stderr(&out));
    // The command-line overrides.
    let (_dir, path) = robot_file("sim.yaml", sim_robot(""));
    let out = situate([
        "run".as_ref(),
        path.as_os_str(),
        "--no-link".as_ref(),
        "--cycles".as_ref(),
        "30".as_ref(),
        "--people".as_ref(),
        "2".as_ref(),
        "--door-closures".as_ref(),
        "--dead-sonar".as_ref(),
        "5".as_ref(),
        "--dead-sonar".as_ref(),
        "6".as_ref(),
    ]);
    assert_no_panic(&out);
    assert!(out.status.success(), "{}", stderr(&out));
}

#[test]
fn bad_simulator_values_name_the_file_and_line() {
    let cases = [
        ("  people: -1\n", 6, "`people` expects a whole number of people per floor, 0 to 100"),
        ("  people: many\n", 6, "`people` expects a whole number"),
        ("  door_closures: sometimes\n", 6, "`door_closures` expects `true` or `false`"),
        ("  dead_sonars: 3\n", 6, "`dead_sonars` expects a list of sonar indexes"),
        ("  people: 1\n  dead_sonars: [1, 24]\n", 7, "a dead sonar is a sonar index, a whole number from 0 to 23"),
        ("  dead_sonar: [1]\n", 6, "unknown key `dead_sonar` in `simulator` — did you mean `dead_sonars`?"),
    ];
    for (keys, line, message) in cases {
        let (_dir, path) = robot_file("bad.yaml", sim_robot(keys));
        for verb in ["check", "run"] {
            let out =
                situate([verb.as_ref(), path.as_os_str(), "--no-link".as_ref()].into_iter().take(if verb == "check" {
                    2
                } else {
                    3
                }));
            assert_no_panic(&out);
            assert!(!out.status.success(), "{verb} accepted {keys:?}");
            let err = stderr(&out);
            let at = format!("{}:{line}:", path.display());
            assert!(err.lines().any(|l| l.starts_with(&at) && l.contains(message)), "{verb} {keys:?}: {err}");
        }
    }
}

#[test]
fn bad_overrides_are_refused() {
    let (_dir, path) = robot_file("sim.yaml", sim_robot(""));
    for args in [["--dead-sonar", "24"], ["--people", "-2"], ["--people", "101"]] {
        let out = situate(
            ["run".as_ref(), path.as_os_str(), "--no-link".as_ref()].into_iter().chain(args.iter().map(OsStr::new)),
        );
        assert_no_panic(&out);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {}", stderr(&out));
    }
    let out = situate(["run", TOYBOT, "--no-link", "--cycles", "2", "--people", "3"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out)
            .contains("--people, --door-closures and --dead-sonar need a robot file with a `simulator:` section"),
        "{}",
        stderr(&out)
    );
}
