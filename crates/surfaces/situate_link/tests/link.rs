//! The link end to end over real Zenoh sessions on loopback: requests and
//! replies, events, the default session's sockets, remote skills, and a
//! flood of bad requests that must change nothing.

mod common;

use common::{free_port, Running};
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

use serde_json::{json, Value as Json};
use situate::manager::{ClockKind, Manager, RobotFile, RobotSpec};
use situate_link::{Client, ClientError, Link, LinkConfig, RemoteSkill};
use zenoh::Wait;

const ROBOT: &str = "\
robot: linkbot
cycle: {rate_hz: 200}
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
    active: false
  - name: doubler
    remote:
      inputs: {x: \"f32[]\"}
      outputs: {y: f64}
      params: {gain: {type: f64, default: 2.0, min: 0, max: 10}}
    remap: {x: sonar.range}
    active: false
";

fn start(clock: ClockKind) -> Running {
    let file = RobotFile::parse("linkbot.yaml", ROBOT).unwrap();
    let port = free_port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).unwrap();
    let mut registry = situate_toys::registry();
    for (name, decl) in file.remote_decls().unwrap() {
        registry.add(RemoteSkill::skill_type(&session, "linkbot", &name, decl));
    }
    let spec = RobotSpec::from_file(&file).clock(clock);
    let manager = Manager::build(&spec, &registry).unwrap();
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("linkbot", handle.clone(), session, &config).unwrap();
    Running { handle, link: Some(link), join: Some(join), endpoint }
}

fn client(r: &Running) -> Client {
    let mut c = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
    c.timeout = Duration::from_secs(10);
    c
}

fn remote_err(e: ClientError) -> (String, String) {
    match e {
        ClientError::Remote(r) => (r.kind, r.message),
        other => panic!("expected an error reply, got {other}"),
    }
}

#[test]
fn requests_and_errors_travel_over_zenoh() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    assert_eq!(c.resolve_robot(None).unwrap(), "linkbot");
    // A name nobody serves, with another robot there: the error names the one that answered.
    match c.request("otherbot", "stats", &json!({})) {
        Err(e @ ClientError::OtherRobots { .. }) => {
            assert_eq!(e.to_string(), "robot `otherbot` did not answer; robot `linkbot` did (name it with --robot)")
        }
        other => panic!("expected OtherRobots, got {other:?}"),
    }
    let hello = c.request("linkbot", "hello", &json!({})).unwrap();
    assert_eq!(hello["protocol"], 1);
    let (kind, msg) = remote_err(c.request("linkbot", "activate", &json!({"skills": ["wandr"]})).unwrap_err());
    assert_eq!((kind.as_str(), msg.as_str()), ("unknown_skill", "unknown skill `wandr` — did you mean `wander`?"));
    let changed = c.request("linkbot", "activate", &json!({"skills": ["wander"]})).unwrap();
    assert_eq!(changed["changed"], json!(["wander"]));
    let (kind, msg) = remote_err(
        c.request("linkbot", "set_param", &json!({"skill": "runaway", "param": "safe_distance", "value": "far"}))
            .unwrap_err(),
    );
    assert_eq!(kind, "bad_param");
    assert_eq!(msg, "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got \"far\"");
    c.request("linkbot", "set_param", &json!({"skill": "runaway", "param": "safe_distance", "value": 0.3})).unwrap();
    assert_eq!(
        c.request("linkbot", "get_param", &json!({"skill": "runaway", "param": "safe_distance"})).unwrap(),
        json!(0.3)
    );
    // Wait (bounded) for a first sonar reading, then read it over the link.
    let deadline = Instant::now() + Duration::from_secs(20);
    let reading = loop {
        let q = c.request("linkbot", "query", &json!({"signal": "sonar.range"})).unwrap();
        if !q["value"].is_null() || Instant::now() > deadline {
            break q;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(reading["type"], "f32[24]");
    assert_eq!(reading["value"].as_array().map(Vec::len), Some(24));
    assert_eq!(reading["writer"], "sonar");
    let (kind, msg) =
        remote_err(c.request("linkbot", "monitor_add", &json!({"condition": "sonar.range[0] < "})).unwrap_err());
    assert_eq!(kind, "bad_condition");
    assert!(msg.starts_with("column 18: "), "{msg}");
}

#[test]
fn an_any_monitor_travels_over_zenoh_and_says_which_condition_held() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let (_sub, events) = c.subscribe("linkbot", "events/monitor_fired").unwrap();
    // A bad condition is named by its index, with its column and pointer.
    let err = c.request("linkbot", "monitor_add", &json!({"any": ["cycle > 0", "sonar.range[0] < "]})).unwrap_err();
    let ClientError::Remote(e) = err else { panic!("{err}") };
    assert_eq!(e.kind, "bad_condition");
    assert!(e.message.starts_with("any[1]: column 18: "), "{}", e.message);
    assert_eq!((e.detail["index"].clone(), e.detail["column"].clone()), (json!(1), json!(18)));
    // A level monitor fires every cycle, so a subscription that reaches the
    // manager's session late still sees it.
    let any =
        json!({"any": ["cycle > 0", "cycle < 0", "cycle > 1"], "mode": "level", "report": ["runaway.safe_distance"]});
    let id = c.request("linkbot", "monitor_add", &any).unwrap()["monitor"].clone();
    let deadline = Instant::now() + Duration::from_secs(30);
    let event = loop {
        let left = deadline.checked_duration_since(Instant::now()).expect("the monitor fires within 30 s");
        let e = events.recv_timeout(left).expect("the monitor fires within 30 s");
        if e["monitor"] == id && e["cycle"].as_u64() > Some(1) {
            break e;
        }
    };
    assert_eq!(event["held"], json!([0, 2]));
    assert_eq!(event["condition"], "(cycle > 0) || (cycle < 0) || (cycle > 1)");
    let names: Vec<&String> = event["values"].as_object().unwrap().keys().collect();
    assert_eq!(names, ["cycle", "runaway.safe_distance"]);
    let list = c.request("linkbot", "monitor_list", &json!({})).unwrap();
    assert_eq!(list[0]["any"], json!(["cycle > 0", "cycle < 0", "cycle > 1"]));
}

