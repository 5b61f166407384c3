//! Per-call overhead of a trivial skill (`y = x + 1`, one f64 in, one f64
//! out) written in C and in C++ (through the C ABI, `situate_cabi`) against
//! the same skill in Rust (`#[derive(Skill)]`): one manager cycle running N
//! instances, measured interleaved in this run. The figure is the difference
//! of cycle times divided by N, in wall time (the target, as in `core`) and
//! in this thread's on-CPU time (`CLOCK_THREAD_CPUTIME_ID`, which time spent
//! preempted by other processes does not inflate; shown in the target's note).
//!
//! ```text
//! cargo bench -p situate_bench --bench languages [-- [--quick] [--samples N] [--json PATH]]
//! ```
//!
//! It compiles the C and C++ skills with gcc/g++ -O2 from generated headers
//! (`situate_cabi::generate`) into a scratch directory first.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use situate::manager::{ClockKind, ExecutorKind, Manager, Registry, Reply, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_bench::measure::{interleaved, paired, Settings};
use situate_bench::report::{results_path, CpuTimes, Machine, Report, Target};

/// Instances per cycle.
const N: usize = 1000;
/// The target: C and C++ per-call overhead over Rust.
const TARGET_NS: f64 = 20.0;

/// The source: x = 1, 2, 3, … (one step per cycle).
#[derive(Skill, Default)]
#[skill(name = "bench.x")]
struct X {
    #[output]
    x: f64,
}

impl Body for X {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.x += 1.0;
        Ok(())
    }
}

/// The trivial skill in Rust.
#[derive(Skill, Default)]
#[skill(name = "rust.trivial")]
struct Trivial {
    #[input]
    x: f64,
    #[output]
    y: f64,
}

impl Body for Trivial {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = self.x + 1.0;
        Ok(())
    }
}

const MANIFEST: &str = "name: NAME\ninputs: {x: f64}\noutputs: {y: f64}\n";

const C_SOURCE: &str = r#"#include "c_trivial.h"
struct c_trivial_state { char unused; };
situate_status c_trivial_step(c_trivial_state* s, const c_trivial_inputs* in, c_trivial_outputs* out,
                              const c_trivial_params* p, situate_context* cx) {
    (void)s; (void)p; (void)cx;
    out->y = in->x + 1.0;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_trivial))
"#;

const CPP_SOURCE: &str = r#"#include "cpp_trivial.hpp"
class Trivial : public cpp_trivial::Skill {
 public:
  void step(const Inputs& in, Outputs& out, const Params&, situate::Context&) {
    out.y = in.x + 1.0;
    out.has_y = true;
  }
};
SITUATE_CPP_LIBRARY(Trivial)
"#;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Generates the header and compiles one trivial skill library.
fn compile(dir: &Path, name: &str, cpp: bool) -> Result<PathBuf, String> {
    let manifest = dir.join(format!("{name}.yaml"));
    std::fs::write(&manifest, MANIFEST.replace("NAME", &name.replace('_', "."))).map_err(|e| e.to_string())?;
    let lang = if cpp { situate_cabi::Lang::Cpp } else { situate_cabi::Lang::C };
    for f in situate_cabi::generate(lang, &manifest).map_err(|e| e.to_string())? {
        std::fs::write(dir.join(&f.path), f.contents).map_err(|e| e.to_string())?;
    }
    let src = dir.join(if cpp { format!("{name}.cpp") } else { format!("{name}.c") });
    std::fs::write(&src, if cpp { CPP_SOURCE } else { C_SOURCE }).map_err(|e| e.to_string())?;
    let lib = dir.join(format!("lib{name}.so"));
    let out = Command::new(if cpp { "g++" } else { "gcc" })
        .args(if cpp { ["-std=c++17"] } else { ["-std=c11"] })
        .args(["-O2", "-shared", "-fPIC", "-fvisibility=hidden", "-I"])
        .arg(repo().join("include"))
        .arg("-I")
        .arg(dir)
        .arg(&src)
        .arg("-o")
        .arg(&lib)
        .output()
        .map_err(|e| format!("cannot run the compiler: {e}"))?;
    if !out.status.success() {
        return Err(format!("compiling {}: {}", src.display(), String::from_utf8_lossy(&out.stderr)));
    }
    Ok(lib)
}

