//! A body is told when its skill is switched on and off (`Skill::activate`, `Skill::deactivate`):
//! before its first run after an activation, after its last run before a deactivation, on the
//! thread that runs it, whatever its kind.

mod common;

use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use common::*;
use situate_core::{Context, Io, Skill, SkillDecl, SkillError, SkillKind, SkillType, Value};
use situate_manager::{ClockKind, Control, Event, Registry, Request, RobotSpec};

/// What a hook does besides logging.
#[derive(Clone, Copy, PartialEq)]
enum Hook {
    Quiet,
    Fail,
    Panic,
}

/// Logs `activate@cycle`, `step@cycle` and `deactivate@cycle`, each with the name of its
/// thread after a space.
struct Hooked {
    log: Log,
    on_activate: Hook,
    on_deactivate: Hook,
}

impl Hooked {
    fn note(&self, what: &str, cycle: u64) {
        let thread = std::thread::current().name().unwrap_or("?").to_string();
        self.log.lock().unwrap().push(format!("{what}@{cycle} {thread}"));
    }
}

fn hook(hook: Hook, what: &str) -> Result<(), SkillError> {
    match hook {
        Hook::Quiet => Ok(()),
        Hook::Fail => Err(SkillError::from(format!("no {what} today").as_str())),
        Hook::Panic => panic!("{what} went wrong"),
    }
}

impl Skill for Hooked {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        self.note("step", io.cx.cycle());
        io.outputs[0] = Some(Value::F64(io.cx.cycle() as f64));
        Ok(())
    }

    fn set_param(&mut self, _: usize, _: &Value) {}

    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.note("activate", cx.cycle());
        cx.print("switched on");
        hook(self.on_activate, "activation")
    }

    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.note("deactivate", cx.cycle());
        cx.print("switched off");
        hook(self.on_deactivate, "deactivation")
    }
}

fn hooked_type(kind: SkillKind, log: &Log, on_activate: Hook, on_deactivate: Hook) -> SkillType {
    let d: SkillDecl = decl("hooked", kind, &[], &[("y", "f64")]);
    let log = log.clone();
    SkillType::new(d, move || Ok(Box::new(Hooked { log: log.clone(), on_activate, on_deactivate }) as _))
}

/// The entries without their threads.
fn what(log: &Log) -> Vec<String> {
    entries(log).iter().map(|e| e.split(' ').next().unwrap().to_string()).collect()
}

fn robot(log: &Log, on_activate: Hook, on_deactivate: Hook) -> situate_manager::Manager {
    let mut reg = Registry::new();
    reg.add(hooked_type(SkillKind::Sync, log, on_activate, on_deactivate));
    build(&simulated("hooks").skill(skill("h", "hooked")), &reg)
}

