//! The chain benchmark beside its peers: the same chain of N steps passing
//! `[f32; 24]`, each adding a constant, as situate skills, as bevy_ecs
//! systems on a single-threaded schedule (releases 0.20 and 0.17, the
//! fastest on this chain) and (with `--features copper`, for
//! N = 10 and 100) as copper-rs tasks, against the same direct-call
//! baseline, all interleaved in one run (see `bench/README.md`, "Peers").
//!
//! ```text
//! cd bench/peers && cargo bench --bench peers [--features copper] [-- --quick] [--samples N] [--json PATH]
//! ```

use std::hint::black_box;

use situate::manager::Manager;
use situate_bench::measure::{interleaved, paired, Settings, Summary};
use situate_bench::report::{results_path, CpuTimes, Machine, Report, Target};
use situate_bench::skills::{self, Flavor};

const NS: [usize; 3] = [10, 100, 1000];

/// The chain on bevy_ecs 0.20 (this crate's bevy_ecs); 0.17 is the crate
/// `situate_peers_bevy017`, the same source (`bevy_chain.rs`).
#[path = "../../bevy_chain.rs"]
mod bevy020;

/// bevy_ecs 0.20's single-threaded executor (for `bevy020`).
fn single_threaded(schedule: &mut bevy_ecs::schedule::Schedule) {
    schedule.set_executor(bevy_ecs::schedule::SingleThreadedExecutor::new());
}

/// How the bevy_ecs systems pass the arrays.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Passing {
    /// Through one resource holding every step's array (no query).
    Resource,
    /// Through a component on one entity per step (a query for two entities).
    Components,
}

/// The releases of bevy_ecs measured: the latest, and the fastest on this
/// chain (0.17: 13–16 ns per system where 0.20 took 20–25 ns, issue 36).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Release {
    V020,
    V017,
}

impl Release {
    fn chain(self, n: usize, passing: Passing) -> Box<dyn FnMut(u64)> {
        let resource = passing == Passing::Resource;
        match self {
            Release::V020 => bevy020::chain(n, resource),
            Release::V017 => situate_peers_bevy017::chain(n, resource),
        }
    }

    fn label(self, passing: Passing) -> &'static str {
        match (self, passing) {
            (Release::V020, Passing::Resource) => "bevy_ecs 0.20, arrays in a resource",
            (Release::V020, Passing::Components) => "bevy_ecs 0.20, arrays in components",
            (Release::V017, Passing::Resource) => "bevy_ecs 0.17, arrays in a resource",
            (Release::V017, Passing::Components) => "bevy_ecs 0.17, arrays in components",
        }
    }
}

fn situate_chain(n: usize) -> Manager {
    let mut spec = skills::robot("chain");
    spec.skills = skills::chain("", n, Flavor::Derive, true);
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "", n);
    m
}

const PASSINGS: [Passing; 2] = [Passing::Resource, Passing::Components];
const RELEASES: [Release; 2] = [Release::V020, Release::V017];
const SITUATE: &str = "situate (derive [f32; 24])";
#[cfg(feature = "copper")]
const COPPER: &str = "copper-rs (cu29 tasks)";

#[cfg(feature = "copper")]
mod copper;

