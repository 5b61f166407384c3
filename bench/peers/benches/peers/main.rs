//! The chain benchmark beside its peers: the same chain of N steps passing
//! `[f32; 24]`, each adding a constant, as situate skills, as bevy_ecs
//! systems on a single-threaded schedule and (with `--features copper`, for
//! N = 10 and 100) as copper-rs tasks, against the same direct-call
//! baseline, all interleaved in one run (see `bench/README.md`, "Peers").
//!
//! ```text
//! cd bench/peers && cargo bench --bench peers [--features copper] [-- --quick] [--samples N] [--json PATH]
//! ```

use std::hint::black_box;

use bevy_ecs::prelude::*;
use bevy_ecs::schedule::SingleThreadedExecutor;
use situate::manager::Manager;
use situate_bench::measure::{interleaved, paired, Settings, Summary};
use situate_bench::report::{results_path, CpuTimes, Machine, Report, Target};
use situate_bench::skills::{self, add_k, Flavor, K, LEN};

const NS: [usize; 3] = [10, 100, 1000];

/// The chain's signals as one resource: `sig[j]` is step `j`'s output.
#[derive(Resource)]
struct Signals {
    t: f32,
    sig: Vec<[f32; LEN]>,
}

/// Each step's output as a component of an entity of its own.
#[derive(Component, Clone, Copy)]
struct Sig([f32; LEN]);

/// Step `j` of a chain, to order the systems.
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Step(usize);

/// How the bevy_ecs systems pass the arrays.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Passing {
    /// Through one resource holding every step's array (no query).
    Resource,
    /// Through a component on one entity per step (a query for two entities).
    Components,
}

impl Passing {
    fn label(self) -> &'static str {
        match self {
            Passing::Resource => "bevy_ecs, arrays in a resource",
            Passing::Components => "bevy_ecs, arrays in components",
        }
    }
}

/// A chain of `n` systems, single-threaded, ordered step by step.
fn bevy_chain(n: usize, passing: Passing) -> (World, Schedule) {
    let mut world = World::new();
    let mut last_entity = None;
    let mut schedule = Schedule::default();
    schedule.set_executor(SingleThreadedExecutor::new());
    match passing {
        Passing::Resource => {
            world.insert_resource(Signals { t: 0.0, sig: vec![[0.0; LEN]; n] });
            schedule.add_systems(
                (|mut s: ResMut<Signals>| {
                    s.t += 1.0;
                    let t = s.t;
                    s.sig[0] = [t; LEN];
                })
                .in_set(Step(0)),
            );
            for j in 1..n {
                schedule.add_systems(
                    (move |mut s: ResMut<Signals>| {
                        let y = add_k(&s.sig[j - 1]);
                        s.sig[j] = y;
                    })
                    .in_set(Step(j))
                    .after(Step(j - 1)),
                );
            }
        }
        Passing::Components => {
            let ids: Vec<Entity> = (0..n).map(|_| world.spawn(Sig([0.0; LEN])).id()).collect();
            let first = ids[0];
            last_entity = ids.last().copied();
            let mut t = 0.0f32;
            schedule.add_systems(
                (move |mut q: Query<&mut Sig>| {
                    t += 1.0;
                    if let Ok(mut s) = q.get_mut(first) {
                        s.0 = [t; LEN];
                    }
                })
                .in_set(Step(0)),
            );
            for j in 1..n {
                let (a, b) = (ids[j - 1], ids[j]);
                schedule.add_systems(
                    (move |mut q: Query<&mut Sig>| {
                        if let Ok([x, mut y]) = q.get_many_mut([a, b]) {
                            y.0 = add_k(&x.0);
                        }
                    })
                    .in_set(Step(j))
                    .after(Step(j - 1)),
                );
            }
        }
    }
    schedule.run(&mut world);
    let last = match passing {
        Passing::Resource => world.resource::<Signals>().sig[n - 1],
        Passing::Components => last_entity.and_then(|e| world.get::<Sig>(e)).map_or([0.0; LEN], |s| s.0),
    };
    let want = 1.0 + (n - 1) as f32 * K;
    assert_eq!(last[0], want, "bevy_ecs chain of {n} ({passing:?}) did not run");
    (world, schedule)
}

fn situate_chain(n: usize) -> Manager {
    let mut spec = skills::robot("chain");
    spec.skills = skills::chain("", n, Flavor::Derive, true);
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "", n);
    m
}

const PASSINGS: [Passing; 2] = [Passing::Resource, Passing::Components];
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
            let (mut world, mut schedule) = bevy_chain(n, p);
            row.push((
                p.label(),
                Box::new(move |iters| {
                    for _ in 0..iters {
                        schedule.run(&mut world);
                    }
                }),
            ));
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
            if *label == Passing::Resource.label() {
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
        name: "chain overhead per step, situate / bevy_ecs (resource), worst of N = 10, 100, 1000".into(),
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
