//! situate's chain (the derive flavour, `Manager::cycle`) run steadily,
//! unmeasured: a load for callgrind or `perf`, to count its instructions
//! and cache misses per step beside bevy_ecs 0.17's (`bevy017/examples/prof.rs`;
//! `bench/README.md`, "The sixth part"). Per step: the difference of two
//! runs of different length, divided by the extra steps, so set-up cancels.
//!
//! ```text
//! cd bench/peers && cargo build --release --example prof_situate
//! N=100 ITERS=1000 valgrind --tool=callgrind --cache-sim=yes target/release/examples/prof_situate
//! N=100 ITERS=3000 valgrind --tool=callgrind --cache-sim=yes target/release/examples/prof_situate
//! ```

use situate_bench::skills::{self, Flavor};

fn main() {
    let n: usize = std::env::var("N").ok().and_then(|v| v.parse().ok()).unwrap_or(100);
    let iters: u64 = std::env::var("ITERS").ok().and_then(|v| v.parse().ok()).unwrap_or(20_000);
    let mut spec = skills::robot("chain");
    spec.skills = skills::chain("", n, Flavor::Derive, true);
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "", n);
    for _ in 0..iters {
        m.cycle();
    }
}
