//! The skill manager's core benchmarks: every figure is a ratio or a
//! difference of subjects measured interleaved in this run. See README.md.
//!
//! ```text
//! cargo bench -p situate_bench --bench core [-- [--quick] [--samples N] [--json PATH] [NAME…]]
//! ```
//!
//! `NAME`s select benchmarks by name: chain, inactive, parallel, request,
//! monitor, parts (default: all).

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use situate::manager::{Manager, MonitorMode, Request, SkillSpec};
use situate::prelude::*;
use situate::{Declare, Io};
use situate_bench::measure::{interleaved, paired, ratio, Settings, Summary};
use situate_bench::report::{results_path, CpuTimes, Machine, Report, Target};
use situate_bench::skills::{self, Flavor};

const BENCHES: &[&str] = &["chain", "spawned", "inactive", "parallel", "request", "monitor", "parts", "record"];

type Bench = fn(&Settings, &mut Report);

struct Args {
    settings: Settings,
    /// Seconds to run only the N = 1000 derive chain, unmeasured (for `perf record`).
    profile: Option<f64>,
    only: Vec<String>,
    json: Option<PathBuf>,
}

fn parse_args() -> Args {
    let mut settings = Settings::default();
    let mut samples = None;
    let mut min_sample = None;
    let mut only = Vec::new();
    let mut json = None;
    let mut profile = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            // `cargo bench` passes `--bench` to every bench target.
            "--bench" => {}
            "--quick" => settings = Settings::quick(),
            "--samples" => samples = args.next().and_then(|n| n.parse().ok()),
            "--min-sample-ms" => {
                if let Some(ms) = args.next().and_then(|n| n.parse::<f64>().ok()) {
                    min_sample = Some(std::time::Duration::from_secs_f64(ms / 1000.0));
                }
            }
            "--json" => json = args.next().map(PathBuf::from),
            "--profile" => profile = args.next().and_then(|n| n.parse().ok()).or(Some(10.0)),
            "--help" | "-h" => {
                println!(
                    "core [--quick] [--samples N] [--min-sample-ms MS] [--json PATH] [--profile SECONDS] [{}]…",
                    BENCHES.join("|")
                );
                std::process::exit(0);
            }
            name if BENCHES.contains(&name) => only.push(a),
            other => {
                eprintln!("unknown argument `{other}` (benchmarks: {})", BENCHES.join(", "));
                std::process::exit(2);
            }
        }
    }
    if let Some(n) = samples {
        settings.samples = n;
    }
    if let Some(t) = min_sample {
        settings.min_sample = t;
    }
    Args { settings, profile, only, json }
}

fn main() {
    let args = parse_args();
    if let Some(seconds) = args.profile {
        profile_chain(seconds);
        return;
    }
    let want = |name: &str| args.only.is_empty() || args.only.iter().any(|o| o == name);
    let cli: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let machine = Machine::detect(&cli.join(" "));
    println!(
        "situate core benchmarks — {} CPUs ({}), {}, load average {}; {} samples of ≥ {:?} each, interleaved",
        machine.cpus, machine.cpu_model, machine.date, machine.loadavg, args.settings.samples, args.settings.min_sample
    );
    let started = Instant::now();
    let mut report = Report::default();
    let benches: [(&str, Bench); 8] = [
        ("chain", chain),
        ("spawned", spawned),
        ("inactive", inactive),
        ("parallel", parallel),
        ("request", request),
        ("monitor", monitors),
        ("parts", parts),
        ("record", record),
    ];
    let all = CpuTimes::now();
    for (name, bench) in benches {
        if want(name) {
            let before = CpuTimes::now();
            let first_target = report.targets.len();
            bench(&args.settings, &mut report);
            if let Some(share) = before.zip(CpuTimes::now()).and_then(|(a, b)| a.since(&b)) {
                report.note(format!("{name}: {share}"));
                // Other work preempts the samples (and, with the scheduler's
                // autogroups, holds this session to about one core whatever
                // its thread count): say so next to the verdict.
                if share.busy() {
                    for t in &mut report.targets[first_target..] {
                        t.inconclusive = Some(format!(
                            "the machine was busy (other processes {:.0}%, hypervisor steal {:.0}% of all CPU time): rerun on an idle machine",
                            share.others, share.steal
                        ));
                        println!("{}", t.line());
                    }
                }
            }
        }
    }
    if let Some(share) = all.zip(CpuTimes::now()).and_then(|(a, b)| a.since(&b)) {
        report.note(format!("whole run: {share}"));
    }
    println!();
    println!(
        "== targets ({:.1} s; load average {} → {})",
        started.elapsed().as_secs_f64(),
        machine.loadavg,
        situate_bench::report::loadavg()
    );
    for t in &report.targets {
        println!("{}", t.line());
    }
    let path = args.json.unwrap_or_else(|| results_path("core.json"));
    match report.write_json(&path, &machine) {
        Ok(()) => println!("results: {}", path.display()),
        Err(e) => eprintln!("could not write {}: {e}", path.display()),
    }
}

