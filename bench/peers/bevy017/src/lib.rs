//! The chain on bevy_ecs 0.17 (see `../../bevy_chain.rs`).

#[path = "../../bevy_chain.rs"]
mod bevy_chain;

pub use bevy_chain::chain;

/// bevy_ecs 0.17's single-threaded executor.
fn single_threaded(schedule: &mut bevy_ecs::schedule::Schedule) {
    schedule.set_executor_kind(bevy_ecs::schedule::ExecutorKind::SingleThreaded);
}
