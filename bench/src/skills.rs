//! The skills and robots the benchmarks run.
//!
//! The chain skills exist in three flavours, so the cost of the user-facing
//! path can be told apart from the manager's own:
//! - [`Gen`]/[`Add`]: `#[derive(Skill)]` with `[f32; 24]` ports (the real
//!   user path; the derive copies the array out of the input value and puts
//!   the output in a fresh `Arc<[f32]>` every run);
//! - [`GenArc`]/[`AddArc`]: `#[derive(Skill)]` with `Arc<[f32]>` ports (the
//!   input is a shared pointer; the body collects a new `Arc<[f32]>`);
//! - closures over the raw ports ([`FnSkill`], the binding path).

use std::hint::black_box;
use std::sync::Arc;

use situate::manager::{ClockKind, ExecutorKind, Manager, Registry, Reply, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate::{FnSkill, Io, PortSpec, SignalType, SkillDecl, SkillType};

/// Length of the array passed down the chain.
pub const LEN: usize = 24;
/// What every adder adds.
pub const K: f32 = 1.0;

/// Generates `[t; 24]`, `t` = 1, 2, 3, … (one step per run).
#[derive(Skill, Default)]
#[skill(name = "bench.gen")]
pub struct Gen {
    #[output]
    out: [f32; LEN],
    t: f32,
}

impl Body for Gen {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.t += 1.0;
        self.out = [self.t; LEN];
        Ok(())
    }
}

/// `y = x + K`, element-wise.
#[derive(Skill, Default)]
#[skill(name = "bench.add")]
pub struct Add {
    #[input]
    x: [f32; LEN],
    #[output]
    y: [f32; LEN],
}

impl Body for Add {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = add_k(&self.x);
        Ok(())
    }
}

/// [`Gen`] with an `Arc<[f32]>` output.
#[derive(Skill, Default)]
#[skill(name = "bench.gen_arc")]
pub struct GenArc {
    #[output]
    out: Arc<[f32]>,
    t: f32,
}

impl Body for GenArc {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.t += 1.0;
        self.out = Arc::from([self.t; LEN]);
        Ok(())
    }
}

/// [`Add`] with `Arc<[f32]>` ports.
#[derive(Skill, Default)]
#[skill(name = "bench.add_arc")]
pub struct AddArc {
    #[input]
    x: Arc<[f32]>,
    #[output]
    y: Arc<[f32]>,
}

impl Body for AddArc {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = self.x.iter().map(|v| v + K).collect();
        Ok(())
    }
}

/// The arithmetic of one adder, shared by the skills and the baseline.
#[inline]
pub fn add_k(x: &[f32; LEN]) -> [f32; LEN] {
    let mut y = *x;
    for v in &mut y {
        *v += K;
    }
    y
}

/// One adder as a plain function: the baseline's "direct call".
#[inline(never)]
pub fn add_call(x: &[f32; LEN]) -> [f32; LEN] {
    add_k(x)
}

/// The baseline of a chain of `n`: the source's step, then `n - 1` direct
/// calls doing the adders' arithmetic. `black_box` keeps every intermediate
/// array, so the loop can't be folded into one addition.
pub fn baseline_chain(n: usize, t: &mut f32) -> f32 {
    *t += 1.0;
    let mut a = [*t; LEN];
    for _ in 1..n {
        a = add_call(black_box(&a));
    }
    black_box(&a)[LEN - 1]
}

/// How a chain's skills are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Flavor {
    Derive,
    DeriveArc,
    Closure,
}

impl Flavor {
    pub fn types(self) -> (&'static str, &'static str) {
        match self {
            Flavor::Derive => ("bench.gen", "bench.add"),
            Flavor::DeriveArc => ("bench.gen_arc", "bench.add_arc"),
            Flavor::Closure => ("bench.fn_gen", "bench.fn_add"),
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            Flavor::Derive => "derive [f32; 24]",
            Flavor::DeriveArc => "derive Arc<[f32]>",
            Flavor::Closure => "closure (FnSkill)",
        }
    }
}

fn f32_array() -> SignalType {
    SignalType::parse("f32[24]").expect("a signal type")
}

