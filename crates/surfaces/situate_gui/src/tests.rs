//! The server's tests: serving the app and refusing other hosts and origins, runs and outcomes,
//! metrics, the open files limit, configuration errors.

use std::io::{Read, Write};
use std::net::TcpStream;

use situate::manager::{Control, Manager, RobotSpec, SkillSpec};

use super::*;
use crate::session::hello_message;

pub(crate) fn robot() -> (Handle, situate_manager::Joiner) {
    let spec = RobotSpec::new("guitest")
        .skill(SkillSpec::new("sonar", "toy.sonar"))
        .skill(SkillSpec::new("wheels", "toy.wheels"))
        .skill(SkillSpec::new("runaway", "toy.runaway"))
        .skill(SkillSpec::new("wander", "toy.wander").active(false));
    let manager = Manager::build(&spec, &situate_toys::registry()).expect("the toy robot builds");
    manager.spawn(true)
}

pub(crate) fn shared(handle: Handle) -> Shared {
    let (wake, _) = crossbeam_channel::unbounded();
    Shared {
        handle,
        run: RunInfo::new(),
        activity: Mutex::new(Activity::default()),
        outcome: Mutex::new(None),
        world: None,
        sample_hz: 10.0,
        ws_idle: DEFAULT_WS_IDLE_TIMEOUT,
        clients: AtomicUsize::new(0),
        next_client: AtomicU64::new(1),
        watched: Mutex::new(HashMap::new()),
        history: None,
        replay: None,
        foxglove: foxglove::Hub::default(),
        telemetry: broadcast::channel(4).0,
        events: broadcast::channel(4).0,
        wake,
        shutdown: watch::channel(false).1,
    }
}

pub(crate) fn http(addr: SocketAddr, request: &str) -> String {
    let mut s = TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(10))).expect("timeout");
    s.write_all(request.as_bytes()).expect("write");
    let mut buf = Vec::new();
    let mut chunk = [0u8; 4096];
    // Read the head (and whatever body came with it); upgrades never close the stream.
    while let Ok(n) = s.read(&mut chunk) {
        if n == 0 {
            break;
        }
        buf.extend_from_slice(&chunk[..n]);
        let text = String::from_utf8_lossy(&buf);
        // An upgrade request keeps the connection open: its head is the whole answer.
        if request.contains("Upgrade: websocket") && text.contains("\r\n\r\n") {
            break;
        }
    }
    String::from_utf8_lossy(&buf).into_owned()
}

