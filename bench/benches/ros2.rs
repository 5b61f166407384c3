//! ROS 2 topics in (issue "A ROS 2 robot is a situate robot"), measured over loopback Zenoh:
//!
//! - **latency**: a `/scan` put by a ROS 2 publisher (rmw_zenoh's key, attachment and CDR) until
//!   the robot's `sonar.range` holds it, seen by `Query` requests in a loop; against the target
//!   "one cycle + 1 ms" at p99 (a 100 Hz cycle: 11 ms).
//! - **cycle**: the mean cycle time of the same toy robot (runaway, wander) fed by ROS 2 — a
//!   720-ray `/scan` at 10 Hz and `/odom` at 50 Hz in, `cmd_vel` out at 20 Hz — over the one fed by
//!   the toy sonar device, in alternating windows of one run (target ≤ 1.05×).
//! - **fuzz**: the cycle rate while a publisher floods `/scan` with malformed messages, over the
//!   rate without (target ≥ 0.98), and that every one was counted.
//!
//! Nothing is asserted; figures and verdicts are printed. `--quick` makes short windows.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use situate::manager::{ClockKind, Control, Handle, Joiner, Manager, Request, RobotFile, RobotSpec};
use situate::Value;
use situate_link::{Link, LinkConfig};
use situate_ros2::msgs::{encode, Header, LaserScan, Odometry};
use situate_ros2::{rmw, Bridge, Inputs, MsgType, Ros2Node};

const SKILLS: &str = "skills:\n  - {name: runaway, type: toy.runaway}\n  - {name: wander, type: toy.wander}\n";
const ROS2: &str = "ros2:\n  topics:\n    \
    - {topic: /scan, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in}\n    \
    - {topic: /odom, type: nav_msgs/msg/Odometry, signal: odom, direction: in}\n    \
    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n";

struct Robot {
    handle: Handle,
    join: Option<Joiner>,
    _link: Link,
    bridge: Option<Bridge>,
    endpoint: String,
}

impl Drop for Robot {
    fn drop(&mut self) {
        drop(self.bridge.take());
        let _ = self.handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").expect("bind").local_addr().expect("addr").port()
}

/// A 100 Hz toy robot: fed by ROS 2 (`ros2`) or by the toy sonar device.
fn robot(name: &str, ros2: bool) -> Robot {
    let devices = if ros2 { "" } else { "devices:\n  - {name: sonar, type: toy.sonar}\n" };
    let text = format!("robot: {name}\ncycle: {{rate_hz: 100}}\n{devices}{SKILLS}");
    let file = RobotFile::parse(&format!("{name}.yaml"), &text).expect("robot file");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let link_config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&link_config).expect("session");
    let mut spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let mut registry = situate_toys::registry();
    let config = {
        let tree = situate::manager::yaml::parse(ROS2).expect("YAML");
        situate_ros2::Ros2Config::from_node(tree.value.get("ros2").expect("ros2")).expect("valid")
    };
    let mut node = None;
    if ros2 {
        let n = Ros2Node::declare(name, session.clone(), &config).expect("node");
        let (inputs, devices) = Inputs::declare(&n, &config).expect("topics in");
        for (skill, ty) in devices {
            registry.add(ty);
            spec.skills.push(skill);
        }
        node = Some((n, inputs));
    }
    let manager = Manager::build(&spec, &registry).expect("builds");
    let (handle, join) = manager.spawn(true);
    let link = Link::serve(name, handle.clone(), session, &link_config).expect("link");
    let bridge = node.map(|(n, inputs)| Bridge::start_on(n, Some(inputs), handle.clone(), &config).expect("bridge"));
    Robot { handle, join: Some(join), _link: link, bridge, endpoint }
}

fn peer(endpoint: &str) -> zenoh::Session {
    use zenoh::Wait;
    let config = situate_link::session::client_config(&[endpoint.to_string()], None).expect("config");
    zenoh::open(config).wait().expect("peer session")
}

fn key(topic: &str, ty: MsgType) -> String {
    format!("0/{topic}/{}/{}", ty.dds_name(), ty.type_hash())
}

