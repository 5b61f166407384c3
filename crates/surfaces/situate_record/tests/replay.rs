//! Deterministic replay: two recordings of one run are the same cycle by
//! cycle; a replay with every skill live reproduces its recording exactly;
//! a skill changed since names the first cycle and signal that differ.

use std::path::PathBuf;

use situate::manager::{ClockKind, Manager, Registry, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_record::read::Recording;
use situate_record::replay::{build_tape, cast, run, Outcome};
use situate_record::Recorder;

/// A device whose readings follow a seeded pseudo-random walk.
#[derive(Skill, Default)]
#[skill(name = "rep.sensor", kind = "device")]
struct Sensor {
    #[output(signal = "range")]
    range: f64,
    #[output(signal = "ring")]
    ring: [f32; 4],
    state: u64,
}

impl Body for Sensor {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.state = self.state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        self.range = (self.state >> 11) as f64 / (1u64 << 53) as f64;
        self.ring = [self.range as f32, 0.5, -0.0, self.range as f32 * 3.1];
        Ok(())
    }
}

/// A computation with a parameter and some memory.
#[derive(Skill, Default)]
#[skill(name = "rep.filter")]
struct Filter {
    #[input(signal = "range")]
    range: f64,
    #[output(signal = "smooth")]
    smooth: f64,
    #[param(default = 0.5, min = 0.0, max = 1.0)]
    alpha: f64,
}

impl Body for Filter {
    /// Switched on, it forgets what it smoothed.
    fn activate(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.smooth = 0.0;
        Ok(())
    }

    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.smooth += self.alpha * (self.range - self.smooth);
        Ok(())
    }
}

/// Writes the resource `cmd` from `smooth`.
#[derive(Skill, Default)]
#[skill(name = "rep.command")]
struct Command {
    #[input(signal = "smooth")]
    smooth: f64,
    #[output(signal = "cmd")]
    cmd: f64,
    #[param(default = 1.0, min = -10.0, max = 10.0)]
    gain: f64,
}

impl Body for Command {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.cmd = self.gain * self.smooth;
        if cx.cycle().is_multiple_of(7) {
            cx.print(format!("cmd {}", self.cmd));
        }
        Ok(())
    }
}

fn registry() -> Registry {
    let mut r = Registry::new();
    r.register::<Sensor>();
    r.register::<Filter>();
    r.register::<Command>();
    r
}

fn spec(alpha: f64) -> RobotSpec {
    RobotSpec::new("rep")
        .clock(ClockKind::Simulated)
        .period_s(0.01)
        .skill(SkillSpec::new("sensor", "rep.sensor"))
        .skill(SkillSpec::new("filter", "rep.filter").param("alpha", Value::F64(alpha)))
        .skill(SkillSpec::new("low", "rep.command").priority(1))
        // A second writer of `cmd`, of higher priority, switched on mid-run.
        .skill(SkillSpec::new("high", "rep.command").priority(5).param("gain", Value::F64(-2.0)).active(false))
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("situate-replay-{}-{name}.mcap", std::process::id()))
}

/// Records the run: 30 cycles, `high` on, its gain changed, `low`'s priority raised over
/// `high`'s, `filter` restarted (off and on before one cycle: the recording lists it as
/// activated only), `high` off, 80 cycles in all.
fn record(name: &str) -> Recording {
    let path = temp(name);
    let mut m = Manager::build(&spec(0.5), &registry()).unwrap_or_else(|e| panic!("{e}"));
    let recorder = Recorder::start(&path, &mut m).unwrap_or_else(|e| panic!("{e}"));
    m.run_cycles(30);
    m.request(Request::Activate { skills: vec!["high".into()], with_providers: false }).unwrap();
    m.run_cycles(10);
    m.request(Request::SetParam { skill: "high".into(), param: "gain".into(), value: Value::F64(3.0) }).unwrap();
    m.run_cycles(5);
    // `low` overtakes `high`: the winner of `cmd` changes hands by priority.
    m.request(Request::SetPriority { skill: "low".into(), priority: 10 }).unwrap();
    m.run_cycles(8);
    m.request(Request::Deactivate { skills: vec!["filter".into()] }).unwrap();
    m.request(Request::Activate { skills: vec!["filter".into()], with_providers: false }).unwrap();
    m.run_cycles(7);
    m.request(Request::Deactivate { skills: vec!["high".into()] }).unwrap();
    m.run_cycles(20);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(summary.dropped, 0);
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    rec
}

