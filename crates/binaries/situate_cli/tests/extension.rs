//! Rust skill types added to the program (`Extensions::skills`): in process, every command that
//! builds a registry knows them and a clash with a built-in name is an error naming it; from
//! outside, `examples/rust/extension` (a crate of its own, as a user's would be) builds into a
//! program that lists its types, checks and runs its robot file and serves it over the link.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use common::*;
use serde_json::Value as Json;
use situate::prelude::*;
use situate_cli::{main_with, Extensions};

/// A skill type of a host's own.
#[derive(Skill, Default)]
#[skill(name = "mine.double")]
struct Double {
    #[input(signal = "sonar.range")]
    sonar: Arc<[f32]>,
    /// Twice the first range.
    #[output]
    twice: f64,
}

impl Body for Double {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.twice = 2.0 * f64::from(self.sonar.first().copied().unwrap_or_default());
        Ok(())
    }
}

/// Named like a built-in type.
#[derive(Skill, Default)]
#[skill(name = "toy.wander")]
struct NotWander {
    #[output]
    drive: f64,
}

impl Body for NotWander {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        Ok(())
    }
}

const WITH_DOUBLE: &str = "\
robot: mine
cycle: {rate_hz: 20, clock: simulated}
devices:
  - {name: sonar, type: toy.sonar}
skills:
  - {name: double, type: mine.double}
";

fn with_double() -> Extensions {
    Extensions::default().skills(|r| {
        r.register::<Double>();
    })
}

/// `situate ARGS…` run in this process with these extensions; its exit code.
fn in_process(args: &[&str], ext: Extensions) -> u8 {
    main_with(std::iter::once("situate").chain(args.iter().copied()), ext)
}

#[test]
fn every_command_that_builds_a_registry_knows_the_hosts_types() {
    let (_dir, path) = robot_file("mine.yaml", WITH_DOUBLE);
    let file = path.to_str().expect("a UTF-8 temporary path");
    for args in [
        &["types", "-q"][..],
        &["check", file, "-q"],
        &["signals", file, "-q"],
        &["graph", file, "-q"],
        &["run", file, "--no-link", "--cycles", "3", "-q"],
    ] {
        assert_eq!(in_process(args, with_double()), 0, "{args:?} with mine.double");
    }
    // Without the extension the same file does not check (3: a bad file).
    assert_eq!(in_process(&["check", file, "-q"], Extensions::default()), 3);
    // serve-skill finds the type, then finds no robot (4); without it, the type is unknown (2).
    let nobody = free_endpoint();
    let serve = ["serve-skill", "mine.double", "--robot", "mine", "--connect", &nobody, "--timeout", "1", "-q"];
    assert_eq!(in_process(&serve, with_double()), 4);
    assert_eq!(in_process(&serve, Extensions::default()), 2);
}

#[test]
fn a_type_named_like_a_built_in_one_is_an_error_and_not_a_replacement() {
    let clash = || {
        Extensions::default().skills(|r| {
            r.register::<NotWander>();
        })
    };
    // 1: the program is wrong, not the command line or the file.
    assert_eq!(in_process(&["types", "-q"], clash()), 1);
    assert_eq!(in_process(&["check", TOYBOT, "-q"], clash()), 1);
    // Registered by two calls.
    let twice = with_double().skills(|r| {
        r.register::<Double>();
    });
    assert_eq!(in_process(&["types", "-q"], twice), 1);
    // Commands that build no registry are not concerned.
    assert_eq!(in_process(&["schema", "robot"], clash()), 0);
}

/// The example crate's folder.
fn example() -> PathBuf {
    repo().join("examples/rust/extension")
}

/// `name version` of every registry package of a Cargo.lock.
fn locked(lock: &Path) -> Vec<(String, String)> {
    let text = std::fs::read_to_string(lock).unwrap_or_else(|e| panic!("{}: {e}", lock.display()));
    let mut found = Vec::new();
    for package in text.split("[[package]]").skip(1) {
        let field = |key: &str| {
            package.lines().find_map(|l| l.strip_prefix(key)).map(|v| v.trim().trim_matches('"').to_string())
        };
        if field("source = ").is_some() {
            found.push((field("name = ").unwrap_or_default(), field("version = ").unwrap_or_default()));
        }
    }
    found
}

