//! `situate echo` and `situate hz` against a real running robot: values as
//! the telemetry brings them, the selection other clients asked for left as
//! it was, rates from the cycles between writes, Ctrl-C, and the exit codes.

mod common;

use common::*;
use serde_json::{json, Value as Json};
use std::io::{BufRead as _, BufReader};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn json_lines(out: &Output) -> Vec<Json> {
    stdout(out)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON ({e}): {l}\nstderr:\n{}", stderr(out))))
        .collect()
}

/// Waits (up to [`WAIT`]) for a telemetry sample whose selection is exactly `want`.
fn wait_for_selection(client: &situate_link::Client, want: &[&str]) {
    let (_sub, samples) = client.subscribe("toybot", "telemetry").expect("a subscription");
    let deadline = Instant::now() + WAIT;
    let mut last = Json::Null;
    while Instant::now() < deadline {
        if let Ok(s) = samples.recv_timeout(Duration::from_millis(500)) {
            let mut keys: Vec<&str> =
                s["signals"].as_object().map(|m| m.keys().map(String::as_str).collect()).unwrap_or_default();
            keys.sort_unstable();
            if keys == want {
                return;
            }
            last = s;
        }
    }
    panic!("no telemetry sample selected {want:?} within {WAIT:?}; the last: {last}");
}

