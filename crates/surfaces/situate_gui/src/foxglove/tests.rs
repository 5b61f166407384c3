//! The Foxglove server's tests: frames, the poller, clients' bounds, the route, the channels.

use std::sync::atomic::Ordering;

use axum::body::Bytes;
use axum::extract::ws::Message;
use serde_json::{json, Value as Json};
use situate_core::Value;
use situate_manager::Request;

use super::client::size;
use super::poller::{collect, deliver};
use super::protocol::{advertise, WARNING};
use super::schemas::history_schemas;
use super::*;
use crate::history::{Layout, LeafLayout};
use crate::History;
use situate_manager::{Event, Frame};

fn history() -> History {
    let leaves =
        ["odom.x", "sonar.range"].iter().map(|p| LeafLayout { path: p.to_string(), writers: vec![] }).collect();
    History::new(Layout { leaves, skills: vec![] }, 100, 0)
}

fn frame(cycle: u64, values: Vec<(usize, Value)>) -> Frame {
    Frame { cycle, time_s: cycle as f64 * 0.05, values: values.into(), prints: vec![], winners: vec![] }
}

#[test]
fn a_message_data_frame_is_opcode_subscription_timestamp_payload_little_endian() {
    let f = message_data(0x0102_0304, 0x1122_3344_5566_7788, b"{\"cycle\":3}");
    assert_eq!(f[0], 0x01);
    assert_eq!(&f[1..5], &[0x04, 0x03, 0x02, 0x01]);
    assert_eq!(&f[5..13], &[0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11]);
    assert_eq!(&f[13..], b"{\"cycle\":3}");
    assert_eq!(nanos(1.5), 1_500_000_000);
    assert_eq!(nanos(-1.0), 0);
    assert_eq!(nanos(f64::NAN), 0);
}

#[test]
fn the_poller_sends_every_cycle_past_the_last_sent_once() {
    let mut h = history();
    let mut cursor = Cursor::default();
    for c in 1..=3 {
        h.push_frame(frame(c, vec![(0, Value::F64(c as f64)), (1, Value::F64(0.5))]));
    }
    let out: Vec<_> = collect(&h, &mut cursor, &[1]).into_iter().map(|p| p.encode(0)).collect();
    let cycles: Vec<Json> = out
        .iter()
        .map(|(ch, _, p)| {
            assert_eq!(*ch, 1);
            serde_json::from_slice::<Json>(p).expect("JSON")
        })
        .collect();
    assert_eq!(
        cycles,
        vec![json!({"cycle": 1, "value": 1.0}), json!({"cycle": 2, "value": 2.0}), json!({"cycle": 3, "value": 3.0})]
    );
    assert_eq!(out[2].1, 150_000_000, "the manager's clock at cycle 3");
    assert!(collect(&h, &mut cursor, &[1]).is_empty(), "nothing new");
    h.push_frame(frame(4, vec![(0, Value::F64(4.0))]));
    h.push_event(&Event::ManagerStopped { cycle: 4 });
    let out: Vec<_> = collect(&h, &mut cursor, &[1, 2, 3]).into_iter().map(|p| p.encode(0)).collect();
    let topics: Vec<u32> = out.iter().map(|(c, _, _)| *c).collect();
    assert_eq!(topics, vec![1, 3], "x at cycle 4 and the event (sonar.range was not written): {out:?}");
    let event: Json = serde_json::from_slice(&out[1].2).expect("JSON");
    assert_eq!(event["cycle"], 4);
    assert!(event["value"]["kind"].is_string(), "{event}");
    // An event of a cycle already sent, arriving late, is still sent once.
    h.push_event(&Event::ManagerStopped { cycle: 4 });
    assert_eq!(collect(&h, &mut cursor, &[3]).len(), 1);
    assert!(collect(&h, &mut cursor, &[3]).is_empty());
}

