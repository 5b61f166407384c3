//! Access control on the link, set up the way a robot file does it: a
//! `link:` section whose `zenoh:` settings turn on user-password
//! authentication and Zenoh's ACL. The rules let user `sequencer` do
//! everything under `situate/aclbot/**` and user `viewer` only read-only
//! requests. A request the rules refuse is dropped by the manager's Zenoh
//! session before the manager sees it; Zenoh then ends the query at once, so
//! the client gets no reply at all (no error, no timeout), and nothing
//! changes.

mod common;

use common::{free_port, Running};
use std::time::{Duration, Instant};

use serde_json::{json, Value as Json};
use situate::manager::{ClockKind, Manager, RobotFile, RobotSpec};
use situate_link::{Link, LinkConfig};
use zenoh::{Session, Wait};

/// The robot file; `{PORT}` and `{USERS}` are filled in by [`robot_file`].
/// The `link:` section is the one documented in robot-files.md.
const ROBOT: &str = r#"robot: aclbot
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
link:
  listen: [tcp/127.0.0.1:{PORT}]
  zenoh:
    transport:
      auth:
        usrpwd: {dictionary_file: "{USERS}"}
    access_control:
      enabled: true
      default_permission: deny
      rules:
        - id: control
          permission: allow
          flows: [ingress, egress]
          messages: [query, reply, put, declare_subscriber]
          key_exprs: ["situate/aclbot/**", "situate/*/req/hello"]
        - id: read_only
          permission: allow
          flows: [ingress, egress]
          messages: [query, reply]
          key_exprs:
            - "situate/*/req/hello"
            - "situate/aclbot/req/stats"
            - "situate/aclbot/req/skills"
            - "situate/aclbot/req/skill"
            - "situate/aclbot/req/get_param"
            - "situate/aclbot/req/query"
            - "situate/aclbot/req/winners"
            - "situate/aclbot/req/graph"
            - "situate/aclbot/req/monitor_list"
      subjects:
        - {id: sequencers, usernames: [sequencer]}
        - {id: viewers, usernames: [viewer]}
      policies:
        - {rules: [control], subjects: [sequencers]}
        - {rules: [read_only], subjects: [viewers]}
"#;

/// The users dictionary (`user:password` lines) the manager authenticates against.
const USERS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/acl_users.txt");

/// How long a client the rules refuse would wait for a reply (it gets none).
const REFUSED_TIMEOUT: Duration = Duration::from_secs(2);
/// How long an allowed client waits: generous, an answer always comes.
const ALLOWED_TIMEOUT: Duration = Duration::from_secs(10);

fn robot_file(port: u16) -> String {
    ROBOT.replace("{PORT}", &port.to_string()).replace("{USERS}", USERS)
}

/// Starts the manager with the link its robot file describes.
fn start() -> Running {
    let port = free_port();
    let file = RobotFile::parse("aclbot.yaml", &robot_file(port)).unwrap();
    let config = LinkConfig::from_node(file.link.as_ref().expect("the robot file has a `link:` section"))
        .unwrap_or_else(|errors| panic!("{errors:?}"));
    let endpoint = format!("tcp/127.0.0.1:{port}");
    assert_eq!(config.listen, std::slice::from_ref(&endpoint));
    let session = Link::open(&config).unwrap();
    let spec = RobotSpec::from_file(&file).clock(ClockKind::Wall);
    let manager = Manager::build(&spec, &situate_toys::registry()).unwrap();
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("aclbot", handle.clone(), session, &config).unwrap();
    Running { handle, link: Some(link), join: Some(join), endpoint }
}

/// A client session authenticated as `user` (or with no credentials).
fn open_client(r: &Running, credentials: Option<(&str, &str)>) -> zenoh::Result<Session> {
    let extra = match credentials {
        Some((user, password)) => json!({"transport": {"auth": {"usrpwd": {"user": user, "password": password}}}}),
        None => json!({}),
    };
    zenoh::open(situate_link::session::client_config(std::slice::from_ref(&r.endpoint), Some(&extra)).unwrap()).wait()
}

