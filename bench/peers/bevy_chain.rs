//! The chain as bevy_ecs systems, written once and compiled against each
//! release of bevy_ecs that `bench/peers` measures: the bench itself
//! includes it against bevy_ecs 0.20 (`benches/peers/main.rs`), the crate
//! `bevy017/` against 0.17 (the faster release on the chain: issue 36). A
//! file included by both, since one crate cannot name two releases of
//! bevy_ecs to its derive macros. The includer defines
//! `single_threaded(&mut Schedule)`, which the releases spell differently.

use bevy_ecs::prelude::*;
use situate_bench::skills::{add_k, K, LEN};

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

/// A chain of `n` systems, single-threaded, ordered step by step, passing
/// the arrays through one resource holding every step's array (no query:
/// `resource`) or through a component on one entity per step (a query for
/// two entities). Checked to compute the chain once; returns a runner of
/// `iters` cycles of it.
pub fn chain(n: usize, resource: bool) -> Box<dyn FnMut(u64)> {
    let mut world = World::new();
    let mut last_entity = None;
    let mut schedule = Schedule::default();
    // Each release names its single-threaded executor its own way.
    super::single_threaded(&mut schedule);
    if resource {
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
    } else {
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
    schedule.run(&mut world);
    let last = if resource {
        world.resource::<Signals>().sig[n - 1]
    } else {
        last_entity.and_then(|e| world.get::<Sig>(e)).map_or([0.0; LEN], |s| s.0)
    };
    let want = 1.0 + (n - 1) as f32 * K;
    assert_eq!(last[0], want, "bevy_ecs chain of {n} (resource: {resource}) did not run");
    Box::new(move |iters| {
        for _ in 0..iters {
            schedule.run(&mut world);
        }
    })
}