/// The closure flavour: a declaration plus a closure over the raw ports.
fn closure_types() -> [SkillType; 2] {
    let mut gen = SkillDecl::new("bench.fn_gen", SkillKind::Sync);
    gen.outputs.push(PortSpec::new("out", f32_array()));
    let gen_decl = gen.clone();
    let gen = SkillType::new(gen, move || {
        let mut t = 0.0f32;
        Ok(Box::new(FnSkill::new(&gen_decl, move |io: &mut Io<'_>, _: &[Value]| {
            t += 1.0;
            io.outputs[0] = Some(Value::F32s(Arc::from([t; LEN])));
            Ok(())
        })) as _)
    });
    let mut add = SkillDecl::new("bench.fn_add", SkillKind::Sync);
    add.inputs.push(PortSpec::new("x", f32_array()));
    add.outputs.push(PortSpec::new("y", f32_array()));
    let add_decl = add.clone();
    let add = SkillType::new(add, move || {
        Ok(Box::new(FnSkill::new(&add_decl, |io: &mut Io<'_>, _: &[Value]| {
            let Some(Value::F32s(x)) = &io.inputs[0] else { return Err("no x".into()) };
            io.outputs[0] = Some(Value::F32s(x.iter().map(|v| v + K).collect()));
            Ok(())
        })) as _)
    });
    [gen, add]
}

/// Every skill type of the benchmarks.
pub fn registry() -> Registry {
    let mut r = Registry::new();
    r.register::<Gen>().register::<Add>().register::<GenArc>().register::<AddArc>().register::<Work>();
    for t in closure_types() {
        r.add(t);
    }
    r
}

/// The signal written by step `j` of chain `prefix`.
pub fn chain_signal(prefix: &str, j: usize) -> String {
    format!("{prefix}s{j}")
}

/// A chain of `n` skills: a source, then `n - 1` adders, each reading the
/// previous one's output.
pub fn chain(prefix: &str, n: usize, flavor: Flavor, active: bool) -> Vec<SkillSpec> {
    let (gen, add) = flavor.types();
    (0..n)
        .map(|j| {
            let s = if j == 0 {
                SkillSpec::new(&format!("{prefix}g0"), gen).remap("out", &chain_signal(prefix, 0))
            } else {
                SkillSpec::new(&format!("{prefix}a{j}"), add)
                    .remap("x", &chain_signal(prefix, j - 1))
                    .remap("y", &chain_signal(prefix, j))
            };
            s.active(active)
        })
        .collect()
}

/// A robot on a simulated clock (cycles run back to back) and the serial
/// executor.
pub fn robot(name: &str) -> RobotSpec {
    RobotSpec::new(name).clock(ClockKind::Simulated).period_s(0.01).executor(ExecutorKind::Serial, None)
}

pub fn build(spec: &RobotSpec) -> Manager {
    match Manager::build(spec, &registry()) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

/// Reads an `f32` array signal.
pub fn read_array(m: &mut Manager, signal: &str) -> Option<Arc<[f32]>> {
    match m.request(Request::QuerySignal { signal: signal.into() }) {
        Ok(Reply::Signal(r)) => match r.value {
            Some(Value::F32s(a)) => Some(a),
            _ => None,
        },
        _ => None,
    }
}

/// Checks that a chain of `n` really runs: after the manager's first cycle
/// its last signal holds `1 + (n - 1) K`.
pub fn check_chain(m: &mut Manager, prefix: &str, n: usize) {
    assert_eq!(m.cycle_count(), 0, "check a fresh manager");
    m.cycle();
    let got = read_array(m, &chain_signal(prefix, n - 1));
    let want = 1.0 + (n - 1) as f32 * K;
    assert_eq!(got.as_deref().map(|a| (a.len(), a[0])), Some((LEN, want)), "chain `{prefix}` of {n} did not run");
}

// ----- independent work ----------------------------------------------------

/// `iters` steps of a dependent multiply-add chain: arithmetic the optimizer
/// can neither vectorize nor fold, about the same time per step everywhere.
#[inline(never)]
pub fn spin(iters: u64, seed: f64) -> f64 {
    let mut x = black_box(seed);
    for _ in 0..iters {
        x = x * 0.999_999_9 + 1e-9;
    }
    x
}

/// Burns `iters` steps of [`spin`] per run.
#[derive(Skill, Default)]
#[skill(name = "bench.work")]
pub struct Work {
    #[output]
    y: f64,
    #[param(default = 1000, min = 0)]
    iters: i64,
}

impl Body for Work {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = spin(self.iters.max(0) as u64, self.y);
        Ok(())
    }
}

/// `count` independent [`Work`] skills writing `w0`, `w1`, ….
pub fn workers(count: usize, iters: u64) -> Vec<SkillSpec> {
    (0..count)
        .map(|k| {
            SkillSpec::new(&format!("work{k}"), "bench.work")
                .remap("y", &format!("w{k}"))
                .param("iters", Value::I64(iters as i64))
        })
        .collect()
}
