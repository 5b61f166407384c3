//! No link thread dies silently (issue 17): each that panics is reported as
//! a `worker_failed` event and in `stats`, and restarted; one that keeps
//! panicking stops the robot with a clear error.

mod common;

use std::time::{Duration, Instant};

use common::Running;
use serde_json::{json, Value as Json};
use situate_link::Client;

fn start() -> Running {
    common::toy_robot("supbot")
}

const LIMIT: Duration = Duration::from_secs(60);

/// Waits (at most `LIMIT`) for a message on `rx` that `pick` accepts.
fn wait_for(rx: &crossbeam_channel::Receiver<Json>, what: &str, pick: impl Fn(&Json) -> bool) -> Json {
    let until = Instant::now() + LIMIT;
    loop {
        let left = until.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(j) if pick(&j) => return j,
            Ok(_) => {}
            Err(_) => panic!("no {what} within {LIMIT:?}"),
        }
    }
}

/// Asks until `ok` holds of the answer (a restarted thread may take a moment).
fn eventually(c: &Client, verb: &str, args: &Json, ok: impl Fn(&Json) -> bool) -> Json {
    let until = Instant::now() + LIMIT;
    loop {
        if let Ok(j) = c.request("supbot", verb, args) {
            if ok(&j) {
                return j;
            }
        }
        assert!(Instant::now() < until, "`{verb}` never answered as expected");
        std::thread::sleep(Duration::from_millis(50));
    }
}

#[test]
fn a_link_thread_that_panics_is_reported_and_restarted() {
    let r = start();
    let mut c = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
    c.timeout = Duration::from_secs(10);
    let (_sub, failed) = c.subscribe("supbot", "events/worker_failed").unwrap();
    let (_tsub, telemetry) = c.subscribe("supbot", "telemetry").unwrap();
    let (_psub, params) = c.subscribe("supbot", "events/param_changed").unwrap();
    let link = r.link.as_ref().unwrap();
    c.request("supbot", "telemetry", &json!({"signals": [], "rate_hz": 50})).unwrap();
    wait_for(&telemetry, "telemetry", |_| true);

    for (k, thread) in situate_link::server::THREADS.iter().enumerate() {
        link.inject_panic(thread);
        if *thread == "situate-link-req" {
            // The request in hand when the bridge panics is lost; the ones after it are answered.
            let mut once = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
            once.timeout = Duration::from_secs(2);
            let _ = once.request("supbot", "hello", &json!({}));
        }
        let event = wait_for(&failed, "worker_failed", |e| e["thread"] == *thread);
        assert_eq!(event["action"], "restarted", "{event}");
        assert!(event["cause"].as_str().unwrap().starts_with("panicked: a panic injected by a test"), "{event}");
        let stats = eventually(&c, "stats", &json!({}), |s| s["worker_failures"].as_u64() >= Some(k as u64 + 1));
        assert_eq!(stats["running"], true);
    }
    // Each works again: requests are answered, events and telemetry published.
    assert_eq!(c.request("supbot", "hello", &json!({})).unwrap()["robot"], "supbot");
    c.request("supbot", "set_param", &json!({"skill": "wander", "param": "seed", "value": 7})).unwrap();
    wait_for(&params, "param_changed", |e| e["value"] == 7);
    while telemetry.try_recv().is_ok() {}
    wait_for(&telemetry, "telemetry after the restart", |_| true);
}

#[test]
fn a_link_thread_that_keeps_panicking_stops_the_robot_and_says_so() {
    let r = start();
    let mut c = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
    c.timeout = Duration::from_secs(10);
    let (_sub, failed) = c.subscribe("supbot", "events/worker_failed").unwrap();
    c.request("supbot", "telemetry", &json!({"signals": [], "rate_hz": 100})).unwrap();
    let link = r.link.as_ref().unwrap();
    let times = situate::manager::supervise::MAX_RESTARTS + 1;
    for _ in 0..times {
        link.inject_panic("situate-link-telemetry");
    }
    let last = wait_for(&failed, "the last worker_failed", |e| e["action"] != "restarted");
    assert_eq!(last["action"], format!("not restarted ({times} panics within 60 s): the robot is stopped"), "{last}");
    let stats = eventually(&c, "stats", &json!({}), |s| s["running"] == false);
    assert_eq!(stats["worker_failures"], times as u64);
}
