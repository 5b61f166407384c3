//! Broken robot files through the real `situate check`: every mistake is
//! refused with its `FILE:LINE:COL`, nothing is silently accepted, and
//! nothing panics.

mod common;

use common::*;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `situate ARGS…` in `cwd` to completion.
fn situate_in<I, S>(cwd: &Path, args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(args)
        .current_dir(cwd)
        .env_remove("RUST_LOG")
        .output()
        .expect("the situate binary runs")
}

/// `situate check FILE`, run from a directory of its own (not the file's).
fn check(path: &Path) -> Output {
    let elsewhere = tempfile::tempdir().expect("a temporary directory");
    let out = situate_in(elsewhere.path(), [OsStr::new("check"), path.as_os_str()]);
    assert_no_panic(&out);
    out
}

/// The file fails the check with exactly these error lines (after the file's
/// path) and the count line.
fn assert_errors(out: &Output, path: &Path, want: &[&str]) {
    let shown = path.display().to_string();
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(3), "3: a bad file; stdout: {}\nstderr: {err}", stdout(out));
    let mut expected: Vec<String> = want.iter().map(|w| format!("{shown}:{w}")).collect();
    expected.push(format!("{shown}: {} error{}", want.len(), if want.len() == 1 { "" } else { "s" }));
    assert_eq!(err.lines().collect::<Vec<_>>(), expected);
}

#[test]
fn a_nul_byte_is_refused_at_its_place_instead_of_ending_the_file() {
    let (_dir, path) = robot_file("nul.yaml", "robot: r\n\0skills:\n  - {name: w, type: toy.wander}\n");
    let out = check(&path);
    assert_errors(
        &out,
        &path,
        &["2:1: error: control character U+0000 (NUL): a robot file is UTF-8 text (is this one UTF-16, or binary?)"],
    );
}

#[test]
fn a_tab_after_a_dash_is_refused_at_the_tab() {
    // Accepted before: the tab silently set the column of the entry's keys.
    let (_dir, path) = robot_file("tab.yaml", "robot: r\nskills:\n-\tname: w\n  type: toy.wander\n");
    let out = check(&path);
    assert_errors(&out, &path, &["3:2: error: tab character in indentation; indent YAML with spaces"]);
}

#[test]
fn a_fullwidth_colon_is_refused_on_its_own_line_with_a_hint() {
    // Blamed on line 5 (`simple key expect ':'`) before.
    let (_dir, path) = robot_file("colon.yaml", "robot: r\nskills:\n  - name: w\n    type： toy.wander\n");
    let out = check(&path);
    assert_errors(
        &out,
        &path,
        &["4:9: error: fullwidth colon `：` (U+FF1A); use ':' (or quote a value that should contain it)"],
    );
}

#[test]
fn a_period_out_of_range_is_quoted_as_written_at_its_place() {
    // Before: "FILE: error: cycle period must be > 0 s and at most a day, got 1e297 s".
    let (_dir, path) = robot_file("period.yaml", "robot: r\ncycle:\n  period_ms: 1e300\n");
    let out = check(&path);
    assert_errors(
        &out,
        &path,
        &["3:14: error: `period_ms` is out of range: expects a number from 0.01 to 86400000 (10 µs to a day), got 1e300"],
    );
    let (_dir, path) = robot_file(
        "param.yaml",
        "robot: r\ndevices:\n  - {name: sonar, type: toy.sonar}\nskills:\n  - {name: run, type: toy.runaway, params: {safe_distance: 1e300}}\n",
    );
    let out = check(&path);
    assert_errors(
        &out,
        &path,
        &["5:60: error: skill `run`: parameter `safe_distance` expects a number in [0.1, 3.0], got 1e300"],
    );
}

