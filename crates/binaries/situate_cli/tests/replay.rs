//! `situate replay` from the outside: a robot file with tight deadlines
//! replays identically (a replay runs bodies to completion), and damaged
//! recordings are refused as bad files (exit 3) naming where, without
//! reading what is not there.

mod common;

use std::path::{Path, PathBuf};

use common::{assert_no_panic, json_of, situate, stderr, TOYBOT};

/// Records the toy robot on the simulated clock, `cycles` cycles, into `dir`.
fn record(dir: &Path, cycles: u32) -> PathBuf {
    let path = dir.join("toy.mcap");
    let cycles = cycles.to_string();
    let out = situate([
        "run",
        TOYBOT,
        "--clock",
        "simulated",
        "--cycles",
        cycles.as_str(),
        "--no-link",
        "--no-gui",
        "--record",
        path.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    path
}

fn replay(args: &[&str]) -> std::process::Output {
    let mut all = vec!["replay", "--json"];
    all.extend_from_slice(args);
    let out = situate(all);
    assert_no_panic(&out);
    out
}

#[test]
fn replay_with_a_robot_file_of_tight_deadlines_is_identical() {
    let dir = tempfile::tempdir().unwrap();
    let rec = record(dir.path(), 300);
    // The same robot, every run given a nanosecond: on the wall clock each
    // would be faulted; a replay runs them to completion.
    let source = std::fs::read_to_string(TOYBOT).unwrap();
    let tight =
        source.replace("  executor: serial\n", "  executor: serial\n  budget_ms: 0.000001\n  liveness_ms: 0.000001\n");
    assert_ne!(tight, source, "the toy robot's cycle section changed");
    let robot = dir.path().join("tight.yaml");
    std::fs::write(&robot, tight).unwrap();
    let out = replay(&[rec.to_str().unwrap(), "--robot", robot.to_str().unwrap()]);
    let result = json_of(&out);
    assert_eq!(out.status.code(), Some(0), "{result}\n{}", stderr(&out));
    assert_eq!(result["identical"], true, "{result}");
    assert_eq!((result["cycles"].as_u64(), result["matched"].as_u64()), (Some(300), Some(300)), "{result}");
    assert_eq!(result["dropped_cycles"], 0, "{result}");
}

/// Where the first chunk record starts (walking the records from the magic).
fn first_chunk(bytes: &[u8]) -> usize {
    let mut pos = 8;
    while pos + 9 <= bytes.len() {
        let len = u64::from_le_bytes(bytes[pos + 1..pos + 9].try_into().unwrap()) as usize;
        if bytes[pos] == 0x06 {
            return pos;
        }
        pos += 9 + len;
    }
    panic!("no chunk in the recording");
}

/// `situate replay FILE` refused as a bad file: exit 3, the error (JSON)
/// naming the file.
fn refused(file: &Path) -> String {
    let out = replay(&[file.to_str().unwrap()]);
    let result = json_of(&out);
    assert_eq!(out.status.code(), Some(3), "{result}");
    assert_eq!(result["error"]["kind"], "bad_file", "{result}");
    let message = result["error"]["message"].as_str().unwrap_or_default().to_string();
    assert!(message.starts_with(file.to_str().unwrap()), "{message}");
    message
}

#[test]
fn replay_refuses_a_damaged_recording_as_a_bad_file_naming_where() {
    let dir = tempfile::tempdir().unwrap();
    let rec = record(dir.path(), 300);
    let bytes = std::fs::read(&rec).unwrap();
    let at = first_chunk(&bytes);
    let bad = dir.path().join("bad.mcap");
    // The chunk's header zeroed: it claims to hold nothing.
    let mut zeroed = bytes.clone();
    zeroed[at + 9..at + 9 + 40].fill(0);
    std::fs::write(&bad, &zeroed).unwrap();
    let message = refused(&bad);
    assert!(message.contains(&format!("at byte {at} (chunk)")), "{message}");
    // Cut short, as by a robot killed while recording.
    std::fs::write(&bad, &bytes[..bytes.len() * 2 / 3]).unwrap();
    assert!(refused(&bad).contains("cut short"));
    // Not a file at all: refused before anything is read (it never ends).
    let message = refused(Path::new("/dev/zero"));
    assert!(message.contains("not a regular file"), "{message}");
}

/// `path`'s bytes with the first `from` replaced by `to` (the same length),
/// the data section's CRC set to 0 ("not computed", as MCAP allows).
fn patched(path: &Path, from: &str, to: &str) -> PathBuf {
    assert_eq!(from.len(), to.len());
    let mut bytes = std::fs::read(path).unwrap();
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap_or_else(|| panic!("no {from:?} in the file"));
    bytes[at..at + from.len()].copy_from_slice(to.as_bytes());
    let mut pos = 8;
    while bytes[pos] != 0x0F {
        pos += 9 + u64::from_le_bytes(bytes[pos + 1..pos + 9].try_into().unwrap()) as usize;
    }
    bytes[pos + 9..pos + 13].fill(0);
    let out = path.with_file_name(format!("patched-{}.mcap", to.len()));
    std::fs::write(&out, bytes).unwrap();
    out
}

#[test]
fn a_recording_whose_robot_file_is_gone_is_viewed_from_its_own_wiring() {
    let dir = tempfile::tempdir().unwrap();
    let robot = dir.path().join("robot.yaml");
    std::fs::copy(TOYBOT, &robot).unwrap();
    let rec = dir.path().join("toy.mcap");
    let (r, f) = (robot.to_str().unwrap(), rec.to_str().unwrap());
    let out = situate(["run", r, "--clock", "simulated", "--cycles", "300", "--no-link", "--no-gui", "--record", f]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    std::fs::remove_file(&robot).unwrap();

    // A re-simulation needs the robot file, and says so, naming the way out.
    let out = replay(&[f]);
    let err = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("robot.yaml, is gone") && err.contains("--view"), "{err}");

    // A viewer does not: every skill plays, and every cycle is the recording's.
    let out = replay(&[f, "--view"]);
    let result = json_of(&out);
    assert_eq!(out.status.code(), Some(0), "{result}\n{}", stderr(&out));
    assert_eq!((result["view"].as_bool(), result["identical"].as_bool()), (Some(true), Some(true)), "{result}");
    assert_eq!((result["cycles"].as_u64(), result["matched"].as_u64()), (Some(300), Some(300)), "{result}");
    let mut played: Vec<&str> = result["played"].as_array().unwrap().iter().filter_map(|s| s.as_str()).collect();
    played.sort_unstable();
    assert_eq!(played, ["runaway", "sonar", "wander", "wheels"], "{result}");
    assert_eq!(result["live"], serde_json::json!([]), "{result}");

    // It re-simulates nothing, so it takes nothing that would.
    for extra in [["--live", "wander"], ["--robot", TOYBOT], ["--set", "wander.speed=0.3"]] {
        let mut args = vec![f, "--view"];
        args.extend_from_slice(&extra);
        let out = replay(&args);
        assert_eq!(out.status.code(), Some(2), "--view {extra:?}: {}", stderr(&out));
    }

    // A recording without the wiring (made before it was recorded) or with a
    // wiring that cannot be read is a bad file, and the error says what.
    // (An MCAP metadata key is its length, 4 bytes little-endian, then its bytes.)
    let old = patched(&rec, "\u{6}\0\0\0wiring", "\u{6}\0\0\0wirinG");
    let out = replay(&[old.to_str().unwrap(), "--view"]);
    let err = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("holds no robot wiring"), "{err}");
    let bad = patched(&rec, "\"kind\":\"sync\"", "\"kind\":\"sink\"");
    let out = replay(&[bad.to_str().unwrap(), "--view"]);
    let err = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(
        err.contains("`wiring`: skill 2 (`runaway`): `kind`")
            && err.contains("sink")
            && err.contains("not sync, async or device"),
        "{err}"
    );
}

#[test]
fn a_robot_killed_while_recording_leaves_a_file_whose_cycles_can_be_viewed() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("crash.mcap");
    let f = rec.to_str().unwrap();
    let mut robot = std::process::Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["run", TOYBOT, "--clock", "simulated", "--cycles", "100000000", "--no-link", "--no-gui", "--record", f])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // Killed (SIGKILL: no clean-up at all) once a few chunks are on disk.
    let bound = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while std::fs::metadata(&rec).map_or(0, |m| m.len()) < 400_000 {
        assert!(std::time::Instant::now() < bound, "the recording did not grow to 400 kB in 120 s");
        assert!(robot.try_wait().unwrap().is_none(), "the robot stopped by itself");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    robot.kill().unwrap();
    robot.wait().unwrap();

    // As it is, the file is refused, and the refusal names the way to read it.
    let out = replay(&[f, "--view"]);
    let err = format!("{}{}", String::from_utf8_lossy(&out.stdout), stderr(&out));
    assert_eq!(out.status.code(), Some(3), "{err}");
    assert!(err.contains("cut short") && err.contains("--recover"), "{err}");
    // Read up to its last complete cycle: every cycle kept matches, and the
    // result is never "identical".
    for extra in [&["--view"][..], &[][..]] {
        let mut args = vec![f, "--recover"];
        args.extend_from_slice(extra);
        let out = replay(&args);
        let result = json_of(&out);
        assert_eq!(out.status.code(), Some(1), "{result}\n{}", stderr(&out));
        assert_eq!(result["identical"], false, "{result}");
        let cut = &result["cut_short"];
        let last = cut["last_cycle"].as_u64().expect("a last complete cycle");
        assert!(last > 100, "{result}");
        assert_eq!((result["cycles"].as_u64(), result["matched"].as_u64()), (Some(last), Some(last)), "{result}");
        assert!(cut["reason"].as_str().is_some_and(|r| !r.is_empty()), "{result}");
    }
}
