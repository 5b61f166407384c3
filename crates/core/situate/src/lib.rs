//! Situate: the reactive layer of a robot.
//!
//! A skill is written by giving its inputs, outputs and computational body;
//! wiring, scheduling, the link to the sequencer and display are derived from
//! that declaration. Start with the [`prelude`].

pub use situate_core::*;
pub use situate_derive::{Record, Skill};
/// The skill manager: the cycle, the control API, robot files.
pub use situate_manager as manager;

/// What generated code names; not a public API.
#[doc(hidden)]
pub use situate_core as __core;

/// Everything needed to write a skill.
pub mod prelude {
    pub use situate_core::{
        sprint, Body, Context, Declare, SignalValue, Skill as SkillTrait, SkillError, SkillKind, Value,
    };
    pub use situate_derive::{Record, Skill};
    pub use std::sync::Arc;
}