#[test]
fn clients_subscriptions_and_queues_are_bounded() {
    let hub = Hub::default();
    let mut joined: Vec<_> = (0..MAX_CLIENTS).map(|_| hub.join(4).expect("admitted")).collect();
    assert!(hub.join(4).is_none(), "no more than MAX_CLIENTS");
    let (client, mut rx) = joined.remove(0);
    hub.leave(&client);
    assert_eq!(hub.len(), MAX_CLIENTS - 1);
    assert!(hub.join(4).is_some(), "a place freed");
    // Subscriptions: bad ones are refused one by one.
    let errors = client.subscribe(
        &json!({"subscriptions": [{"id": 1, "channelId": 1}, {"id": 1, "channelId": 2},
        {"id": 2, "channelId": 1}, {"id": 3, "channelId": 99}, {"id": -1, "channelId": 1}, {"id": 4, "channelId": 2}]}),
        3,
    );
    assert_eq!(errors.len(), 4, "{errors:?}");
    assert!(errors[0].contains("id 1 is in use"), "{errors:?}");
    assert!(errors[1].contains("subscribed already"), "{errors:?}");
    assert!(errors[2].contains("no channel 99"), "{errors:?}");
    assert_eq!(client.subscribe(&json!({"subscriptions": 3}), 3).len(), 1);
    let _ = client.unsubscribe(&json!({"subscriptionIds": [4]}));
    let many: Vec<Json> = (10..10 + MAX_SUBSCRIPTIONS as u32).map(|i| json!({"id": i, "channelId": i})).collect();
    let errors = client.subscribe(&json!({"subscriptions": many}), u32::MAX);
    assert_eq!(errors.len(), 1, "one held already, so the last is one too many: {errors:?}");
    assert!(errors[0].contains(&format!("at most {MAX_SUBSCRIPTIONS}")), "{errors:?}");
    client.subs.lock().expect("lock").retain(|id, _| *id == 1);
    assert_eq!(client.unsubscribe(&json!({"subscriptionIds": [1, 77]})).len(), 1, "77 was never subscribed");
    // A full queue drops and counts, without waiting.
    let out: Vec<(u32, u64, Bytes)> = (0..10).map(|i| (2, i, Bytes::from_static(b"{}"))).collect();
    client.subs.lock().expect("lock").insert(5, 2);
    deliver(&[Arc::clone(&client)], &out);
    assert_eq!(client.dropped(), 6, "4 queued, 6 dropped");
    let mut frames = Vec::new();
    while let Ok(m) = rx.try_recv() {
        client.taken(&m);
        frames.push(m);
    }
    assert_eq!(frames.len(), 4);
    match &frames[0] {
        Message::Binary(b) => assert_eq!(&b[..], &message_data(5, 0, b"{}")[..]),
        other => panic!("a binary frame, got {other:?}"),
    }
    assert_eq!(client.queued_bytes.load(Ordering::SeqCst), 0, "all taken");
    frames.iter().for_each(|m| assert!(size(m) > 0));
    // The bytes are bounded too: one message of more than half the budget leaves no room for a second.
    let big = Bytes::from(vec![b'x'; QUEUE_BYTES / 2 + 1]);
    let before = client.dropped();
    deliver(&[Arc::clone(&client)], &[(2, 0, big.clone()), (2, 1, big)]);
    assert_eq!(client.dropped(), before + 1, "the second big message is dropped");
    let m = rx.try_recv().expect("the first is queued");
    client.taken(&m);
    // Room again: the client is told of its losses.
    client.report_drops();
    match rx.try_recv() {
        Ok(Message::Text(t)) => {
            let s: Json = serde_json::from_str(t.as_str()).expect("JSON");
            assert_eq!(s["op"], "status");
            assert_eq!(s["level"], WARNING);
            assert!(s["message"].as_str().unwrap_or("").starts_with("7 messages dropped"), "{s}");
        }
        other => panic!("a status, got {other:?}"),
    }
}

#[test]
fn a_client_follows_the_parameters_it_names_or_all() {
    let (client, _rx) = Client::new(4);
    let (r, p) = ("circle.radius", "circle.period_s");
    let (v, w) = (Value::F64(3.0), Value::F64(9.0));
    let changed = [(r, &v), (p, &w)];
    assert!(!client.follows_params());
    assert_eq!(client.param_update(&changed), None);
    assert!(client.subscribe_params(&json!({"parameterNames": [r]})).is_empty());
    let m = client.param_update(&changed).expect("an update");
    assert_eq!(m["op"], "parameterValues");
    assert_eq!(m["parameters"], json!([{"name": r, "value": 3.0, "type": "float64"}]));
    assert!(client.subscribe_params(&json!({"parameterNames": []})).is_empty(), "all");
    assert_eq!(client.param_update(&changed).expect("an update")["parameters"].as_array().map(Vec::len), Some(2));
    let known = [r.to_string(), p.to_string()];
    assert!(client.unsubscribe_params(&json!({"parameterNames": [r]}), &known).is_empty());
    assert_eq!(client.param_update(&changed).expect("an update")["parameters"][0]["name"], p);
    assert!(client.unsubscribe_params(&json!({}), &known).is_empty());
    assert!(!client.follows_params());
    assert_eq!(client.subscribe_params(&json!({"parameterNames": "x"})).len(), 1, "a bad list is an error");
}

