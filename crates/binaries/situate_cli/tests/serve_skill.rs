//! `situate serve-skill`: a C library's skill type served out of process as
//! a running robot's remote skill (an asynchronous cskill over the link),
//! end to end with the real binary, a real Zenoh session and a C library
//! built here with gcc.
//!
//! The point of running a C skill out of process is that its crash is
//! contained: the test makes the C body abort and checks that the manager
//! runs on, faults only that skill, and takes it back once a new host runs.

mod common;

use common::*;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::{json, Value as Json};
use situate_link::Client;

const SOURCE_MANIFEST: &str = "\
name: t.source
doc: Writes its parameter x every cycle.
outputs: {x: f64}
params:
  x: 1.5
";

const SCALE_MANIFEST: &str = "\
name: t.scale
doc: y = gain * x; fails on a negative x; hangs on x in (50, 100]; aborts the process on x > 100.
inputs: {x: f64}
outputs: {y: f64}
params:
  gain: {type: f64, default: 2.0, min: 0, max: 10}
";

const C_SOURCE: &str = r#"
#define _POSIX_C_SOURCE 200809L
#include <stdlib.h>
#include <unistd.h>
#include "t_source.h"
#include "t_scale.h"
struct t_source_state { char unused; };
struct t_scale_state { int runs; };
situate_status t_source_step(t_source_state* s, const t_source_inputs* in, t_source_outputs* out,
                             const t_source_params* p, situate_context* cx) {
    (void)s; (void)in; (void)cx;
    out->x = p->x;
    out->has_x = true;
    return SITUATE_OK;
}
situate_status t_scale_step(t_scale_state* s, const t_scale_inputs* in, t_scale_outputs* out,
                            const t_scale_params* p, situate_context* cx) {
    s->runs++;
    if (in->x > 100.0) abort(); /* a crash no process can contain */
    if (in->x > 50.0) sleep(3600); /* a hang: only a deadline tells */
    if (in->x < 0.0) return situate_fail(cx, "negative x = %.1f", in->x);
    if (s->runs == 1) situate_print(cx, "scale: first run, gain %.1f", p->gain);
    out->y = p->gain * in->x;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(t_source), SITUATE_SKILL(t_scale))
"#;

/// Generates the two skills' I/O with `situate gen c` and builds the library.
fn build_library(dir: &Path) -> PathBuf {
    for (file, text) in [("t_source.yaml", SOURCE_MANIFEST), ("t_scale.yaml", SCALE_MANIFEST)] {
        std::fs::write(dir.join(file), text).expect("manifest written");
        run_ok(Command::new(env!("CARGO_BIN_EXE_situate")).arg("gen").arg("c").arg(dir.join(file)).arg("-o").arg(dir));
    }
    std::fs::write(dir.join("skills.c"), C_SOURCE).expect("source written");
    let lib = dir.join("libhosted.so");
    run_ok(
        Command::new("gcc")
            .args(["-std=c11", "-O2", "-Wall", "-Werror", "-shared", "-fPIC", "-fvisibility=hidden", "-I"])
            .arg(repo().join("include"))
            .arg("-I")
            .arg(dir)
            .arg(dir.join("skills.c"))
            .arg("-o")
            .arg(&lib),
    );
    lib
}

/// A child process killed when the test ends, however it ends.
struct Proc(Child);