fn manager(type_name: &str, registry: &Registry) -> Manager {
    let mut spec =
        RobotSpec::new("languages").clock(ClockKind::Simulated).period_s(0.01).executor(ExecutorKind::Serial, None);
    spec.skills.push(SkillSpec::new("x", "bench.x"));
    for i in 0..N {
        spec.skills.push(SkillSpec::new(&format!("t{i}"), type_name).remap("y", &format!("y{i}")));
    }
    match Manager::build(&spec, registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

/// Checks that every instance ran and wrote x + 1 this cycle.
fn check(m: &mut Manager, label: &str) {
    m.cycle();
    let cycle = m.cycle_count();
    for i in [0, N / 2, N - 1] {
        match m.request(Request::QuerySignal { signal: format!("y{i}") }) {
            Ok(Reply::Signal(r)) if r.value == Some(Value::F64(cycle as f64 + 1.0)) && r.cycle == cycle => {}
            other => panic!("{label}: y{i} is not x + 1 at cycle {cycle}: {other:?}"),
        }
    }
}

/// This thread's CPU time in nanoseconds (`CLOCK_THREAD_CPUTIME_ID`): time
/// the thread was preempted does not count.
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
fn thread_cpu_ns() -> Option<u64> {
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    extern "C" {
        fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut ts = Timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: a valid out-pointer; `clock_gettime` is in the C library std links.
    let rc = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    (rc == 0).then(|| ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64)
}

#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
fn thread_cpu_ns() -> Option<u64> {
    None
}

/// The cycle time of each manager in on-CPU nanoseconds, interleaved like
/// `interleaved` (A B C, C B A, …), samples of about 10 ms.
fn on_cpu(settings: &Settings, managers: &mut [Manager]) -> Option<Vec<situate_bench::measure::Summary>> {
    let start = thread_cpu_ns()?;
    for _ in 0..10 {
        managers[0].cycle();
    }
    let per_cycle = (thread_cpu_ns()? - start).max(1) / 10;
    let iters = (10_000_000 / per_cycle).max(1);
    let n = managers.len();
    let mut samples = vec![Vec::with_capacity(settings.samples); n];
    for round in 0..settings.samples {
        for k in 0..n {
            let s = if round % 2 == 0 { k } else { n - 1 - k };
            let t0 = thread_cpu_ns()?;
            for _ in 0..iters {
                managers[s].cycle();
            }
            let t1 = thread_cpu_ns()?;
            samples[s].push((t1 - t0) as f64 / iters as f64);
        }
    }
    Some(samples.into_iter().map(situate_bench::measure::Summary::of).collect())
}

fn main() {
    let (settings, json) = Settings::from_args("languages", std::env::args().skip(1)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("languages");
    if let Err(e) = std::fs::create_dir_all(&dir) {
        eprintln!("{}: {e}", dir.display());
        std::process::exit(1);
    }
    let mut registry = Registry::new();
    registry.register::<X>().register::<Trivial>();
    for (name, cpp) in [("c_trivial", false), ("cpp_trivial", true)] {
        let loaded =
            compile(&dir, name, cpp).and_then(|lib| situate_cabi::load_library(&lib).map_err(|e| e.to_string()));
        match loaded {
            Ok(types) => types.into_iter().for_each(|t| {
                registry.add(t);
            }),
            Err(e) => {
                eprintln!("cannot build the {name} skill: {e}");
                std::process::exit(1);
            }
        }
    }
    let cli: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let machine = Machine::detect(&cli.join(" "));
    println!(
        "situate language benchmarks — {} CPUs ({}), {}, load average {}; {} samples of ≥ {:?} each, interleaved",
        machine.cpus, machine.cpu_model, machine.date, machine.loadavg, settings.samples, settings.min_sample
    );
    let started = Instant::now();
    let subjects = [("Rust (derive)", "rust.trivial"), ("C", "c.trivial"), ("C++", "cpp.trivial")];
    let mut managers: Vec<Manager> = subjects
        .iter()
        .map(|(label, ty)| {
            let mut m = manager(ty, &registry);
            check(&mut m, label);
            m
        })
        .collect();
    let before = CpuTimes::now();
    let out = interleaved(&settings, managers.len(), &mut |s, iters| {
        let m = &mut managers[s];
        for _ in 0..iters {
            m.cycle();
        }
        black_box(m.cycle_count());
    });
    let cpu = on_cpu(&settings, &mut managers);
    for (m, (label, _)) in managers.iter_mut().zip(subjects) {
        check(m, label);
    }
    let bench = "languages";
    let mut report = Report::default();
    for ((label, _), s) in subjects.iter().zip(&out) {
        let per_call = s.map(|x| x / N as f64);
        report.figure(bench, &format!("{label}: cycle of {N} calls, per call"), "ns", &per_call);
    }
    let mut diffs = Vec::new();
    for (k, (label, _)) in subjects.iter().enumerate().skip(1) {
        let d = paired(&out[0], &out[k], |rust, other| (other - rust) / N as f64);
        let v = report.figure(bench, &format!("{label} − Rust, per call"), "ns", &d);
        diffs.push((label.to_string(), v));
    }
    // On a shared machine, preemption only ever adds time: the fastest
    // sample of each subject is its least disturbed one.
    let fastest: Vec<f64> =
        out.iter().map(|s| s.samples.iter().copied().fold(f64::INFINITY, f64::min) / N as f64).collect();
    report.note(format!(
        "fastest samples, per call: Rust {:.1} ns, C {:.1} ns ({:+.1} ns), C++ {:.1} ns ({:+.1} ns)",
        fastest[0],
        fastest[1],
        fastest[1] - fastest[0],
        fastest[2],
        fastest[2] - fastest[0]
    ));
    let mut cpu_diffs = Vec::new();
    if let Some(cpu) = &cpu {
        for ((label, _), s) in subjects.iter().zip(cpu) {
            report.figure(bench, &format!("{label}: on-CPU time per call"), "ns", &s.map(|x| x / N as f64));
        }
        for (k, (label, _)) in subjects.iter().enumerate().skip(1) {
            let d = paired(&cpu[0], &cpu[k], |rust, other| (other - rust) / N as f64);
            cpu_diffs.push(report.figure(bench, &format!("{label} − Rust, on-CPU per call"), "ns", &d));
        }
    }
    report.print_table(
        bench,
        &format!("Per-call overhead of a trivial skill (f64 in, f64 out), {N} instances per cycle"),
    );
    let busy = before.zip(CpuTimes::now()).and_then(|(a, b)| a.since(&b));
    for (k, (label, v)) in diffs.into_iter().enumerate() {
        let note = match cpu_diffs.get(k) {
            Some(c) => format!("on-CPU time (immune to preemption): {c:+.1} ns"),
            None => String::new(),
        };
        let mut t = Target {
            bench: bench.into(),
            name: format!("{label} per-call overhead over Rust"),
            unit: "ns",
            value: v,
            target: format!("≤ +{TARGET_NS:.0} ns"),
            met: v <= TARGET_NS,
            note,
            inconclusive: None,
        };
        if let Some(share) = busy.as_ref().filter(|s| s.busy()) {
            t.inconclusive = Some(format!(
                "the machine was busy (other processes {:.0}%, hypervisor steal {:.0}% of all CPU time): rerun on an idle machine",
                share.others, share.steal
            ));
        }
        report.target(t);
    }
    if let Some(share) = busy {
        report.note(format!("{bench}: {share}"));
    }
    println!();
    println!("== targets ({:.1} s)", started.elapsed().as_secs_f64());
    for t in &report.targets {
        println!("{}", t.line());
    }
    let path = json.unwrap_or_else(|| results_path("languages.json"));
    match report.write_json(&path, &machine) {
        Ok(()) => println!("results: {}", path.display()),
        Err(e) => eprintln!("could not write {}: {e}", path.display()),
    }
}