fn replay(rec: &Recording, alpha: f64, live: Option<&[String]>) -> Outcome {
    replay_spec(rec, spec(alpha), live)
}

fn replay_spec(rec: &Recording, mut spec: RobotSpec, live: Option<&[String]>) -> Outcome {
    let mut registry = registry();
    let cast = cast(&mut spec, &mut registry, &[], live).unwrap_or_else(|e| panic!("{e}"));
    let mut m = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
    let tape = build_tape(rec, m.graph(), &cast.players).unwrap_or_else(|e| panic!("{e}"));
    assert!(cast.tape.set(tape).is_ok());
    run(rec, &mut m, &cast.live, |_, _| {})
}

#[test]
fn two_recordings_of_one_run_have_the_same_fingerprint_every_cycle() {
    let (a, b) = (record("a"), record("b"));
    assert_eq!(a.span(), Some((1, 80)));
    let hashes = |r: &Recording| r.cycles.iter().map(|(c, x)| (*c, x.hash)).collect::<Vec<_>>();
    assert!(hashes(&a).iter().all(|(_, h)| h.is_some()), "every cycle has a fingerprint");
    assert_eq!(hashes(&a), hashes(&b));
    // The fingerprint sees the run: cycles differ from each other.
    let distinct: std::collections::HashSet<_> = hashes(&a).into_iter().map(|(_, h)| h).collect();
    assert!(distinct.len() > 70, "{} distinct fingerprints", distinct.len());
}

#[test]
fn a_replay_with_every_skill_live_reproduces_the_recording_exactly() {
    let rec = record("live");
    let outcome = replay(&rec, 0.5, None);
    assert_eq!(outcome.first, None);
    assert_eq!((outcome.cycles, outcome.matched), (80, 80));
}

#[test]
fn a_replay_with_one_skill_live_and_the_others_from_the_log_reproduces_it() {
    let rec = record("one");
    // The holder of `cmd` changed three times: `high` on, `low` raised over it, `high` off.
    let holders: Vec<&str> = rec.winners.iter().map(|(_, _, s)| s.as_str()).collect();
    assert_eq!(holders, ["low", "high", "low"], "{:?}", rec.winners);
    for live in [vec!["high".to_string()], vec!["filter".to_string()], vec![]] {
        let outcome = replay(&rec, 0.5, Some(&live));
        assert_eq!(outcome.first, None, "live: {live:?}");
        assert_eq!(outcome.matched, 80, "live: {live:?}");
    }
}

#[test]
fn a_changed_skill_names_the_first_cycle_and_signal_that_differ() {
    let rec = record("changed");
    // `filter` changed: its output differs from the first cycle it runs in.
    let outcome = replay(&rec, 0.25, None);
    let first = outcome.first.expect("a difference");
    assert_eq!(first.signal, "smooth");
    assert_eq!(first.what, "value");
    assert_eq!(first.others, vec!["cmd".to_string()], "downstream of it");
    let first_smooth = rec.cycles.iter().find(|(_, c)| c.leaves.iter().any(|(p, _)| p == "smooth")).map(|(c, _)| *c);
    assert_eq!(Some(first.cycle), first_smooth);
    // With `filter` played from the log, the change does not matter.
    let outcome = replay(&rec, 0.25, Some(&["low".to_string(), "high".to_string()]));
    assert_eq!(outcome.first, None);
}