#[test]
fn serves_the_app_the_world_and_refuses_cross_origin_sockets() {
    let (mut handle, join) = robot();
    let world = json!({"floors": [], "cars": [], "robot_radius": 0.25});
    let gui = serve(handle.clone(), GuiConfig { world: Some(world.clone()), ..GuiConfig::default() }).expect("serve");
    let addr = gui.local_addr();
    assert!(addr.ip().is_loopback());
    assert_ne!(addr.port(), 0);
    let get = |path: &str, host: &str| {
        http(addr, &format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"))
    };
    let page = get("/", &addr.to_string());
    assert!(page.starts_with("HTTP/1.1 200"), "{page}");
    assert!(page.contains("<html") || page.contains("<!doctype html>"), "{page}");
    if !has_web_app() {
        assert!(page.contains("make gui"), "the placeholder says what to run: {page}");
    }
    let w = get("/api/world", &addr.to_string());
    assert!(w.contains("\"robot_radius\":0.25"), "{w}");
    let missing = get("/nope.js", &addr.to_string());
    assert!(missing.starts_with("HTTP/1.1 404"), "{missing}");
    let upgrade = |host: &str, origin: &str| {
        format!(
            "GET /ws HTTP/1.1\r\nHost: {host}\r\nConnection: Upgrade\r\nUpgrade: websocket\r\n\
             Sec-WebSocket-Version: 13\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n{origin}\r\n"
        )
    };
    let evil = http(addr, &upgrade(&addr.to_string(), "Origin: http://evil.example\r\n"));
    assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
    let ok = http(addr, &upgrade(&addr.to_string(), &format!("Origin: http://{addr}\r\n")));
    assert!(ok.starts_with("HTTP/1.1 101"), "{ok}");
    // DNS rebinding: a page at evil.example, its name pointed at this machine, is its own
    // origin; only the Host tells it apart, on every route.
    let port = addr.port();
    let rebound = format!("evil.example:{port}");
    let evil = http(addr, &upgrade(&rebound, &format!("Origin: http://{rebound}\r\n")));
    assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
    let page = get("/", &rebound);
    assert!(page.contains("--gui-allow-host evil.example"), "the refusal says how to allow a name: {page}");
    for path in ["/", "/index.html", "/api/world", "/metrics", "/nope.js", "/foxglove"] {
        let page = get(path, &rebound);
        assert!(page.starts_with("HTTP/1.1 403"), "{path}: {page}");
    }
    let no_host = http(addr, "GET /api/world HTTP/1.0\r\n\r\n");
    assert!(no_host.starts_with("HTTP/1.0 400") || no_host.starts_with("HTTP/1.1 400"), "{no_host}");
    assert!(no_host.contains("no Host header"), "{no_host}");
    let absolute =
        http(addr, &format!("GET http://{rebound}/api/world HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"));
    assert!(absolute.starts_with("HTTP/1.1 403"), "the request-target's host counts too: {absolute}");
    // What a browser sends for this server: its address (browser tests open
    // http://127.0.0.1:<port>/), localhost, or a tunnel's port.
    for host in [format!("localhost:{port}"), format!("[::1]:{port}"), "localhost:9000".into()] {
        let page = get("/api/world", &host);
        assert!(page.starts_with("HTTP/1.1 200"), "{host}: {page}");
    }
    gui.stop();
    // A name the user allows.
    let gui = serve(handle.clone(), GuiConfig { allowed_hosts: vec!["Robot.LAN".into()], ..GuiConfig::default() })
        .expect("serve");
    let (addr, port) = (gui.local_addr(), gui.local_addr().port());
    let named = format!("robot.lan:{port}");
    let ok = http(addr, &upgrade(&named, &format!("Origin: http://{named}\r\n")));
    assert!(ok.starts_with("HTTP/1.1 101"), "{ok}");
    let evil = http(addr, &upgrade(&rebound, &format!("Origin: http://{rebound}\r\n")));
    assert!(evil.starts_with("HTTP/1.1 403"), "{evil}");
    gui.stop();
    match serve(handle.clone(), GuiConfig { allowed_hosts: vec!["robot.lan:80".into()], ..GuiConfig::default() }) {
        Err(GuiError::Config(m)) => assert!(m.contains("without a port"), "{m}"),
        Err(other) => panic!("expected a config error, got {other}"),
        Ok(_) => panic!("expected a config error"),
    }
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
}

#[test]
fn every_server_is_a_new_run_named_in_the_hello_with_its_outcome() {
    let (mut handle, join) = robot();
    let first = serve(handle.clone(), GuiConfig::default()).expect("serve");
    let second = serve(handle.clone(), GuiConfig::default()).expect("serve");
    let hello = hello_message(&first.shared, 1);
    assert_eq!(hello["type"], "hello");
    assert_eq!(hello["run"]["id"], first.run_id(), "{hello}");
    let started = hello["run"]["started_unix_s"].as_f64().unwrap_or(0.0);
    assert!(started > 1.6e9, "a wall-clock start time: {hello}");
    assert_ne!(first.run_id(), second.run_id(), "a restarted server is a new run");
    assert_eq!(hello["outcome"], Json::Null, "no outcome yet");
    let mut listener = first.shared.events.subscribe();
    first.set_outcome(Outcome { ok: false, summary: "not delivered: gave up at t = 1800 s".into() });
    let hello = hello_message(&first.shared, 2);
    assert_eq!(hello["outcome"]["ok"], false, "{hello}");
    assert_eq!(hello["outcome"]["summary"], "not delivered: gave up at t = 1800 s");
    let sent: Json =
        serde_json::from_str(listener.try_recv().expect("the outcome is sent to open pages").as_str()).expect("JSON");
    assert_eq!(sent["type"], "outcome");
    assert_eq!(sent["summary"], "not delivered: gave up at t = 1800 s");
    first.stop();
    second.stop();
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
}

#[test]
fn metrics_count_cycles_skill_time_and_faults_in_prometheus_text_format() {
    let (mut handle, join) = robot();
    let gui = serve(handle.clone(), GuiConfig::default()).expect("serve");
    let scrape = |addr| {
        let page = http(addr, &format!("GET /metrics HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"));
        assert!(page.starts_with("HTTP/1.1 200"), "{page}");
        assert!(page.to_ascii_lowercase().contains("content-type: text/plain; version=0.0.4"), "{page}");
        let body = page.split_once("\r\n\r\n").map(|(_, b)| b.to_string()).unwrap_or_default();
        metrics::tests::parse(&body)
    };
    let before = scrape(gui.local_addr());
    let cycles_before = before["situate_cycles_total{robot=\"guitest\"}"];
    handle.step(5).expect("step");
    let mut after = scrape(gui.local_addr());
    assert!(after["situate_cycles_total{robot=\"guitest\"}"] >= cycles_before + 5.0, "{after:?}");
    // runaway runs on the sonar device's readings, which its thread hands over on the wall
    // clock: on a loaded machine the first may come after those five cycles. Waited for.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while after["situate_skill_runs_total{robot=\"guitest\",skill=\"runaway\"}"] < 1.0 {
        assert!(std::time::Instant::now() < deadline, "runaway never ran: {after:?}");
        std::thread::sleep(std::time::Duration::from_millis(20));
        after = scrape(gui.local_addr());
    }
    for skill in ["sonar", "wheels", "runaway", "wander"] {
        let active = after[&format!("situate_skill_active{{robot=\"guitest\",skill=\"{skill}\"}}")];
        assert_eq!(active, if skill == "wander" { 0.0 } else { 1.0 }, "{skill}");
    }
    assert!(after.contains_key("situate_cycle_overruns_total{robot=\"guitest\"}"));
    assert_eq!(after["situate_skill_faults_total{robot=\"guitest\",skill=\"runaway\"}"], 0.0);
    // A fault as the events thread records it.
    gui.shared.activity.lock().expect("lock").note(&situate_manager::Event::SkillFaulted {
        skill: "runaway".into(),
        cause: "panicked: test".into(),
        cycle: 9,
    });
    let faulted = scrape(gui.local_addr());
    assert_eq!(faulted["situate_skill_faults_total{robot=\"guitest\",skill=\"runaway\"}"], 1.0);
    assert_eq!(faulted["situate_skill_faults_total{robot=\"guitest\",skill=\"wander\"}"], 0.0);
    gui.stop();
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
}

