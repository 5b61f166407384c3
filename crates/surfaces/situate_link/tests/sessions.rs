//! Who holds a monitor, over real Zenoh sessions on loopback: a monitor
//! belongs to the client session that added it (a secret and a liveliness
//! token, docs/protocol.md "Sessions"), only that session cancels it, one
//! session's allowance does not grow with the names it gives itself, and a
//! session's monitors go when its client does.

mod common;

use std::time::{Duration, Instant};

use common::{free_port, Running};
use serde_json::{json, Value as Json};
use situate::manager::{Manager, RobotFile, RobotSpec};
use situate_link::client_session::{public_id, token_key};
use situate_link::{Client, ClientError, Link, LinkConfig};
use zenoh::Wait;

const ROBOT: &str = "\
robot: sessbot
cycle: {rate_hz: 100}
devices:
  - name: sonar
    type: toy.sonar
  - name: wheels
    type: toy.wheels
skills:
  - name: runaway
    type: toy.runaway
";

fn start() -> Running {
    let file = RobotFile::parse("sessbot.yaml", ROBOT).unwrap();
    let endpoint = format!("tcp/127.0.0.1:{}", free_port());
    let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
    let session = Link::open(&config).unwrap();
    let manager = Manager::build(&RobotSpec::from_file(&file), &situate_toys::registry()).unwrap();
    let (handle, join) = manager.spawn(true);
    let link = Link::serve("sessbot", handle.clone(), session, &config).unwrap();
    Running { handle, link: Some(link), join: Some(join), endpoint }
}

fn client(r: &Running) -> Client {
    let mut c = Client::connect(std::slice::from_ref(&r.endpoint)).unwrap();
    c.timeout = Duration::from_secs(20);
    c
}

fn refused(result: Result<Json, ClientError>) -> (String, String) {
    match result {
        Err(ClientError::Remote(e)) => (e.kind, e.message),
        other => panic!("expected an error reply, got {other:?}"),
    }
}

fn monitors(c: &Client) -> Vec<Json> {
    c.request("sessbot", "monitor_list", &json!({})).unwrap().as_array().cloned().unwrap_or_default()
}

/// Waits (generously) until `done` holds.
fn wait_until(what: &str, mut done: impl FnMut() -> bool) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while !done() {
        assert!(Instant::now() < deadline, "{what}: not within 60 s");
        std::thread::sleep(Duration::from_millis(20));
    }
}

#[test]
fn a_monitor_needs_a_live_session_and_only_its_session_cancels_it() {
    let r = start();
    let (a, b) = (client(&r), client(&r));
    // No session: refused before it reaches the manager.
    let raw = |c: &Client, verb: &str, args: Json| -> Json {
        let replies = c
            .session()
            .get(format!("situate/sessbot/req/{verb}"))
            .payload(args.to_string())
            .timeout(Duration::from_secs(30))
            .wait()
            .unwrap();
        let reply = replies.recv().expect("a reply");
        serde_json::from_slice(&reply.result().unwrap().payload().to_bytes()).unwrap()
    };
    let e = raw(&a, "monitor_add", json!({"condition": "cycle > 0"}));
    assert_eq!(e["error"]["kind"], "bad_request", "{e}");
    assert!(e["error"]["message"].as_str().unwrap().contains("missing argument `session`"), "{e}");
    // A secret whose token nobody declared: refused, naming the key to declare.
    let secret = "s".repeat(32);
    let e = raw(&a, "monitor_add", json!({"condition": "cycle > 0", "session": secret}));
    assert_eq!(e["error"]["kind"], "no_session", "{e}");
    let key = token_key("sessbot", &public_id(&secret).unwrap());
    assert!(e["error"]["message"].as_str().unwrap().contains(&key), "{e}");
    // The clients open their sessions themselves.
    let id = a.request("sessbot", "monitor_add", &json!({"condition": "cycle < 0"})).unwrap()["monitor"].clone();
    let list = monitors(&b);
    assert_eq!(list.len(), 1);
    assert_eq!(list[0]["session"], json!(a.session_id("sessbot").unwrap()), "the public id, never the secret");
    // Another session cannot cancel it…
    let (kind, message) = refused(b.request("sessbot", "monitor_cancel", &json!({"monitor": id})));
    assert_eq!(kind, "not_owner");
    assert!(message.contains("only its session cancels it"), "{message}");
    // …nor can a request that gives no session.
    let e = raw(&b, "monitor_cancel", json!({"monitor": id}));
    assert_eq!(e["error"]["kind"], "bad_request", "{e}");
    assert_eq!(monitors(&b).len(), 1, "a refused cancel changes nothing");
    // The owner can.
    a.request("sessbot", "monitor_cancel", &json!({"monitor": id})).unwrap();
    assert!(monitors(&b).is_empty());
}

#[test]
fn names_a_client_gives_itself_do_not_multiply_its_allowance() {
    let r = start();
    let c = client(&r);
    let cap = situate_manager::MAX_MONITORS_PER_SESSION;
    // One session that calls itself a0..a3: it once held all 1000 of the robot's monitors.
    let any = json!(vec!["cycle < 0"; 50]);
    for k in 0..cap / 50 {
        c.request("sessbot", "monitor_add", &json!({"any": any, "client": format!("a{}", k % 4)})).unwrap();
    }
    let (kind, message) =
        refused(c.request("sessbot", "monitor_add", &json!({"condition": "cycle < 0", "client": "a3"})));
    assert_eq!(kind, "invalid");
    assert!(message.contains("past the most one session keeps (250)"), "{message}");
    // Another client (another session) still has its own allowance.
    let other = client(&r);
    other.request("sessbot", "monitor_add", &json!({"condition": "cycle < 0"})).unwrap();
}

#[test]
fn a_sessions_monitors_go_when_its_client_does_and_its_owner_is_told_why() {
    let r = start();
    let watcher = client(&r);
    let (_sub, events) = watcher.subscribe("sessbot", "events/monitor_cancelled").unwrap();
    // A sequencer that fills its allowance and crashes, five times over: the robot is never full.
    for start_no in 0..5 {
        let sequencer = client(&r);
        let any = json!(vec!["cycle < 0"; 48]);
        for _ in 0..5 {
            sequencer.request("sessbot", "monitor_add", &json!({"any": any})).expect("a fresh allowance each start");
        }
        let id = sequencer.session_id("sessbot").unwrap();
        assert_eq!(monitors(&watcher).iter().filter(|m| m["session"] == json!(id)).count(), 5, "start {start_no}");
        // The client goes (its Zenoh session closes, as when its process dies): so does its token.
        drop(sequencer);
        wait_until("the session's monitors are removed", || {
            monitors(&watcher).iter().all(|m| m["session"] != json!(id))
        });
        let mut told = 0;
        while told < 5 {
            let e = events.recv_timeout(Duration::from_secs(60)).expect("a monitor_cancelled event per monitor");
            if e["session"] == json!(id) {
                assert_eq!(e["reason"], "session_ended", "{e}");
                told += 1;
            }
        }
    }
    assert!(monitors(&watcher).is_empty());
}
