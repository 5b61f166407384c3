//! What the `situate` program's tests share: running it, reading its output,
//! temporary robot files, building test libraries, free endpoints, a robot
//! running in the background.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::io::{BufRead as _, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value as Json;

/// The toy robot of the examples (`examples/toybot.yaml`).
pub const TOYBOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../examples/toybot.yaml");

/// How long a test waits for something to happen (a robot to come up, a
/// sample to arrive): generous, this is no timing assertion.
pub const WAIT: Duration = Duration::from_secs(60);

/// Runs `situate ARGS…` to completion (without the caller's `RUST_LOG`).
pub fn situate<I, S>(args: I) -> Output
where
    I: IntoIterator<Item = S>,
    S: AsRef<OsStr>,
{
    Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(args)
        .env_remove("RUST_LOG")
        .output()
        .expect("the situate binary runs")
}

/// Stdout as one JSON value.
pub fn json_of(out: &Output) -> Json {
    serde_json::from_str(&stdout(out))
        .unwrap_or_else(|e| panic!("stdout is not one JSON value ({e}):\n{}\nstderr:\n{}", stdout(out), stderr(out)))
}

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../..").canonicalize().expect("repo root")
}

/// Runs `cmd` to completion; fails the test with its output if it fails.
pub fn run_ok(cmd: &mut Command) {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    assert!(
        out.status.success(),
        "{cmd:?} failed:\n{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

pub fn stdout(out: &Output) -> String {
    String::from_utf8(out.stdout.clone()).expect("stdout is UTF-8")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8(out.stderr.clone()).expect("stderr is UTF-8")
}

/// Writes `source` as `name` in a fresh temporary directory.
pub fn robot_file(name: &str, source: impl AsRef<[u8]>) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join(name);
    std::fs::write(&path, source).expect("the robot file is written");
    (dir, path)
}

/// The program did not panic (101 is the exit status of a Rust panic).
pub fn assert_no_panic(out: &Output) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "situate panicked:\n{err}");
    assert_ne!(out.status.code(), Some(101), "situate panicked:\n{err}");
}

/// A loopback TCP endpoint nobody listens on right now (below the range of outgoing
/// connections' ports: `situate_link::free_loopback_port`).
pub fn free_endpoint() -> String {
    let port = situate_link::free_loopback_port().expect("a free port");
    format!("tcp/127.0.0.1:{port}")
}

/// `situate run FILE` in the background on a free endpoint, started once it
/// says it serves the link; killed when dropped.
pub struct Robot {
    child: Child,
    /// Where it listens (`tcp/127.0.0.1:PORT`).
    pub endpoint: String,
}

impl Robot {
    /// The toybot, run by this crate's `situate`.
    pub fn start() -> Robot {
        Robot::start_with(Path::new(env!("CARGO_BIN_EXE_situate")), Path::new(TOYBOT), "toybot")
    }

    /// `program run FILE`, whose robot is named `robot`; waits (up to [`WAIT`])
    /// until it serves the link. A port taken between [`free_endpoint`] and the program's bind
    /// (by another test) is tried again on another.
    pub fn start_with(program: &Path, file: &Path, robot: &str) -> Robot {
        for _ in 0..4 {
            if let Some(robot) = Robot::try_start(program, file, robot) {
                return robot;
            }
        }
        panic!("{} run: its port was taken five times running", file.display())
    }

    /// [`Robot::start_with`] once: `None` when the program could not listen on its port.
    fn try_start(program: &Path, file: &Path, robot: &str) -> Option<Robot> {
        let endpoint = free_endpoint();
        let mut child = Command::new(program)
            .arg("run")
            .arg(file)
            .args(["--listen", &endpoint])
            .env_remove("RUST_LOG")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| panic!("{} run starts: {e}", program.display()));
        let err = BufReader::new(child.stderr.take().expect("stderr"));
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in err.lines().map_while(Result::ok) {
                let _ = tx.send(line);
            }
        });
        let deadline = Instant::now() + WAIT;
        let serving = format!("serving situate/{robot}/**");
        let robot = Robot { child, endpoint };
        let mut said = Vec::new();
        loop {
            match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
                Ok(line) if line.contains(&serving) => return Some(robot),
                Ok(line) if line.contains("Address already in use") => return None,
                Ok(line) => said.push(line),
                Err(_) => {
                    panic!("{} run did not say it serves the link; it said:\n{}", file.display(), said.join("\n"))
                }
            }
        }
    }

    /// `args` and the options that reach this robot.
    pub fn args<'a>(&'a self, args: &[&'a str]) -> Vec<&'a str> {
        args.iter().copied().chain(["--connect", &self.endpoint, "--timeout", "30"]).collect()
    }

    /// `situate ARGS…` against this robot.
    pub fn verb(&self, args: &[&str]) -> Output {
        situate(self.args(args))
    }

    /// A link client of this robot (requests time out after 30 s).
    pub fn client(&self) -> situate_link::Client {
        let mut c = situate_link::Client::connect(std::slice::from_ref(&self.endpoint)).expect("a client connects");
        c.timeout = Duration::from_secs(30);
        c
    }
}

impl Drop for Robot {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
