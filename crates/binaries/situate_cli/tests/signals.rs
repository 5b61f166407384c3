//! Signals, end to end with the real binary: SIGTERM and SIGHUP stop
//! `situate run` as Ctrl-C does (the summary, status 0), a stop never waits
//! for a skill's body that does not return (in the cycle, or served by
//! `situate serve-skill`), and a second signal ends the program at once.
//!
//! Every wait is for a condition (a line of output, the process's exit),
//! bounded generously; none is a fixed sleep.
#![cfg(unix)]

mod common;

use common::*;
use std::io::{BufRead as _, BufReader, Read};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

use serde_json::json;
use situate_link::Client;

const TOYBOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../examples/toybot.yaml");

/// Generous: these are conditions to wait for, not timings.
const WAIT: Duration = Duration::from_secs(60);

const HANG_MANIFEST: &str = "\
name: t.hang
doc: Writes x; with hang > 0 its body never returns.
outputs: {x: f64}
params:
  hang: 0.0
";

const C_SOURCE: &str = r#"
#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <unistd.h>
#include "t_hang.h"
struct t_hang_state { char unused; };
situate_status t_hang_step(t_hang_state* s, const t_hang_inputs* in, t_hang_outputs* out,
                           const t_hang_params* p, situate_context* cx) {
    (void)s; (void)in; (void)cx;
    if (p->hang > 0.0) {
        fprintf(stderr, "t.hang: hanging\n");
        fflush(stderr);
        for (;;) sleep(3600);
    }
    out->x = 1.0;
    out->has_x = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(t_hang))
"#;

fn situate() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_situate"));
    c.env_remove("RUST_LOG").env_remove("SITUATE_STOP_TIMEOUT_S");
    c
}

/// The manifest and a library of `t.hang`, built with gcc in `dir`.
fn build_library(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("t_hang.yaml"), HANG_MANIFEST).expect("manifest written");
    run_ok(situate().arg("gen").arg("c").arg(dir.join("t_hang.yaml")).arg("-o").arg(dir));
    std::fs::write(dir.join("hang.c"), C_SOURCE).expect("source written");
    let lib = dir.join("libhang.so");
    let include = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../include");
    run_ok(
        Command::new("gcc")
            .args(["-std=c11", "-O2", "-Wall", "-Werror", "-shared", "-fPIC", "-fvisibility=hidden", "-I"])
            .arg(include)
            .arg("-I")
            .arg(dir)
            .arg(dir.join("hang.c"))
            .arg("-o")
            .arg(&lib),
    );
    lib
}

/// A running `situate`, its stderr read line by line; killed when dropped.
struct Proc {
    child: Child,
    lines: Receiver<String>,
    /// Every stderr line read so far.
    seen: Vec<String>,
}

impl Proc {
    fn spawn(cmd: &mut Command) -> Proc {
        let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().expect("situate starts");
        let err = child.stderr.take().expect("stderr piped");
        let (tx, lines) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            for line in BufReader::new(err).lines().map_while(Result::ok) {
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        Proc { child, lines, seen: Vec::new() }
    }

    /// Waits for a stderr line containing `text`.
    fn wait_for_line(&mut self, text: &str) {
        let deadline = Instant::now() + WAIT;
        loop {
            if self.seen.iter().any(|l| l.contains(text)) {
                return;
            }
            match self.lines.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
                Ok(line) => self.seen.push(line),
                Err(RecvTimeoutError::Timeout) => {
                    panic!("no line with `{text}` within {WAIT:?}; stderr so far:\n{}", self.seen.join("\n"))
                }
                Err(RecvTimeoutError::Disconnected) => {
                    panic!("situate ended without a line with `{text}`; stderr:\n{}", self.seen.join("\n"))
                }
            }
        }
    }

    fn signal(&self, sig: i32) {
        let pid = libc::pid_t::try_from(self.child.id()).expect("a pid");
        // SAFETY: kill(2) on our own child, not yet reaped.
        assert_eq!(unsafe { libc::kill(pid, sig) }, 0, "kill({pid}, {sig})");
    }