#[test]
fn events_are_published_as_they_happen() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let (_sub, events) = c.subscribe("linkbot", "events/**").unwrap();
    // A level monitor fires every cycle, so a subscription that reaches the
    // manager's session late still sees it; activation is toggled until seen.
    c.request("linkbot", "monitor_add", &json!({"condition": "wander.speed > 0", "mode": "level"})).unwrap();
    let mut kinds = std::collections::BTreeSet::new();
    let mut on = false;
    let deadline = Instant::now() + Duration::from_secs(30);
    while Instant::now() < deadline && !(kinds.contains("activation_applied") && kinds.contains("monitor_fired")) {
        if !kinds.contains("activation_applied") {
            on = !on;
            let verb = if on { "activate" } else { "deactivate" };
            c.request("linkbot", verb, &json!({"skills": ["wander"]})).unwrap();
        }
        let until = Instant::now() + Duration::from_millis(500);
        while let Some(left) = until.checked_duration_since(Instant::now()) {
            match events.recv_timeout(left) {
                Ok(e) => {
                    kinds.insert(e["kind"].as_str().unwrap_or("").to_string());
                }
                Err(_) => break,
            }
        }
    }
    assert!(kinds.contains("activation_applied"), "{kinds:?}");
    assert!(kinds.contains("monitor_fired"), "{kinds:?}");
}

#[test]
fn the_default_session_listens_on_loopback_tcp_only() {
    // The default configuration, on a free port so tests can run side by side.
    let port = free_port();
    let config = LinkConfig { listen: vec![format!("tcp/127.0.0.1:{port}")], ..LinkConfig::default() };
    assert_eq!(LinkConfig::default().listen, vec!["tcp/127.0.0.1:7447".to_string()]);
    let session = Link::open(&config).unwrap();
    let out = std::process::Command::new("ss").args(["-H", "-tuanp"]).output().expect("ss (iproute2) is installed");
    let pid = format!("pid={},", std::process::id());
    let ours: Vec<String> =
        String::from_utf8_lossy(&out.stdout).lines().filter(|l| l.contains(&pid)).map(str::to_string).collect();
    assert!(!ours.is_empty(), "ss shows no socket of this process");
    for line in &ours {
        assert!(!line.starts_with("udp"), "a UDP socket is open: {line}");
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.get(1) == Some(&"LISTEN") {
            assert!(fields[4].starts_with("127.0.0.1:"), "a listener not on loopback: {line}");
        }
    }
    assert!(ours.iter().any(|l| l.contains(&format!("127.0.0.1:{port}"))), "{ours:?}");
    drop(session);
}

