//! The skill model of situate: signal types and values, skill declarations,
//! parameters, and the traits a skill implements.
//!
//! This crate does no I/O and knows nothing of scheduling; the skill manager
//! (`situate_manager`) builds on it, and so do the language bindings.

pub mod decl;
pub mod names;
pub mod resources;
pub mod skill;
pub mod types;
pub mod value;

pub use decl::{ParamSpec, ParamType, ParamValue, ParamValueError, PortSpec, SkillDecl, SkillKind};
pub use names::{did_you_mean, param_suggestion, suggestion};
pub use resources::{ResourceError, Resources};
pub use skill::{Body, Context, Declare, FnSkill, Io, Skill, SkillError, SkillMaker, SkillType};
pub use types::{ElemType, RecordType, SignalType, TypeParseError};
#[doc(hidden)]
pub use value::{fill_field, record_fields_to_fill, record_names, record_of};
pub use value::{record_type, record_value, RecordValue, SignalValue, Value, ValueRef};