// ----- 1. the chain ----------------------------------------------------------

const CHAIN_NS: [usize; 4] = [1, 10, 100, 1000];
const FLAVORS: [Flavor; 3] = [Flavor::Derive, Flavor::DeriveArc, Flavor::Closure];

/// Chains of N skills passing `[f32; 24]`, each adding a constant, against a
/// loop of N direct calls doing the same arithmetic. One interleaved set for
/// every N and flavour, so differences across N are paired too.
fn chain(settings: &Settings, report: &mut Report) {
    let bench = "chain";
    // managers[n][f]
    let mut managers: Vec<Vec<Manager>> = CHAIN_NS
        .iter()
        .map(|&n| {
            FLAVORS
                .iter()
                .map(|&f| {
                    let mut spec = skills::robot("chain");
                    spec.skills = skills::chain("", n, f, true);
                    let mut m = skills::build(&spec);
                    skills::check_chain(&mut m, "", n);
                    m
                })
                .collect()
        })
        .collect();
    let per_n = 1 + FLAVORS.len();
    let mut t = 0.0f32;
    let out = interleaved(settings, CHAIN_NS.len() * per_n, &mut |s, iters| {
        let (ni, k) = (s / per_n, s % per_n);
        if k == 0 {
            for _ in 0..iters {
                black_box(skills::baseline_chain(CHAIN_NS[ni], &mut t));
            }
        } else {
            let m = &mut managers[ni][k - 1];
            for _ in 0..iters {
                m.cycle();
            }
        }
    });
    let mut overhead: Vec<Vec<Summary>> = Vec::new();
    for (ni, &n) in CHAIN_NS.iter().enumerate() {
        let base = &out[ni * per_n];
        report.figure(bench, &format!("N={n:<4} baseline: direct calls"), "ns", base);
        let mut row = Vec::new();
        for (fi, f) in FLAVORS.iter().enumerate() {
            let cyc = &out[ni * per_n + 1 + fi];
            report.figure(bench, &format!("N={n:<4} cycle, {}", f.label()), "ns", cyc);
            let o = paired(base, cyc, |b, c| (c - b) / n as f64);
            report.figure(bench, &format!("N={n:<4} overhead per skill, {}", f.label()), "ns", &o);
            row.push(o);
        }
        overhead.push(row);
    }
    // Overhead(N) = fixed + N × marginal: the marginal cost from the two
    // largest chains, the fixed part per cycle from N = 1.
    let (i_hi, i_lo) = (CHAIN_NS.len() - 1, CHAIN_NS.len() - 2);
    let (n_hi, n_lo) = (CHAIN_NS[i_hi] as f64, CHAIN_NS[i_lo] as f64);
    for (fi, f) in FLAVORS.iter().enumerate() {
        let marginal =
            paired(&overhead[i_lo][fi], &overhead[i_hi][fi], |lo, hi| (hi * n_hi - lo * n_lo) / (n_hi - n_lo));
        report.figure(bench, &format!("marginal per skill N={n_lo}→{n_hi}, {}", f.label()), "ns", &marginal);
    }
    report.print_table(
        bench,
        "1. chain of N sync skills passing f32[24], each adding a constant (serial, simulated clock)",
    );
    let worst = CHAIN_NS
        .iter()
        .enumerate()
        .filter(|&(_, &n)| n >= 10)
        .map(|(ni, &n)| (n, overhead[ni][0].median))
        .fold((0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
    let at = |n: usize| overhead[CHAIN_NS.iter().position(|&x| x == n).unwrap_or(0)][0].median;
    report.target(Target {
        bench: bench.into(),
        name: "chain overhead per skill (derive [f32; 24], worst of N = 10, 100, 1000)".into(),
        unit: "ns",
        value: worst.1,
        target: "≤ 50 ns".into(),
        met: worst.1 <= 50.0,
        note: format!(
            "worst at N={}; N=10: {:.0} ns, N=100: {:.0} ns, N=1000: {:.0} ns (N=1, all fixed cycle cost: {:.0} ns)",
            worst.0,
            at(10),
            at(100),
            at(1000),
            at(1)
        ),
        inconclusive: None,
    });
}

/// Runs the derive chain (N = 1000, or `$PROFILE_N`) for `seconds`,
/// unmeasured: a steady load for `perf record`.
fn profile_chain(seconds: f64) {
    let n = std::env::var("PROFILE_N").ok().and_then(|n| n.parse().ok()).unwrap_or(1000);
    let mut spec = skills::robot("chain");
    spec.skills = skills::chain("", n, Flavor::Derive, true);
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "", n);
    let end = Instant::now() + std::time::Duration::from_secs_f64(seconds);
    while Instant::now() < end {
        for _ in 0..100 {
            m.cycle();
        }
    }
    println!("{} cycles of a {n}-skill chain", m.cycle_count());
}

// ----- 1b. the chain on the spawned manager ------------------------------------

/// The chain of N = 10 and 100 run by a spawned manager (its own cycle thread
/// and watchdog, cycles asked for with a `Step` request of `iters` cycles:
/// the path a running robot takes) beside `Manager::cycle` on this thread.
/// Reported: the spawned path's extra cost per skill and its ratio.
fn spawned(settings: &Settings, report: &mut Report) {
    use situate::manager::control::Control;
    let bench = "spawned";
    const NS: [usize; 2] = [10, 100];
    let mut plain: Vec<Manager> = Vec::new();
    let mut handles = Vec::new();
    for &n in &NS {
        let mut spec = skills::robot("chain");
        spec.skills = skills::chain("", n, Flavor::Derive, true);
        let mut m = skills::build(&spec);
        skills::check_chain(&mut m, "", n);
        plain.push(m);
        let mut m = skills::build(&spec);
        skills::check_chain(&mut m, "", n);
        handles.push(m.spawn(false));
    }
    let out = interleaved(settings, NS.len() * 2, &mut |s, iters| {
        let (ni, spawned) = (s / 2, s % 2 == 1);
        if spawned {
            let handle = &mut handles[ni].0;
            if let Err(e) = handle.request(Request::Step { cycles: iters }) {
                panic!("spawned chain: step refused: {e}");
            }
        } else {
            for _ in 0..iters {
                plain[ni].cycle();
            }
        }
    });
    let mut worst = (0usize, f64::MIN);
    for (ni, &n) in NS.iter().enumerate() {
        let (a, b) = (&out[ni * 2], &out[ni * 2 + 1]);
        report.figure(bench, &format!("N={n:<4} cycle, Manager::cycle"), "ns", a);
        report.figure(bench, &format!("N={n:<4} cycle, spawned (Step)"), "ns", b);
        let extra = paired(a, b, |a, b| (b - a) / n as f64);
        report.figure(bench, &format!("N={n:<4} spawned − plain, per skill"), "ns", &extra);
        report.figure(bench, &format!("N={n:<4} spawned / plain"), "×", &ratio(b, a));
        if extra.median > worst.1 {
            worst = (n, extra.median);
        }
    }
    for (handle, joiner) in handles {
        drop(handle);
        let _ = joiner.join_timeout(std::time::Duration::from_secs(10));
    }
    report.print_table(bench, "1b. the chain on a spawned manager (Step requests) vs Manager::cycle (serial)");
    report.note(format!("spawned: worst extra cost per skill {:.1} ns at N={}", worst.1, worst.0));
}

// ----- 2. inactive skills ------------------------------------------------------

/// The same 100-skill chain active, alone or among 9,900 inactive skills of
/// the same types (99 more chains of 100).
fn inactive(settings: &Settings, report: &mut Report) {
    let bench = "inactive";
    const CHAINS: usize = 100;
    const LEN: usize = 100;
    let chains: Vec<Vec<SkillSpec>> =
        (0..CHAINS).map(|c| skills::chain(&format!("c{c}_"), LEN, Flavor::Derive, c == 0)).collect();
    let mut small = skills::robot("small");
    small.skills = chains[0].clone();
    // Contiguous: the active chain is declared first.
    let mut contiguous = skills::robot("contiguous");
    contiguous.skills = chains.concat();
    // Spread: declared step by step across chains, so the active skills sit
    // 100 instances apart (the worst case for locality).
    let mut spread = skills::robot("spread");
    spread.skills = (0..LEN).flat_map(|j| chains.iter().map(move |c| c[j].clone())).collect();
    // Spread among 1,000 (10 chains): does the cost grow with the number of
    // inactive skills, or with how far apart the active ones are?
    let mut spread_1k = skills::robot("spread_1k");
    spread_1k.skills = (0..LEN).flat_map(|j| chains[..10].iter().map(move |c| c[j].clone())).collect();
    let t0 = Instant::now();
    let mut managers: Vec<Manager> =
        [&small, &contiguous, &spread, &spread_1k].iter().map(|s| skills::build(s)).collect();
    let build_s = t0.elapsed().as_secs_f64();
    for m in &mut managers {
        skills::check_chain(m, "c0_", LEN);
    }
    let out = interleaved(settings, managers.len(), &mut |s, iters| {
        let m = &mut managers[s];
        for _ in 0..iters {
            m.cycle();
        }
    });
    report.figure(bench, "100 active of 100", "ns", &out[0]);
    report.figure(bench, "100 active of 10,000 (active declared first)", "ns", &out[1]);
    report.figure(bench, "100 active of 10,000 (active spread out)", "ns", &out[2]);
    let r_cont = ratio(&out[0], &out[1]);
    let r_spread = ratio(&out[0], &out[2]);
    report.figure(bench, "100 active of 1,000 (active spread out)", "ns", &out[3]);
    report.figure(bench, "ratio 10,000 / 100 (declared first)", "×", &r_cont);
    report.figure(bench, "ratio 10,000 / 100 (spread out)", "×", &r_spread);
    report.figure(bench, "ratio 1,000 / 100 (spread out)", "×", &ratio(&out[0], &out[3]));
    report.print_table(bench, "2. 100 active skills among 10,000 registered vs 100 registered");
    report.note(format!("building the four managers (21,100 instances in all) took {build_s:.2} s"));
    let worst = r_cont.median.max(r_spread.median);
    report.target(Target {
        bench: bench.into(),
        name: "inactive skills: cycle ratio 10,000 / 100 registered (worst arrangement)".into(),
        unit: "×",
        value: worst,
        target: "≤ 1.05×".into(),
        met: worst <= 1.05,
        note: format!("declared first {:.3}×, spread out {:.3}×", r_cont.median, r_spread.median),
        inconclusive: None,
    });
}

// ----- 3. parallel executor ---------------------------------------------------

/// Steps of [`skills::spin`] that take about `want_ns`.
fn calibrate_spin(want_ns: f64) -> u64 {
    let probe = 200_000u64;
    for _ in 0..3 {
        black_box(skills::spin(probe, 1.0));
    }
    let mut per: Vec<f64> = (0..9)
        .map(|_| {
            let t = Instant::now();
            black_box(skills::spin(probe, 1.0));
            t.elapsed().as_nanos() as f64 / probe as f64
        })
        .collect();
    per.sort_by(f64::total_cmp);
    (want_ns / per[per.len() / 2]).round().max(1.0) as u64
}

/// 8 independent skills of ~50 µs each: serial vs parallel executor with 2
/// threads.
fn parallel(settings: &Settings, report: &mut Report) {
    let bench = "parallel";
    const COUNT: usize = 8;
    let iters = calibrate_spin(50_000.0);
    let build = |executor| {
        let mut spec = skills::robot("parallel").executor(executor, Some(2));
        spec.skills = skills::workers(COUNT, iters);
        let mut m = skills::build(&spec);
        assert_eq!(m.executor(), executor);
        m.cycle();
        for k in 0..COUNT {
            let r = m.request(Request::QuerySignal { signal: format!("w{k}") });
            assert!(
                matches!(r, Ok(situate::manager::Reply::Signal(ref s)) if s.value.is_some()),
                "worker {k} did not run"
            );
        }
        m
    };
    let mut serial = build(situate::manager::ExecutorKind::Serial);
    let mut par = build(situate::manager::ExecutorKind::Parallel);
    let mut x = 1.0;
    // Long samples (≥ 20 ms, ~50 cycles): the pool's threads fall asleep while
    // the other subjects run, and waking them costs the first cycle of a
    // sample dearly on a virtual machine; here that is amortized. The cost
    // itself is measured below ("after an idle gap").
    let long =
        Settings { min_sample: settings.min_sample.max(std::time::Duration::from_millis(20)), ..settings.clone() };
    let out = interleaved(&long, 3, &mut |s, n| match s {
        0 => {
            for _ in 0..n {
                for _ in 0..COUNT {
                    x = skills::spin(iters, x);
                }
            }
            black_box(x);
        }
        1 => {
            for _ in 0..n {
                serial.cycle();
            }
        }
        _ => {
            for _ in 0..n {
                par.cycle();
            }
        }
    });
    report.figure(bench, "one body alone (calibrated to 50 µs)", "ns", &out[0].map(|v| v / COUNT as f64));
    report.figure(bench, "8 bodies, direct calls", "ns", &out[0]);
    report.figure(bench, "cycle, serial executor", "ns", &out[1]);
    report.figure(bench, "cycle, parallel executor (2 threads)", "ns", &out[2]);
    report.figure(bench, "serial cycle / direct calls", "×", &ratio(&out[0], &out[1]));
    let speedup = ratio(&out[2], &out[1]);
    report.figure(bench, "speed-up serial / parallel", "×", &speedup);
    // Under a wall clock the cycle waits for its period between cycles, and
    // the pool's threads go to sleep: time single cycles that each follow a
    // 5 ms pause, alternating the executors.
    const GAP: std::time::Duration = std::time::Duration::from_millis(5);
    let rounds = settings.samples * 3;
    let (mut cold_serial, mut cold_par) = (Vec::with_capacity(rounds), Vec::with_capacity(rounds));
    for round in 0..rounds {
        for k in 0..2 {
            let which = if round % 2 == 0 { k } else { 1 - k };
            let (m, into) = if which == 0 { (&mut serial, &mut cold_serial) } else { (&mut par, &mut cold_par) };
            std::thread::sleep(GAP);
            let t = Instant::now();
            m.cycle();
            into.push(t.elapsed().as_nanos() as f64);
        }
    }
    let (cold_serial, cold_par) = (Summary::of(cold_serial), Summary::of(cold_par));
    report.figure(bench, "after a 5 ms idle gap: cycle, serial", "ns", &cold_serial);
    report.figure(bench, "after a 5 ms idle gap: cycle, parallel", "ns", &cold_par);
    let cold_ratio = ratio(&cold_par, &cold_serial);
    report.figure(bench, "after a 5 ms idle gap: speed-up serial / parallel", "×", &cold_ratio);
    report.print_table(bench, "3. 8 independent skills of ~50 µs: serial vs parallel executor (2 threads)");
    report.target(Target {
        bench: bench.into(),
        name: "parallel speed-up, 8 × 50 µs skills on 2 threads (serial / parallel)".into(),
        unit: "×",
        value: speedup.median,
        target: "≥ 1.8×".into(),
        met: speedup.median >= 1.8,
        note: format!(
            "iqr {:.2}..{:.2}; after a 5 ms idle gap {:.2}×",
            speedup.q1,
            speedup.q3,
            Summary::of(cold_ratio.samples.clone()).median
        ),
        inconclusive: None,
    });
}

// ----- 4. control requests ----------------------------------------------------

/// The cost of a signal query between cycles, against a cycle of a
/// 100-skill chain.
fn request(settings: &Settings, report: &mut Report) {
    let bench = "request";
    let mut spec = skills::robot("request");
    spec.skills = skills::chain("", 100, Flavor::Derive, true);
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "", 100);
    let signal = skills::chain_signal("", 50);
    let out = interleaved(settings, 3, &mut |s, n| match s {
        0 => {
            for _ in 0..n {
                m.cycle();
            }
        }
        1 => {
            for _ in 0..n {
                black_box(m.request(Request::QuerySignal { signal: signal.clone() }).is_ok());
            }
        }
        _ => {
            for _ in 0..n {
                black_box(m.request(Request::QuerySkill { skill: "a50".into() }).is_ok());
            }
        }
    });
    report.figure(bench, "cycle, chain of 100", "ns", &out[0]);
    report.figure(bench, "request QuerySignal (f32[24])", "ns", &out[1]);
    report.figure(bench, "request QuerySkill", "ns", &out[2]);
    report.figure(bench, "QuerySignal / cycle", "×", &ratio(&out[0], &out[1]));
    report.figure(
        bench,
        "QuerySignal / (cycle / 100): in skill runs",
        "×",
        &paired(&out[0], &out[1], |c, q| q / (c / 100.0)),
    );
    report.figure(bench, "QuerySkill / cycle", "×", &ratio(&out[0], &out[2]));
    report.print_table(bench, "4. control requests between cycles (no target)");
}

