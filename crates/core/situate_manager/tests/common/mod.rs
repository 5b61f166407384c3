//! Test skills built from declarations and closures (the way foreign-language
//! bindings register skills), and small helpers.
#![allow(dead_code)]

use std::sync::{mpsc, Arc, Condvar, Mutex};
use std::time::Duration;

use situate_core::{
    FnSkill, Io, ParamSpec, ParamType, PortSpec, SignalType, Skill, SkillDecl, SkillError, SkillKind, SkillType, Value,
};
use situate_manager::{ClockKind, Manager, Registry, RobotSpec, SkillSpec};

pub type Log = Arc<Mutex<Vec<String>>>;

pub fn log() -> Log {
    Arc::new(Mutex::new(Vec::new()))
}

pub fn entries(log: &Log) -> Vec<String> {
    log.lock().unwrap().clone()
}

pub fn ty(text: &str) -> SignalType {
    SignalType::parse(text).unwrap()
}

/// A declaration: `inputs`/`outputs` as (port, type); an input type ending in
/// `?` is optional.
pub fn decl(name: &str, kind: SkillKind, inputs: &[(&str, &str)], outputs: &[(&str, &str)]) -> SkillDecl {
    let mut d = SkillDecl::new(name, kind);
    for (p, t) in inputs {
        let (t, optional) = match t.strip_suffix('?') {
            Some(t) => (t, true),
            None => (*t, false),
        };
        let mut spec = PortSpec::new(p, ty(t));
        spec.optional = optional;
        d.inputs.push(spec);
    }
    for (p, t) in outputs {
        d.outputs.push(PortSpec::new(p, ty(t)));
    }
    d
}

pub fn with_param(mut d: SkillDecl, name: &str, default: f64, min: f64, max: f64) -> SkillDecl {
    d.params.push(ParamSpec::new(name, ParamType::F64, Value::F64(default)).range(Some(min), Some(max)));
    d
}

pub fn with_priority(mut d: SkillDecl, priority: i32) -> SkillDecl {
    d.priority = priority;
    d
}

