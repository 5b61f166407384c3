//! The bridge on a real robot and a real Zenoh session: what a ROS 2 node on rmw_zenoh would see
//! (keys, liveliness tokens, attachments, CDR payloads), read by a second session.

use std::collections::HashMap;
use std::time::{Duration, Instant};

use situate::manager::{ClockKind, Handle, Joiner, Manager, Reply, Request, RobotFile, RobotSpec};
use situate_link::{Link, LinkConfig};
use situate_ros2::msgs::{self, LaserScan, Odometry, Twist};
use situate_ros2::{Bridge, MsgType, Ros2Config, Ros2Error};
use zenoh::Wait;

/// Bounds for things that take milliseconds on an idle machine (CI machines are shared).
const WAIT: Duration = Duration::from_secs(60);

fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0").expect("bind").local_addr().expect("addr").port()
}

struct Robot {
    handle: Handle,
    link: Option<Link>,
    join: Option<Joiner>,
    endpoint: String,
}

impl Drop for Robot {
    fn drop(&mut self) {
        drop(self.link.take());
        let _ = self.handle.request_timeout(Request::Shutdown, Duration::from_secs(5));
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

fn toy_robot(name: &str) -> Robot {
    let text = format!(
        "robot: {name}\ncycle: {{rate_hz: 50}}\ndevices:\n  - {{name: sonar, type: toy.sonar}}\n  \
         - {{name: wheels, type: toy.wheels}}\nskills:\n  - {{name: runaway, type: toy.runaway}}\n  \
         - {{name: wander, type: toy.wander}}\n"
    );
    let file = RobotFile::parse(&format!("{name}.yaml"), &text).expect("robot file");
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).expect("session");
    let spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let manager = Manager::build(&spec, &situate_toys::registry()).expect("builds");
    let (handle, join) = manager.spawn(true);
    let link = Link::serve(name, handle.clone(), session, &config).expect("link");
    Robot { handle, link: Some(link), join: Some(join), endpoint }
}

fn config(yaml: &str) -> Ros2Config {
    let tree = situate::manager::yaml::parse(yaml).expect("YAML");
    Ros2Config::from_node(tree.value.get("ros2").expect("ros2")).expect("valid")
}

fn observer(endpoint: &str) -> zenoh::Session {
    let config = situate_link::session::client_config(&[endpoint.to_string()], None).expect("config");
    zenoh::open(config).wait().expect("observer session")
}

/// The liveliness tokens under `@ros2_lv/<domain>/**`, asked until `done` holds (a minute at most).
fn tokens_until(session: &zenoh::Session, domain: u32, done: impl Fn(&[String]) -> bool) -> Vec<String> {
    let deadline = Instant::now() + WAIT;
    loop {
        let replies = session.liveliness().get(format!("@ros2_lv/{domain}/**")).wait().expect("liveliness get");
        let mut keys = Vec::new();
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                keys.push(sample.key_expr().to_string());
            }
        }
        keys.sort();
        if done(&keys) {
            return keys;
        }
        assert!(Instant::now() < deadline, "the tokens never got there; the last seen: {keys:#?}");
        std::thread::sleep(Duration::from_millis(50));
    }
}

const THREE_TOPICS: &str = "ros2:\n  namespace: /toy\n  rate_hz: 50\n  topics:\n    \
    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n    \
    - {signal: odom, topic: /odom, type: nav_msgs/msg/Odometry, child_frame_id: base_footprint}\n    \
    - {signal: sonar.range, topic: sonar, type: sensor_msgs/msg/LaserScan, range_max: 3.5}\n";