/// A client that connects while the program is still starting: the session is open (it
/// accepts connections) but the link is served only later, as `situate run` does. The client
/// must wait for it within its timeout, not give up. (With this Zenoh configuration the get
/// itself waits; a get that finds nobody can also end at once, as the Python client's test
/// `test_hello_race.py` shows, and then the client asks again.)
#[test]
fn a_client_finds_a_robot_whose_link_is_served_after_it_connected() {
    let file = RobotFile::parse("linkbot.yaml", ROBOT).unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).unwrap();
    let mut c = Client::connect(std::slice::from_ref(&endpoint)).unwrap();
    c.timeout = Duration::from_secs(60);
    // The named request first: it may wait the whole timeout; `robots` is capped at 2 s.
    let asked = std::thread::spawn(move || {
        let hello = c.request("linkbot", "hello", &json!({}));
        (c.robots(), hello)
    });
    std::thread::sleep(Duration::from_millis(300));
    let mut registry = situate_toys::registry();
    for (name, decl) in file.remote_decls().unwrap() {
        registry.add(RemoteSkill::skill_type(&session, "linkbot", &name, decl));
    }
    let manager = Manager::build(&RobotSpec::from_file(&file), &registry).unwrap();
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("linkbot", handle.clone(), session, &config).unwrap();
    let running = Running { handle, link: Some(link), join: Some(join), endpoint };
    let (robots, hello) = asked.join().expect("the client's thread");
    assert_eq!(hello.expect("hello")["robot"], "linkbot");
    assert_eq!(robots.expect("robots"), vec!["linkbot".to_string()]);
    drop(running);
}

/// A remote skill, as another process would serve it: subscribe to its
/// inputs, publish outputs. The manager never waits for it.
#[test]
fn a_remote_skill_joins_the_cycle_through_the_link() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let remote = zenoh::open(situate_link::session::client_config(std::slice::from_ref(&r.endpoint), None).unwrap())
        .wait()
        .unwrap();
    let publisher = remote.clone();
    let _sub = remote
        .declare_subscriber("situate/linkbot/remote/doubler/inputs")
        .callback(move |sample| {
            let msg: Json = serde_json::from_slice(&sample.payload().to_bytes()).unwrap();
            let gain = msg["params"]["gain"].as_f64().unwrap();
            let min =
                msg["inputs"]["x"].as_array().unwrap().iter().filter_map(Json::as_f64).fold(f64::INFINITY, f64::min);
            let out = json!({"cycle": msg["cycle"], "outputs": {"y": min * gain}, "prints": ["computed"]});
            publisher.put("situate/linkbot/remote/doubler/outputs", out.to_string()).wait().unwrap();
        })
        .wait()
        .unwrap();
    c.request("linkbot", "set_param", &json!({"skill": "doubler", "param": "gain", "value": 3})).unwrap();
    c.request("linkbot", "activate", &json!({"skills": ["doubler"]})).unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    let (y, range) = loop {
        let y = c.request("linkbot", "query", &json!({"signal": "y"})).unwrap();
        let range = c.request("linkbot", "query", &json!({"signal": "sonar.range"})).unwrap();
        if !y["value"].is_null() || Instant::now() > deadline {
            break (y, range);
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let y = y["value"].as_f64().expect("the remote result reached the cycle");
    let room = range["value"].as_array().unwrap().iter().filter_map(Json::as_f64).fold(0.0, f64::max);
    assert!(y > 0.0 && y <= room * 3.0 + 1e-9, "y = {y}");
    let info = c.request("linkbot", "skill", &json!({"skill": "doubler"})).unwrap();
    assert_eq!(info["kind"], "async");
    assert!(info["prints"].as_array().unwrap().iter().any(|p| p[1] == "computed"), "{info}");
    // A remote error faults the skill like any other.
    let failing = remote.clone();
    failing
        .put("situate/linkbot/remote/doubler/outputs", json!({"cycle": 0, "error": "division by zero"}).to_string())
        .wait()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(30);
    let faulted = loop {
        let info = c.request("linkbot", "skill", &json!({"skill": "doubler"})).unwrap();
        if !info["faulted"].is_null() || Instant::now() > deadline {
            break info["faulted"].clone();
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(faulted, json!("the remote skill failed: division by zero"));
}

/// Strips what changes by itself (time, counters) from the state.
fn state(c: &Client) -> BTreeMap<String, Json> {
    let mut out = BTreeMap::new();
    for s in c.request("linkbot", "skills", &json!({})).unwrap().as_array().unwrap() {
        let keep = json!({"active": s["active"], "faulted": s["faulted"], "priority": s["priority"], "params": s["params"], "verbose": s["verbose"]});
        out.insert(s["name"].as_str().unwrap().to_string(), keep);
    }
    out.insert("monitors".into(), c.request("linkbot", "monitor_list", &json!({})).unwrap());
    out
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn pick<'a>(&mut self, items: &[&'a str]) -> &'a str {
        items[(self.next() % items.len() as u64) as usize]
    }
}