#[test]
fn echo_prints_samples_and_leaves_the_selection_it_found() {
    let robot = Robot::start();
    let client = robot.client();
    // Another client (a sequencer, say) has chosen its telemetry.
    client.request("toybot", "telemetry", &json!({"signals": ["drive.v"]})).expect("telemetry is chosen");
    wait_for_selection(&client, &["drive.v"]);

    let out = robot.verb(&["echo", "sonar.range", "drive.w", "--count", "3", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 3, "{}", stdout(&out));
    for l in &lines {
        let signals = l["signals"].as_object().expect("signals");
        assert_eq!(signals.keys().collect::<Vec<_>>(), ["drive.w", "sonar.range"], "only its own: {l}");
        assert_eq!(signals["sonar.range"].as_array().map(Vec::len), Some(24), "{l}");
        assert!(l["cycle"].as_u64().is_some() && l["time_s"].as_f64().is_some(), "{l}");
    }
    assert!(lines[0]["cycle"].as_u64() < lines[2]["cycle"].as_u64(), "samples advance: {lines:?}");
    // The sequencer's choice is back.
    wait_for_selection(&client, &["drive.v"]);

    let text = robot.verb(&["echo", "drive.v", "--count", "1"]);
    assert_eq!(text.status.code(), Some(0), "{}", stderr(&text));
    let line = stdout(&text);
    assert!(line.starts_with("cycle ") && line.contains("(t = ") && line.contains("): drive.v = "), "{line}");
    assert_eq!(line.lines().count(), 1, "{line}");
}

#[test]
fn echo_ends_cleanly_on_ctrl_c_and_puts_the_selection_back() {
    let robot = Robot::start();
    let client = robot.client();
    let mut echo = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(robot.args(&["echo", "sonar.range", "--rate", "5"]))
        .env_remove("RUST_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("situate echo starts");
    let mut lines = BufReader::new(echo.stdout.take().expect("stdout")).lines();
    let first = lines.next().expect("a line").expect("text");
    assert!(first.contains("sonar.range = ["), "{first}");
    wait_for_selection(&client, &["sonar.range"]);
    // SIGINT, as Ctrl-C sends it.
    let pid = i32::try_from(echo.id()).expect("a pid");
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let deadline = Instant::now() + WAIT;
    let status = loop {
        if let Some(status) = echo.try_wait().expect("echo's status") {
            break status;
        }
        assert!(Instant::now() < deadline, "echo did not end within {WAIT:?} of Ctrl-C");
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(status.code(), Some(0), "a clean end");
    wait_for_selection(&client, &[]);
}

/// The fields docs/cli.md gives for `situate hz --json`, sorted: the quoted names of the `{...}`
/// after "with `--json`" in the paragraph on `hz`.
fn documented_hz_fields() -> Vec<String> {
    let doc = std::fs::read_to_string(repo().join("docs/cli.md")).expect("docs/cli.md");
    let para = doc.find("`situate hz sonar.range` reports").expect("docs/cli.md's paragraph on `hz`");
    let from = para + doc[para..].find("with `--json`").expect("its `--json` form") + "with `--json`".len();
    let open = from + doc[from..].find("`{").expect("`{");
    let close = open + doc[open..].find("}`").expect("}`");
    let mut fields: Vec<String> = doc[open..close].split('"').skip(1).step_by(2).map(str::to_string).collect();
    fields.sort_unstable();
    fields
}

#[test]
fn hz_reports_the_rate_of_a_signal_written_every_cycle() {
    let robot = Robot::start();
    let out = robot.verb(&["hz", "drive.v", "--window", "0.5", "--count", "3", "--json"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    let reports = json_lines(&out);
    assert_eq!(reports.len(), 3, "{}", stdout(&out));
    let last = &reports[2];
    assert_eq!(last["signal"], "drive.v");
    assert_eq!(last["cycle_hz"], 20.0, "{last}");
    let rate = last["rate_hz"].as_f64().unwrap_or_else(|| panic!("a rate: {last}"));
    assert!(rate > 0.0 && rate <= 20.0 + 1e-9, "{last}");
    if last["at_least"] == false {
        // The toybot's winner writes the drive every cycle: the shortest interval seen is one
        // cycle. A busy machine makes polls miss writes (the flake hunt saw every 2.2 cycles
        // on average, 19 at most): the rate is then lower by as much, and said to be lower
        // only through `max_cycles`. With no write missed, it is the cycle rate exactly.
        assert_eq!(last["min_cycles"], 1, "{last}");
        if last["max_cycles"] == 1 {
            assert!((rate - 20.0).abs() < 1e-9, "{last}");
        }
    }
    // The fields are the ones docs/cli.md lists (it once left `written` out).
    let mut fields: Vec<String> = last.as_object().expect("an object").keys().cloned().collect();
    fields.sort_unstable();
    assert_eq!(fields, documented_hz_fields(), "docs/cli.md's `hz --json` fields differ: {last}");
    let text = robot.verb(&["rate", "drive.v", "--window", "0.3", "--count", "1"]);
    assert_eq!(text.status.code(), Some(0), "{}", stderr(&text));
    assert!(stdout(&text).starts_with("drive.v: "), "{}", stdout(&text));
}

#[test]
fn unknown_signals_bad_options_and_no_robot_have_their_exit_codes() {
    let robot = Robot::start();
    let unknown = robot.verb(&["echo", "sonar.rang", "--count", "1"]);
    assert_eq!(unknown.status.code(), Some(5), "{}", stderr(&unknown));
    assert!(stdout(&unknown).is_empty(), "{}", stdout(&unknown));
    let unknown = robot.verb(&["hz", "sonar.rang", "--count", "1"]);
    assert_eq!(unknown.status.code(), Some(5), "{}", stderr(&unknown));
    for bad in [&["echo", "drive.v", "--rate", "0"][..], &["hz", "drive.v", "--window", "nan"], &["echo"]] {
        let out = robot.verb(bad);
        assert_eq!(out.status.code(), Some(2), "{bad:?}: {}", stderr(&out));
    }
    drop(robot);
    let nobody = free_endpoint();
    for verb in [&["echo", "drive.v", "--count", "1"][..], &["hz", "drive.v", "--count", "1"]] {
        let out = situate(verb.iter().copied().chain(["--connect", &nobody, "--timeout", "1"]));
        assert_no_panic(&out);
        assert_eq!(out.status.code(), Some(4), "{verb:?}: {}", stderr(&out));
    }
}
