//! The cycle rate under a flood of worst-case link requests (issue 17): a
//! 50 Hz wall-clock robot served by the link, measured idle and while 4
//! Zenoh clients send the costliest requests the protocol allows
//! (`situate_link::flood`), in alternating windows of one run. Reported: each
//! window's achieved rate on the manager's own clock, the flood/idle ratio
//! (target ≥ 0.98), what requests held the cycle back, and the requests
//! answered per second. Nothing is asserted; `--quick` makes short windows.

use std::time::{Duration, Instant};

use serde_json::{json, Value as Json};
use situate::manager::{ClockKind, Manager, Request, RobotFile, RobotSpec};
use situate_link::flood::{Flood, FloodCount, Target};
use situate_link::{Client, Link, LinkConfig};

const ROBOT: &str = "\
robot: floodbench
cycle: {rate_hz: 50}
devices:
  - name: sonar
    type: toy.sonar
  - name: wheels
    type: toy.wheels
skills:
  - name: runaway
    type: toy.runaway
  - name: wander
    type: toy.wander
";

struct Window {
    rate_hz: f64,
    hold_ms: f64,
    late_starts: u64,
    count: Option<FloodCount>,
    seconds: f64,
}

fn stats(c: &Client) -> Json {
    c.request("floodbench", "stats", &json!({})).expect("stats")
}

fn measure(c: &Client, seconds: f64, flood: Option<&Target>) -> Window {
    let running = flood.map(|t| Flood::start(t, 4, 16).expect("flood clients"));
    if running.is_some() {
        std::thread::sleep(Duration::from_millis(300));
    }
    let before = stats(c);
    let started = Instant::now();
    let after = loop {
        std::thread::sleep(Duration::from_millis(200));
        let s = stats(c);
        let t = s["time_s"].as_f64().unwrap_or(0.0) - before["time_s"].as_f64().unwrap_or(0.0);
        if t >= seconds || started.elapsed() > Duration::from_secs_f64(seconds * 10.0 + 30.0) {
            break s;
        }
    };
    let count = running.map(|f| f.stop().expect("flood"));
    let d = |k: &str| after[k].as_f64().unwrap_or(0.0) - before[k].as_f64().unwrap_or(0.0);
    Window {
        rate_hz: d("cycle") / d("time_s"),
        hold_ms: d("request_hold_ns") / 1e6,
        late_starts: d("late_starts") as u64,
        count,
        seconds: d("time_s"),
    }
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let (rounds, seconds) = if quick { (1, 2.0) } else { (3, 6.0) };
    let file = RobotFile::parse("floodbench.yaml", ROBOT).expect("robot file");
    let port = std::net::TcpListener::bind("127.0.0.1:0").and_then(|l| l.local_addr()).expect("a free port").port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).expect("session");
    let spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let manager = Manager::build(&spec, &situate_toys::registry()).expect("robot");
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("floodbench", handle.clone(), session, &config).expect("link");
    let mut client = Client::connect(std::slice::from_ref(&endpoint)).expect("client");
    client.timeout = Duration::from_secs(30);
    let target = Target {
        endpoints: vec![endpoint.clone()],
        robot: "floodbench".into(),
        skill: "wander".into(),
        array_signal: "sonar.range".into(),
    };

    println!("flood: a 50 Hz robot, idle vs 4 clients of worst-case requests ({rounds} rounds of {seconds} s windows)");
    println!(
        "{:>6} {:>7} {:>10} {:>10} {:>8} {:>12} {:>9}",
        "round", "subject", "rate Hz", "held ms", "late", "requests/s", "busy"
    );
    let mut ratios = Vec::new();
    for round in 1..=rounds {
        // Alternating order, so slow drift hits both alike.
        let order = if round % 2 == 1 { [false, true] } else { [true, false] };
        let mut idle = 0.0;
        let mut flooded = 0.0;
        for flood in order {
            let w = measure(&client, seconds, flood.then_some(&target));
            let (rps, busy) = w.count.map(|c| (c.answered as f64 / w.seconds, c.busy)).unwrap_or((0.0, 0));
            println!(
                "{round:>6} {:>7} {:>10.2} {:>10.3} {:>8} {:>12.0} {:>9}",
                if flood { "flood" } else { "idle" },
                w.rate_hz,
                w.hold_ms,
                w.late_starts,
                rps,
                busy
            );
            if flood {
                flooded = w.rate_hz;
            } else {
                idle = w.rate_hz;
            }
        }
        ratios.push(flooded / idle);
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    println!("flood / idle cycle rate: median {median:.4} (rounds: {ratios:.4?})");
    println!("TARGET flood / idle ≥ 0.98: {}", if median >= 0.98 { "met" } else { "NOT met" });
    drop(link);
    let _ = handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
    let _ = join.join_timeout(Duration::from_secs(5));
}