fn scan(rays: usize, marker: f32) -> Vec<u8> {
    let mut ranges = vec![3.0f32; rays];
    ranges[0] = marker;
    encode(&LaserScan {
        header: Header { frame_id: "laser".into(), ..Header::default() },
        angle_min: -std::f32::consts::PI,
        angle_increment: std::f32::consts::TAU / rays as f32,
        range_max: 10.0,
        ranges,
        ..LaserScan::default()
    })
    .expect("encodes")
}

fn put(session: &zenoh::Session, key: &str, payload: Vec<u8>, seq: i64, gid: &[u8; 16]) {
    use zenoh::Wait;
    session
        .put(key, payload)
        .attachment(rmw::attachment(seq, 0, gid))
        .congestion_control(zenoh::qos::CongestionControl::Block)
        .wait()
        .expect("put");
}

fn pct(sorted: &[f64], q: f64) -> f64 {
    sorted[((sorted.len() as f64 - 1.0) * q).round() as usize]
}

fn latency(quick: bool) {
    let mut r = robot("latbench", true);
    let s = peer(&r.endpoint);
    let gid = rmw::gid("bench-scan");
    let k = key("scan", MsgType::LaserScan);
    let samples = if quick { 50 } else { 300 };
    let mut seq = 0;
    let mut out = Vec::with_capacity(samples);
    let mut marker = 0.5f32;
    // Warm up until the subscription routes (the first puts may find no subscriber yet).
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        seq += 1;
        put(&s, &k, scan(720, 0.25), seq, &gid);
        if matches!(r.handle.query("sonar.range").ok().and_then(|x| x.value), Some(Value::F32s(a)) if a[0] == 0.25) {
            break;
        }
        assert!(Instant::now() < deadline, "the scan never reached the robot");
        std::thread::sleep(Duration::from_millis(5));
    }
    for i in 0..samples {
        // A phase spread over the cycle: the put lands anywhere in it.
        std::thread::sleep(Duration::from_micros(2_000 + (i as u64 * 7_919) % 10_000));
        marker = if marker > 2.0 { 0.5 } else { marker + 0.001 };
        seq += 1;
        let start = Instant::now();
        put(&s, &k, scan(720, marker), seq, &gid);
        loop {
            if let Some(Value::F32s(a)) = r.handle.query("sonar.range").ok().and_then(|x| x.value) {
                if a[0] == marker {
                    break;
                }
            }
            if start.elapsed() > Duration::from_secs(5) {
                break;
            }
        }
        out.push(start.elapsed().as_secs_f64() * 1e3);
    }
    out.sort_by(f64::total_cmp);
    let (p50, p99) = (pct(&out, 0.5), pct(&out, 0.99));
    let target = 10.0 + 1.0;
    println!("latency  /scan put → sonar.range (720 rays, 100 Hz cycle, {samples} samples): p50 {p50:.2} ms, p99 {p99:.2} ms, max {:.2} ms", out[out.len() - 1]);
    println!(
        "TARGET latency p99 ≤ one cycle + 1 ms ({target:.0} ms): {} ({p99:.2} ms)",
        if p99 <= target { "met" } else { "NOT met" }
    );
}

/// Mean cycle time (ns) over a window of `seconds`, from the manager's own stats.
fn window_mean_ns(handle: &mut Handle, seconds: f64) -> f64 {
    let before = handle.stats().expect("stats");
    std::thread::sleep(Duration::from_secs_f64(seconds));
    let after = handle.stats().expect("stats");
    let n = after.cycle.saturating_sub(before.cycle).max(1) as f64;
    // mean_cycle_ns is the mean since the start: the window's mean from the two means.
    (after.mean_cycle_ns * after.cycle as f64 - before.mean_cycle_ns * before.cycle as f64) / n
}

