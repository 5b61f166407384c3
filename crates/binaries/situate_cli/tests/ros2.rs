//! A robot file's `ros2:` section through the real binary: `situate check`
//! refuses a bad one with its place, and `situate run` starts the bridge on
//! the link's session, its ROS 2 node visible to another Zenoh session.
//! (`situate_ros2`'s own tests check the topics, keys and CDR messages.)

mod common;

use common::*;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use zenoh::Wait as _;

const TOYBOT: &str = include_str!("../../../../examples/toybot.yaml");

fn situate() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_situate"));
    c.env_remove("SITUATE_STOP_TIMEOUT_S").env("RUST_LOG", "warn,zenoh=error");
    c
}

#[test]
fn a_bad_ros2_section_is_a_bad_file_named_with_its_line() {
    let lines = TOYBOT.lines().count();
    let source = format!("{TOYBOT}\nros2:\n  domain_id: 999\n  topics:\n    - {{signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}}\n");
    let (_dir, path) = robot_file("bad.yaml", source);
    let out = situate().arg("check").arg(&path).output().expect("situate check runs");
    assert_no_panic(&out);
    assert_eq!(out.status.code(), Some(3), "a bad file: {}", stderr(&out));
    let err = stderr(&out);
    assert!(err.contains("ros2") && err.contains("domain"), "says what: {err}");
    let at = format!("bad.yaml:{}:", lines + 3);
    assert!(err.contains(&at), "says where ({at}): {err}");
}

#[test]
fn situate_run_starts_the_ros2_bridge_on_the_link() {
    let source = format!(
        "{TOYBOT}\nros2:\n  domain_id: 7\n  topics:\n    - {{signal: drive, topic: cmd_vel, type: geometry_msgs/msg/Twist}}\n"
    );
    let (_dir, path) = robot_file("ros2.yaml", source);
    let endpoint = free_endpoint();
    let mut child = situate()
        .arg("run")
        .arg(&path)
        .args(["--listen", &endpoint])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("situate run starts");
    // Generous: conditions to wait for, not timings.
    let deadline = Instant::now() + Duration::from_secs(60);
    let session = loop {
        let config = situate_link::session::client_config(std::slice::from_ref(&endpoint), None).expect("config");
        match zenoh::open(config).wait() {
            Ok(s) => break s,
            Err(e) if Instant::now() > deadline || child.try_wait().ok().flatten().is_some() => {
                let _ = child.kill();
                panic!("`situate run` never served its link on {endpoint}: {e}");
            }
            Err(_) => std::thread::sleep(Duration::from_millis(100)),
        }
    };
    let keys = loop {
        let replies = session.liveliness().get("@ros2_lv/7/**").wait().expect("liveliness get");
        let mut keys = Vec::new();
        while let Ok(reply) = replies.recv() {
            if let Ok(sample) = reply.result() {
                keys.push(sample.key_expr().to_string());
            }
        }
        if keys.iter().any(|k| k.contains("/MP/") && k.contains("cmd_vel")) {
            break keys;
        }
        if Instant::now() > deadline || child.try_wait().ok().flatten().is_some() {
            let _ = child.kill();
            panic!("no ROS 2 publisher token from `situate run`; seen: {keys:#?}");
        }
        std::thread::sleep(Duration::from_millis(100));
    };
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        keys.iter().any(|k| k.contains("/NN/") && k.ends_with("/toybot")),
        "the node, named after the robot: {keys:#?}"
    );
}