/// A random request that must be refused: random bytes, or well-formed JSON
/// with wrong names, types or values.
fn bad_payload(rng: &mut Rng, verb: &str) -> Vec<u8> {
    let junk_values = [
        json!(null),
        json!("x"),
        json!(1e300),
        json!(-1),
        json!([1, "a"]),
        json!({"a": 1}),
        json!(true),
        json!(""),
        json!("wandr"),
        json!(7.5),
    ];
    match rng.next() % 6 {
        0 => (0..rng.next() % 80).map(|_| (rng.next() & 0xff) as u8).collect(),
        1 => format!("{{\"skills\": {}}}", junk_values[(rng.next() % 10) as usize]).into_bytes(),
        2 => json!({"skill": rng.pick(&["wandr", "", "runawy", "sonar.range", "\u{1F916}"]), "param": "safe_distance", "value": 0.3, "signal": "nosuch", "condition": "sonar.range[0] <", "skills": ["nosuch"], "cycles": 0, "monitor": 99999, "verbose": "yes", "priority": "high"}).to_string().into_bytes(),
        3 => json!({"skill": "runaway", "param": rng.pick(&["safe_distnce", "speed", "safe_distance"]), "value": junk_values[(rng.next() % 10) as usize]}).to_string().into_bytes(),
        4 => format!("{{\"protocol\": {}, \"{}\": 1}}", rng.next() % 5 + 2, verb).into_bytes(),
        _ => json!({"signal": rng.pick(&["sonr.range", "sonar.range[0]", "", "odom.z"]), "condition": rng.pick(&["((((", "sonar.range[-1] < 1", "1 +", "odom.x < \"a\""]), "mode": rng.pick(&["always", "", "ONCE"]), "cycles": -5, "skills": 7}).to_string().into_bytes(),
    }
}

#[test]
fn a_flood_of_bad_requests_changes_nothing_and_the_cycle_goes_on() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let before = state(&c);
    let stats_before = c.request("linkbot", "stats", &json!({})).unwrap();
    let verbs: Vec<&str> = situate_link::json::VERBS
        .iter()
        .copied()
        .filter(|v| {
            !matches!(*v, "run" | "stop" | "step" | "hello" | "skills" | "winners" | "graph" | "stats" | "monitor_list")
        })
        .chain(["nosuch", "activate_"])
        .collect();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let total = 100_000;
    let mut sent = 0;
    let mut answered = 0;
    let mut accepted = Vec::new();
    let started = Instant::now();
    while sent < total {
        // Batches of concurrent queries; every one must get an error reply.
        let mut pending = Vec::new();
        for _ in 0..500 {
            let verb = rng.pick(&verbs);
            let payload = bad_payload(&mut rng, verb);
            let replies = c
                .session()
                .get(format!("situate/linkbot/req/{verb}"))
                .payload(payload.clone())
                .timeout(Duration::from_secs(60))
                .wait()
                .unwrap();
            pending.push((verb, payload, replies));
            sent += 1;
        }
        for (verb, payload, replies) in pending {
            if let Ok(reply) = replies.recv() {
                answered += 1;
                let body: Json = serde_json::from_slice(&reply.result().unwrap().payload().to_bytes()).unwrap();
                if body.get("error").is_none() {
                    accepted.push(format!("{verb} {}", String::from_utf8_lossy(&payload)));
                }
            }
        }
    }
    let elapsed = started.elapsed();
    let stats_after = c.request("linkbot", "stats", &json!({})).unwrap();
    assert!(accepted.is_empty(), "accepted: {:?}", &accepted[..accepted.len().min(5)]);
    assert_eq!(answered, total, "every request gets a reply");
    assert_eq!(state(&c), before, "the manager's state is exactly as before");
    assert_eq!(stats_after["running"], true);
    let cycles = stats_after["cycle"].as_u64().unwrap() - stats_before["cycle"].as_u64().unwrap();
    assert!(cycles > 0, "the cycle went on");
    // Reported, not asserted (timing): the rate held during the flood.
    let expected = elapsed.as_secs_f64() * 200.0;
    eprintln!(
        "{total} bad requests in {elapsed:.1?}: {cycles} cycles ({:.0}% of the 200 Hz rate), overruns {} → {}",
        100.0 * cycles as f64 / expected,
        stats_before["overruns"],
        stats_after["overruns"]
    );
}