/// The head of the server's answer to an upgrade request to `/foxglove`.
fn upgrade_head(addr: std::net::SocketAddr, extra: &str) -> String {
    use std::io::{Read, Write};
    let mut s = std::net::TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
    let request = format!(
        "GET /foxglove HTTP/1.1\r\nHost: {addr}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
         Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{extra}\r\n"
    );
    s.write_all(request.as_bytes()).expect("write");
    let (mut buf, mut chunk) = (Vec::new(), [0u8; 4096]);
    while !String::from_utf8_lossy(&buf).contains("\r\n\r\n") {
        match s.read(&mut chunk) {
            Ok(0) | Err(_) => break,
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
        }
    }
    String::from_utf8_lossy(&buf).to_ascii_lowercase()
}

#[test]
fn the_route_selects_the_subprotocol_refuses_other_sites_and_needs_a_history() {
    use situate::manager::{Control, Manager, RobotSpec, SkillSpec};
    let spec = RobotSpec::new("foxtest").skill(SkillSpec::new("sonar", "toy.sonar"));
    let mut manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
    let tap = crate::HistoryTap::new(&mut manager);
    let (mut handle, join) = manager.spawn(true);
    let gui = crate::serve_with_history(handle.clone(), crate::GuiConfig::default(), Some(tap)).expect("serve");
    let ok = upgrade_head(gui.local_addr(), "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n");
    assert!(ok.starts_with("http/1.1 101"), "{ok}");
    assert!(ok.contains("sec-websocket-protocol: foxglove.websocket.v1"), "{ok}");
    let foxglove_app = upgrade_head(gui.local_addr(), "Origin: https://app.foxglove.dev\r\n");
    assert!(foxglove_app.starts_with("http/1.1 101"), "{foxglove_app}");
    let evil = upgrade_head(gui.local_addr(), "Origin: https://evil.example\r\n");
    assert!(evil.starts_with("http/1.1 403"), "{evil}");
    gui.stop();
    let plain = crate::serve(handle.clone(), crate::GuiConfig::default()).expect("serve");
    let none = upgrade_head(plain.local_addr(), "");
    assert!(none.starts_with("http/1.1 503"), "no history, no Foxglove: {none}");
    plain.stop();
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
}

#[test]
fn only_foxglove_this_server_or_no_origin_may_connect() {
    let headers = |origin: Option<&str>| {
        let mut h = HeaderMap::new();
        h.insert(header::HOST, "127.0.0.1:8080".parse().expect("header"));
        if let Some(o) = origin {
            h.insert(header::ORIGIN, o.parse().expect("header"));
        }
        h
    };
    assert!(origin_allowed(&headers(None)), "the desktop app sends no origin");
    assert!(origin_allowed(&headers(Some("https://app.foxglove.dev"))));
    assert!(origin_allowed(&headers(Some("http://127.0.0.1:8080"))));
    assert!(!origin_allowed(&headers(Some("https://evil.example"))));
    assert!(!origin_allowed(&headers(Some("https://app.foxglove.dev.evil.example"))));
}

#[test]
fn the_advertisement_names_every_leaf_and_the_events_with_json_schemas() {
    let mut h = history();
    h.push_frame(frame(1, vec![(0, Value::F64(1.0))]));
    let a = advertise(&h);
    let channels = a["channels"].as_array().expect("channels");
    assert_eq!(channels.len(), 4);
    assert_eq!(channels[0]["topic"], "odom.x");
    assert_eq!(channels[0]["id"], 1);
    assert_eq!(channels[2]["topic"], EVENTS_TOPIC);
    assert_eq!(channels[3]["topic"], "foxglove/sonar", "sonar.range as a laser scan too");
    for c in &channels[..3] {
        assert_eq!(c["encoding"], "json");
        assert_eq!(c["schemaEncoding"], "jsonschema");
        let schema: Json = serde_json::from_str(c["schema"].as_str().expect("a string")).expect("JSON");
        assert_eq!(schema["required"], json!(["cycle", "value"]));
    }
    let x: Json = serde_json::from_str(channels[0]["schema"].as_str().unwrap_or("")).expect("JSON");
    assert_eq!(x["properties"]["value"]["anyOf"][0]["type"], "number");
    assert_eq!(value_schema(Some(&Value::I64s(vec![1].into())))["items"]["type"], "integer");
}