#[test]
fn a_dskill_or_an_unknown_skill_cannot_be_live() {
    let mut registry = registry();
    let err = cast(&mut spec(0.5), &mut registry, &[], Some(&["sensor".to_string()])).unwrap_err();
    assert!(err.contains("dskill"), "{err}");
    let err = cast(&mut spec(0.5), &mut registry, &[], Some(&["filtre".to_string()])).unwrap_err();
    assert!(err.contains("no skill `filtre`") && err.contains("filter"), "{err}");
}

#[test]
fn the_state_at_any_cycle_from_a_keyframe_is_the_state_built_from_the_start() {
    // 250 cycles: keyframes at 100 and 200.
    let path = temp("keyframes");
    let mut m = Manager::build(&spec(0.5), &registry()).unwrap_or_else(|e| panic!("{e}"));
    let recorder = Recorder::start(&path, &mut m).unwrap_or_else(|e| panic!("{e}"));
    m.run_cycles(120);
    m.request(Request::Activate { skills: vec!["high".into()], with_providers: false }).unwrap();
    m.run_cycles(130);
    drop(m);
    recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    assert_eq!(rec.keyframes.keys().copied().collect::<Vec<_>>(), [100, 200]);
    let mut from_start = situate_record::read::State::new();
    for (&c, cycle) in &rec.cycles {
        for (p, v) in &cycle.leaves {
            from_start.insert(p.clone(), (c, v.clone()));
        }
        if [1, 99, 100, 101, 150, 200, 249, 250].contains(&c) {
            assert_eq!(rec.state_at(c), from_start, "cycle {c}");
        }
    }
    assert_eq!(rec.keyframes[&100], rec.state_at(100));
    assert!(rec.state_at(150).contains_key("cmd"));
}

#[test]
fn a_window_of_cycles_is_compared_after_running_from_the_start() {
    let rec = record("window");
    let mut spec = spec(0.5);
    let mut registry = registry();
    let cast = cast(&mut spec, &mut registry, &[], None).unwrap_or_else(|e| panic!("{e}"));
    let mut m = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
    let tape = build_tape(&rec, m.graph(), &cast.players).unwrap_or_else(|e| panic!("{e}"));
    assert!(cast.tape.set(tape).is_ok());
    let mut seen = Vec::new();
    let outcome = situate_record::replay::run_window(&rec, &mut m, &cast.live, 41, 50, |f, _| seen.push(f.cycle));
    assert_eq!(seen, (41..=50).collect::<Vec<_>>());
    assert_eq!((outcome.cycles, outcome.matched, outcome.first), (10, 10, None));
    assert_eq!(m.cycle_count(), 50);
}

#[test]
fn a_replay_runs_bodies_to_completion_whatever_the_robot_files_deadlines() {
    let rec = record("budget");
    // Deadlines of a nanosecond, for the robot and for each skill: on the
    // wall clock every run would be late.
    let mut tight = spec(0.5);
    tight.budget_ms = Some(1e-6);
    tight.liveness_ms = Some(1e-6);
    for s in &mut tight.skills {
        s.budget_ms = Some(1e-6);
        s.liveness_ms = Some(1e-6);
    }
    for live in [None, Some(vec!["filter".to_string()])] {
        let outcome = replay_spec(&rec, tight.clone(), live.as_deref());
        assert_eq!(outcome.first, None, "live: {live:?}");
        assert_eq!((outcome.cycles, outcome.matched), (80, 80), "live: {live:?}");
        assert!(outcome.identical());
    }
}