/// The example's program, built once for this test binary, into this build's target folder with
/// the workspace's versions (its Cargo.lock is a trimmed copy of the workspace's) and, through its
/// `workspace-features`, the features `cargo test --workspace` (`make test-rust`) gives the
/// dependencies they share: after that build it compiles no third-party crate, only the situate
/// crates and itself (about 20 s on one core, 15 s on two; after `cargo test -p situate_cli`
/// alone, Zenoh's crates too, once). The situate crates build as files of their own (outside the
/// workspace they have no line tables: the example's `profile.dev.package."*"`), which leaves the
/// workspace's untouched.
fn program() -> &'static Path {
    static PROGRAM: OnceLock<PathBuf> = OnceLock::new();
    PROGRAM.get_or_init(|| {
        let ours = locked(&repo().join("Cargo.lock"));
        let stale: Vec<String> = locked(&example().join("Cargo.lock"))
            .into_iter()
            .filter(|p| !ours.contains(p))
            .map(|(name, version)| format!("{name} {version}"))
            .collect();
        assert!(
            stale.is_empty(),
            "examples/rust/extension/Cargo.lock has versions the workspace's Cargo.lock does not ({}): \
             copy the workspace's Cargo.lock there, then run `cargo metadata --offline --format-version 1 \
             >/dev/null` in examples/rust/extension to trim it",
            stale.join(", ")
        );
        // `<target>/debug/situate` (`<target>/release/situate` under `cargo test --release`).
        let situate = Path::new(env!("CARGO_BIN_EXE_situate"));
        let profile_dir = situate.parent().expect("the binary's folder");
        let target = profile_dir.parent().expect("the target folder");
        let release = profile_dir.file_name().is_some_and(|n| n == "release");
        let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
        let mut build = Command::new(cargo);
        build
            .args(["build", "--locked", "--offline", "--features", "workspace-features", "--manifest-path"])
            .arg(example().join("Cargo.toml"))
            .arg("--target-dir")
            .arg(target)
            .args(release.then_some("--release"))
            // Built once per change, not edited: incremental state would only take disk.
            .env("CARGO_INCREMENTAL", "0");
        // What cargo sets for this test's process is not the build's environment: a build script
        // that reruns when one of these changes (ring's: CARGO_MANIFEST_DIR) would rerun, and
        // the Zenoh stack above it would compile again.
        for (key, _) in std::env::vars_os() {
            let set_for_the_test = key.to_str().is_some_and(|k| {
                k.starts_with("CARGO_PKG_")
                    || k.starts_with("CARGO_BIN_EXE_")
                    || matches!(
                        k,
                        "CARGO_MANIFEST_DIR"
                            | "CARGO_MANIFEST_PATH"
                            | "CARGO_CRATE_NAME"
                            | "CARGO_BIN_NAME"
                            | "CARGO_PRIMARY_PACKAGE"
                            | "CARGO_TARGET_TMPDIR"
                            | "OUT_DIR"
                    )
            });
            if set_for_the_test {
                build.env_remove(key);
            }
        }
        run_ok(&mut build);
        let program = profile_dir.join(format!("my-situate{}", std::env::consts::EXE_SUFFIX));
        assert!(program.is_file(), "{} was not built", program.display());
        program
    })
}

fn my_situate(args: &[&str]) -> std::process::Output {
    my_situate_with(args, |_| ())
}

/// [`my_situate`] with more settings of the command (its environment).
fn my_situate_with(args: &[&str], with: impl FnOnce(&mut Command)) -> std::process::Output {
    let mut command = Command::new(program());
    command.args(args).current_dir(example()).env_remove("RUST_LOG").env_remove("ESTOP_LINE");
    with(&mut command);
    let out = command.output().expect("my-situate runs");
    assert_no_panic(&out);
    out
}

#[test]
fn the_example_program_lists_checks_and_runs_its_own_types() {
    let types = my_situate(&["types", "--json"]);
    assert_eq!(types.status.code(), Some(0), "{}", stderr(&types));
    let types = json_of(&types);
    let names: Vec<&str> = types.as_array().expect("a list").iter().filter_map(|t| t["name"].as_str()).collect();
    for name in ["ext.nearest", "ext.brake", "toy.wander", "std.wander"] {
        assert!(names.contains(&name), "{name} in {names:?}");
    }
    let brake = types.as_array().and_then(|l| l.iter().find(|t| t["name"] == "ext.brake")).expect("ext.brake");
    assert_eq!(brake["priority"], 30, "{brake}");
    assert!(brake["params"].as_array().is_some_and(|p| p.iter().any(|p| p["name"] == "stop_distance")), "{brake}");

    let check = my_situate(&["check", "robot.yaml", "--json"]);
    assert_eq!(check.status.code(), Some(0), "{}", stderr(&check));
    let check = json_of(&check);
    assert_eq!((&check["robot"], &check["skills"]), (&Json::from("extbot"), &Json::from(5)), "{check}");

    // A bounded run on the simulated clock: nearest and brake run in every cycle that has a sonar
    // reading (all but the first), and brake says it brakes.
    let run = my_situate(&["run", "robot.yaml", "--no-link", "--cycles", "20", "--clock", "simulated", "--json"]);
    assert_eq!(run.status.code(), Some(0), "{}", stderr(&run));
    let run = json_of(&run);
    assert_eq!(run["stats"]["cycle"], 20, "{run}");
    let skill = |name: &str| {
        run["skills"].as_array().and_then(|l| l.iter().find(|s| s["name"] == name)).cloned().unwrap_or_default()
    };
    for name in ["nearest", "brake"] {
        assert_eq!(skill(name)["faulted"], Json::Null, "{run}");
        let runs = skill(name)["timing"]["runs"].as_u64().unwrap_or_default();
        assert!((19..=20).contains(&runs), "{name} ran {runs} times in 20 cycles: {run}");
    }
    let prints = skill("brake")["prints"].to_string();
    assert!(prints.contains("braking"), "{run}");
}