#[test]
fn a_ros2_node_sees_the_topics_their_tokens_and_cdr_messages_in_rmw_zenohs_format() {
    let robot = toy_robot("rosbot");
    let obs = observer(&robot.endpoint);
    let received = obs.declare_subscriber("0/**").with(flume_like()).wait().expect("subscriber");
    let session = robot.link.as_ref().expect("link").session().clone();
    let zid = session.zid().to_string();
    let bridge = Bridge::start("rosbot", robot.handle.clone(), session, &config(THREE_TOPICS)).expect("starts");

    // Discovery: the node and one publisher per topic, exactly as rmw_zenoh writes them.
    let qos = "::,10:,:,:,,";
    let expected = vec![
        format!("@ros2_lv/0/{zid}/0/0/NN/%/%toy/rosbot"),
        format!(
            "@ros2_lv/0/{zid}/0/1/MP/%/%toy/rosbot/%toy%cmd_vel/geometry_msgs::msg::dds_::Twist_/{}/{qos}",
            MsgType::Twist.type_hash()
        ),
        format!(
            "@ros2_lv/0/{zid}/0/2/MP/%/%toy/rosbot/%odom/nav_msgs::msg::dds_::Odometry_/{}/{qos}",
            MsgType::Odometry.type_hash()
        ),
        format!(
            "@ros2_lv/0/{zid}/0/3/MP/%/%toy/rosbot/%toy%sonar/sensor_msgs::msg::dds_::LaserScan_/{}/{qos}",
            MsgType::LaserScan.type_hash()
        ),
    ];
    let mut want = expected.clone();
    want.sort();
    let tokens = tokens_until(&obs, 0, |keys| keys == want.as_slice());
    assert_eq!(tokens, want);
    assert_eq!(bridge.node_token(), expected[0]);

    // Data: every topic on its key, each put with rmw_zenoh's attachment and a CDR payload.
    let keys: HashMap<&str, String> = [
        ("cmd_vel", format!("0/toy/cmd_vel/geometry_msgs::msg::dds_::Twist_/{}", MsgType::Twist.type_hash())),
        ("odom", format!("0/odom/nav_msgs::msg::dds_::Odometry_/{}", MsgType::Odometry.type_hash())),
        ("sonar", format!("0/toy/sonar/sensor_msgs::msg::dds_::LaserScan_/{}", MsgType::LaserScan.type_hash())),
    ]
    .into_iter()
    .collect();
    let bridge_keys: Vec<&str> = bridge.topics().iter().map(|(_, k)| k.as_str()).collect();
    for k in keys.values() {
        assert!(bridge_keys.contains(&k.as_str()), "{k} not in {bridge_keys:?}");
    }
    let mut seen: HashMap<String, Vec<(i64, i64, [u8; 16])>> = HashMap::new();
    let deadline = Instant::now() + WAIT;
    let mut twist = None;
    let mut odom = None;
    let mut scan = None;
    while seen.len() < 3 || seen.values().any(|v| v.len() < 2) {
        let left = deadline.saturating_duration_since(Instant::now());
        assert!(!left.is_zero(), "not every topic twice within a minute: {:?}", seen.keys());
        let Ok(Some(sample)) = received.recv_timeout(left) else { continue };
        let key = sample.key_expr().to_string();
        assert!(keys.values().any(|k| *k == key), "an unexpected key: {key}");
        let payload = sample.payload().to_bytes().into_owned();
        assert_eq!(&payload[..4], &[0, 1, 0, 0], "CDR little endian encapsulation");
        let att = sample.attachment().expect("every put has an attachment");
        let mut d = zenoh_ext::ZDeserializer::new(att);
        let sequence: i64 = d.deserialize().expect("sequence number");
        let stamp: i64 = d.deserialize().expect("source timestamp");
        let gid: [u8; 16] = d.deserialize().expect("gid");
        assert!(d.done(), "nothing after the gid");
        seen.entry(key.clone()).or_default().push((sequence, stamp, gid));
        if key == keys["cmd_vel"] {
            twist = Some(msgs::decode::<Twist>(&payload).expect("a Twist"));
        } else if key == keys["odom"] {
            odom = Some(msgs::decode::<Odometry>(&payload).expect("an Odometry"));
        } else {
            scan = Some(msgs::decode::<LaserScan>(&payload).expect("a LaserScan"));
        }
    }
    let now_ns = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).expect("clock").as_nanos() as i64;
    let mut gids = Vec::new();
    for (key, puts) in &seen {
        assert_eq!(puts[0].0, 1, "{key}: sequence numbers start at 1");
        assert!(puts.windows(2).all(|w| w[1].0 == w[0].0 + 1), "{key}: one more each put: {puts:?}");
        assert!(puts.iter().all(|p| p.2 == puts[0].2), "{key}: one gid per publisher");
        assert!(puts.iter().all(|p| (now_ns - p.1).abs() < 600_000_000_000), "{key}: a wall-clock timestamp");
        gids.push(puts[0].2);
    }
    gids.sort();
    gids.dedup();
    assert_eq!(gids.len(), 3, "each publisher its own gid");

    let twist = twist.expect("a twist");
    assert!(twist.linear.y == 0.0 && twist.angular.x == 0.0, "{twist:?}");
    assert!(twist.linear.x.abs() > 0.0 || twist.angular.z.abs() > 0.0, "wander or runaway commands motion: {twist:?}");
    let odom = odom.expect("odometry");
    assert_eq!(odom.header.frame_id, "odom");
    assert_eq!(odom.child_frame_id, "base_footprint");
    let q = odom.pose.pose.orientation;
    assert!((q.z * q.z + q.w * q.w - 1.0).abs() < 1e-9, "a unit yaw quaternion: {q:?}");
    let scan = scan.expect("a scan");
    assert_eq!(scan.ranges.len(), 24);
    assert_eq!(scan.header.frame_id, "base_link");
    assert_eq!(scan.range_max, 3.5);
    assert!((scan.angle_increment - std::f32::consts::TAU / 24.0).abs() < 1e-6);
    assert!(scan.ranges.iter().all(|r| *r > 0.0 && *r <= 2.0), "the toy room is 2 m: {:?}", scan.ranges);

    // Stopping withdraws the node and its publishers.
    bridge.stop();
    tokens_until(&obs, 0, |keys| keys.is_empty());
}

