//! Benchmarks of the skill manager, as ratios measured within one run.
//!
//! `cargo bench -p situate_bench --bench core` runs them all (see
//! `bench/README.md`); this library holds what the bench target uses:
//! [`measure`] (sampling and statistics), [`report`] (tables, `TARGET`
//! lines, JSON) and [`skills`] (the skills and robots measured).

pub mod measure;
pub mod report;
pub mod skills;