impl Drop for Proc {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn host(lib: &Path, endpoint: &str) -> Proc {
    Proc(
        Command::new(env!("CARGO_BIN_EXE_situate"))
            .args(["serve-skill", "t.scale", "--name", "scale", "--robot", "hosted", "--library"])
            .arg(lib)
            .args(["--connect", endpoint])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("situate serve-skill starts"),
    )
}

/// Waits (bounded, generously: this is not a timing assertion) until `f` gives `Some`.
fn wait_for<T>(what: &str, mut f: impl FnMut() -> Option<T>) -> T {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(v) = f() {
            return v;
        }
        assert!(Instant::now() < deadline, "gave up waiting for {what}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn value_of(c: &Client, signal: &str) -> Option<f64> {
    c.request("hosted", "query", &json!({"signal": signal})).ok()?.get("value")?.as_f64()
}

fn skill(c: &Client, name: &str) -> Json {
    c.request("hosted", "skill", &json!({"skill": name})).expect("skill info")
}

fn cycle(c: &Client) -> u64 {
    c.request("hosted", "stats", &json!({})).expect("stats")["cycle"].as_u64().expect("a cycle count")
}

/// The first `skill_faulted` event for `skill` (waiting, bounded).
fn fault_of(events: &crossbeam_channel::Receiver<Json>, skill: &str) -> String {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        let e = events.recv_timeout(left).unwrap_or_else(|_| panic!("no skill_faulted event for `{skill}`"));
        if e["skill"] == skill {
            return e["cause"].as_str().unwrap_or_default().to_string();
        }
    }
}

#[test]
fn a_c_skill_served_out_of_process_joins_the_cycle_and_its_crash_is_contained() {
    let dir = tempfile::tempdir().expect("a temporary directory");
    let lib = build_library(dir.path());
    // `situate types --library` lists the library's types with their declarations.
    let out = Command::new(env!("CARGO_BIN_EXE_situate")).arg("types").arg("--library").arg(&lib).output().unwrap();
    let listed = String::from_utf8_lossy(&out.stdout);
    assert!(listed.contains("t.scale (sync, priority 0)"), "{listed}");
    assert!(listed.contains("param gain: f64 = 2 (a number in [0.0, 10.0])"), "{listed}");
    let endpoint = free_endpoint();
    let robot = dir.path().join("robot.yaml");
    std::fs::write(
        &robot,
        format!(
            // The remote skill is declared by the very manifest the C type was built from.
            "robot: hosted\ncycle: {{rate_hz: 50}}\nlibraries: [{}]\nskills:\n  \
             - {{name: source, type: t.source}}\n  \
             - {{name: scale, remote: t_scale.yaml, timeout_ms: 5000}}\n",
            lib.display()
        ),
    )
    .expect("robot file written");
    let _manager = Proc(
        Command::new(env!("CARGO_BIN_EXE_situate"))
            .arg("run")
            .arg(&robot)
            .args(["--listen", &endpoint])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("situate run starts"),
    );
    let mut c = wait_for("the manager to listen", || Client::connect(std::slice::from_ref(&endpoint)).ok());
    c.timeout = Duration::from_secs(2);
    wait_for("the manager", || c.request("hosted", "hello", &json!({})).ok());
    let (_sub, events) = c.subscribe("hosted", "events/skill_faulted").expect("events");

    // Served: the C body's answer arrives as the remote skill's output.
    let mut first = host(&lib, &endpoint);
    wait_for("y = 2 × 1.5", || value_of(&c, "y").filter(|y| *y == 3.0));
    wait_for("the C body's print", || {
        skill(&c, "scale")["prints"]
            .as_array()
            .filter(|p| p.iter().any(|l| l[1] == "scale: first run, gain 2.0"))
            .map(|_| ())
    });

    // A parameter set through the link reaches the body in the other process;
    // one out of the manifest's range is refused and changes nothing.
    c.request("hosted", "set_param", &json!({"skill": "scale", "param": "gain", "value": 3.0})).expect("gain set");
    wait_for("y = 3 × 1.5", || value_of(&c, "y").filter(|y| *y == 4.5));
    let refused = c.request("hosted", "set_param", &json!({"skill": "scale", "param": "gain", "value": 20.0}));
    assert!(refused.is_err(), "gain 20 is out of [0, 10]: {refused:?}");
    assert_eq!(c.request("hosted", "get_param", &json!({"skill": "scale", "param": "gain"})).unwrap(), json!(3.0));

    // The C body's error status faults the skill with its message.
    c.request("hosted", "set_param", &json!({"skill": "source", "param": "x", "value": -1.0})).expect("x set");
    let cause = fault_of(&events, "scale");
    assert!(cause.contains("negative x = -1.0"), "{cause}");
    assert_eq!(skill(&c, "scale")["active"], json!(false));

    // The sequencer may take it back.
    c.request("hosted", "set_param", &json!({"skill": "source", "param": "x", "value": 2.0})).expect("x set");
    c.request("hosted", "activate", &json!({"skills": ["scale"]})).expect("scale activated");
    wait_for("y = 3 × 2", || value_of(&c, "y").filter(|y| *y == 6.0));

    // The C body aborts: only the host process dies.
    c.request("hosted", "set_param", &json!({"skill": "source", "param": "x", "value": 500.0})).expect("x set");
    let status = wait_for("the host to die", || first.0.try_wait().expect("wait on the host"));
    assert!(!status.success(), "the host should have died of the abort: {status:?}");
    let cause = fault_of(&events, "scale");
    assert!(cause.contains("gone"), "{cause}");
    let before = cycle(&c);
    wait_for("the cycle to go on", || (cycle(&c) > before + 10).then_some(()));
    assert_eq!(value_of(&c, "x"), Some(500.0), "the other skill runs on");
    assert_eq!(skill(&c, "scale")["active"], json!(false));

    // A new host, and the sequencer reactivates the skill.
    c.request("hosted", "set_param", &json!({"skill": "source", "param": "x", "value": 1.0})).expect("x set");
    let _second = host(&lib, &endpoint);
    // The proxy faults again while no host is back; retry until one is.
    wait_for("y from the new host", || {
        let _ = c.request("hosted", "activate", &json!({"skills": ["scale"]}));
        value_of(&c, "y").filter(|y| *y == 3.0)
    });

    // The C body hangs: the process lives on, only `timeout_ms` tells. (The
    // retried activations above faulted while no host was back: skip those.)
    c.request("hosted", "set_param", &json!({"skill": "source", "param": "x", "value": 60.0})).expect("x set");
    let cause = loop {
        let cause = fault_of(&events, "scale");
        if !cause.contains("is gone") {
            break cause;
        }
    };
    assert!(cause.contains("no answer") && cause.contains("5000 ms"), "{cause}");
    assert_eq!(skill(&c, "scale")["active"], json!(false));
    let before = cycle(&c);
    wait_for("the cycle to go on", || (cycle(&c) > before + 10).then_some(()));
}

#[test]
fn serve_skill_names_what_it_cannot_serve() {
    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["serve-skill", "t.nothing", "--robot", "r", "--connect", &free_endpoint()])
        .output()
        .expect("situate runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("no skill type `t.nothing`") && err.contains("--library"), "{err}");

    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["serve-skill", "t.scale", "--library", "/nonexistent/libx.so", "--robot", "r"])
        .output()
        .expect("situate runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("/nonexistent/libx.so"), "{err}");

    let out = Command::new(env!("CARGO_BIN_EXE_situate"))
        .args(["serve-skill", "mybot.skills:doubler", "--robot", "r"])
        .output()
        .expect("situate runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("Python package"), "{err}");
}