#[test]
fn signals_that_do_not_exist_or_do_not_fit_their_message_are_refused_by_name() {
    let robot = toy_robot("rosbad");
    let session = robot.link.as_ref().expect("link").session().clone();
    let start = |yaml: &str| Bridge::start("rosbad", robot.handle.clone(), session.clone(), &config(yaml));
    match start("ros2:\n  topics:\n    - {signal: sonar.rang, topic: sonar, type: sensor_msgs/msg/LaserScan}\n") {
        Err(e @ Ros2Error::Signal { .. }) => {
            let m = e.to_string();
            assert!(m.contains("`/sonar`") && m.contains("sonar.range"), "names the topic and suggests: {m}");
        }
        Err(other) => panic!("expected an unknown signal, got {other}"),
        Ok(_) => panic!("expected an unknown signal"),
    }
    match start("ros2:\n  topics:\n    - {signal: sonar.range, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n") {
        Err(e @ Ros2Error::Type { .. }) => {
            let m = e.to_string();
            assert!(m.contains("f32[24]") && m.contains("`v` and `w`"), "says what it is and what is needed: {m}");
        }
        Err(other) => panic!("expected a type mismatch, got {other}"),
        Ok(_) => panic!("expected a type mismatch"),
    }
    // Nothing was left declared by the refused starts.
    let obs = observer(&robot.endpoint);
    tokens_until(&obs, 0, |keys| keys.is_empty());
    // The robot itself is fine.
    assert!(matches!(robot.handle.request_timeout(Request::QueryStats, WAIT), Ok(Reply::Stats(_))));
}

/// A bounded FIFO channel handler for the subscriber (zenoh's default).
fn flume_like() -> zenoh::handlers::FifoChannel {
    zenoh::handlers::FifoChannel::new(1024)
}

/// Calls a service of the bridge as an rmw_zenoh client does; the reply's payload and its
/// attachment's sequence number and GID, or the error reply's text.
fn call(
    observer: &zenoh::Session,
    key: &str,
    request: &[u8],
    sequence: i64,
) -> Result<(Vec<u8>, i64, [u8; 16]), String> {
    let gid = [7u8; 16];
    let replies = observer
        .get(key)
        .payload(request.to_vec())
        .attachment(situate_ros2::rmw::attachment(sequence, 0, &gid))
        .timeout(WAIT)
        .wait()
        .expect("get");
    let reply = replies.recv().map_err(|_| "no reply".to_string())?;
    match reply.result() {
        Ok(sample) => {
            let mut d = zenoh_ext::ZDeserializer::new(sample.attachment().expect("the reply's attachment"));
            let seq: i64 = d.deserialize().expect("sequence number");
            let _stamp: i64 = d.deserialize().expect("timestamp");
            let client: [u8; 16] = d.deserialize().expect("GID");
            assert_eq!(client, gid, "the reply names the client");
            Ok((sample.payload().to_bytes().into_owned(), seq, client))
        }
        Err(e) => Err(e.payload().try_to_string().map(|s| s.into_owned()).unwrap_or_default()),
    }
}

#[test]
fn the_parameter_services_answer_and_say_so_when_the_manager_is_gone() {
    use situate_ros2::services::{ListParametersRequest, ListParametersResponse, LIST_PARAMETERS};
    let robot = toy_robot("srvbot");
    let session = robot.link.as_ref().expect("link").session().clone();
    let bridge =
        Bridge::start("srvbot", robot.handle.clone(), session, &config("ros2:\n  services: true\n")).expect("starts");
    let key = bridge
        .services()
        .iter()
        .find(|(name, _)| name == "/srvbot/list_parameters")
        .map(|(_, key)| key.clone())
        .expect("list_parameters offered");
    assert!(key.ends_with(&format!("/rcl_interfaces::srv::dds_::ListParameters_/{}", LIST_PARAMETERS.hash)), "{key}");
    let observer = observer(&robot.endpoint);
    let request = msgs::encode(&ListParametersRequest { prefixes: vec!["wander".into()], depth: 0 }).expect("encode");
    let deadline = Instant::now() + WAIT;
    let (payload, seq, _) = loop {
        // The observer may ask before it has heard of the queryable: asked again, bounded.
        match call(&observer, &key, &request, 1) {
            Ok(r) => break r,
            Err(e) => {
                assert!(Instant::now() < deadline, "no answer from list_parameters: {e}");
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    };
    assert_eq!(seq, 1, "the reply carries the request's sequence number");
    let listed: ListParametersResponse = msgs::decode(&payload).expect("a ListParameters response");
    assert_eq!(listed.result.names, vec!["wander.speed".to_string(), "wander.seed".to_string()]);

    // The manager stops; the bridge still serves, and says why it cannot answer.
    robot.handle.request_timeout(Request::Shutdown, Duration::from_secs(5)).expect("shutdown");
    let err = call(&observer, &key, &request, 2).expect_err("an error reply");
    assert!(err.contains("did not answer"), "{err}");
    drop(bridge);
}