#[test]
fn a_recording_that_lacks_cycles_replays_up_to_the_first_and_is_never_identical() {
    // A wall-clock recording whose writer was held: cycles 1-4 queued,
    // 5-50 dropped.
    let path = temp("dropped");
    let mut wall = spec(0.5);
    wall.clock = ClockKind::Wall;
    let mut m = Manager::build(&wall, &registry()).unwrap_or_else(|e| panic!("{e}"));
    let (release, hold) = crossbeam_channel::bounded::<()>(0);
    let options = situate_record::Options { queue_frames: 4, hold: Some(hold) };
    let recorder = Recorder::start_with_options(&path, &mut m, std::collections::BTreeMap::new(), options)
        .unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..50 {
        m.cycle();
    }
    drop(release);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((summary.frames, summary.dropped), (4, 46), "{summary:?}");
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    assert_eq!(rec.span(), Some((1, 4)));
    let outcome = replay(&rec, 0.5, None);
    // The cycles present match; the outcome says what the file lacks.
    assert_eq!(outcome.first, None);
    assert_eq!((outcome.cycles, outcome.matched), (4, 4));
    assert_eq!((outcome.dropped, outcome.dropped_ranges.clone()), (46, vec![(5, 50)]));
    assert_eq!(outcome.stopped_before, Some(5));
    assert!(!outcome.identical(), "{outcome:?}");
}

/// Runs a viewer of `rec` (every skill a player, built from the recording's
/// wiring alone) from cycle `from`, stopping after `to`; its manager after.
fn view(rec: &Recording, from: u64, to: u64) -> (Outcome, Manager) {
    let situate_record::wiring::View { spec, registry, cast } =
        situate_record::wiring::view(rec).unwrap_or_else(|e| panic!("{e}"));
    let mut m = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
    let tape = build_tape(rec, m.graph(), &cast.players).unwrap_or_else(|e| panic!("{e}"));
    assert!(cast.tape.set(tape).is_ok());
    let outcome = situate_record::replay::run_window(rec, &mut m, &cast.players, from, to, |_, _| {});
    (outcome, m)
}

fn skill(m: &mut Manager, name: &str) -> situate::manager::control::SkillInfo {
    match m.request(Request::QuerySkills) {
        Ok(situate::manager::Reply::Skills(s)) => s.into_iter().find(|s| s.name == name).expect("the skill"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_viewer_built_from_the_recording_alone_reproduces_it_with_the_skills_state() {
    let rec = record("view");
    // Every cycle, from the wiring alone: no registry of the robot's skills.
    let (outcome, mut m) = view(&rec, 0, u64::MAX);
    assert_eq!((outcome.cycles, outcome.matched, outcome.first), (80, 80, None));
    // The skills' state follows the recording: `high` switched off again,
    // its gain changed, `low`'s priority raised, `filter`'s alpha as set.
    let high = skill(&mut m, "high");
    assert!(!high.active);
    assert_eq!(high.params.iter().find(|(p, _)| p.name == "gain").map(|(_, v)| v.clone()), Some(Value::F64(3.0)));
    let gain = high.params.iter().find(|(p, _)| p.name == "gain").map(|(p, _)| p.clone()).expect("gain");
    assert_eq!((gain.default.clone(), gain.min, gain.max), (Value::F64(1.0), Some(-10.0), Some(10.0)));
    assert_eq!(skill(&mut m, "low").priority, 10);
    assert_eq!(skill(&mut m, "filter").params[0].1, Value::F64(0.5));
    // Stopped while `high` held `cmd`, the viewer shows it on.
    let (outcome, mut m) = view(&rec, 0, 40);
    assert_eq!((outcome.cycles, outcome.matched), (40, 40));
    assert!(skill(&mut m, "high").active);
}

#[test]
fn a_recording_started_on_a_running_robot_is_viewed_from_its_first_cycle() {
    let path = temp("midrun");
    let mut m = Manager::build(&spec(0.5), &registry()).unwrap_or_else(|e| panic!("{e}"));
    m.run_cycles(30);
    m.request(Request::Activate { skills: vec!["high".into()], with_providers: false }).unwrap();
    let recorder = Recorder::start(&path, &mut m).unwrap_or_else(|e| panic!("{e}"));
    m.run_cycles(25);
    drop(m);
    recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    assert_eq!(rec.span(), Some((31, 55)));
    // The wiring holds the state when the recording started: `high` on.
    let (outcome, mut m) = view(&rec, 31, u64::MAX);
    assert_eq!((outcome.cycles, outcome.matched, outcome.first), (25, 25, None));
    assert!(skill(&mut m, "high").active);
}