#[test]
fn the_example_programs_emergency_stop_holds_the_robot_still_while_pressed() {
    // The e-stop line the program follows (`ESTOP_LINE`): a file that reads `0` while released,
    // read as the program starts. A bounded run on the simulated clock: brake (given the program's
    // e-stop as a resource) wins the drive in every cycle with a sonar reading (all but the first).
    let dir = tempfile::tempdir().expect("a temporary folder");
    let line = dir.path().join("value");
    let run = |state: Option<&str>| {
        match state {
            Some(state) => std::fs::write(&line, state).expect("the line is written"),
            None => {
                let _ = std::fs::remove_file(&line); // absent, as after a first run without one
            }
        }
        let args = ["run", "robot.yaml", "--no-link", "--cycles", "20", "--clock", "simulated", "--json"];
        let out = my_situate_with(&args, |c| {
            c.env("ESTOP_LINE", &line);
        });
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let run = json_of(&out);
        let skill = |name: &str| {
            run["skills"].as_array().and_then(|l| l.iter().find(|s| s["name"] == name)).cloned().unwrap_or_default()
        };
        let drive = skill("wheels")["inputs"][0]["value"].clone();
        let theta = skill("wheels")["outputs"][0]["value"]["theta"].as_f64().expect("the odometry's heading");
        (drive, theta, skill("brake")["prints"].to_string(), run)
    };
    // Released: brake turns on the spot, away from the drifting box (1 rad/s for ~19 cycles of
    // 50 ms).
    let (drive, theta, prints, json) = run(Some("0\n"));
    assert_eq!(drive["v"], 0.0, "{json}");
    assert_eq!(drive["w"].as_f64().map(f64::abs), Some(1.0), "{json}");
    assert!(theta.abs() > 0.5, "released, the robot turned only {theta} rad: {json}");
    assert!(prints.contains("braking") && !prints.contains("emergency stop"), "{json}");
    // Pressed, or a line that cannot be read (a cut wire): zero velocity; the robot turns no more
    // than wander's one command of the first cycle allows (0.05 s at most 1 rad/s or so).
    for state in [Some("1\n"), None] {
        let (drive, theta, prints, json) = run(state);
        assert_eq!((&drive["v"], &drive["w"]), (&Json::from(0.0), &Json::from(0.0)), "{state:?}: {json}");
        assert!(theta.abs() < 0.1, "{state:?}: pressed, the robot turned {theta} rad: {json}");
        assert_eq!(prints.matches("emergency stop pressed: holding still").count(), 1, "{state:?}: {json}");
        assert!(!prints.contains("braking"), "{state:?}: {json}");
    }
}

#[test]
fn the_example_program_serves_its_robot_its_brake_wins_the_drive_and_says_when_switched_off() {
    let robot = Robot::start_with(program(), &example().join("robot.yaml"), "extbot");
    // The workspace's `situate` is the client: the verbs speak the protocol, whatever the skills.
    // The toy sonar's drifting box is always nearer than brake's stop_distance, so brake wins the
    // drive over wander in every cycle that has a new sonar reading (on the wall clock, a busy
    // machine may make the sonar's thread miss a cycle, and wander win that one).
    let deadline = std::time::Instant::now() + WAIT;
    loop {
        let out = robot.verb(&["winners", "--json"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let winners = json_of(&out);
        let drive = winners.as_array().and_then(|l| l.iter().find(|w| w["signal"] == "drive.v")).cloned();
        if let Some(drive) = drive.filter(|d| d["winner"] == "brake") {
            let writers = drive["writers"].to_string();
            assert!(writers.contains("brake") && writers.contains("wander"), "{winners}");
            break;
        }
        assert!(std::time::Instant::now() < deadline, "brake did not win drive.v within {WAIT:?}: {winners}");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    // Switched off, brake's `deactivate` says how long it braked (a count `activate` reset).
    let out = robot.verb(&["deactivate", "brake"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let deadline = std::time::Instant::now() + WAIT;
    loop {
        let out = robot.verb(&["skills", "--json"]);
        assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        if text.contains("switched off after braking") {
            return;
        }
        assert!(std::time::Instant::now() < deadline, "brake never said it was switched off: {text}");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}
