//! Robot files: the YAML file that says which skills a robot runs.
//!
//! [`RobotFile::parse`] reads a file into a model whose every name and value
//! keeps its position, and checks its shape: known keys, value types and
//! ranges, identifiers. It collects every such error it finds, in file order,
//! each reading `FILE:LINE:COL: error: message`. Whether skill types,
//! parameters and signals exist and fit together is checked later by the
//! manager against its registry; it reports through [`RobotFile::error`] in
//! the same format. The format is documented in `docs/robot-files.md`.
//!
//! One file per part: `robot_file.rs` (the model, reading, the top level),
//! `cycle.rs` (`cycle:`), `entries.rs` (`devices:` and `skills:`, their
//! `params:` and `remap:`), `paths.rs` (`libraries:`, `python:`, the paths
//! in `link.zenoh`), `remote.rs` (remote skills' manifests) and `check.rs`
//! (the checker and the value checks every section shares). The error type
//! is [`ConfigError`]; the bounds are in [`crate::limits`].

mod check;
mod cycle;
mod entries;
mod paths;
mod remote;
mod robot_file;
#[cfg(test)]
mod tests;

pub use crate::error::ConfigError;
pub use crate::include::{LoadOptions, SourceFile};
pub use crate::limits::{
    DEFAULT_RATE_HZ, MAX_DEADLINE_MS, MAX_ENTRIES, MAX_NAME_CHARS, MAX_RATE_HZ, MAX_ROBOT_FILE_BYTES, MAX_THREADS,
    MIN_PERIOD_MS, MIN_RATE_HZ,
};
pub use crate::names::{is_identifier, is_robot_name, is_signal_name};
pub use crate::yaml::{Node, Pos, Spanned};
pub use cycle::{ClockKind, CycleConfig, ExecutorKind};
pub use entries::{Param, Section, SkillEntry};
pub use paths::ZENOH_PATH_KEYS;
pub use robot_file::RobotFile;
