//! The bevy_ecs 0.17 chain run steadily, unmeasured: a load for callgrind
//! or `perf`, to count its instructions and cache misses per system beside
//! situate's (`core --profile`; `bench/README.md`, "The fifth part").
//!
//! ```text
//! cd bench/peers && cargo build --release -p situate_peers_bevy017 --example prof
//! N=100 ITERS=4000 valgrind --tool=callgrind --cache-sim=yes target/release/examples/prof
//! ```

fn main() {
    let n: usize = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    let iters: u64 = std::env::var("ITERS").ok().and_then(|v| v.parse().ok()).unwrap_or(20_000);
    let mut run = situate_peers_bevy017::chain(n, true);
    run(iters);
}
