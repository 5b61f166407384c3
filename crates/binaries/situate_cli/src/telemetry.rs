//! Live signals from the command line, as `ros2 topic echo` and `ros2 topic
//! hz` give them: `situate echo SIGNAL…` prints a running robot's signal
//! values as its telemetry brings them; `situate hz SIGNAL` reports how
//! often a signal is written.
//!
//! Both use the link as it is (docs/protocol.md), no verb of their own:
//! `echo` subscribes to `situate/<robot>/telemetry` and asks for its signals
//! with the `telemetry` request. That request sets the robot's one telemetry
//! selection, shared by every client, so `echo` adds its signals to the
//! selection it finds in the first sample and puts that selection back when
//! it ends. `hz` polls the `query` request, whose reading says the cycle the
//! signal was last written in, and turns the cycles between writes into a
//! rate with the robot's cycle period (from `stats`).

use std::collections::BTreeSet;
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use serde_json::{json, Map, Value as Json};
use situate_link::Client;

use crate::client::{client_verb, Remote};
use crate::output::{problem, Exit, Out};
use crate::signals;

/// How long `hz` waits between two polls: it polls at most 500 times a second.
const POLL_GAP: Duration = Duration::from_millis(2);

/// `situate echo SIGNAL… [--rate HZ] [--count N]`.
pub(crate) fn echo(
    signals: &[String],
    rate: Option<f64>,
    count: Option<u64>,
    remote: &Remote,
    out: Out,
) -> anyhow::Result<()> {
    if let Some(hz) = rate {
        if !(hz.is_finite() && hz > 0.0) {
            return Err(problem(Exit::Usage, format!("--rate {hz}: expects a number of lines a second > 0")));
        }
    }
    client_verb(remote, |c, robot| {
        // An unknown signal is refused here, with the manager's suggestion, rather than echoed as null.
        for s in signals {
            c.request(robot, "query", &json!({"signal": s}))?;
        }
        let (_sub, samples) = c.subscribe(robot, "telemetry")?;
        // The selection other clients asked for, as the first sample shows it.
        let found: Option<Vec<String>> = samples
            .recv_timeout(c.timeout)
            .ok()
            .map(|s| s["signals"].as_object().map(|m| m.keys().cloned().collect()).unwrap_or_default());
        if found.is_none() && !out.quiet {
            eprintln!(
                "situate: no telemetry from `{robot}` within {:.1} s; asking for it anyway",
                c.timeout.as_secs_f64()
            );
        }
        let before: Vec<String> = found.clone().unwrap_or_default();
        let mut union: BTreeSet<String> = before.iter().cloned().collect();
        union.extend(signals.iter().cloned());
        let changed = union.len() != before.len() || found.is_none();
        if changed {
            c.request(robot, "telemetry", &json!({"signals": union.iter().collect::<Vec<_>>()}))?;
        }
        let result = print_samples(&samples, signals, rate, count, out);
        if changed {
            // Put back what others had asked for (the robot may be gone: then nothing to do).
            let _ = c.request(robot, "telemetry", &json!({"signals": before}));
        }
        result
    })
}

/// Prints the samples that carry all of `signals` (one line each), at most
/// `rate` a second, until `count` are printed or a stop is asked for.
fn print_samples(
    samples: &crossbeam_channel::Receiver<Json>,
    signals: &[String],
    rate: Option<f64>,
    count: Option<u64>,
    out: Out,
) -> anyhow::Result<()> {
    let stop = signals::Stop::install()?;
    let gap = rate.map(|hz| Duration::from_secs_f64((1.0 / hz).min(86_400.0)));
    let mut last: Option<Instant> = None;
    let mut printed = 0u64;
    while count.is_none_or(|n| printed < n) && !stop.flag().load(Ordering::SeqCst) {
        let Ok(sample) = samples.recv_timeout(Duration::from_millis(200)) else { continue };
        let Some(values) = sample["signals"].as_object() else { continue };
        // Samples from before the request took effect do not carry them yet.
        if !signals.iter().all(|s| values.contains_key(s)) {
            continue;
        }
        let now = Instant::now();
        if let (Some(gap), Some(last)) = (gap, last) {
            // A little slack, so that telemetry at exactly the rate asked for is not halved.
            if now.duration_since(last) + gap / 10 < gap {
                continue;
            }
        }
        last = Some(now);
        let mine: Map<String, Json> = signals.iter().map(|s| (s.clone(), values[s].clone())).collect();
        let line = json!({"cycle": sample["cycle"], "time_s": sample["time_s"], "signals": mine});
        out.result(&line, || {
            let values: Vec<String> = signals.iter().map(|s| format!("{s} = {}", values[s])).collect();
            format!(
                "cycle {} (t = {:.3} s): {}",
                sample["cycle"],
                sample["time_s"].as_f64().unwrap_or(0.0),
                values.join(", ")
            )
        });
        printed += 1;
    }
    Ok(())
}