/// Publishes a 720-ray /scan at 10 Hz and /odom at 50 Hz until stopped.
fn feed(endpoint: &str, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<()> {
    let s = peer(endpoint);
    std::thread::spawn(move || {
        let (ks, ko) = (key("scan", MsgType::LaserScan), key("odom", MsgType::Odometry));
        let (gs, go) = (rmw::gid("bench-scan"), rmw::gid("bench-odom"));
        let odom = encode(&Odometry::default()).expect("encodes");
        let mut tick = 0i64;
        let start = Instant::now();
        while !stop.load(Ordering::Relaxed) {
            tick += 1;
            put(&s, &ko, odom.clone(), tick, &go);
            if tick % 5 == 0 {
                put(&s, &ks, scan(720, 2.0), tick / 5, &gs);
            }
            let next = start + Duration::from_millis(20 * tick as u64);
            if let Some(d) = next.checked_duration_since(Instant::now()) {
                std::thread::sleep(d);
            }
        }
    })
}

fn cycle_ratio(quick: bool) {
    let mut sim = robot("simbench", false);
    let mut ros = robot("rosbench", true);
    let stop = Arc::new(AtomicBool::new(false));
    let feeder = feed(&ros.endpoint, Arc::clone(&stop));
    let seconds = if quick { 0.5 } else { 2.0 };
    let rounds = if quick { 3 } else { 8 };
    std::thread::sleep(Duration::from_millis(500));
    let (mut a, mut b) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        a.push(window_mean_ns(&mut sim.handle, seconds));
        b.push(window_mean_ns(&mut ros.handle, seconds));
    }
    stop.store(true, Ordering::Relaxed);
    let _ = feeder.join();
    let mut ratios: Vec<f64> = a.iter().zip(&b).map(|(x, y)| y / x).collect();
    ratios.sort_by(f64::total_cmp);
    a.sort_by(f64::total_cmp);
    b.sort_by(f64::total_cmp);
    let ratio = pct(&ratios, 0.5);
    println!(
        "cycle    mean cycle time, sim devices {:.1} µs, ROS 2 in/out {:.1} µs (medians of {rounds} windows); ratio {ratio:.3} (q1 {:.3}, q3 {:.3})",
        pct(&a, 0.5) / 1e3,
        pct(&b, 0.5) / 1e3,
        pct(&ratios, 0.25),
        pct(&ratios, 0.75)
    );
    println!(
        "TARGET cycle time ≤ 1.05× the sim devices': {} ({ratio:.3}×)",
        if ratio <= 1.05 { "met" } else { "NOT met" }
    );
    drop(ros);
    drop(sim);
}

fn fuzz(quick: bool) {
    let mut r = robot("fuzzbench", true);
    let s = peer(&r.endpoint);
    let k = key("scan", MsgType::LaserScan);
    let gid = rmw::gid("bench-fuzz");
    let n: u64 = if quick { 10_000 } else { 100_000 };
    let rate = |h: &mut Handle, f: &mut dyn FnMut()| {
        let before = h.stats().expect("stats");
        let t = Instant::now();
        f();
        let after = h.stats().expect("stats");
        (after.cycle - before.cycle) as f64 / t.elapsed().as_secs_f64()
    };
    let good = scan(720, 1.0);
    let mut state: u64 = 0x2545_F491_4F6C_DD1D;
    let mut sent = 0u64;
    let flood_start = Instant::now();
    let flooded = rate(&mut r.handle, &mut || {
        for i in 0..n {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let mut m = good.clone();
            m.truncate((state as usize) % good.len());
            put(&s, &k, m, i as i64 + 1, &gid);
            sent += 1;
        }
    });
    let flood_s = flood_start.elapsed().as_secs_f64();
    let idle = rate(&mut r.handle, &mut || std::thread::sleep(Duration::from_secs_f64(flood_s.max(1.0))));
    let stats = r.bridge.as_ref().map(|b| b.input_stats()).unwrap_or_default();
    let counted = stats.first().map_or(0, |s| s.undecodable + s.accepted + s.wrong_type);
    let ratio = flooded / idle;
    println!(
        "fuzz     {sent} truncated scans in {flood_s:.1} s: cycle rate {flooded:.1} Hz vs {idle:.1} Hz idle, ratio {ratio:.3}; counted {counted} of {sent}"
    );
    println!("TARGET fuzz cycle rate within 2 %: {} ({ratio:.3})", if ratio >= 0.98 { "met" } else { "NOT met" });
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let quick = args.iter().any(|a| a == "--quick");
    let which: Vec<&str> = args.iter().skip(1).filter(|a| !a.starts_with('-')).map(String::as_str).collect();
    let wants = |name: &str| which.is_empty() || which.contains(&name);
    println!(
        "situate ROS 2 bench (loopback Zenoh; {} CPUs)",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    if wants("latency") {
        latency(quick);
    }
    if wants("cycle") {
        cycle_ratio(quick);
    }
    if wants("fuzz") {
        fuzz(quick);
    }
}
