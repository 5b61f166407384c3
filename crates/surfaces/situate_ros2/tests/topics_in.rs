//! Topics in on a real Zenoh session: a ROS 2 publisher (here a second session writing what
//! rmw_zenoh writes: key, attachment, CDR) feeds a device of the robot, and a skill acts on it.
//! Messages of another type, or that cannot be read, are counted and reported once, and the
//! robot runs on. (python/tests/test_ros2_in.py does it end to end through `situate run`, encoding with
//! `rosbags`, a CDR library this crate does not share.)

mod support;

use std::time::{Duration, Instant};

use situate::manager::{ClockKind, Control, Handle, Joiner, Manager, Request, RobotFile, RobotSpec};
use situate::Value;
use situate_link::{Link, LinkConfig};
use situate_ros2::msgs::{encode, BatteryState, Header, LaserScan, Twist};
use situate_ros2::{rmw, Bridge, Inputs, MsgType, Ros2Node};
use support::{config, free_port, observer, tokens_until, WAIT};
use zenoh::Wait;

const ROS2: &str = "ros2:\n  topics:\n    \
    - {topic: /scan, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in, ring: 24}\n    \
    - {topic: battery, type: sensor_msgs/msg/BatteryState, signal: battery, direction: in, name: bms}\n    \
    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n";

/// A scan of 360 rays from -π, all at 3 m but an obstacle `ahead_m` straight ahead.
fn scan(ahead_m: f32) -> Vec<u8> {
    let mut ranges = vec![3.0f32; 360];
    for r in &mut ranges[175..=185] {
        *r = ahead_m;
    }
    encode(&LaserScan {
        header: Header { frame_id: "laser".into(), ..Header::default() },
        angle_min: -std::f32::consts::PI,
        angle_max: std::f32::consts::PI,
        angle_increment: std::f32::consts::TAU / 360.0,
        range_min: 0.05,
        range_max: 10.0,
        ranges,
        ..LaserScan::default()
    })
    .expect("encodes")
}