#[test]
fn the_open_files_limit_is_raised_to_the_hard_limit() {
    let get = || {
        let mut l = libc::rlimit { rlim_cur: 0, rlim_max: 0 };
        // SAFETY: getrlimit writes the struct it is given.
        assert_eq!(unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut l) }, 0);
        l
    };
    let before = get();
    if before.rlim_cur == before.rlim_max && before.rlim_max > 64 {
        // Lowered a little first (other tests run beside this one), so there is a raise to see.
        let lowered = libc::rlimit { rlim_cur: before.rlim_max - 1, rlim_max: before.rlim_max };
        // SAFETY: setrlimit reads the struct it is given.
        assert_eq!(unsafe { libc::setrlimit(libc::RLIMIT_NOFILE, &lowered) }, 0);
    }
    let now = raise_open_files_limit().expect("raised");
    let after = get();
    assert_eq!(after.rlim_cur, after.rlim_max, "the soft limit is the hard one");
    #[allow(clippy::useless_conversion)]
    let soft = u64::from(after.rlim_cur);
    assert_eq!(soft, now);
}

#[test]
fn a_busy_port_and_a_bad_rate_are_clear_errors() {
    let (mut handle, join) = robot();
    let taken = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    let addr = taken.local_addr().expect("addr");
    match serve(handle.clone(), GuiConfig { listen: addr, ..GuiConfig::default() }) {
        Err(e @ GuiError::Bind { .. }) => assert!(e.to_string().contains(&addr.to_string()), "{e}"),
        Err(other) => panic!("expected a bind error, got {other}"),
        Ok(_) => panic!("expected a bind error"),
    }
    match serve(handle.clone(), GuiConfig { sample_hz: 0.0, ..GuiConfig::default() }) {
        Err(GuiError::Config(m)) => assert!(m.contains("sample_hz"), "{m}"),
        Err(other) => panic!("expected a config error, got {other}"),
        Ok(_) => panic!("expected a config error"),
    }
    match serve(handle.clone(), GuiConfig { history_frames: 0, ..GuiConfig::default() }) {
        Err(GuiError::Config(m)) => assert!(m.contains("history_frames"), "{m}"),
        Err(other) => panic!("expected a config error, got {other}"),
        Ok(_) => panic!("expected a config error"),
    }
    for (config, name) in [
        (GuiConfig { max_connections: 0, ..GuiConfig::default() }, "max_connections"),
        (GuiConfig { header_timeout: Duration::ZERO, ..GuiConfig::default() }, "header_timeout"),
        (GuiConfig { ws_idle_timeout: Duration::from_millis(1), ..GuiConfig::default() }, "ws_idle_timeout"),
    ] {
        match serve(handle.clone(), config) {
            Err(GuiError::Config(m)) => assert!(m.contains(name), "{m}"),
            Err(other) => panic!("expected a config error, got {other}"),
            Ok(_) => panic!("expected a config error"),
        }
    }
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
}