/// What a request got back.
#[derive(Debug, Clone, PartialEq)]
enum Answer {
    /// The manager's reply: `{"ok": …}` or `{"error": …}`.
    Manager(Json),
    /// An error reply made by Zenoh itself (its payload as text), e.g. the
    /// client's own "Timeout" when nothing answered in time.
    Zenoh(String),
    /// The query ended without any reply at all.
    Nothing,
}

fn ask(session: &Session, verb: &str, args: &Json, timeout: Duration) -> Answer {
    let replies =
        session.get(format!("situate/aclbot/req/{verb}")).payload(args.to_string()).timeout(timeout).wait().unwrap();
    match replies.recv() {
        Err(_) => Answer::Nothing,
        Ok(reply) => match reply.result() {
            Ok(sample) => Answer::Manager(serde_json::from_slice(&sample.payload().to_bytes()).unwrap()),
            Err(e) => Answer::Zenoh(e.payload().try_to_string().map(|s| s.into_owned()).unwrap_or_default()),
        },
    }
}

/// A request that must succeed; its `ok` result.
fn ok(session: &Session, verb: &str, args: &Json) -> Json {
    match ask(session, verb, args, ALLOWED_TIMEOUT) {
        Answer::Manager(body) if body.get("ok").is_some() => body["ok"].clone(),
        other => panic!("`{verb}` {args} was not answered ok: {other:?}"),
    }
}

/// A request the access-control rules refuse: the manager never sees it, and
/// the query ends without any reply (Zenoh 1.10 finalises a query its ACL
/// drops, rather than leave the client waiting for its timeout).
fn assert_refused(session: &Session, verb: &str, args: &Json) {
    let answer = ask(session, verb, args, REFUSED_TIMEOUT);
    assert_eq!(answer, Answer::Nothing, "`{verb}` {args} should get no reply");
}

/// The robots answering `situate/*/req/hello`, as `situate` finds them when
/// no robot is named: that wildcard key needs its own rule, since
/// `situate/aclbot/**` does not include it.
fn discover(session: &Session) -> Vec<Json> {
    let replies = session.get("situate/*/req/hello").timeout(ALLOWED_TIMEOUT).wait().unwrap();
    let mut robots = Vec::new();
    while let Ok(reply) = replies.recv() {
        let body: Json = serde_json::from_slice(&reply.result().unwrap().payload().to_bytes()).unwrap();
        robots.push(body["ok"]["robot"].clone());
    }
    robots
}

fn param(info: &Json, name: &str) -> Json {
    info["params"].as_array().unwrap().iter().find(|p| p["name"] == name).unwrap()["value"].clone()
}