/// A skill type whose body is a closure over the raw ports and parameters.
pub fn fn_type<F>(d: SkillDecl, body: F) -> SkillType
where
    F: Fn(&mut Io<'_>, &[Value]) -> Result<(), SkillError> + Clone + Send + Sync + 'static,
{
    let decl = d.clone();
    SkillType::new(d, move || {
        let body = body.clone();
        Ok(Box::new(FnSkill::new(&decl, move |io: &mut Io<'_>, params: &[Value]| body(io, params))) as _)
    })
}

/// How a test's bodies let the manager run them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Way {
    /// No hook: the usual way only.
    Usual,
    /// Outputs typed by construction: the short way.
    Fast,
    /// Also filled and set on every `Ok` run (`Skill::writes_output`), as
    /// the derive's are: the short way, written in the output's slot.
    InSlot,
}

/// A body that says its output is of its port's type by construction, as
/// the derive's bodies do: the manager may then run its step the short way;
/// with `in_slot`, that it sets it on every `Ok` run (the bodies here do)
/// and splits its run in two, as the derive's do: the body, its outputs
/// kept in `outputs`, then those written.
pub struct Typed {
    body: Box<dyn Skill>,
    in_slot: bool,
    outputs: Vec<Option<Value>>,
}

impl Skill for Typed {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        self.run_unwritten(io)?;
        self.write_outputs(io.outputs);
        Ok(())
    }

    fn run_unwritten(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        self.outputs.fill(None);
        self.body.step(&mut Io { inputs: io.inputs, outputs: &mut self.outputs, cx: io.cx })
    }

    fn write_outputs(&mut self, outputs: &mut [Option<Value>]) {
        for (out, value) in outputs.iter_mut().zip(&mut self.outputs) {
            *out = value.take();
        }
    }

    fn set_param(&mut self, index: usize, value: &Value) {
        self.body.set_param(index, value)
    }

    fn output_typed(&self, _port: usize, _ty: &SignalType) -> bool {
        true
    }

    fn fills_outputs(&self) -> bool {
        self.in_slot
    }

    fn writes_output(&self, _port: usize) -> bool {
        self.in_slot
    }
}

/// [`fn_type`], typed ([`Typed`]) unless `way` is [`Way::Usual`].
pub fn body_type<F>(d: SkillDecl, way: Way, body: F) -> SkillType
where
    F: Fn(&mut Io<'_>, &[Value]) -> Result<(), SkillError> + Clone + Send + Sync + 'static,
{
    if way == Way::Usual {
        return fn_type(d, body);
    }
    let decl = d.clone();
    SkillType::new(d, move || {
        let body = body.clone();
        let inner = FnSkill::new(&decl, move |io: &mut Io<'_>, params: &[Value]| body(io, params));
        let outputs = vec![None; decl.outputs.len()];
        Ok(Box::new(Typed { body: Box::new(inner), in_slot: way == Way::InSlot, outputs }) as _)
    })
}

/// A source writing `value` to `out` every run.
pub fn constant(name: &str, out_ty: &str, value: Value) -> SkillType {
    fn_type(decl(name, SkillKind::Sync, &[], &[("out", out_ty)]), move |io, _| {
        io.outputs[0] = Some(value.clone());
        Ok(())
    })
}

/// A sync cskill that logs its instance tag and the cycle, then copies
/// input 0 (f64) plus `add` to its output.
pub fn adder(name: &str, add: f64, log: &Log, tag: &str) -> SkillType {
    let log = log.clone();
    let tag = tag.to_string();
    fn_type(decl(name, SkillKind::Sync, &[("x", "f64")], &[("y", "f64")]), move |io, _| {
        log.lock().unwrap().push(format!("{tag}@{}", io.cx.cycle()));
        let x = io.inputs[0].as_ref().and_then(Value::as_f64).ok_or("no x")?;
        io.outputs[0] = Some(Value::F64(x + add));
        Ok(())
    })
}

pub fn simulated(robot: &str) -> RobotSpec {
    RobotSpec::new(robot).clock(ClockKind::Simulated).period_s(0.01)
}

pub fn build(spec: &RobotSpec, registry: &Registry) -> Manager {
    match Manager::build(spec, registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

pub fn skill(name: &str, type_name: &str) -> SkillSpec {
    SkillSpec::new(name, type_name)
}

/// Generous: a loaded machine is slow, never this slow (a hang is the failure
/// the bound turns into a test failure).
pub const BOUND: Duration = Duration::from_secs(60);

/// A gate a test body waits at until the test opens it.
#[derive(Clone, Default)]
pub struct Gate(Arc<(Mutex<bool>, Condvar)>);

impl Gate {
    /// Waits until the gate is open.
    pub fn pass(&self) {
        let (open, cv) = &*self.0;
        let mut o = open.lock().unwrap();
        while !*o {
            o = cv.wait(o).unwrap();
        }
    }
    pub fn open(&self) {
        *self.0 .0.lock().unwrap() = true;
        self.0 .1.notify_all();
    }
}

/// Runs `f` on a thread; fails if it does not finish within [`BOUND`].
pub fn within_bound<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(BOUND).expect("the cycle blocked")
}

/// The cause of the next fault of `skill` reported on `events`, waited for within [`BOUND`].
pub fn fault_of(events: &crossbeam_channel::Receiver<situate_manager::Event>, skill: &str) -> String {
    let deadline = std::time::Instant::now() + BOUND;
    loop {
        match events.recv_deadline(deadline) {
            Ok(situate_manager::Event::SkillFaulted { skill: s, cause, .. }) if s == skill => return cause,
            Ok(_) => {}
            Err(e) => panic!("no fault of `{skill}` reported: {e}"),
        }
    }
}

/// Waits until `f` holds, within [`BOUND`] (a condition, never a time).
pub fn until(what: &str, mut f: impl FnMut() -> bool) {
    let deadline = std::time::Instant::now() + BOUND;
    while !f() {
        assert!(std::time::Instant::now() < deadline, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(2));
    }
}