fn main() {
    let (settings, json) = Settings::from_args("peers", std::env::args().skip(1)).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let machine = Machine::detect(&std::env::args().skip(1).collect::<Vec<_>>().join(" "));
    let mut report = Report::default();
    let bench = "peers";
    let cpu0 = CpuTimes::now();

    // Per N: the baseline, situate, then the peers; each subject runs
    // `iters` cycles of its chain.
    type Subject = Box<dyn FnMut(u64)>;
    #[cfg(feature = "copper")]
    let copper_dir = std::env::temp_dir().join(format!("situate-peers-{}", std::process::id()));
    #[cfg(feature = "copper")]
    if let Err(e) = std::fs::create_dir_all(&copper_dir) {
        panic!("{}: {e}", copper_dir.display());
    }
    let mut labels: Vec<Vec<&'static str>> = Vec::new();
    let mut subjects: Vec<Subject> = Vec::new();
    for &n in &NS {
        let mut t = 0.0f32;
        let mut row: Vec<(&'static str, Subject)> = vec![(
            "baseline: direct calls",
            Box::new(move |iters| {
                for _ in 0..iters {
                    black_box(skills::baseline_chain(n, &mut t));
                }
            }),
        )];
        let mut m = situate_chain(n);
        row.push((
            SITUATE,
            Box::new(move |iters| {
                for _ in 0..iters {
                    m.cycle();
                }
            }),
        ));
        for p in PASSINGS {
            for r in RELEASES {
                row.push((r.label(p), r.chain(n, p)));
            }
        }
        #[cfg(feature = "copper")]
        if copper::NS.contains(&n) {
            let mut step = copper::chain(n, &copper_dir);
            row.push((
                COPPER,
                Box::new(move |iters| {
                    for _ in 0..iters {
                        step();
                    }
                }),
            ));
        }
        labels.push(row.iter().map(|(l, _)| *l).collect());
        subjects.extend(row.into_iter().map(|(_, s)| s));
    }
    let out = interleaved(&settings, subjects.len(), &mut |s, iters| subjects[s](iters));

    let mut worst_ratio: Vec<(usize, Summary)> = Vec::new();
    let mut at = 0;
    for (ni, &n) in NS.iter().enumerate() {
        let row = &out[at..at + labels[ni].len()];
        at += labels[ni].len();
        let base = &row[0];
        report.figure(bench, &format!("N={n:<4} baseline: direct calls"), "ns", base);
        for (label, cyc) in labels[ni].iter().zip(row).skip(1) {
            let o = paired(base, cyc, |b, c| (c - b) / n as f64);
            report.figure(bench, &format!("N={n:<4} overhead per step, {label}"), "ns", &o);
        }
        // Per round: situate's overhead over each peer's, both from that
        // round's baseline.
        let sit = &row[1];
        for (label, peer) in labels[ni].iter().zip(row).skip(2) {
            let r = Summary::of(
                base.samples.iter().zip(&sit.samples).zip(&peer.samples).map(|((b, s), v)| (s - b) / (v - b)).collect(),
            );
            report.figure(bench, &format!("N={n:<4} situate / {label} (per-step overhead)"), "×", &r);
            // Against every release: the target is to beat the fastest.
            if RELEASES.iter().any(|r| *label == r.label(Passing::Resource)) {
                worst_ratio.push((n, r));
            }
        }
    }
    #[cfg(feature = "copper")]
    drop(std::fs::remove_dir_all(&copper_dir));
    report.print_table(bench, "chain of N steps passing f32[24]: situate beside its peers (single-threaded), one run");
    let share = cpu0.and_then(|c| c.since(&CpuTimes::now()?));
    let (wn, w) = worst_ratio.iter().fold((0, f64::MIN), |a, (n, r)| if r.median > a.1 { (*n, r.median) } else { a });
    let inconclusive = share.filter(|s| s.busy()).map(|s| format!("the machine was busy ({s})"));
    if let Some(s) = share {
        report.note(format!("peers: {s}"));
    }
    report.target(Target {
        bench: bench.into(),
        name: "chain overhead per step, situate / bevy_ecs (resource, each release), worst of N = 10, 100, 1000".into(),
        unit: "×",
        value: w,
        target: "< 1×".into(),
        met: w < 1.0,
        note: format!("worst at N={wn}"),
        inconclusive,
    });
    let path = json.unwrap_or_else(|| results_path("peers.json"));
    match report.write_json(&path, &machine) {
        Ok(()) => println!("results: {}", path.display()),
        Err(e) => eprintln!("could not write {}: {e}", path.display()),
    }
}