    /// Waits for the process to exit; its status, stdout and whole stderr.
    fn wait_exit(mut self) -> (ExitStatus, String, String) {
        let deadline = Instant::now() + WAIT;
        let status = loop {
            if let Some(status) = self.child.try_wait().expect("waiting for situate") {
                break status;
            }
            if Instant::now() > deadline {
                let _ = self.child.kill();
                let _ = self.child.wait();
                panic!("situate did not exit within {WAIT:?} of the signal; stderr:\n{}", self.seen.join("\n"));
            }
            std::thread::sleep(Duration::from_millis(20));
        };
        let mut out = String::new();
        if let Some(mut o) = self.child.stdout.take() {
            let _ = o.read_to_string(&mut out);
        }
        // The reader ends at the end of stderr, which the exit closed.
        while let Ok(line) = self.lines.recv_timeout(WAIT) {
            self.seen.push(line);
        }
        (status, out, self.seen.join("\n"))
    }
}

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A client of the robot at `endpoint`, once it answers.
fn client(endpoint: &str, robot: &str) -> Client {
    let deadline = Instant::now() + WAIT;
    loop {
        if let Ok(mut c) = Client::connect(&[endpoint.to_string()]) {
            c.timeout = Duration::from_secs(5);
            if c.request(robot, "hello", &json!({})).is_ok() {
                return c;
            }
        }
        assert!(Instant::now() < deadline, "the robot at {endpoint} never answered");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn run_stops_cleanly_on_sigterm_sighup_and_sigint() {
    for (sig, name) in [(libc::SIGTERM, "SIGTERM"), (libc::SIGHUP, "SIGHUP"), (libc::SIGINT, "SIGINT")] {
        let endpoint = free_endpoint();
        let mut run = Proc::spawn(situate().args(["run", TOYBOT, "--listen", &endpoint]));
        run.wait_for_line("serving situate/toybot/**");
        run.signal(sig);
        let (status, out, err) = run.wait_exit();
        assert_eq!(status.code(), Some(0), "{name}: {status:?}, stderr:\n{err}");
        assert!(err.contains(&format!("situate: {name}: stopping")), "{name}: {err}");
        assert!(out.starts_with("robot `toybot`: "), "{name}: no summary:\n{out}");
        assert!(out.contains("runaway"), "{name}: {out}");
    }
}

#[test]
fn a_stuck_cycle_does_not_keep_run_from_stopping() {
    // A budget of an hour: the watchdog leaves the body alone, the cycle
    // stays stuck, and the stop must still end.
    let (run, _dir) = hanging_run("budget_ms: 3600000");
    // Ctrl-C used to be noticed and then wait for the cycle for ever.
    run.signal(libc::SIGINT);
    let (status, _out, err) = run.wait_exit();
    assert!(err.contains("situate: SIGINT: stopping"), "{err}");
    assert_eq!(status.code(), Some(1), "{status:?}, stderr:\n{err}");
    assert!(err.contains("the cycle did not stop within 2 s of the shutdown request"), "{err}");
    assert!(err.contains("exiting without it"), "{err}");
}

#[test]
fn a_body_past_its_budget_is_left_behind_and_run_stops_cleanly() {
    let (mut run, _dir) = hanging_run("budget_ms: 100");
    run.wait_for_line("skill `hang` faulted: its body has been running for");
    run.signal(libc::SIGINT);
    let (status, out, err) = run.wait_exit();
    assert!(err.contains("over its execution budget of 100 ms"), "{err}");
    assert_eq!(status.code(), Some(0), "{status:?}, stderr:\n{err}");
    assert!(out.starts_with("robot `stuck`: "), "no summary:\n{out}");
}

/// `situate run` of a robot whose C skill `hang` (with `extra` in its
/// entry) has been made to hang in its body.
fn hanging_run(extra: &str) -> (Proc, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let lib = build_library(dir.path());
    let robot = dir.path().join("robot.yaml");
    std::fs::write(
        &robot,
        format!(
            "robot: stuck\ncycle: {{rate_hz: 50}}\nlibraries: [{}]\nskills:\n  - {{name: hang, type: t.hang, {extra}}}\n",
            lib.display()
        ),
    )
    .expect("robot file written");
    let endpoint = free_endpoint();
    let mut run = Proc::spawn(situate().arg("run").arg(&robot).args(["--listen", &endpoint]));
    run.wait_for_line("serving situate/stuck/**");
    let c = client(&endpoint, "stuck");
    c.request("stuck", "set_param", &json!({"skill": "hang", "param": "hang", "value": 1.0})).expect("hang set");
    run.wait_for_line("t.hang: hanging");
    (run, dir)
}

/// A robot with the remote skill `hang` and its host, `situate serve-skill`
/// (with `host_env` set), serving; the host's body is made to hang.
fn hanging_host(dir: &Path, host_env: &[(&str, &str)]) -> (Proc, Proc) {
    let lib = build_library(dir);
    let robot = dir.join("robot.yaml");
    std::fs::write(&robot, "robot: hosted\ncycle: {rate_hz: 50}\nskills:\n  - {name: hang, remote: t_hang.yaml}\n")
        .expect("robot file written");
    let endpoint = free_endpoint();
    let mut manager = Proc::spawn(situate().arg("run").arg(&robot).args(["--listen", &endpoint]));
    manager.wait_for_line("serving situate/hosted/**");
    let mut host = Proc::spawn(
        situate()
            .args(["serve-skill", "t.hang", "--robot", "hosted", "--connect", &endpoint, "--library"])
            .arg(&lib)
            .envs(host_env.iter().copied()),
    );
    host.wait_for_line("situate: serving `hang`");
    let c = client(&endpoint, "hosted");
    c.request("hosted", "set_param", &json!({"skill": "hang", "param": "hang", "value": 1.0})).expect("hang set");
    host.wait_for_line("t.hang: hanging");
    (manager, host)
}

#[test]
fn serve_skill_stops_on_sigterm_even_when_the_body_does_not_return() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let (_manager, host) = hanging_host(dir.path(), &[]);
    host.signal(libc::SIGTERM);
    let (status, _, err) = host.wait_exit();
    assert_eq!(status.code(), Some(1), "{status:?}, stderr:\n{err}");
    assert!(err.contains("situate: SIGTERM: stopping (again to exit at once)"), "{err}");
    assert!(err.contains("`hang`'s body did not return within 2 s of the stop request; exiting without it"), "{err}");
}

#[test]
fn a_second_signal_ends_the_program_at_once() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    // The stop would wait for the body for ten minutes: only the second signal ends it.
    let (_manager, mut host) = hanging_host(dir.path(), &[("SITUATE_STOP_TIMEOUT_S", "600")]);
    host.signal(libc::SIGTERM);
    host.wait_for_line("situate: SIGTERM: stopping");
    host.signal(libc::SIGINT);
    let (status, _, err) = host.wait_exit();
    assert_eq!(status.code(), Some(130), "{status:?}, stderr:\n{err}");
    assert!(err.contains("situate: SIGINT while stopping: exiting at once"), "{err}");
}