// ----- 5. monitors ------------------------------------------------------------

/// A 10-skill chain with and without 10 monitors `s{k}[0] > 1e9`, one on
/// each of its signals (never holding; level mode, so evaluated every cycle).
/// The chain is short so that the monitors' share stands out of the noise.
fn monitors(settings: &Settings, report: &mut Report) {
    let bench = "monitor";
    const MONITORS: usize = 10;
    let mut spec = skills::robot("monitor");
    spec.skills = skills::chain("", 10, Flavor::Derive, true);
    let mut plain = skills::build(&spec);
    let mut watched = skills::build(&spec);
    skills::check_chain(&mut plain, "", 10);
    skills::check_chain(&mut watched, "", 10);
    for k in 0..MONITORS {
        let condition = format!("{}[0] > 1e9", skills::chain_signal("", k));
        if let Err(e) = watched.request(Request::AddMonitor {
            condition: condition.into(),
            mode: MonitorMode::Level,
            pause: false,
            report: Vec::new(),
            session: None,
            client: None,
        }) {
            panic!("monitor refused: {e}");
        }
    }
    let mut managers = [plain, watched];
    let out = interleaved(settings, 2, &mut |s, n| {
        let m = &mut managers[s];
        for _ in 0..n {
            m.cycle();
        }
    });
    report.figure(bench, "cycle, chain of 10", "ns", &out[0]);
    report.figure(bench, "cycle, chain of 10 + 10 monitors", "ns", &out[1]);
    report.figure(bench, "ratio with / without", "×", &ratio(&out[0], &out[1]));
    report.figure(
        bench,
        "cost per monitor per cycle",
        "ns",
        &paired(&out[0], &out[1], |a, b| (b - a) / MONITORS as f64),
    );
    report.figure(
        bench,
        "one monitor / one skill run",
        "×",
        &paired(&out[0], &out[1], |a, b| ((b - a) / MONITORS as f64) / (a / 10.0)),
    );
    report.print_table(bench, "5. monitor evaluation per cycle (no target)");
}