#[test]
fn the_robot_frame_pose_and_sonar_are_published_in_foxgloves_schemas() {
    let paths = [
        "truth.pose.x",
        "truth.pose.y",
        "truth.pose.theta",
        "truth.pose.floor",
        "sonar.range",
        "odom.x",
        "odom.y",
        "odom.theta",
    ];
    let leaves = paths.iter().map(|p| LeafLayout { path: p.to_string(), writers: vec![] }).collect();
    let mut h = History::new(Layout { leaves, skills: vec![] }, 100, 0);
    let known = history_schemas(&h);
    let topics: Vec<_> = known.channels.iter().map(|c| (c.topic, c.kind.schema_name())).collect();
    assert_eq!(
        topics,
        vec![
            ("foxglove/tf", "foxglove.FrameTransforms"),
            ("foxglove/truth.pose", "foxglove.PoseInFrame"),
            ("foxglove/odom", "foxglove.PoseInFrame"),
            ("foxglove/sonar", "foxglove.LaserScan")
        ]
    );
    assert_eq!(known.channels[0].kind, Known::Transform { parent: "world" }, "the ground truth places the robot");
    let odom_only = Schemas::of(["odom.x", "odom.y", "odom.theta"].into_iter());
    assert_eq!(odom_only.channels[0].kind, Known::Transform { parent: "odom" });
    assert!(Schemas::of(["odom.x", "odom.y"].into_iter()).channels.is_empty(), "no theta, no pose");
    // The advertisement: the leaves, the events, then these, with Foxglove's schemas.
    let a = advertise(&h);
    let channels = a["channels"].as_array().expect("channels");
    assert_eq!(channels.len(), paths.len() + 1 + 4);
    let scan = &channels[paths.len() + 4];
    assert_eq!((scan["topic"].as_str(), scan["id"].as_u64()), (Some("foxglove/sonar"), Some(paths.len() as u64 + 5)));
    assert_eq!(scan["schemaEncoding"], "jsonschema");
    let schema: Json = serde_json::from_str(scan["schema"].as_str().unwrap_or("")).expect("JSON");
    assert_eq!(schema["title"], "foxglove.LaserScan");
    assert_eq!(schema["properties"]["timestamp"]["properties"]["nsec"]["maximum"], 999_999_999);
    let tf: Json = serde_json::from_str(channels[paths.len() + 1]["schema"].as_str().unwrap_or("")).expect("JSON");
    assert_eq!(tf["properties"]["transforms"]["items"]["properties"]["child_frame_id"]["type"], "string");
    // Messages: one per cycle a pose leaf was written in, with the values of that cycle.
    let ring: Vec<f32> = (0..24).map(|i| 1.0 + i as f32 / 10.0).collect();
    h.push_frame(frame(
        1,
        vec![
            (0, Value::F64(2.0)),
            (1, Value::F64(3.0)),
            (2, Value::F64(std::f64::consts::FRAC_PI_2)),
            (4, Value::F32s(ring.into())),
        ],
    ));
    h.push_frame(frame(2, vec![(2, Value::F64(0.0))]));
    let base = paths.len() as u32 + 2;
    let mut cursor = Cursor::default();
    let epoch = 1_700_000_000_000_000_000;
    let out: Vec<_> =
        collect(&h, &mut cursor, &[base, base + 1, base + 3]).into_iter().map(|p| p.encode(epoch)).collect();
    let ids: Vec<u32> = out.iter().map(|o| o.0).collect();
    assert_eq!(ids, vec![base, base, base + 1, base + 1, base + 3], "tf and pose at cycles 1 and 2, the scan at 1");
    let msg = |k: usize| serde_json::from_slice::<Json>(&out[k].2).expect("JSON");
    let tf1 = msg(0);
    let t = &tf1["transforms"][0];
    assert_eq!((t["parent_frame_id"].as_str(), t["child_frame_id"].as_str()), (Some("world"), Some(BASE_FRAME)));
    assert_eq!((t["translation"]["x"].as_f64(), t["translation"]["y"].as_f64()), (Some(2.0), Some(3.0)));
    let half = (std::f64::consts::FRAC_PI_4).sin();
    assert!((t["rotation"]["z"].as_f64().unwrap_or(0.0) - half).abs() < 1e-12, "{t}");
    assert_eq!(
        out[0].1, 1_700_000_000_050_000_000,
        "the run's start on the wall clock + the manager's clock at cycle 1"
    );
    assert_eq!(t["timestamp"], json!({"sec": 1_700_000_000u64, "nsec": 50_000_000}));
    let pose2 = msg(3);
    assert_eq!(pose2["frame_id"], "world");
    assert_eq!(pose2["pose"]["position"]["x"], 2.0, "x at cycle 2 is the one of cycle 1 (written then)");
    assert_eq!(pose2["pose"]["orientation"]["w"], 1.0, "theta 0 at cycle 2");
    let scan = msg(4);
    assert_eq!(scan["frame_id"], BASE_FRAME);
    assert_eq!(scan["ranges"].as_array().map(Vec::len), Some(24));
    assert_eq!(scan["start_angle"], 0.0);
    assert!((scan["end_angle"].as_f64().unwrap_or(0.0) - 23.0 * 15f64.to_radians()).abs() < 1e-12, "{scan}");
    assert!((scan["ranges"][3].as_f64().unwrap_or(0.0) - 1.3).abs() < 1e-6);
}
