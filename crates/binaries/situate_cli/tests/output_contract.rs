//! The program's output contract (docs/cli.md) and its introspection verbs:
//! `--json` on every command, errors as JSON, the exit codes, `-q`/`-v`, no
//! colour off a terminal; `signals`, `graph`, `winners`, `monitors`,
//! `param dump|load`, `schema`, `completions`; `--set` and `${ENV}`.

mod common;

use common::*;
use serde_json::Value as Json;
use std::ffi::OsStr;
use std::process::{Command, Output};

/// The failure under `--json`: this exit code, one JSON error of this kind on stdout, nothing on stderr.
fn json_error(out: &Output, code: i32, kind: &str) -> Json {
    assert_no_panic(out);
    assert_eq!(out.status.code(), Some(code), "stdout:\n{}\nstderr:\n{}", stdout(out), stderr(out));
    assert_eq!(stderr(out), "", "errors go to stdout as JSON under --json");
    let j = json_of(out);
    assert_eq!(j["error"]["kind"], kind, "{j}");
    assert_eq!(j["error"]["exit"], code, "{j}");
    j
}

const BROKEN: &str = "robot: broken\nskills:\n  - name: wander\n    type: toy.wandr\n";

#[test]
fn check_and_types_give_json() {
    let ok = situate(["check", TOYBOT, "--json"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let j = json_of(&ok);
    assert_eq!(j["ok"], true);
    assert_eq!(j["robot"], "toybot");
    assert_eq!(j["skills"], 4);
    let types = json_of(&situate(["types", "--json"]));
    let runaway = types.as_array().unwrap().iter().find(|t| t["name"] == "toy.runaway").expect("toy.runaway");
    assert!(runaway["params"].as_array().unwrap().iter().any(|p| p["name"] == "safe_distance"), "{runaway}");
}

#[test]
fn a_bad_file_is_exit_3_and_its_errors_are_json_under_json() {
    let (_dir, path) = robot_file("broken.yaml", BROKEN);
    let text = situate([OsStr::new("check"), path.as_os_str()]);
    assert_eq!(text.status.code(), Some(3));
    assert!(stderr(&text).contains("toy.wandr"), "{}", stderr(&text));
    let j = json_error(&situate([OsStr::new("check"), path.as_os_str(), OsStr::new("--json")]), 3, "bad_file");
    let lines = j["error"]["lines"].as_array().unwrap();
    assert!(lines.iter().any(|l| l.as_str().unwrap().contains("broken.yaml:4:")), "{j}");
    assert_eq!(j["error"]["file"], path.display().to_string());
}

#[test]
fn bad_usage_is_exit_2_and_json_under_json() {
    let j = json_error(&situate(["chekc", "--json"]), 2, "usage");
    assert!(j["error"]["message"].as_str().unwrap().contains("chekc"), "{j}");
    assert_eq!(situate(["chekc"]).status.code(), Some(2));
}

#[test]
fn no_robot_answering_is_exit_4() {
    let endpoint = free_endpoint();
    let out = situate(["skills", "--connect", &endpoint, "--timeout", "1"]);
    assert_eq!(out.status.code(), Some(4), "{}", stderr(&out));
    assert!(stderr(&out).starts_with("situate: "), "{}", stderr(&out));
    json_error(&situate(["stats", "--connect", &endpoint, "--timeout", "1", "--json"]), 4, "no_robot");
}

#[test]
fn run_gives_its_summary_as_json() {
    let out = situate(["run", TOYBOT, "--no-link", "--cycles", "3", "--clock", "simulated", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let j = json_of(&out);
    assert_eq!(j["stats"]["cycle"], 3, "{j}");
    assert_eq!(j["skills"].as_array().unwrap().len(), 4, "{j}");
}

#[test]
fn run_records_to_mcap_and_says_what_the_file_holds() {
    let path = std::env::temp_dir().join(format!("situate-cli-record-{}.mcap", std::process::id()));
    let file = path.to_str().unwrap();
    let out =
        situate(["run", TOYBOT, "--no-link", "--cycles", "30", "--clock", "simulated", "--json", "--record", file]);
    assert!(out.status.success(), "{}", stderr(&out));
    let j = json_of(&out);
    let rec = &j["recording"];
    assert_eq!(rec["cycles"], 30, "{j}");
    assert_eq!((rec["first_cycle"].as_u64(), rec["last_cycle"].as_u64()), (Some(1), Some(30)), "{j}");
    assert_eq!(rec["dropped_cycles"], 0, "{j}");
    let bytes = std::fs::metadata(&path).unwrap().len();
    assert_eq!(rec["bytes"], bytes, "{j}");
    // An MCAP file: its magic at both ends.
    let data = std::fs::read(&path).unwrap();
    assert!(data.starts_with(b"\x89MCAP0\r\n") && data.ends_with(b"\x89MCAP0\r\n"), "not an MCAP file");
    std::fs::remove_file(&path).ok();
    // A file that cannot be made: refused as bad usage, naming it, before the robot starts.
    let bad = situate(["run", TOYBOT, "--no-link", "--cycles", "3", "--json", "--record", "/nonexistent-dir/x.mcap"]);
    assert_eq!(bad.status.code(), Some(2), "{}", stdout(&bad));
    let e = json_of(&bad);
    assert_eq!(e["error"]["kind"], "usage", "{e}");
    assert!(e["error"]["message"].as_str().unwrap().contains("/nonexistent-dir/x.mcap"), "{e}");
}

#[test]
fn quiet_drops_the_notes_and_verbose_logs_without_colour_off_a_terminal() {
    let listen = free_endpoint();
    let args = ["run", TOYBOT, "--cycles", "2", "--clock", "simulated", "--listen", &listen];
    let loud = situate(args);
    assert!(loud.status.success(), "{}", stderr(&loud));
    assert!(stderr(&loud).contains("situate: robot `toybot` serving"), "{}", stderr(&loud));
    let quiet = situate(args.iter().chain(&["-q"]));
    assert!(quiet.status.success(), "{}", stderr(&quiet));
    assert_eq!(stderr(&quiet), "", "-q: errors only");
    let verbose = situate(args.iter().chain(&["-vvv"]));
    assert!(verbose.status.success(), "{}", stderr(&verbose));
    let err = stderr(&verbose);
    assert!(err.contains("TRACE") || err.contains("DEBUG"), "-vvv logs:\n{err}");
    assert!(!err.contains('\u{1b}'), "no ANSI escapes when stderr is not a terminal:\n{err}");
}

#[test]
fn signals_of_a_robot_file_are_listed_statically_with_their_types() {
    let out = situate(["signals", TOYBOT]);
    assert!(out.status.success(), "{}", stderr(&out));
    let line = stdout(&out).lines().find(|l| l.starts_with("sonar.range ")).map(str::to_string);
    let line = line.unwrap_or_else(|| panic!("no sonar.range in:\n{}", stdout(&out)));
    assert!(line.contains("f32[24]") && line.contains("written by sonar"), "{line}");
    let j = json_of(&situate(["signals", TOYBOT, "--json"]));
    let drive = j.as_array().unwrap().iter().find(|s| s["signal"] == "drive.v").expect("drive.v");
    assert_eq!(drive["writers"], serde_json::json!(["runaway", "wander"]));
}

#[test]
fn graph_of_a_robot_file_in_dot() {
    let out = situate(["graph", TOYBOT, "--dot"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let dot = stdout(&out);
    assert!(dot.starts_with("digraph situate {"), "{dot}");
    assert!(dot.contains("\"skill:runaway\" -> \"signal:drive.v\";"), "{dot}");
    assert!(dot.contains("\"signal:sonar.range\" -> \"skill:runaway\";"), "{dot}");
    assert!(dot.trim_end().ends_with('}'));
}

#[test]
fn set_overrides_a_parameter_and_names_a_bad_one() {
    let out = situate(["check", TOYBOT, "--set", "runaway.safe_distance=4.5"]);
    assert_eq!(out.status.code(), Some(3), "4.5 is past the parameter's max: {}", stderr(&out));
    assert!(stderr(&out).contains("safe_distance"), "{}", stderr(&out));
    let ok = situate(["check", TOYBOT, "--set", "runaway.safe_distance=1.5"]);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let bad = situate(["check", TOYBOT, "--set", "runawya.safe_distance=1"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(stderr(&bad).contains("did you mean `runaway`?"), "{}", stderr(&bad));
    let malformed = situate(["check", TOYBOT, "--set", "runaway"]);
    assert_eq!(malformed.status.code(), Some(2));
    assert!(stderr(&malformed).contains("expected SKILL.PARAM=VALUE"), "{}", stderr(&malformed));
}

#[test]
fn environment_variables_are_substituted_and_an_unset_one_is_named_at_its_place() {
    let (_dir, path) = robot_file(
        "env.yaml",
        "# ${NOT_READ_IN_A_COMMENT}\nrobot: ${SITUATE_TEST_ROBOT}\ncycle: {rate_hz: ${SITUATE_TEST_UNSET_RATE:-20}}\n",
    );
    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args([OsStr::new("check"), path.as_os_str(), OsStr::new("--json")])
        .env("SITUATE_TEST_ROBOT", "envbot")
        .env_remove("SITUATE_TEST_UNSET_RATE")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}{}", stdout(&out), stderr(&out));
    assert_eq!(json_of(&out)["robot"], "envbot");
    let unset = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args([OsStr::new("check"), path.as_os_str()])
        .env_remove("SITUATE_TEST_ROBOT")
        .output()
        .unwrap();
    assert_eq!(unset.status.code(), Some(3));
    let err = stderr(&unset);
    assert!(
        err.starts_with(&format!("{}:2:8: error: `${{SITUATE_TEST_ROBOT}}`: the environment variable", path.display())),
        "{err}"
    );
}

#[test]
fn schema_and_completions() {
    for format in ["robot", "manifest", "map"] {
        let j = json_of(&situate(["schema", format]));
        assert_eq!(j["$schema"], "https://json-schema.org/draft/2020-12/schema");
    }
    assert_eq!(situate(["schema", "robto"]).status.code(), Some(2));
    let bash = situate(["completions", "bash"]);
    assert!(bash.status.success());
    assert!(stdout(&bash).contains("situate") && stdout(&bash).contains("signals"), "{}", stdout(&bash));
}

/// `COMPLETE=fish situate -- situate ARGS…`: the candidates the shell would show, one per line as
/// `name<TAB>help` (fish's protocol is the plainest of clap_complete's).
fn complete(endpoint: &str, args: &[&str]) -> Vec<String> {
    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["--", "situate"])
        .args(args)
        .env("COMPLETE", "fish")
        .env("SITUATE_CONNECT", endpoint)
        .env("SITUATE_COMPLETE_TIMEOUT_S", "30")
        .env_remove("RUST_LOG")
        .output()
        .expect("situate runs");
    assert!(out.status.success(), "{}", stderr(&out));
    stdout(&out).lines().map(|l| l.split('\t').next().unwrap_or("").to_string()).collect()
}

#[test]
fn completions_offer_the_running_robots_skills_signals_and_parameters() {
    let robot = Robot::start();
    assert_eq!(complete(&robot.endpoint, &["activate", "wa"]), ["wander"]);
    let signals = complete(&robot.endpoint, &["echo", "od"]);
    assert_eq!(signals, ["odom", "odom.theta", "odom.x", "odom.y"]);
    assert!(complete(&robot.endpoint, &["hz", ""]).contains(&"sonar.range".to_string()));
    let params = complete(&robot.endpoint, &["param", "set", "runaway", "sa"]);
    assert_eq!(params, ["safe_distance"]);
    assert_eq!(complete(&robot.endpoint, &["param", "get", "run"]), ["runaway"]);
    // The registration a shell sources.
    let bash = Command::new(env!("CARGO_BIN_EXE_situate")).env("COMPLETE", "bash").output().unwrap();
    assert!(stdout(&bash).contains("_clap_complete_situate"), "{}", stdout(&bash));
    // Nobody there: no names, only the options, and no error.
    let nobody = free_endpoint();
    let offered = complete(&nobody, &["activate", ""]);
    assert!(offered.iter().all(|c| c.starts_with('-')), "{offered:?}");
}

#[test]
fn completions_offer_the_robot_files_parameters_with_no_robot_running() {
    // `run FILE --set <TAB>`: every skill's parameters, as `skill.param=`; nobody answers.
    let nobody = free_endpoint();
    let offered = complete(&nobody, &["run", TOYBOT, "--set", "run"]);
    assert_eq!(offered, ["runaway.safe_distance=", "runaway.speed="]);
    assert!(complete(&nobody, &["check", TOYBOT, "--set", ""]).contains(&"wander.seed=".to_string()));
    // No file on the line, or one that does not load: nothing, and no error.
    assert_eq!(complete(&nobody, &["run", "--set", "run"]), Vec::<String>::new());
    let dir = tempfile::tempdir().unwrap();
    let broken = dir.path().join("broken.yaml");
    std::fs::write(&broken, "robot: [\n").unwrap();
    assert_eq!(complete(&nobody, &["run", broken.to_str().unwrap(), "--set", ""]), Vec::<String>::new());
}

#[test]
fn a_running_robot_refuses_with_5_and_answers_the_introspection_verbs() {
    let robot = Robot::start();
    let refused = robot.verb(&["activate", "wandr"]);
    assert_eq!(refused.status.code(), Some(5), "{}", stderr(&refused));
    assert!(stderr(&refused).contains("did you mean `wander`?"), "{}", stderr(&refused));
    let j = json_error(&robot.verb(&["param", "set", "runaway", "safe_distance", "99", "--json"]), 5, "refused");
    assert_eq!(j["error"]["remote"]["kind"], "bad_param", "{j}");

    // signals and graph, live: the same shape as from the file.
    let live = json_of(&robot.verb(&["signals", "--json"]));
    let file = json_of(&situate(["signals", TOYBOT, "--json"]));
    assert_eq!(live, file);
    assert!(stdout(&robot.verb(&["graph", "--dot"])).starts_with("digraph situate {"));

    let winners = json_of(&robot.verb(&["winners", "--json"]));
    assert!(winners.as_array().unwrap().iter().any(|w| w["signal"] == "drive.v"), "{winners}");

    let none = robot.verb(&["monitors"]);
    assert_eq!(stdout(&none).trim(), "no monitors", "{}", stderr(&none));

    // param dump → edit → load → dump again.
    let dump = json_of(&robot.verb(&["param", "dump", "--json"]));
    assert_eq!(dump["runaway"]["safe_distance"], 0.6, "{dump}");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("params.json");
    let mut edited = dump.clone();
    edited["runaway"]["safe_distance"] = serde_json::json!(0.9);
    std::fs::write(&file, edited.to_string()).unwrap();
    let load = robot.verb(&["param", "load", file.to_str().unwrap()]);
    assert!(load.status.success(), "{}", stderr(&load));
    let again = json_of(&robot.verb(&["param", "dump", "--json", "--skill", "runaway"]));
    assert_eq!(again["runaway"]["safe_distance"], 0.9, "{again}");
    assert!(again.get("wander").is_none(), "--skill keeps that skill only: {again}");

    std::fs::write(&file, "[1, 2]").unwrap();
    let bad = robot.verb(&["param", "load", file.to_str().unwrap()]);
    assert_eq!(bad.status.code(), Some(3), "{}", stderr(&bad));
}

/// The exit code a sentence of a doc claims: `template` with `{N}` where the code is, matched
/// against the doc with its line breaks as spaces. A sentence that is gone fails the test too.
fn claimed_exit(doc: &str, template: &str) -> i32 {
    let text = std::fs::read_to_string(repo().join(doc)).unwrap_or_else(|e| panic!("{doc}: {e}"));
    let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
    let (before, after) = template.split_once("{N}").expect("a template with {N}");
    let at = text.find(before).unwrap_or_else(|| panic!("{doc} no longer says `{before}…`: update this test"));
    let rest = &text[at + before.len()..];
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    assert!(rest[digits.len()..].starts_with(after), "{doc}: `{before}{digits}` is not followed by `{after}`");
    digits.parse().unwrap_or_else(|_| panic!("{doc}: no exit code after `{before}`"))
}

/// What the docs say about exit codes in running prose, checked against the program, so that
/// they cannot drift again (`check` was once documented as exiting with 1, and was 3).
#[test]
fn the_docs_say_the_exit_codes_the_program_gives() {
    let (dir, broken) = robot_file("broken.yaml", BROKEN);
    let check = claimed_exit(
        "docs/robot-files.md",
        "`situate check` exits with status 0 when the file has no errors, {N} otherwise",
    );
    assert_eq!(situate([OsStr::new("check"), broken.as_os_str()]).status.code(), Some(check));
    assert_eq!(situate(["check", TOYBOT]).status.code(), Some(0));

    let unwritable = claimed_exit(
        "docs/recording.md",
        "A path that cannot be written is refused before the robot starts (exit {N},",
    );
    let nowhere = dir.path().join("no-such-folder").join("run.mcap");
    let out = situate([
        OsStr::new("run"),
        OsStr::new(TOYBOT),
        OsStr::new("--cycles"),
        OsStr::new("5"),
        OsStr::new("--no-link"),
        OsStr::new("--record"),
        nowhere.as_os_str(),
    ]);
    assert_eq!(out.status.code(), Some(unwritable), "{}", stderr(&out));
    assert!(stderr(&out).contains("--record: "), "{}", stderr(&out));

    let replay_unreadable = claimed_exit(
        "docs/cli.md",
        "exit 1 when it differs or the recording lacks cycles, {N} for a recording that cannot be read",
    );
    let garbage = dir.path().join("garbage.mcap");
    std::fs::write(&garbage, b"not a recording").unwrap();
    let out = situate([OsStr::new("replay"), garbage.as_os_str()]);
    assert_eq!(out.status.code(), Some(replay_unreadable), "{}", stderr(&out));
}
