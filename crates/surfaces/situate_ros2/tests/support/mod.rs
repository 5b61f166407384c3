//! What the bridge's integration tests share: a toy robot served on a free port, an observer
//! session on it, and a service call as an rmw_zenoh client makes it.

#![allow(dead_code)] // each test file uses its own part

use std::time::{Duration, Instant};

use situate::manager::{ClockKind, Handle, Joiner, Manager, Request, RobotFile, RobotSpec};
use situate_link::{Link, LinkConfig};
use situate_ros2::Ros2Config;
use zenoh::Wait;

/// Bounds for things that take milliseconds on an idle machine (CI machines are shared).
pub const WAIT: Duration = Duration::from_secs(60);

pub fn free_port() -> u16 {
    situate_link::free_loopback_port().expect("a free port")
}

pub struct Robot {
    pub handle: Handle,
    pub link: Option<Link>,
    join: Option<Joiner>,
    pub endpoint: String,
}

impl Robot {
    /// The link's Zenoh session, which the bridge shares.
    pub fn session(&self) -> zenoh::Session {
        self.link.as_ref().expect("link").session().clone()
    }
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

pub fn toy_robot(name: &str) -> Robot {
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

pub fn config(yaml: &str) -> Ros2Config {
    let tree = situate::manager::yaml::parse(yaml).expect("YAML");
    Ros2Config::from_node(tree.value.get("ros2").expect("ros2")).expect("valid")
}

pub fn observer(endpoint: &str) -> zenoh::Session {
    let config = situate_link::session::client_config(&[endpoint.to_string()], None).expect("config");
    zenoh::open(config).wait().expect("observer session")
}

/// The liveliness tokens under `@ros2_lv/<domain>/**`, asked until `done` holds (a minute at most).
pub fn tokens_until(session: &zenoh::Session, domain: u32, done: impl Fn(&[String]) -> bool) -> Vec<String> {
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

/// The GID the test client calls with.
pub const CLIENT_GID: [u8; 16] = [7; 16];

/// Calls a service of the bridge as an rmw_zenoh client does; the reply's payload and its
/// attachment's sequence number and GID, or the error reply's text.
pub fn call(
    observer: &zenoh::Session,
    key: &str,
    request: &[u8],
    sequence: i64,
) -> Result<(Vec<u8>, i64, [u8; 16]), String> {
    let replies = observer
        .get(key)
        .payload(request.to_vec())
        .attachment(situate_ros2::rmw::attachment(sequence, 0, &CLIENT_GID))
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
            assert_eq!(client, CLIENT_GID, "the reply names the client");
            Ok((sample.payload().to_bytes().into_owned(), seq, client))
        }
        Err(e) => Err(e.payload().try_to_string().map(|s| s.into_owned()).unwrap_or_default()),
    }
}

/// The key of the bridge's service `name` (its fully qualified name).
pub fn service_key(bridge: &situate_ros2::Bridge, name: &str) -> String {
    bridge
        .services()
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, key)| key.clone())
        .unwrap_or_else(|| panic!("{name} not offered: {:?}", bridge.services()))
}

/// Calls until the service answers: the observer may ask before it has heard of the queryable.
pub fn call_until_answered(observer: &zenoh::Session, key: &str, request: &[u8]) -> (Vec<u8>, i64, [u8; 16]) {
    let deadline = Instant::now() + WAIT;
    loop {
        match call(observer, key, request, 1) {
            Ok(r) => return r,
            Err(e) => {
                assert!(Instant::now() < deadline, "no answer from {key}: {e}");
                std::thread::sleep(Duration::from_millis(50));
            }
        }
    }
}