#[test]
fn the_rules_let_the_sequencer_control_and_the_viewer_only_read() {
    let r = start();
    let sequencer = open_client(&r, Some(("sequencer", "seq-secret"))).unwrap();
    let viewer = open_client(&r, Some(("viewer", "view-secret"))).unwrap();
    assert_eq!(ok(&sequencer, "hello", &json!({}))["robot"], "aclbot");
    assert_eq!(discover(&sequencer), [json!("aclbot")]);
    assert_eq!(discover(&viewer), [json!("aclbot")]);

    // The viewer reads: the rules are per key, not all or nothing.
    assert_eq!(ok(&viewer, "hello", &json!({}))["robot"], "aclbot");
    assert_eq!(ok(&viewer, "stats", &json!({}))["robot"], "aclbot");
    let safe_distance = json!({"skill": "runaway", "param": "safe_distance"});
    assert_eq!(ok(&viewer, "get_param", &safe_distance), json!(0.5));
    let active = ok(&sequencer, "stats", &json!({}))["active"].clone();
    assert_eq!(active, json!(["sonar", "wheels", "runaway"]));

    // The viewer may not act: no reply, and nothing changes.
    assert_refused(&viewer, "activate", &json!({"skills": ["wander"]}));
    assert_refused(&viewer, "set_param", &json!({"skill": "runaway", "param": "safe_distance", "value": 1.5}));
    assert_refused(&viewer, "deactivate", &json!({"skills": ["runaway"]}));
    assert_eq!(ok(&sequencer, "skill", &json!({"skill": "wander"}))["active"], false);
    let runaway = ok(&sequencer, "skill", &json!({"skill": "runaway"}));
    assert_eq!(runaway["active"], true);
    assert_eq!(param(&runaway, "safe_distance"), json!(0.5));
    assert_eq!(ok(&sequencer, "stats", &json!({}))["active"], active);

    // The sequencer may: events reach it too.
    let (tx, events) = crossbeam_channel::unbounded();
    let sub = sequencer
        .declare_subscriber("situate/aclbot/events/**")
        .callback(move |sample| {
            if let Ok(j) = serde_json::from_slice::<Json>(&sample.payload().to_bytes()) {
                let _ = tx.send(j);
            }
        })
        .wait()
        .unwrap();
    // The subscription must be known to the manager's session before we act.
    std::thread::sleep(Duration::from_millis(300));
    assert_eq!(ok(&sequencer, "activate", &json!({"skills": ["wander"]}))["changed"], json!(["wander"]));
    assert_eq!(
        ok(&sequencer, "set_param", &json!({"skill": "runaway", "param": "safe_distance", "value": 1.5})),
        Json::Null
    );
    // Activation takes effect from the next cycle: wait for it, bounded.
    let deadline = Instant::now() + ALLOWED_TIMEOUT;
    let wander = loop {
        let info = ok(&sequencer, "skill", &json!({"skill": "wander"}));
        if info["active"] == true || Instant::now() > deadline {
            break info;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    assert_eq!(wander["active"], true);
    assert_eq!(param(&ok(&sequencer, "skill", &json!({"skill": "runaway"})), "safe_distance"), json!(1.5));
    // …and the viewer sees the change.
    assert_eq!(ok(&viewer, "get_param", &safe_distance), json!(1.5));
    // The sequencer may subscribe to events. Should its subscription reach the
    // manager late, later activation changes still show it.
    let deadline = Instant::now() + ALLOWED_TIMEOUT;
    let mut kinds = Vec::new();
    let mut next_toggle = Instant::now() + Duration::from_secs(1);
    let mut on = true;
    while Instant::now() < deadline && !kinds.contains(&"activation_applied".to_string()) {
        if let Ok(e) = events.recv_timeout(Duration::from_millis(200)) {
            kinds.push(e["kind"].as_str().unwrap_or("").to_string());
        } else if Instant::now() > next_toggle {
            on = !on;
            ok(&sequencer, if on { "activate" } else { "deactivate" }, &json!({"skills": ["wander"]}));
            next_toggle = Instant::now() + Duration::from_secs(1);
        }
    }
    assert!(kinds.contains(&"activation_applied".to_string()), "{kinds:?}");

    drop(sub);
    sequencer.close().wait().unwrap();
    viewer.close().wait().unwrap();
}

#[test]
fn clients_without_valid_credentials_cannot_connect() {
    let r = start();
    for (credentials, what) in [
        (Some(("sequencer", "guess")), "a wrong password"),
        (Some(("intruder", "seq-secret")), "an unknown user"),
        (None, "no credentials"),
    ] {
        match open_client(&r, credentials) {
            Err(e) => eprintln!("{what}: refused: {e}"),
            Ok(session) => {
                // Connected anyway? Then it must not get anything.
                let answer = ask(&session, "hello", &json!({}), REFUSED_TIMEOUT);
                session.close().wait().unwrap();
                panic!("a client with {what} could open a session (its `hello` got {answer:?})");
            }
        }
    }
    // The valid one still can.
    let sequencer = open_client(&r, Some(("sequencer", "seq-secret"))).unwrap();
    assert_eq!(ok(&sequencer, "hello", &json!({}))["robot"], "aclbot");
    sequencer.close().wait().unwrap();
}

#[test]
fn a_client_with_wrong_credentials_is_told_they_may_have_been_refused() {
    // It was told only "no skill manager answered … is `situate run` running?".
    let r = start();
    let extra = json!({"transport": {"auth": {"usrpwd": {"user": "sequencer", "password": "guess"}}}});
    let message = match situate_link::Client::connect_with(std::slice::from_ref(&r.endpoint), Some(&extra)) {
        Err(e) => e.to_string(),
        Ok(mut c) => {
            c.timeout = Duration::from_secs(2);
            c.request("aclbot", "hello", &json!({})).expect_err("refused").to_string()
        }
    };
    assert!(message.contains("credentials"), "{message}");
}