// ----- 6. parts of a skill run ------------------------------------------------

/// What one skill run costs besides the body, piece by piece, to explain
/// the chain's overhead: the pieces a manager's run of a `[f32; 24]` adder
/// is made of, measured alone.
fn parts(settings: &Settings, report: &mut Report) {
    let bench = "parts";
    let value = Value::F32s(Arc::from([1.0f32; skills::LEN]));
    let mut skill = skills::Add::create(&situate::Resources::new()).expect("an adder needs no resource");
    let inputs = [Some(value.clone())];
    let mut outputs = [None];
    let mut cx = situate::Context::new(0, 0.0);
    let arr = [1.0f32; skills::LEN];
    let out = interleaved(settings, 5, &mut |s, n| match s {
        0 => {
            for _ in 0..n {
                black_box(skills::add_call(black_box(&arr)));
            }
        }
        1 => {
            for _ in 0..n {
                black_box(Instant::now());
            }
        }
        2 => {
            for _ in 0..n {
                black_box(Arc::<[f32]>::from(black_box(arr)));
            }
        }
        3 => {
            for _ in 0..n {
                black_box(black_box(&value).clone());
            }
        }
        _ => {
            for _ in 0..n {
                let mut io = Io { inputs: &inputs, outputs: &mut outputs, cx: &mut cx };
                let _ = black_box(skill.step(&mut io));
            }
        }
    });
    report.figure(bench, "adder arithmetic, direct call", "ns", &out[0]);
    report.figure(bench, "Instant::now()", "ns", &out[1]);
    report.figure(bench, "Arc<[f32]> of 24: allocate + free", "ns", &out[2]);
    report.figure(bench, "Value::F32s clone + drop (atomic inc/dec)", "ns", &out[3]);
    report.figure(bench, "derived Add::step via dyn Skill (glue + body)", "ns", &out[4]);
    report.figure(bench, "derive glue = step − direct call", "ns", &paired(&out[0], &out[4], |a, b| b - a));
    report.print_table(bench, "6. pieces of one skill run, measured alone (no target; explains benchmark 1)");
}

