//! The bridge on a real robot and a real Zenoh session: what a ROS 2 node on rmw_zenoh would see
//! (keys, liveliness tokens, attachments, CDR payloads), read by a second session.

mod support;

use std::collections::HashMap;
use std::time::{Duration, Instant};

use situate::manager::{Reply, Request};
use situate_ros2::msgs::{self, LaserScan, Odometry, Twist};
use situate_ros2::{rmw, Bridge, MsgType, Ros2Error};
use support::{call, call_until_answered, config, observer, service_key, tokens_until, toy_robot, CLIENT_GID, WAIT};
use zenoh::Wait;

const THREE_TOPICS: &str = "ros2:\n  namespace: /toy\n  rate_hz: 50\n  topics:\n    \
    - {signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}\n    \
    - {signal: odom, topic: /odom, type: nav_msgs/msg/Odometry, child_frame_id: base_footprint}\n    \
    - {signal: sonar.range, topic: sonar, type: sensor_msgs/msg/LaserScan, range_max: 3.5}\n";

#[test]
fn a_ros2_node_sees_the_topics_their_tokens_and_cdr_messages_in_rmw_zenohs_format() {
    let robot = toy_robot("rosbot");
    let obs = observer(&robot.endpoint);
    let received = obs.declare_subscriber("0/**").with(flume_like()).wait().expect("subscriber");
    let session = robot.session();
    let zid = session.zid().to_string();
    // A subscriber declared here is not yet known to the robot: a put made before its declaration
    // reaches the robot's session goes to nobody, as it would to a ROS 2 subscriber that joins
    // late (a loaded machine saw the first put missed). The bridge starts once the robot's
    // session routes its topics' keys to the subscriber, so every put from the first is seen.
    let keys: HashMap<&str, String> = [
        ("cmd_vel", format!("0/toy/cmd_vel/geometry_msgs::msg::dds_::Twist_/{}", MsgType::Twist.type_hash())),
        ("odom", format!("0/odom/nav_msgs::msg::dds_::Odometry_/{}", MsgType::Odometry.type_hash())),
        ("sonar", format!("0/toy/sonar/sensor_msgs::msg::dds_::LaserScan_/{}", MsgType::LaserScan.type_hash())),
    ]
    .into_iter()
    .collect();
    for key in keys.values() {
        wait_for_a_subscriber(&session, key);
    }
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
    let session = robot.session();
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

/// Waits until `session` would deliver a put on `key` to some subscriber (a minute at most).
fn wait_for_a_subscriber(session: &zenoh::Session, key: &str) {
    let probe = session.declare_publisher(key.to_string()).wait().expect("probe publisher");
    let deadline = Instant::now() + WAIT;
    while !probe.matching_status().wait().expect("matching status").matching() {
        assert!(Instant::now() < deadline, "the robot's session never saw the subscriber for {key}");
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// A bounded FIFO channel handler for the subscriber (zenoh's default).
fn flume_like() -> zenoh::handlers::FifoChannel {
    zenoh::handlers::FifoChannel::new(1024)
}

#[test]
fn the_parameter_services_answer_and_say_so_when_the_manager_is_gone() {
    use situate_ros2::services::{ListParametersRequest, ListParametersResponse, LIST_PARAMETERS};
    let robot = toy_robot("srvbot");
    let session = robot.session();
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

#[test]
fn every_call_past_the_service_queue_gets_an_error_reply_at_once() {
    use situate_ros2::services::{GetParameterTypesResponse, Names, QUEUE};
    let robot = toy_robot("floodbot");
    let bridge = Bridge::start("floodbot", robot.handle.clone(), robot.session(), &config("ros2:\n  services: true\n"))
        .expect("starts");
    let key = service_key(&bridge, "/floodbot/get_parameter_types");
    let observer = observer(&robot.endpoint);
    let request = msgs::encode(&Names { names: vec!["wander.speed".into()] }).expect("encode");
    call_until_answered(&observer, &key, &request);

    // Many more calls than the queue holds, all sent before any reply is read (each answer asks
    // the manager; sending a call does not wait), then every call's replies read in turn.
    const CALLS: usize = 3000;
    let pending: Vec<_> = (0..CALLS)
        .map(|i| {
            observer
                .get(&key)
                .payload(request.clone())
                .attachment(rmw::attachment(i as i64 + 1, 0, &CLIENT_GID))
                .timeout(WAIT)
                .wait()
                .expect("get")
        })
        .collect();
    let (mut answered, mut refused) = (0usize, 0usize);
    for (i, replies) in pending.iter().enumerate() {
        let reply = replies.recv().unwrap_or_else(|_| {
            panic!("call {} of {CALLS} got no reply ({answered} answered and {refused} refused before it)", i + 1)
        });
        match reply.result() {
            Ok(sample) => {
                let mut d = zenoh_ext::ZDeserializer::new(sample.attachment().expect("the reply's attachment"));
                let seq: i64 = d.deserialize().expect("sequence number");
                assert_eq!(seq, i as i64 + 1, "the reply answers its own call");
                let types: GetParameterTypesResponse =
                    msgs::decode(&sample.payload().to_bytes()).expect("a GetParameterTypes response");
                assert_eq!(types.types, vec![3], "wander.speed is a double");
                answered += 1;
            }
            Err(e) => {
                let text = e.payload().try_to_string().map(|s| s.into_owned()).unwrap_or_default();
                assert!(text.contains("queue is full") && text.contains(&format!("{QUEUE} calls")), "{text}");
                refused += 1;
            }
        }
        assert!(replies.recv().is_err(), "call {}: one reply only", i + 1);
    }
    assert!(refused > 0, "the flood never filled the queue ({answered} answered): the test tested nothing");
    // When a call was refused, the queue held QUEUE calls, and each of them was answered.
    assert!(answered >= QUEUE, "{answered} answered, {refused} refused");
    assert_eq!(bridge.service_stats().refused_queue_full, refused as u64, "every refusal counted");
    println!("{CALLS} calls: {answered} answered, {refused} refused with the queue full");
}
