//! The client verbs' errors are sentences (`situate: …`), never the link's
//! own data: a robot whose cycle is stuck (its link up, its manager never
//! answering) and a robot nobody serves, with the real binary against a real
//! Zenoh session.

use std::process::{Command, Output};
use std::time::Duration;

use crossbeam_channel::{Receiver, Sender};
use situate::manager::{ClockKind, Handle, Joiner, Manager, Registry, Request, RobotSpec, SkillSpec};
use situate::{FnSkill, Io, SkillDecl, SkillKind, SkillType, Value};
use situate_link::{Link, LinkConfig};

/// How long a test waits for a condition: generous, this is no timing assertion.
const WAIT: Duration = Duration::from_secs(60);

/// A robot whose one skill's body blocks (within an hour-long budget) until
/// the robot is dropped: its cycle is stuck, so the manager answers nothing,
/// while its link is up and takes every request.
struct StuckRobot {
    endpoint: String,
    release: Option<Sender<()>>,
    link: Option<Link>,
    handle: Handle,
    join: Option<Joiner>,
}

impl StuckRobot {
    fn start() -> StuckRobot {
        let (release, gate): (Sender<()>, Receiver<()>) = crossbeam_channel::unbounded();
        let (entered_tx, entered) = crossbeam_channel::unbounded::<()>();
        let decl = SkillDecl::new("t.hang", SkillKind::Sync);
        let body_decl = decl.clone();
        let ty = SkillType::new(decl, move || {
            let (gate, entered) = (gate.clone(), entered_tx.clone());
            Ok(Box::new(FnSkill::new(&body_decl, move |_io: &mut Io<'_>, _params: &[Value]| {
                let _ = entered.send(());
                let _ = gate.recv(); // until the sender is dropped
                Ok(())
            })) as _)
        });
        let mut registry = Registry::new();
        registry.add(ty);
        let spec = RobotSpec::new("stuck")
            .clock(ClockKind::Wall)
            .period_s(0.01)
            .skill(SkillSpec::new("hang", "t.hang").budget_ms(3_600_000.0));
        let manager = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
        let port = situate_link::free_loopback_port().expect("a free port");
        let endpoint = format!("tcp/127.0.0.1:{port}");
        let config = LinkConfig { listen: vec![endpoint.clone()], ..LinkConfig::default() };
        let session = Link::open(&config).unwrap_or_else(|e| panic!("{e}"));
        let (handle, join) = manager.spawn(true);
        let link = Link::serve("stuck", handle.clone(), session, &config).unwrap_or_else(|e| panic!("{e}"));
        entered.recv_timeout(WAIT).expect("the body runs, and from then on the cycle is stuck");
        StuckRobot { endpoint, release: Some(release), link: Some(link), handle, join: Some(join) }
    }
}

impl Drop for StuckRobot {
    fn drop(&mut self) {
        drop(self.release.take());
        drop(self.link.take());
        let _ = self.handle.request_timeout(Request::Shutdown, WAIT);
        if let Some(j) = self.join.take() {
            let _ = j.join();
        }
    }
}

fn situate(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_situate")).args(args).output().expect("situate runs")
}

/// The one error line of a failed client verb, checked to be a sentence.
fn sentence(out: &Output) -> String {
    let err = String::from_utf8_lossy(&out.stderr).trim().to_string();
    assert_eq!(out.status.code(), Some(4), "4: no robot answered; stderr:\n{err}");
    assert!(out.stdout.is_empty(), "{}", String::from_utf8_lossy(&out.stdout));
    assert_eq!(err.lines().count(), 1, "one line:\n{err}");
    assert!(err.starts_with("situate: "), "{err}");
    for raw in ["Timeout", "b\"", "Err(", "Ok(", "ReplyError", "ZBytes", "{ ", "panicked", "Single("] {
        assert!(!err.contains(raw), "`{raw}` in: {err}");
    }
    err
}

#[test]
fn stats_on_a_stuck_robot_says_so_in_a_sentence() {
    let robot = StuckRobot::start();
    for verb in [&["stats"][..], &["query", "odom.x"], &["activate", "hang"]] {
        let mut args = verb.to_vec();
        args.extend(["--robot", "stuck", "--connect", &robot.endpoint, "--timeout", "1"]);
        let err = sentence(&situate(&args));
        assert_eq!(
            err,
            format!(
                "situate: no answer from robot `stuck` to `{}` within 1 s (is it running, is its cycle stuck, or do its \
                 access rules drop this request? a longer --timeout may help a busy one)",
                verb[0]
            )
        );
    }
}

#[test]
fn a_robot_nobody_serves_is_said_in_a_sentence() {
    let robot = StuckRobot::start();
    // Another robot answers there: the sentence names it (the name given was likely misspelt),
    // a second after nobody served the name (the timeout only bounds the wait).
    let err = sentence(&situate(&["stats", "--robot", "nobody", "--connect", &robot.endpoint, "--timeout", "30"]));
    assert_eq!(err, "situate: robot `nobody` did not answer; robot `stuck` did (name it with --robot)");
}

#[test]
fn an_endpoint_where_nothing_listens_is_said_in_a_sentence() {
    // Zenoh's own text here is `Unable to connect to any of [Single(tcp/…)]!`: not shown.
    let port = std::net::TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port();
    let endpoint = format!("tcp/127.0.0.1:{port}");
    let err = sentence(&situate(&["stats", "--connect", &endpoint, "--timeout", "1"]));
    assert_eq!(
        err,
        format!("situate: no skill manager answered at {endpoint}: nothing could be reached there; is `situate run` running, and does it accept these credentials (user and password, certificates)?")
    );
}