/// Sends `payload` as it is (JSON the client's own encoder could not write,
/// such as `1e400`) and returns the reply's `error`.
fn refused_raw(c: &Client, verb: &str, payload: &str) -> (String, String) {
    let replies = c
        .session()
        .get(format!("situate/linkbot/req/{verb}"))
        .payload(payload.to_string())
        .timeout(Duration::from_secs(30))
        .wait()
        .unwrap();
    let reply = replies.recv().unwrap_or_else(|_| panic!("no reply to `{verb}` {payload}"));
    let body: Json = serde_json::from_slice(&reply.result().unwrap().payload().to_bytes()).unwrap();
    let error = body.get("error").unwrap_or_else(|| panic!("`{verb}` {payload} was accepted: {body}"));
    (error["kind"].as_str().unwrap().to_string(), error["message"].as_str().unwrap().to_string())
}

#[test]
fn arguments_of_the_wrong_shape_are_refused_as_the_protocol_says() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let before = state(&c);
    // A string where a list is expected is not a list of one.
    for (verb, payload, arg) in [
        ("deactivate", r#"{"skills": "runaway"}"#, "skills"),
        ("activate", r#"{"skills": "wander"}"#, "skills"),
        ("monitor_add", r#"{"condition": "cycle > 1", "report": "odom"}"#, "report"),
        ("telemetry", r#"{"signals": "odom.x"}"#, "signals"),
    ] {
        let (kind, msg) = refused_raw(&c, verb, payload);
        assert_eq!(kind, "bad_request", "{verb} {payload}: {msg}");
        assert!(msg.starts_with(&format!("`{verb}`: argument `{arg}`: expected a list of strings")), "{msg}");
    }
    // A float where an integer is expected, and numbers beyond JSON readers' range.
    for (verb, payload, arg) in [
        ("step", r#"{"cycles": 2.0}"#, "cycles"),
        ("step", r#"{"cycles": 1e400}"#, "cycles"),
        ("set_priority", r#"{"skill": "wander", "priority": 1.5}"#, "priority"),
        ("telemetry", r#"{"signals": [], "rate_hz": 1e400}"#, "rate_hz"),
    ] {
        let (kind, msg) = refused_raw(&c, verb, payload);
        assert_eq!(kind, "bad_request", "{verb} {payload}: {msg}");
        assert!(msg.starts_with(&format!("`{verb}`: argument `{arg}`: expected ")), "{msg}");
    }
    // A parameter value of the wrong type or out of range is `bad_param`,
    // naming the parameter, its type and range, however far out it is.
    for (payload, expected) in [
        (
            r#"{"skill": "runaway", "param": "safe_distance", "value": 1e400}"#,
            "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got inf",
        ),
        (
            r#"{"skill": "runaway", "param": "safe_distance", "value": -1e400}"#,
            "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got -inf",
        ),
        (
            r#"{"skill": "runaway", "param": "safe_distance", "value": [0.3]}"#,
            "skill `runaway`: parameter `safe_distance` expects a number in [0.1, 3.0], got a list of numbers",
        ),
        (
            r#"{"skill": "wander", "param": "seed", "value": 9223372036854775808}"#,
            "skill `wander`: parameter `seed` expects an integer from -9223372036854775808 to 9223372036854775807, \
             got 9223372036854775808",
        ),
        (
            r#"{"skill": "wander", "param": "seed", "value": 2.0}"#,
            "skill `wander`: parameter `seed` expects an integer from -9223372036854775808 to 9223372036854775807, \
             got 2.0",
        ),
        (
            r#"{"skill": "wander", "param": "seed", "value": 1e400}"#,
            "skill `wander`: parameter `seed` expects an integer from -9223372036854775808 to 9223372036854775807, \
             got inf",
        ),
    ] {
        let (kind, msg) = refused_raw(&c, "set_param", payload);
        assert_eq!((kind.as_str(), msg.as_str()), ("bad_param", expected), "{payload}");
    }
    // An unknown skill or parameter is still named first.
    let (kind, _) = refused_raw(&c, "set_param", r#"{"skill": "runawy", "param": "safe_distance", "value": 1e400}"#);
    assert_eq!(kind, "unknown_skill");
    let (kind, msg) = refused_raw(&c, "set_param", r#"{"skill": "runaway", "param": "safe_distance", "value": null}"#);
    assert_eq!(kind, "bad_request", "{msg}");
    assert_eq!(state(&c), before, "nothing changed");
}

#[test]
fn a_telemetry_rate_out_of_range_is_bad_param_and_a_slow_one_never_holds_shutdown() {
    let mut r = start(ClockKind::Wall);
    let c = client(&r);
    // 1e-300 once panicked the telemetry thread (the link still said `ok`); 1e-9 held shutdown.
    for rate in ["1e-300", "1e-9", "0.001", "100.5"] {
        let args: Json = serde_json::from_str(&format!(r#"{{"signals": [], "rate_hz": {rate}}}"#)).unwrap();
        let (kind, message) = remote_err(c.request("linkbot", "telemetry", &args).unwrap_err());
        assert_eq!(kind, "bad_param", "{rate}: {message}");
        assert!(message.contains("from 0.01 to 100"), "{message}");
    }
    // The slowest rate accepted: its worker sleeps 100 s between samples, and stopping the link
    // must not wait for that (a minute is a hang, not a slow machine).
    c.request("linkbot", "telemetry", &json!({"signals": ["odom"], "rate_hz": 0.01})).unwrap();
    let link = r.link.take().unwrap();
    let (done_tx, done_rx) = crossbeam_channel::bounded(1);
    std::thread::spawn(move || {
        drop(link);
        let _ = done_tx.send(());
    });
    assert!(done_rx.recv_timeout(Duration::from_secs(60)).is_ok(), "the link did not stop within a minute");
}

#[test]
fn a_batch_is_its_requests_in_order_each_answered_as_alone() {
    let r = start(ClockKind::Wall);
    let c = client(&r);
    let batch = json!({"requests": [
        {"verb": "set_param", "args": {"skill": "runaway", "param": "speed", "value": 0.3}},
        {"verb": "get_param", "args": {"skill": "runaway", "param": "speed"}},
        {"verb": "activate", "args": {"skills": ["wandr"]}},
        {"verb": "nosuch"},
        {"verb": "hello"},
        {"verb": "set_param", "args": {"skill": "runaway", "param": "speed", "value": 0.4}},
        {"verb": "get_param", "args": {"skill": "runaway", "param": "speed"}},
    ]});
    let replies = c.request("linkbot", "batch", &batch).unwrap();
    let replies = replies.as_array().expect("a list of replies");
    assert_eq!(replies.len(), 7);
    // In order: each get sees the set before it, not the one after.
    assert_eq!(replies[1]["ok"], json!(0.3));
    assert_eq!(replies[6]["ok"], json!(0.4));
    // A refusal is that request's alone, the same as sent by itself; the others go on.
    let alone = remote_err(c.request("linkbot", "activate", &json!({"skills": ["wandr"]})).unwrap_err());
    assert_eq!(replies[2]["error"]["kind"], json!(alone.0));
    assert_eq!(replies[2]["error"]["message"], json!(alone.1));
    assert_eq!(replies[3]["error"]["kind"], json!("unknown_verb"));
    assert_eq!(replies[4]["ok"]["robot"], json!("linkbot"));
    // A batch that is no batch is refused whole, saying where.
    let many: Vec<Json> = (0..65).map(|_| json!({"verb": "hello"})).collect();
    for (payload, says) in [
        (json!({"requests": []}).to_string(), "1 to 64"),
        (json!({"requests": many}).to_string(), "holds 65 requests"),
        (
            json!({"requests": [{"verb": "hello"}, {"verb": "batch", "args": {"requests": []}}]}).to_string(),
            "request 1: a batch cannot hold a batch",
        ),
        (json!({"requests": [{"verb": 3}]}).to_string(), "request 0: `verb` must be a string"),
        (json!({"requests": [{"verb": "hello", "arg": {}}]}).to_string(), "request 0: unknown key `arg`"),
        (json!({"reqs": []}).to_string(), "unknown argument `reqs`"),
        ("[1, 2]".to_string(), "must be a JSON object"),
    ] {
        let (kind, message) = refused_raw(&c, "batch", &payload);
        assert_eq!(kind, "bad_request", "{payload}");
        assert!(message.contains(says), "{payload}: {message}");
    }
    // Nothing refused whole changed anything.
    assert_eq!(c.request("linkbot", "get_param", &json!({"skill": "runaway", "param": "speed"})).unwrap(), json!(0.4));
}

#[test]
fn query_many_reads_every_signal_in_one_moment_or_refuses_the_whole_list() {
    // On the simulated clock, run as fast as it goes, the devices run in the cycle and write
    // `sonar.range` and `odom` in every one: one moment's readings carry the same cycle, however
    // many cycles run between two requests.
    let r = start(ClockKind::Simulated);
    let c = client(&r);
    let ask = |signals: &[&str]| c.request("linkbot", "query_many", &json!({ "signals": signals }));
    let deadline = Instant::now() + Duration::from_secs(20);
    let mut checked = 0;
    while checked < 50 && Instant::now() < deadline {
        let readings = ask(&["sonar.range", "odom", "sonar.range"]).unwrap();
        let readings = readings.as_array().expect("a list of readings");
        assert_eq!(readings.len(), 3, "{readings:?}");
        if readings.iter().any(|r| r["value"].is_null()) {
            std::thread::sleep(Duration::from_millis(5));
            continue; // before the first cycle
        }
        // In the request's order, a name asked twice read twice (the same reading).
        assert_eq!(
            (readings[0]["signal"].as_str(), readings[1]["signal"].as_str()),
            (Some("sonar.range"), Some("odom"))
        );
        assert_eq!(readings[0], readings[2]);
        assert_eq!(readings[0]["cycle"], readings[1]["cycle"], "one moment: {readings:?}");
        checked += 1;
    }
    assert_eq!(checked, 50, "the robot ran no cycle within 20 s");
    // Stopped, each reading is the one `query` gives for it alone.
    c.request("linkbot", "stop", &json!({})).unwrap();
    c.request("linkbot", "step", &json!({"cycles": 2})).unwrap();
    let names = ["odom", "odom.x", "sonar.range", "drive"];
    let readings = ask(&names).unwrap();
    for (name, reading) in names.iter().zip(readings.as_array().unwrap()) {
        assert_eq!(reading, &c.request("linkbot", "query", &json!({ "signal": name })).unwrap(), "{name}");
    }
    assert_eq!(readings.as_array().unwrap().len(), names.len());
    // An unknown signal anywhere in the list refuses the whole request, naming it; nothing partial.
    let (kind, msg) = remote_err(ask(&["odom", "sonr.range", "odom.z"]).unwrap_err());
    assert_eq!(
        (kind.as_str(), msg.as_str()),
        ("unknown_signal", "unknown signal `sonr.range` — did you mean `sonar.range`?")
    );
    // Its bounds, over the wire as in the decoder.
    let many = vec!["odom"; situate_link::json::MAX_QUERY_SIGNALS + 1];
    let (kind, msg) = remote_err(ask(&many).unwrap_err());
    assert_eq!(
        (kind.as_str(), msg.as_str()),
        ("bad_request", "`query_many`: argument `signals` has 257 signal names, it takes 1 to 256")
    );
    let (kind, msg) = refused_raw(&c, "query_many", r#"{"signals": "odom"}"#);
    assert_eq!(kind, "bad_request", "{msg}");
    assert!(msg.contains(r#"(a list of one is written ["odom"])"#), "{msg}");
}
