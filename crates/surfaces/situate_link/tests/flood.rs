//! The link cannot hurt the cycle (issue 17): a flood of worst-case requests
//! from 4 real Zenoh clients while the cycle keeps its rate.
//!
//! The cycle's rate on a wall clock also depends on the machine: on a loaded
//! CI machine the OS may wake the cycle's thread late whatever the link does.
//! So the test asserts on what the link is responsible for, from the
//! manager's own accounting: the time requests served on the cycle's thread
//! held cycle starts past their due time (`request_hold_ns`) stays under 2 %
//! of the window, and the cycles counted fall short of the nominal rate by
//! at most 2 % plus the periods the manager reports lost to other causes
//! (`lost_ns` minus what requests held). On an idle machine the second is the
//! plain "within 2 % of nominal".

mod common;

use std::time::{Duration, Instant};

use common::Running;
use serde_json::{json, Value as Json};
use situate_link::flood::{Flood, Target};
use situate_link::Client;

const RATE_HZ: f64 = 50.0;

fn start() -> Running {
    common::toy_robot("floodbot")
}

fn stats(c: &Client) -> Json {
    c.request("floodbot", "stats", &json!({})).unwrap()
}

fn num(s: &Json, k: &str) -> f64 {
    s[k].as_f64().unwrap_or_else(|| panic!("stats without `{k}`: {s}"))
}

#[test]
fn a_flood_of_worst_case_requests_from_4_clients_leaves_the_cycle_rate_within_2_percent() {
    let r = start();
    let mut c = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
    c.timeout = Duration::from_secs(60);
    let target = Target {
        endpoints: vec![r.endpoint.clone()],
        robot: "floodbot".into(),
        skill: "wander".into(),
        array_signal: "sonar.range".into(),
    };
    let flood = Flood::start(&target, 4, 16).unwrap();
    // Warm-up: every client has had answers before the window opens.
    std::thread::sleep(Duration::from_millis(500));
    let before = stats(&c);
    // A generous window on the manager's own clock (not a sleep of the test's).
    let window_s = 8.0;
    let limit = Instant::now() + Duration::from_secs(120);
    let after = loop {
        std::thread::sleep(Duration::from_millis(200));
        let s = stats(&c);
        if num(&s, "time_s") - num(&before, "time_s") >= window_s || Instant::now() > limit {
            break s;
        }
    };
    let count = flood.stop().unwrap();
    let elapsed = num(&after, "time_s") - num(&before, "time_s");
    let cycles = num(&after, "cycle") - num(&before, "cycle");
    let expected = elapsed * RATE_HZ;
    let period_ns = 1e9 / RATE_HZ;
    let held_ns = num(&after, "request_hold_ns") - num(&before, "request_hold_ns");
    let lost_ns = num(&after, "lost_ns") - num(&before, "lost_ns");
    let excused = ((lost_ns - held_ns).max(0.0) / period_ns).ceil();
    eprintln!(
        "flood: {count:?}; {cycles} cycles in {elapsed:.2} s = {:.2} % of nominal; requests held the cycle {:.3} ms \
         ({:.4} % of the window); lost to other causes {:.1} ms ({excused} periods); late starts {} → {}",
        100.0 * cycles / expected,
        held_ns / 1e6,
        100.0 * held_ns / (elapsed * 1e9),
        (lost_ns - held_ns).max(0.0) / 1e6,
        before["late_starts"],
        after["late_starts"],
    );
    assert!(elapsed >= window_s, "the window did not close within the limit ({elapsed} s)");
    assert!(count.answered >= 400, "the flood was no flood: {count:?}");
    assert_eq!(count.unanswered, 0, "every request is answered: {count:?}");
    assert!(held_ns <= 0.02 * elapsed * 1e9, "requests held the cycle back {:.1} ms in {elapsed:.1} s", held_ns / 1e6);
    assert!(
        cycles + excused >= (0.98 * expected).floor(),
        "{cycles} cycles in {elapsed:.2} s at {RATE_HZ} Hz (expected {expected:.0}; {excused} periods lost to causes \
         other than requests)"
    );
    assert_eq!(after["running"], true);
}