fn until<T>(what: &str, mut f: impl FnMut() -> Option<T>) -> T {
    let deadline = Instant::now() + WAIT;
    loop {
        if let Some(t) = f() {
            return t;
        }
        assert!(Instant::now() < deadline, "{what}: not within {WAIT:?}");
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A robot of `skills` (robot-file YAML) on a link of its own, with its ROS 2 node: the topics in
/// as devices, then the bridge. Stopped in order when dropped (bridge, link, manager).
struct RosRobot {
    handle: Handle,
    join: Option<Joiner>,
    link: Option<Link>,
    bridge: Option<Bridge>,
    endpoint: String,
}

impl RosRobot {
    fn start(name: &str, rate_hz: u32, skills: &str, ros2: &str, clock: ClockKind) -> RosRobot {
        let text = format!("robot: {name}\ncycle: {{rate_hz: {rate_hz}}}\nskills:\n{skills}");
        let file = RobotFile::parse(&format!("{name}.yaml"), &text).expect("robot file");
        let endpoint = format!("tcp/127.0.0.1:{}", free_port());
        let link_config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
        let session = Link::open(&link_config).expect("session");
        let ros2 = config(ros2);
        let node = Ros2Node::declare(name, session.clone(), &ros2).expect("node");
        let (inputs, devices) = Inputs::declare(&node, &ros2).expect("topics in");
        let mut spec = RobotSpec::from_file(&file).clock(clock);
        let mut registry = situate_toys::registry();
        for (skill, ty) in devices {
            registry.add(ty);
            spec.skills.push(skill);
        }
        let manager = Manager::build(&spec, &registry).expect("the topics in are devices the robot is built with");
        // With ROS time the robot is spawned stopped (its own clock must never run a cycle), the
        // bridge makes /clock its clock, and a run lets the clock's cycles through.
        let (handle, join) = manager.spawn(!ros2.use_sim_time);
        let link = Link::serve(name, handle.clone(), session, &link_config).expect("link");
        let bridge = Bridge::start_on(node, Some(inputs), handle.clone(), &ros2).expect("bridge");
        if ros2.use_sim_time {
            handle.request_timeout(Request::Run, WAIT).expect("run");
        }
        RosRobot { handle, join: Some(join), link: Some(link), bridge: Some(bridge), endpoint }
    }

    fn bridge(&self) -> &Bridge {
        self.bridge.as_ref().expect("the bridge")
    }

    fn zid(&self) -> String {
        self.link.as_ref().expect("the link").session().zid().to_string()
    }
}

impl Drop for RosRobot {
    fn drop(&mut self) {
        drop(self.bridge.take());
        drop(self.link.take());
        let _ = self.handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

#[test]
fn a_ros2_scan_drives_a_skill_and_bad_messages_are_counted_while_the_robot_runs_on() {
    let mut robot = RosRobot::start("lidarbot", 50, "  - {name: runaway, type: toy.runaway}\n", ROS2, ClockKind::Wall);
    let mut handle = robot.handle.clone();
    for device in ["ros2_scan", "bms"] {
        assert_eq!(handle.skill(device).expect("a device of the robot").kind, situate::SkillKind::Device);
    }

    // Discovery: each topic in is a subscription (MS) of the node, as rmw_zenoh declares it.
    let peer = observer(&robot.endpoint);
    let zid = robot.zid();
    let ms = |id: u32, topic: &str, ty: MsgType| {
        format!("@ros2_lv/0/{zid}/0/{id}/MS/%/%/lidarbot/{topic}/{}/{}/::,10:,:,:,,", ty.dds_name(), ty.type_hash())
    };
    let want = [ms(1, "%scan", MsgType::LaserScan), ms(2, "%battery", MsgType::BatteryState)];
    tokens_until(&peer, 0, |keys| want.iter().all(|w| keys.contains(w)));

    // A publisher as rmw_zenoh makes one: data key, attachment with its sequence and GID.
    let key = |topic: &str, ty: MsgType| format!("0/{topic}/{}/{}", ty.dds_name(), ty.type_hash());
    let gid = rmw::gid("@ros2_lv/0/peer/0/1/MP/%/%/lidar/%scan");
    let mut sequence = 0;
    let mut put = |key: &str, payload: Vec<u8>| {
        sequence += 1;
        peer.put(key, payload).attachment(rmw::attachment(sequence, 0, &gid)).wait().expect("put");
    };

    // An obstacle 0.3 m ahead: the runaway backs off (v < 0), from the ROS 2 scan alone.
    let drive = until("the runaway acting on the ROS 2 scan", || {
        put(&key("scan", MsgType::LaserScan), scan(0.3));
        let reading = handle.query("drive").ok()?;
        match reading.value? {
            Value::Record(r) => match r.get("v") {
                Some(Value::F64(v)) if *v < 0.0 => Some(*v),
                _ => None,
            },
            _ => None,
        }
    });
    assert!(drive < 0.0);
    let ring = handle.query("sonar.range").expect("sonar.range");
    let Some(Value::F32s(r)) = ring.value else { panic!("the ring: {ring:?}") };
    assert_eq!(r.len(), 24);
    assert!((r[0] - 0.3).abs() < 1e-6 && (r[12] - 3.0).abs() < 1e-6, "sector 0 ahead, 12 behind: {r:?}");

    // A battery message becomes a record.
    let battery = encode(&BatteryState { voltage: 24.5, percentage: 0.8, ..BatteryState::default() }).expect("encodes");
    let v = until("the battery record", || {
        put(&key("battery", MsgType::BatteryState), battery.clone());
        match handle.query("battery.voltage").ok()?.value? {
            Value::F64(v) => Some(v),
            _ => None,
        }
    });
    assert!((v - 24.5).abs() < 1e-6);

    // A Twist on /scan (another type), and a payload that declares a 4 GiB range array: each
    // counted, each reported once, and the robot runs on with the last good scan.
    let before = handle.stats().expect("stats").cycle;
    for _ in 0..5 {
        put(&key("scan", MsgType::Twist), encode(&Twist::default()).expect("encodes"));
        let mut bad = scan(0.3);
        // The ranges' count sits after the header (8 + 4 + "laser\0" padded to 8 → 20) and
        // seven f32 (28): at body offset 48.
        bad[4 + 48..4 + 52].copy_from_slice(&u32::MAX.to_le_bytes());
        put(&key("scan", MsgType::LaserScan), bad);
    }
    let stats = until("five of each counted", || {
        let s = robot.bridge().input_stats().into_iter().find(|s| s.topic == "/scan")?;
        (s.wrong_type >= 5 && s.undecodable >= 5).then_some(s)
    });
    assert_eq!(stats.device, "ros2_scan");
    assert!(stats.received >= stats.accepted + 10, "{stats:?}");
    let prints = until("the device's prints", || {
        let info = handle.skill("ros2_scan").ok()?;
        let lines: Vec<String> = info.prints.into_iter().map(|(_, l)| l).collect();
        (lines.len() >= 2).then_some(lines)
    });
    assert_eq!(prints.len(), 2, "once per publisher and problem: {prints:#?}");
    assert!(prints
        .iter()
        .any(|l| l.contains("geometry_msgs/msg/Twist") && l.contains("expected sensor_msgs/msg/LaserScan")));
    assert!(prints.iter().any(|l| l.contains("could not be read") && l.contains("ranges")), "{prints:#?}");
    let gid_hex: String = gid.iter().map(|b| format!("{b:02x}")).collect();
    assert!(prints.iter().all(|l| l.contains(&gid_hex)), "each names the publisher: {prints:#?}");
    until("cycles after the bad messages", || (handle.stats().ok()?.cycle > before + 10).then_some(()));
    let ring = handle.query("sonar.range").expect("sonar.range");
    assert!(matches!(ring.value, Some(Value::F32s(r)) if (r[0] - 0.3).abs() < 1e-6), "the last good scan stays");
    let info = handle.skill("ros2_scan").expect("device");
    assert!(info.active && info.faulted.is_none(), "{info:?}");

    drop(robot.bridge.take());
    // Gone with the bridge: the subscriptions' tokens.
    tokens_until(&peer, 0, |keys| !keys.iter().any(|k| k.contains("/MS/")));
}

#[test]
fn with_use_sim_time_the_cycle_follows_ros_time_one_cycle_per_period_and_stops_with_the_clock() {
    // 50 Hz: a 20 ms period. The robot is spawned stopped; only /clock steps it.
    let robot = RosRobot::start(
        "simbot",
        50,
        "  - {name: wander, type: toy.wander}\n",
        "ros2:\n  use_sim_time: true\n  topics:\n    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/TwistStamped}\n",
        ClockKind::Simulated,
    );
    let (mut handle, bridge) = (robot.handle.clone(), robot.bridge());
    let peer = observer(&robot.endpoint);
    let zid = robot.zid();
    let clock_token = format!(
        "@ros2_lv/0/{zid}/0/2/MS/%/%/simbot/%clock/{}/{}/::,10:,:,:,,",
        situate_ros2::clock::CLOCK_DDS,
        situate_ros2::clock::CLOCK_HASH
    );
    tokens_until(&peer, 0, |keys| keys.contains(&clock_token));
    let clock_key = format!("0/clock/{}/{}", situate_ros2::clock::CLOCK_DDS, situate_ros2::clock::CLOCK_HASH);
    let put_clock = |ns: i64| {
        let t = situate_ros2::msgs::Time { sec: (ns / 1_000_000_000) as i32, nanosec: (ns % 1_000_000_000) as u32 };
        peer.put(&clock_key, encode(&situate_ros2::msgs::Clock { clock: t }).expect("encodes")).wait().expect("put");
    };
    let t0: i64 = 1_000 * 1_000_000_000 + 3_000_000; // 1000.003 s of ROS time
                                                     // The first message anchors time 0; say it until it is heard (the subscription may be new).
    until("the first /clock heard", || {
        put_clock(t0);
        (bridge.clock_stats()?.messages > 0).then_some(())
    });
    assert_eq!(handle.stats().expect("stats").cycle, 0, "no cycle before the clock moves");
    // 10× real time in 1 ms messages: 2 s of ROS time in 200 messages of 10 ms each.
    for k in 1..=200 {
        put_clock(t0 + k * 10_000_000);
        std::thread::sleep(Duration::from_millis(1));
    }
    // 2 s at 20 ms: exactly 100 cycles, none skipped, none doubled.
    until("100 cycles for 2 s of ROS time", || (bridge.clock_stats()?.cycles == 100).then_some(()));
    let stats = handle.stats().expect("stats");
    assert_eq!(stats.cycle, 100);
    assert!((stats.time_s - 2.0).abs() < 1e-9, "robot time follows ROS time: {}", stats.time_s);
    // The clock stops; so does the cycle (a later message resumes it where it was).
    put_clock(t0 + 2_000_000_000 + 5_000_000); // half a period more: no cycle
    put_clock(t0 + 2_030_000_000); // 1.5 periods: one more
    until("the 101st cycle", || (bridge.clock_stats()?.cycles == 101).then_some(()));
    assert_eq!(handle.stats().expect("stats").cycle, 101);
    // A reset (the clock goes back): the robot goes on from where it is, never backwards.
    // (The driver keeps the latest time only: the count comes from the clock's value, never from
    // how many messages came, so the reset is said alone, and seen, before the clock goes on.)
    put_clock(t0);
    until("the reset seen", || (bridge.clock_stats()?.resets == 1).then_some(()));
    put_clock(t0 + 40_000_000);
    until("two cycles after the reset", || (bridge.clock_stats()?.cycles == 103).then_some(()));
    assert_eq!(handle.stats().expect("stats").cycle, 103);
    // A jump of a day (a /clock that is no clock): re-anchored, not a day of cycles.
    put_clock(t0 + 86_400_000_000_000);
    until("the jump seen", || (bridge.clock_stats()?.resets == 2).then_some(()));
    put_clock(t0 + 86_400_000_000_000 + 20_000_000);
    until("one cycle after the jump", || (bridge.clock_stats()?.cycles == 104).then_some(()));
    assert_eq!(handle.stats().expect("stats").cycle, 104);
}

#[test]
fn odometry_goes_out_on_tf_and_a_drive_as_twist_stamped() {
    use situate_ros2::msgs::{decode, TfMessage, TwistStamped};
    let ros2 = config(
        "ros2:\n  topics:\n    - {signal: odom, topic: /tf, type: tf2_msgs/msg/TFMessage, child_frame_id: base_footprint}\n    \
         - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/TwistStamped}\n",
    );
    let record = |fields: &[(&str, f64)]| {
        Value::Record(std::sync::Arc::new(situate::RecordValue {
            fields: fields.iter().map(|(n, v)| (std::sync::Arc::from(*n), Value::F64(*v))).collect(),
        }))
    };
    let odom = record(&[("x", 1.5), ("y", -2.0), ("theta", std::f64::consts::FRAC_PI_2), ("v", 0.1), ("w", 0.0)]);
    let stamp = situate_ros2::msgs::Time { sec: 42, nanosec: 7 };
    let tf = situate_ros2::to_payload_stamped(&ros2.topics[0], &odom, stamp).expect("fits").expect("encodes");
    let tf: TfMessage = decode(&tf).expect("a TFMessage");
    assert_eq!(tf.transforms.len(), 1);
    let t = &tf.transforms[0];
    assert_eq!((t.header.frame_id.as_str(), t.child_frame_id.as_str()), ("odom", "base_footprint"));
    assert_eq!(t.header.stamp, stamp);
    assert_eq!((t.transform.translation.x, t.transform.translation.y), (1.5, -2.0));
    let q = t.transform.rotation;
    assert!(
        (q.z - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12 && (q.w - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-12
    );
    let drive = record(&[("v", 0.4), ("w", -0.2)]);
    let twist = situate_ros2::to_payload_stamped(&ros2.topics[1], &drive, stamp).expect("fits").expect("encodes");
    let twist: TwistStamped = decode(&twist).expect("a TwistStamped");
    assert_eq!((twist.twist.linear.x, twist.twist.angular.z), (0.4, -0.2));
    assert_eq!(twist.header.frame_id, "base_link");
    // A value that is no odometry does not fit.
    assert!(situate_ros2::to_payload_stamped(&ros2.topics[0], &drive, stamp).is_none());
}

#[test]
fn twenty_thousand_fuzzed_messages_are_each_counted_and_the_robot_runs_on() {
    let robot = RosRobot::start(
        "fuzzbot",
        100,
        "  - {name: runaway, type: toy.runaway}\n",
        "ros2:\n  topics:\n    - {topic: /scan, type: sensor_msgs/msg/LaserScan, signal: sonar.range, direction: in}\n",
        ClockKind::Wall,
    );
    let (mut handle, bridge) = (robot.handle.clone(), robot.bridge());
    let peer = observer(&robot.endpoint);
    let key = format!("0/scan/{}/{}", MsgType::LaserScan.dds_name(), MsgType::LaserScan.type_hash());
    // Wait until a good scan gets through: the subscription is known to the peer's session.
    let good = scan(2.0);
    let mut sent = 0u64;
    until("a first scan", || {
        peer.put(&key, good.clone()).congestion_control(zenoh::qos::CongestionControl::Block).wait().expect("put");
        sent += 1;
        (bridge.input_stats()[0].accepted > 0).then_some(())
    });
    // Each a mutation of a good scan (bytes flipped, cut, lengths set huge) or random bytes.
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    const N: u64 = 20_000;
    for _ in 0..N {
        let mut m = good.clone();
        match next() % 4 {
            0 => m.truncate((next() as usize) % m.len()),
            1 => {
                for _ in 0..1 + next() % 8 {
                    let i = (next() as usize) % m.len();
                    m[i] = next() as u8;
                }
            }
            2 => {
                let i = 4 + (next() as usize) % (m.len() - 8);
                m[i..i + 4].copy_from_slice(&(next() as u32 | 0x8000_0000).to_le_bytes());
            }
            _ => m = (0..next() % 2048).map(|_| next() as u8).collect(),
        }
        peer.put(&key, m).congestion_control(zenoh::qos::CongestionControl::Block).wait().expect("put");
    }
    let stats = until("every fuzzed message counted", || {
        let s = bridge.input_stats()[0].clone();
        (s.received >= sent + N).then_some(s)
    });
    assert_eq!(stats.received, sent + N, "every message reached the subscription once: {stats:?}");
    assert_eq!(stats.received, stats.accepted + stats.undecodable + stats.wrong_type, "each counted once: {stats:?}");
    assert!(stats.undecodable > N / 2, "most are unreadable: {stats:?}");
    let before = handle.stats().expect("stats").cycle;
    until("the robot cycling on", || (handle.stats().ok()?.cycle > before + 10).then_some(()));
    let info = handle.skill("ros2_scan").expect("device");
    assert!(info.active && info.faulted.is_none(), "{info:?}");
}

/// What the lock-step test's observer heard, in order: a command (`cmd_vel`), or the robot's
/// `~/cycle` saying it has run its cycles up to a ROS time (ns).
#[derive(Debug, Clone, PartialEq)]
enum Heard {
    Command,
    Done(i64),
}

#[test]
fn in_lockstep_each_cycles_commands_go_out_before_the_cycle_done_and_a_stop_holds_ros_time() {
    use situate_ros2::msgs::{decode, Clock};
    use std::sync::{Arc, Mutex};
    // 10 Hz: a 100 ms period; the wander toy commands the base every cycle.
    let robot = RosRobot::start(
        "lockbot",
        10,
        "  - {name: wander, type: toy.wander}\n",
        "ros2:\n  use_sim_time: true\n  lockstep: true\n  topics:\n    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n",
        ClockKind::Simulated,
    );
    let (mut handle, bridge) = (robot.handle.clone(), robot.bridge());
    let peer = observer(&robot.endpoint);
    let zid = robot.zid();
    // Its tokens: cmd_vel (1), /clock (2), ~/cycle (3).
    let (dds, hash) = (situate_ros2::clock::CLOCK_DDS, situate_ros2::clock::CLOCK_HASH);
    let done_token = format!("@ros2_lv/0/{zid}/0/3/MP/%/%/lockbot/%lockbot%cycle/{dds}/{hash}/::,10:,:,:,,");
    tokens_until(&peer, 0, |keys| keys.contains(&done_token));
    let heard = Arc::new(Mutex::new(Vec::<Heard>::new()));
    let h = Arc::clone(&heard);
    let _commands = peer
        .declare_subscriber(format!("0/cmd_vel/{}/{}", MsgType::Twist.dds_name(), MsgType::Twist.type_hash()))
        .callback(move |_| h.lock().unwrap().push(Heard::Command))
        .wait()
        .expect("subscriber");
    let h = Arc::clone(&heard);
    let _done = peer
        .declare_subscriber(format!("0/lockbot/cycle/{dds}/{hash}"))
        .callback(move |s| {
            let c: Clock = decode(&s.payload().to_bytes()).expect("a Clock");
            h.lock().unwrap().push(Heard::Done(i64::from(c.clock.sec) * 1_000_000_000 + i64::from(c.clock.nanosec)));
        })
        .wait()
        .expect("subscriber");
    let clock_key = format!("0/clock/{dds}/{hash}");
    let put_clock = |ns: i64| {
        let t = situate_ros2::msgs::Time { sec: (ns / 1_000_000_000) as i32, nanosec: (ns % 1_000_000_000) as u32 };
        peer.put(&clock_key, encode(&Clock { clock: t }).expect("encodes")).wait().expect("put");
    };
    let t0: i64 = 500 * 1_000_000_000;
    // The first message anchors time 0 and owes no cycle: said done at once (said again each
    // time it is sent, until the subscriptions have met).
    until("the first /clock said done", || {
        put_clock(t0);
        heard.lock().unwrap().contains(&Heard::Done(t0)).then_some(())
    });
    assert_eq!(handle.stats().expect("stats").cycle, 0);
    let take = || std::mem::take(&mut *heard.lock().unwrap());
    // A fence: a time 1 ns on owes no cycle and is said done as itself, after every say-so of
    // the t0 messages still on their way (one session's puts arrive in order).
    put_clock(t0 + 1);
    until("the fence said done", || heard.lock().unwrap().contains(&Heard::Done(t0 + 1)).then_some(()));
    take();
    // One period: one cycle; its command goes out, then the cycle done.
    put_clock(t0 + 100_000_000);
    until("one cycle done", || heard.lock().unwrap().contains(&Heard::Done(t0 + 100_000_000)).then_some(()));
    assert_eq!(take(), [Heard::Command, Heard::Done(t0 + 100_000_000)]);
    // Three periods at once: three cycles, three commands, then done.
    put_clock(t0 + 400_000_000);
    until("three cycles done", || heard.lock().unwrap().contains(&Heard::Done(t0 + 400_000_000)).then_some(()));
    assert_eq!(take(), [Heard::Command, Heard::Command, Heard::Command, Heard::Done(t0 + 400_000_000)]);
    assert_eq!(handle.stats().expect("stats").cycle, 4);
    // Stopped (a client's `stop`, or a pausing monitor): ROS time goes on, the cycle does not,
    // and nothing is said done until it runs again.
    handle.request(Request::Stop).expect("stop");
    let before = bridge.clock_stats().expect("stats").messages;
    put_clock(t0 + 600_000_000);
    until("the message taken", || (bridge.clock_stats()?.messages > before).then_some(()));
    for _ in 0..10 {
        assert_eq!(handle.stats().expect("stats").cycle, 4, "held while stopped");
    }
    assert!(take().is_empty(), "nothing said done while stopped");
    handle.request(Request::Run).expect("run");
    until("the two owed cycles done", || heard.lock().unwrap().contains(&Heard::Done(t0 + 600_000_000)).then_some(()));
    assert_eq!(take(), [Heard::Command, Heard::Command, Heard::Done(t0 + 600_000_000)]);
    assert_eq!(handle.stats().expect("stats").cycle, 6);
    // A client's step runs the next cycles as ROS time gives them, never ahead of it (a cycle
    // run ahead would read no readings, or whichever tick's came first): its reply waits.
    handle.request(Request::Stop).expect("stop");
    take();
    let stepper = {
        let mut h = handle.clone();
        std::thread::spawn(move || h.request(Request::Step { cycles: 3 }))
    };
    put_clock(t0 + 800_000_000);
    until("two of the step's cycles done", || {
        heard.lock().unwrap().contains(&Heard::Done(t0 + 800_000_000)).then_some(())
    });
    assert_eq!(take(), [Heard::Command, Heard::Command, Heard::Done(t0 + 800_000_000)]);
    assert!(!stepper.is_finished(), "the step waits for its third cycle");
    put_clock(t0 + 900_000_000);
    until("the step's third cycle done", || {
        heard.lock().unwrap().contains(&Heard::Done(t0 + 900_000_000)).then_some(())
    });
    assert_eq!(stepper.join().expect("the stepper").expect("step"), situate_manager::Reply::Done);
    assert_eq!(take(), [Heard::Command, Heard::Done(t0 + 900_000_000)]);
    let stats = handle.stats().expect("stats");
    assert_eq!((stats.cycle, stats.running), (9, false), "stepped, then stopped");
    assert_eq!(bridge.clock_stats().expect("stats").cycles, 9, "the driver ran all nine");
}
