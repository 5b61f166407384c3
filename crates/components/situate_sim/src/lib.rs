//! A deterministic 2-D simulator of a Denning-like robot in a multi-floor
//! building (the delivery experiment of the paper's section 6): fixed time
//! step, seeded noise, identical runs for identical seeds.
//!
//! - [`load_map`] reads a building (format: `docs/maps.md`);
//! - [`World`] simulates it: differential drive, 24 sonars, barcode reader,
//!   button arm, speaker, four elevator cars; optionally people walking
//!   ([`people`]), doors closed now and then, dead sonars ([`WorldConfig`]);
//! - [`registry`] makes the dskills (`sim.sonar`, `sim.base`, `sim.barcode`,
//!   `sim.arm`, `sim.speaker`, `sim.altimeter`, `sim.truth`) over one shared
//!   world, with the ports of the robot's signal contract (`situate_robot`).

pub mod check;
pub mod elevator;
pub mod generate;
pub mod geom;
pub mod map;
pub mod people;
pub mod skills;
pub mod task;
pub mod traffic;
pub mod world;

pub use map::{load_map, Map};
pub use situate_robotfile::diagnostic::Diagnostic;
pub use skills::{declarations, register, registry, SharedWorld};
pub use world::{BaseLimits, SonarSettings, World, WorldConfig};