#[test]
fn a_device_under_skills_is_the_first_and_only_error() {
    // Before: first "skills `sonar` and `sonar2` both write resource
    // `sonar.range` with priority 0; give them different priorities".
    let (_dir, path) = robot_file(
        "devices.yaml",
        "robot: r\ndevices:\n  - {name: sonar, type: toy.sonar}\nskills:\n  - {name: sonar2, type: toy.sonar}\n",
    );
    let out = check(&path);
    assert_errors(
        &out,
        &path,
        &["5:26: error: skill `sonar2`: `toy.sonar` is a device (dskill); list it under `devices:`, not `skills:`"],
    );
}

/// Builds the C runaway example as `dir/libc_runaway.so`.
fn build_c_runaway(dir: &Path) {
    let example = repo().join("examples/c/runaway");
    run_ok(
        Command::new(env!("CARGO_BIN_EXE_situate"))
            .args(["gen", "c"])
            .arg(example.join("runaway.yaml"))
            .arg("-o")
            .arg(dir),
    );
    run_ok(
        Command::new("gcc")
            .args(["-std=c11", "-O2", "-Wall", "-Werror", "-shared", "-fPIC", "-fvisibility=hidden", "-I"])
            .arg(repo().join("include"))
            .arg("-I")
            .arg(dir)
            .arg(example.join("runaway.c"))
            .arg("-o")
            .arg(dir.join("libc_runaway.so"))
            .arg("-lm"),
    );
}

#[test]
fn paths_in_a_robot_file_are_relative_to_the_file_whatever_the_current_directory() {
    let tmp = tempfile::tempdir().expect("a temporary directory");
    let robots = tmp.path().join("robots");
    std::fs::create_dir_all(robots.join("maps")).unwrap();
    build_c_runaway(&robots);
    std::fs::copy(repo().join("maps/small.yaml"), robots.join("maps/small.yaml")).unwrap();
    std::fs::write(robots.join("doubler.yaml"), "inputs: {x: f64}\noutputs: {y: f64}\n").unwrap();
    let source = "\
robot: r
simulator: {map: maps/small.yaml}
libraries: [libc_runaway.so]
devices:
  - {name: sonar, type: toy.sonar}
skills:
  - {name: run, type: c.runaway}
  - {name: doubler, remote: doubler.yaml, remap: {x: level, y: doubled}}
  - {name: level, remote: {outputs: {level: f64}}}
";
    std::fs::write(robots.join("robot.yaml"), source).unwrap();
    let ok = "ok — robot `r`, 4 skills";
    // Before: "libc_runaway.so: not a loadable shared library: … cannot open
    // shared object file" — a bare name went to the system's library path.
    for (cwd, file) in [
        (robots.clone(), PathBuf::from("robot.yaml")),
        (tmp.path().to_path_buf(), PathBuf::from("robots/robot.yaml")),
        (robots.join("maps"), PathBuf::from("../robot.yaml")),
        (std::env::temp_dir(), robots.join("robot.yaml")),
    ] {
        let out = situate_in(&cwd, [OsStr::new("check"), file.as_os_str()]);
        assert_no_panic(&out);
        assert!(
            out.status.success() && stdout(&out).contains(ok),
            "from {}: {}\n{}",
            cwd.display(),
            stdout(&out),
            stderr(&out)
        );
    }
    // A missing library is looked for next to the file, and named so.
    std::fs::remove_file(robots.join("libc_runaway.so")).unwrap();
    let out = situate_in(tmp.path(), ["check", "robots/robot.yaml"]);
    assert_no_panic(&out);
    let err = stderr(&out);
    let expected = robots.join("libc_runaway.so").display().to_string();
    assert!(err.starts_with("robots/robot.yaml:3:13: error: ") && err.contains(&expected), "{err}");
}