#[test]
fn a_skill_is_activated_before_its_first_run_and_deactivated_after_its_last() {
    let log = log();
    let mut m = robot(&log, Hook::Quiet, Hook::Quiet);
    assert!(entries(&log).is_empty(), "nothing is told before the first cycle");
    m.step(2).unwrap();
    assert_eq!(what(&log), ["activate@1", "step@1", "step@2"]);
    m.deactivate(&["h"]).unwrap();
    assert_eq!(what(&log).len(), 3, "told at the next cycle, not on the request");
    m.step(2).unwrap();
    assert_eq!(what(&log), ["activate@1", "step@1", "step@2", "deactivate@3"]);
    m.activate(&["h"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(what(&log)[4..], ["activate@5", "step@5"]);
    // The hook's print is the skill's, as a run's would be.
    assert!(m.skill("h").unwrap().prints.iter().any(|(_, p)| p == "switched on"));
}

#[test]
fn switched_off_and_on_between_two_cycles_it_is_deactivated_then_activated() {
    let log = log();
    let mut m = robot(&log, Hook::Quiet, Hook::Quiet);
    m.step(1).unwrap();
    m.deactivate(&["h"]).unwrap();
    m.activate(&["h"]).unwrap();
    m.step(1).unwrap();
    assert_eq!(what(&log), ["activate@1", "step@1", "deactivate@2", "activate@2", "step@2"]);
    // On and off again before a cycle: a body that was off stays untold.
    m.deactivate(&["h"]).unwrap();
    m.step(1).unwrap();
    m.activate(&["h"]).unwrap();
    m.deactivate(&["h"]).unwrap();
    m.step(2).unwrap();
    assert_eq!(what(&log)[5..], ["deactivate@3"]);
}

#[test]
fn an_activation_that_fails_or_panics_faults_the_skill_which_never_runs() {
    for (failing, says) in
        [(Hook::Fail, "`activate` failed: no activation today"), (Hook::Panic, "`activate` panicked")]
    {
        let log = log();
        let mut m = robot(&log, failing, Hook::Quiet);
        let events = m.events();
        m.step(3).unwrap();
        assert_eq!(what(&log), ["activate@1"], "no run, and no deactivation of a body never on");
        let cause = events
            .try_iter()
            .find_map(|e| match e {
                Event::SkillFaulted { skill, cause, cycle } if skill == "h" => Some((cause, cycle)),
                _ => None,
            })
            .expect("a fault");
        assert!(cause.0.contains(says), "{cause:?}");
        assert_eq!(cause.1, 1);
        let info = m.skill("h").unwrap();
        assert!(!info.active && info.faulted.is_some(), "{info:?}");
    }
}

#[test]
fn a_deactivation_that_fails_is_in_the_prints_and_the_skill_is_off_unfaulted() {
    let log = log();
    let mut m = robot(&log, Hook::Quiet, Hook::Fail);
    m.step(1).unwrap();
    m.deactivate(&["h"]).unwrap();
    m.step(2).unwrap();
    assert_eq!(what(&log), ["activate@1", "step@1", "deactivate@2"]);
    let info = m.skill("h").unwrap();
    assert!(!info.active && info.faulted.is_none(), "{info:?}");
    assert!(info.prints.iter().any(|(_, p)| p.contains("`deactivate` failed: no deactivation today")), "{info:?}");
}

#[test]
fn a_body_left_behind_is_not_told_and_its_fresh_replacement_is_activated() {
    // A sync body that blocks in cycle 2 past its budget is left behind; activating the skill
    // again makes a fresh body, which is activated before it runs (the old one is never told).
    let log = log();
    let gate: Gate = Arc::default();
    let (l, g) = (log.clone(), Arc::clone(&gate));
    let d = decl("stuck", SkillKind::Sync, &[], &[("y", "f64")]);
    let mut reg = Registry::new();
    reg.add(SkillType::new(d, move || {
        let inner = Hooked { log: l.clone(), on_activate: Hook::Quiet, on_deactivate: Hook::Quiet };
        Ok(Box::new(Stuck { inner, gate: Arc::clone(&g) }) as _)
    }));
    let spec = simulated("behind").skill(skill("h", "stuck").budget_ms(50.0));
    let m = build(&spec, &reg);
    let events = m.events();
    let (mut handle, join) = m.spawn(true);
    // The body is still blocked (the gate is shut): only the watchdog can have faulted it.
    let cause = fault_of(&events, "h");
    assert!(cause.contains("left behind"), "{cause}");
    handle.request(Request::Stop).unwrap();
    let (open, opened) = &*gate;
    *open.lock().unwrap() = true;
    opened.notify_all();
    // A fresh body is made once the old one has returned.
    let deadline = Instant::now() + BOUND;
    while let Err(e) = handle.activate(&["h"]) {
        assert!(Instant::now() < deadline, "never activated again: {e}");
        std::thread::sleep(Duration::from_millis(10));
    }
    handle.step(1).unwrap();
    let seen = what(&log);
    let activations = seen.iter().filter(|e| e.starts_with("activate@")).count();
    assert_eq!(activations, 2, "the first body and its replacement: {seen:?}");
    assert!(!seen.iter().any(|e| e.starts_with("deactivate")), "{seen:?}");
    handle.request(Request::Shutdown).unwrap();
    join.join_timeout(BOUND).ok().expect("the manager ended").unwrap();
}

/// Shut until the test opens it.
type Gate = Arc<(Mutex<bool>, Condvar)>;

/// [`Hooked`], whose second run (the first body's only) blocks until the gate opens (at most
/// [`BOUND`]): past its budget, however late the watchdog gets a CPU on a busy machine.
struct Stuck {
    inner: Hooked,
    gate: Gate,
}

impl Skill for Stuck {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        if io.cx.cycle() == 2 && what(&self.inner.log).iter().filter(|e| e.starts_with("activate")).count() == 1 {
            let (open, opened) = &*self.gate;
            let shut = open.lock().unwrap();
            drop(opened.wait_timeout_while(shut, BOUND, |open| !*open).unwrap());
        }
        self.inner.step(io)
    }
    fn set_param(&mut self, _: usize, _: &Value) {}
    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.inner.activate(cx)
    }
    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.inner.deactivate(cx)
    }
}

/// Waits, with a generous bound, until `ok` holds of the log.
fn until_logged(log: &Log, what_for: &str, ok: impl Fn(&[String]) -> bool) {
    let deadline = Instant::now() + BOUND;
    while !ok(&entries(log)) {
        assert!(Instant::now() < deadline, "never {what_for}: {:?}", entries(log));
        std::thread::sleep(Duration::from_millis(2));
    }
}

#[test]
fn a_threaded_body_is_told_on_its_own_thread_between_runs() {
    for kind in [SkillKind::Async, SkillKind::Device] {
        let log = log();
        let mut reg = Registry::new();
        reg.add(hooked_type(kind, &log, Hook::Quiet, Hook::Quiet));
        let spec = RobotSpec::new("threads").clock(ClockKind::Wall).period_s(0.01).skill(skill("h", "hooked"));
        let (mut handle, join) = build(&spec, &reg).spawn(true);
        until_logged(&log, "a run", |e| e.iter().any(|e| e.starts_with("step@")));
        handle.deactivate(&["h"]).unwrap();
        until_logged(&log, "a deactivation", |e| e.iter().any(|e| e.starts_with("deactivate@")));
        // What `deactivate` said on the skill's thread is seen while the skill is off.
        let deadline = Instant::now() + BOUND;
        while !handle.skill("h").unwrap().prints.iter().any(|(_, p)| p == "switched off") {
            assert!(Instant::now() < deadline, "{kind:?}: the deactivation's print never seen");
            std::thread::sleep(Duration::from_millis(2));
        }
        handle.activate(&["h"]).unwrap();
        until_logged(&log, "a second activation", |e| e.iter().filter(|e| e.starts_with("activate@")).count() == 2);
        until_logged(&log, "a run after it", |e| e.last().is_some_and(|e| e.starts_with("step@")));
        handle.request(Request::Shutdown).unwrap();
        join.join_timeout(BOUND).ok().expect("the manager ended").unwrap();
        let seen = entries(&log);
        // Every hook and run on the skill's own thread, in order: on, runs, off, on, runs.
        assert!(seen.iter().all(|e| e.ends_with(" skill-h")), "{seen:?}");
        let kinds: Vec<&str> = seen.iter().map(|e| e.split('@').next().unwrap()).collect();
        let mut phases = kinds.clone();
        phases.dedup();
        assert_eq!(phases, ["activate", "step", "deactivate", "activate", "step"], "{kind:?}: {seen:?}");
    }
}
