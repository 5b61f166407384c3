//! A skill's inputs as the GUI's telemetry shows them (issue 38: "a skill's input reads null in 1
//! of 150 samples though written every cycle"): an input written every cycle never reads null in
//! a sample, whether its writer runs in the cycle (a record input: the running manager keeps no
//! copy once the body has read it) or is a device on its own thread whose reading now and then
//! lands a cycle late (the toy sonar on the wall clock).

use std::net::TcpStream;
use std::time::{Duration, Instant};

use serde_json::Value as Json;
use situate::manager::{Control, Manager, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_gui::GuiConfig;

/// A pose, a record of three leaves.
#[derive(Record, Clone, Copy, Debug, Default, PartialEq)]
pub struct Spot {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

/// Writes `spot` (a record) and `count` (one leaf) in every cycle.
#[derive(Skill, Default)]
#[skill(name = "test.writer")]
pub struct Writer {
    #[output]
    spot: Spot,
    #[output]
    count: f64,
}

impl Body for Writer {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let c = cx.cycle() as f64;
        self.spot = Spot { x: c, y: -c, theta: 0.5 };
        self.count = c;
        Ok(())
    }
}

/// Reads them, and the toy sonar's ring.
#[derive(Skill, Default)]
#[skill(name = "test.reader")]
pub struct Reader {
    #[input]
    spot: Spot,
    #[input]
    count: f64,
    #[output]
    seen: f64,
}

impl Body for Reader {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.seen = self.spot.x + self.count;
        Ok(())
    }
}

/// Receives telemetry samples from the GUI's `/ws` until `n` carried the skills, or fails after a
/// generous bound (a hang, not a slow machine).
fn samples(addr: std::net::SocketAddr, n: usize) -> Vec<Json> {
    let stream = TcpStream::connect(addr).expect("connect");
    stream.set_read_timeout(Some(Duration::from_secs(30))).expect("timeout");
    let (mut ws, _) = tungstenite::client(format!("ws://{addr}/ws"), stream).expect("ws");
    let deadline = Instant::now() + Duration::from_secs(300);
    let mut out = Vec::new();
    while out.len() < n {
        assert!(Instant::now() < deadline, "only {} samples within 5 minutes", out.len());
        match ws.read().expect("a message") {
            tungstenite::Message::Text(t) => {
                let m: Json = serde_json::from_str(t.as_str()).expect("JSON");
                if m["type"] == "telemetry" && m["skills"].is_array() {
                    out.push(m);
                }
            }
            tungstenite::Message::Close(c) => panic!("closed: {c:?}"),
            _ => {}
        }
    }
    let _ = ws.close(None);
    out
}

#[test]
fn an_input_written_every_cycle_never_reads_null_in_a_sample() {
    let spec = RobotSpec::new("inputs")
        .period_s(0.01)
        .skill(SkillSpec::new("sonar", "toy.sonar"))
        .skill(SkillSpec::new("runaway", "toy.runaway"))
        .skill(SkillSpec::new("writer", "test.writer"))
        .skill(SkillSpec::new("reader", "test.reader"));
    let mut registry = situate_toys::registry();
    registry.register::<Writer>();
    registry.register::<Reader>();
    let manager = Manager::build(&spec, &registry).expect("the robot builds");
    let (mut handle, join) = manager.spawn(true);
    // The sonar's first reading, before counting (until then its readers have nothing to read).
    let deadline = Instant::now() + Duration::from_secs(120);
    while !matches!(handle.request(Request::QuerySignal { signal: "sonar.range".into() }),
        Ok(situate_manager::Reply::Signal(ref r)) if r.value.is_some())
    {
        assert!(Instant::now() < deadline, "the toy sonar never read within 2 minutes");
        std::thread::sleep(Duration::from_millis(10));
    }
    let config = GuiConfig { listen: "127.0.0.1:0".parse().expect("addr"), sample_hz: 50.0, ..GuiConfig::default() };
    let gui = situate_gui::serve(handle.clone(), config).expect("serve");
    let got = samples(gui.local_addr(), 300);
    gui.stop();
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();

    let mut nulls: std::collections::BTreeMap<String, usize> = Default::default();
    let mut last_count = 0.0;
    for sample in &got {
        for skill in sample["skills"].as_array().expect("skills") {
            let name = skill["name"].as_str().unwrap_or("");
            if !matches!(name, "runaway" | "reader") {
                continue;
            }
            for port in skill["inputs"].as_array().expect("inputs") {
                let key = format!("{name}.{}", port["name"].as_str().unwrap_or(""));
                if port["value"].is_null() {
                    *nulls.entry(key).or_default() += 1;
                } else if key == "reader.spot" {
                    let spot = &port["value"];
                    assert_eq!(spot["y"], -spot["x"].as_f64().unwrap_or(f64::NAN), "a record of one cycle: {spot}");
                    assert_eq!(spot["theta"], 0.5);
                } else if key == "reader.count" {
                    let c = port["value"].as_f64().expect("a number");
                    assert!(c >= last_count, "the count never goes back: {c} after {last_count}");
                    last_count = c;
                }
            }
        }
    }
    assert!(nulls.is_empty(), "inputs that read null, in {} samples: {nulls:?}", got.len());
    assert!(last_count > 0.0, "the writer ran");
}