// ----- record: the cost of recording -------------------------------------------

/// The delivery robot (demo/robot.yaml on the default building, its
/// corridor skills switched on), cycled back to back: alone, and with a
/// recording to MCAP (`situate_record`, its writer on a thread of its own
/// as in `situate run --record`). Issue 14's target: recorded ≤ 1.10×.
fn record(settings: &Settings, report: &mut Report) {
    use std::sync::Mutex;
    let bench = "record";
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let make = || -> Manager {
        let path = repo.join("demo/robot.yaml");
        let file = situate::manager::RobotFile::load(&path).unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
        let spec = situate::manager::RobotSpec::from_file(&file);
        let map = situate_sim::load_map(repo.join("maps/default.yaml")).unwrap_or_else(|e| panic!("{e}"));
        let world = Arc::new(Mutex::new(situate_sim::World::new(map, 1)));
        let mut registry = situate_toys::registry();
        situate_skills::register(&mut registry);
        situate_sim::register(&mut registry, world);
        let mut m = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
        let skills = ["follow_hallway", "avoid", "runaway", "detect_door", "watch_openings", "detect_intersection"];
        m.request(Request::Activate { skills: skills.iter().map(|s| s.to_string()).collect(), with_providers: true })
            .unwrap_or_else(|e| panic!("{e}"));
        m
    };
    let mut plain = make();
    let mut recorded = make();
    let mut tapped = make();
    let path = results_path("record-bench.mcap");
    let recorder = situate_record::Recorder::start(&path, &mut recorded).unwrap_or_else(|e| panic!("{e}"));
    // The cycle's side alone: a tap whose reader only gives the frames back,
    // polling as the recorder's writer does.
    let tap = tapped.tap(situate_record::QUEUE_FRAMES);
    let reader = std::thread::spawn(move || loop {
        loop {
            match tap.frames.try_recv() {
                Ok(frame) => tap.give_back(frame),
                Err(crossbeam_channel::TryRecvError::Empty) => break,
                Err(crossbeam_channel::TryRecvError::Disconnected) => return,
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    });
    let out = interleaved(settings, 3, &mut |s, iters| {
        let m = match s {
            0 => &mut plain,
            1 => &mut recorded,
            _ => &mut tapped,
        };
        for _ in 0..iters {
            m.cycle();
        }
    });
    drop(tapped);
    let _ = reader.join();
    drop(recorded);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    report.figure(bench, "delivery robot cycle, not recorded", "ns", &out[0]);
    report.figure(bench, "delivery robot cycle, recorded", "ns", &out[1]);
    report.figure(bench, "delivery robot cycle, tapped (frames only given back)", "ns", &out[2]);
    let r = ratio(&out[0], &out[1]);
    report.figure(bench, "recorded / not recorded", "×", &r);
    report.figure(bench, "tapped / not recorded (the cycle's own share)", "×", &ratio(&out[0], &out[2]));
    report.print_table(bench, "8. recording to MCAP vs not (the delivery robot, cycles back to back)");
    report.note(format!(
        "record: {} cycles written, {} messages, {} dropped, {:.1} MB",
        summary.frames,
        summary.messages,
        summary.dropped,
        summary.bytes as f64 / 1e6
    ));
    report.target(Target {
        bench: bench.into(),
        name: "cycle time with recording on vs off (delivery robot)".into(),
        unit: "×",
        value: r.median,
        target: "≤ 1.10×".into(),
        met: r.median <= 1.10,
        note: format!(
            "{} of {} cycles dropped (the writer fell 4,096 behind)",
            summary.dropped,
            summary.frames + summary.dropped
        ),
        inconclusive: None,
    });
}