#[test]
fn a_file_over_a_mebibyte_is_refused_by_its_size_quickly() {
    // Before: a 50 MB file took ~3 s and 2 GB of memory to parse.
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("big.yaml");
    let file = std::fs::File::create(&path).unwrap();
    file.set_len(50 << 20).unwrap();
    let started = std::time::Instant::now();
    let out = check(&path);
    assert!(started.elapsed() < std::time::Duration::from_secs(5), "{:?}", started.elapsed());
    assert_errors(
        &out,
        &path,
        &[" error: the file is 52428800 bytes (50 MiB); a robot file may be at most 1048576 bytes (1 MiB)"],
    );
    // A file that never ends (here a device) is read no further than the cap.
    #[cfg(unix)]
    {
        let zero = Path::new("/dev/zero");
        let out = check(zero);
        assert_errors(
            &out,
            zero,
            &[" error: the file is more than 1048576 bytes (1 MiB); a robot file may be at most 1048576 bytes (1 MiB)"],
        );
    }
}

#[test]
fn a_map_file_over_its_cap_is_refused_by_its_size() {
    let (dir, path) = robot_file("sim.yaml", "robot: r\nsimulator: {map: map.yaml}\n");
    let map = dir.path().join("map.yaml");
    std::fs::File::create(&map).unwrap().set_len(64 << 20).unwrap();
    let out = check(&path);
    assert_eq!(out.status.code(), Some(3));
    let err = stderr(&out);
    assert!(
        err.starts_with(&format!(
            "{}: error: the file is 67108864 bytes (64 MiB); a map file may be at most 4194304 bytes (4 MiB)",
            map.display()
        )),
        "{err}"
    );
}

#[test]
fn check_reports_errors_of_an_included_file_with_its_own_path_and_line() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    std::fs::create_dir(dir.path().join("parts")).unwrap();
    let base = dir.path().join("parts/base.yaml");
    std::fs::write(
        &base,
        "skills:\n  - name: runaway\n    type: toy.runaway\n    params: {safe_distance: 0.5}\n  - name: wander\n    type: toy.wandr\n",
    )
    .unwrap();
    let main = dir.path().join("robot.yaml");
    std::fs::write(&main, "robot: inc\ninclude: [parts/base.yaml, parts/gone.yaml]\n").unwrap();
    let out = check(&main);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(3), "{err}");
    let d = dir.path().display();
    assert_eq!(
        err.lines().next(),
        Some(
            format!(
                "{}:2:28: error: cannot read the included file `{d}/parts/gone.yaml`: no such file",
                main.display()
            )
            .as_str()
        ),
        "{err}"
    );
    // Fixed, the manager's own check (an unknown type) names the included file too.
    std::fs::write(&main, "robot: inc\ninclude: [parts/base.yaml]\n").unwrap();
    let out = check(&main);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.starts_with(&format!("{d}/parts/base.yaml:6:11: error: skill `wander`: unknown skill type `toy.wandr`")),
        "{err}"
    );

    // `${ENV}` in the included file and `--set` on an entry it defines.
    std::fs::write(&base, "skills:\n  - name: wander\n    type: ${INC_WANDER_TYPE:-toy.wander}\n").unwrap();
    std::fs::write(&main, "robot: inc\ninclude: [parts/base.yaml]\nskills:\n  - name: wander\n    priority: 3\n")
        .unwrap();
    let out = situate_in(
        dir.path(),
        [
            OsStr::new("check"),
            main.as_os_str(),
            OsStr::new("--json"),
            OsStr::new("--set"),
            OsStr::new("wander.speed=0.4"),
        ],
    );
    assert_eq!(out.status.code(), Some(0), "{}{}", stdout(&out), stderr(&out));
    let j: serde_json::Value = serde_json::from_str(&stdout(&out)).expect("JSON");
    assert_eq!(j["skills"], 1, "{j}");
    let bad = situate_in(
        dir.path(),
        [OsStr::new("check"), main.as_os_str(), OsStr::new("--set"), OsStr::new("wander.nosuch=1")],
    );
    assert_eq!(bad.status.code(), Some(3), "{}", stderr(&bad));
}