/// What `hz` saw of one signal's writes.
#[derive(Default)]
struct Writes {
    /// The distinct cycles it was seen last written in, in order.
    cycles: Vec<u64>,
    /// Polls made, and polls that found the same write as the poll before.
    polls: u64,
    repeats: u64,
    /// Whether it has a value at all.
    written: bool,
}

impl Writes {
    fn see(&mut self, reading: &Json) {
        self.polls += 1;
        self.written = !reading["value"].is_null();
        let Some(cycle) = reading["cycle"].as_u64() else { return };
        if !self.written {
            return;
        }
        match self.cycles.last() {
            Some(&c) if c == cycle => self.repeats += 1,
            _ => self.cycles.push(cycle),
        }
    }

    /// The report of one window: the rate (from the cycle rate `cycle_hz`)
    /// and the cycles between writes.
    fn report(&self, signal: &str, cycle_hz: f64, window_s: f64) -> Json {
        let polled_hz = self.polls as f64 / window_s.max(1e-9);
        if self.cycles.len() < 2 {
            return json!({
                "signal": signal, "rate_hz": null, "writes": self.cycles.len(), "written": self.written,
                "window_s": window_s, "polled_hz": polled_hz,
            });
        }
        let gaps: Vec<u64> = self.cycles.windows(2).map(|w| w[1].saturating_sub(w[0])).collect();
        let span = (self.cycles[self.cycles.len() - 1] - self.cycles[0]) as f64;
        let mean = span / gaps.len() as f64;
        let rate = if mean > 0.0 { cycle_hz / mean } else { 0.0 };
        json!({
            "signal": signal,
            "rate_hz": rate,
            "writes": self.cycles.len(),
            "written": true,
            "mean_cycles": mean,
            "min_cycles": gaps.iter().min(),
            "max_cycles": gaps.iter().max(),
            "cycle_hz": cycle_hz,
            // Every poll saw a new write: writes between polls were missed, the rate is a lower bound.
            "at_least": self.repeats == 0,
            "window_s": window_s,
            "polled_hz": polled_hz,
        })
    }
}

fn report_text(r: &Json) -> String {
    let signal = r["signal"].as_str().unwrap_or("");
    let Some(rate) = r["rate_hz"].as_f64() else {
        return if r["written"].as_bool() == Some(true) {
            format!("{signal}: not written again in {:.1} s", r["window_s"].as_f64().unwrap_or(0.0))
        } else {
            format!("{signal}: never written yet")
        };
    };
    format!(
        "{signal}: {}{rate:.3} Hz — every {:.2} cycles (min {}, max {}) at {:.3} Hz cycles; {} writes seen in {:.1} s",
        if r["at_least"].as_bool() == Some(true) { "at least " } else { "" },
        r["mean_cycles"].as_f64().unwrap_or(0.0),
        r["min_cycles"],
        r["max_cycles"],
        r["cycle_hz"].as_f64().unwrap_or(0.0),
        r["writes"],
        r["window_s"].as_f64().unwrap_or(0.0),
    )
}

/// `situate hz SIGNAL [--window S] [--count N]`: a report every `window`
/// seconds (of what was seen since the start), `count` of them or until
/// a stop is asked for.
pub(crate) fn hz(signal: &str, window: f64, count: Option<u64>, remote: &Remote, out: Out) -> anyhow::Result<()> {
    if !(window.is_finite() && (0.1..=86_400.0).contains(&window)) {
        return Err(problem(Exit::Usage, format!("--window {window}: expects seconds from 0.1 to 86400")));
    }
    client_verb(remote, |c, robot| {
        let stats = c.request(robot, "stats", &json!({}))?;
        // The nominal rate: cycles are counted in the robot's time, whatever the clock.
        let cycle_hz = stats["period_s"].as_f64().filter(|p| *p > 0.0).map_or(0.0, |p| 1.0 / p);
        let stop = signals::Stop::install()?;
        let mut writes = Writes::default();
        let start = Instant::now();
        let mut reports = 0u64;
        let mut next = start + Duration::from_secs_f64(window);
        while count.is_none_or(|n| reports < n) && !stop.flag().load(Ordering::SeqCst) {
            writes.see(&poll(c, robot, signal)?);
            let now = Instant::now();
            if now >= next {
                let r = writes.report(signal, cycle_hz, now.duration_since(start).as_secs_f64());
                out.result(&r, || report_text(&r));
                reports += 1;
                next += Duration::from_secs_f64(window);
            }
            std::thread::sleep(POLL_GAP);
        }
        Ok(())
    })
}

fn poll(c: &Client, robot: &str, signal: &str) -> anyhow::Result<Json> {
    Ok(c.request(robot, "query", &json!({"signal": signal}))?)
}
