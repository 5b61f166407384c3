//! Robot files, the front end of situate: what a robot runs, read from YAML
//! with a position on every name and value, so that every error reads
//! `FILE:LINE:COL: error: message`.
//!
//! - [`yaml`]: the YAML reader (a node tree that remembers positions);
//! - [`config`]: robot files, their sections and shape checks;
//! - [`include`]: `include:` and `${ENV}` substitution;
//! - [`manifest`]: a skill's declaration written as data;
//! - [`spec`]: a robot as plain data, from a file or from code;
//! - [`diagnostic`]: a message at a position, the one type of every problem
//!   found (a robot file's [`error::ConfigError`] is one);
//! - [`limits`], [`names`] and [`error`]: what a file may hold, what a name
//!   may be, and the error of a robot file.
//!
//! The modules form layers, each using only those above it: `yaml`,
//! `limits` and `names`; `diagnostic` and `error`; `include` and `manifest`; `config`;
//! `spec`.
//!
//! Whether skill types, parameters and signals exist and fit together is
//! checked by the skill manager (`situate_manager`), which re-exports these
//! modules under the paths they had there.

pub mod config;
pub mod diagnostic;
pub mod error;
pub mod include;
pub mod limits;
pub mod manifest;
pub mod names;
pub mod spec;
pub mod yaml;
