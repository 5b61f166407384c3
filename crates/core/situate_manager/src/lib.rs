//! The skill manager of situate (paper 3.2): it wires skills by their
//! declarations, runs the periodic data-flow cycle, arbitrates resources by
//! priority, watches monitors, and answers the sequencer's requests.
//!
//! - [`graph`]: signals, leaves, resources, and every static check;
//! - [`manager`]: the cycle, the executors, the control API's handling;
//! - [`control`]: requests, replies, events, handles;
//! - [`expr`] and [`monitor`]: monitor conditions;
//! - [`config`], [`yaml`], [`include`], [`manifest`] and [`spec`]: robot
//!   files and a robot as plain data, the crate `situate_robotfile`, here
//!   under the paths they have always had.

pub mod control;
mod handle;
/// The condition language of monitors: the crate `situate_expr`, here under
/// the path it has always had.
pub use situate_expr as expr;
pub mod frame;
pub mod graph;
pub mod manager;
pub mod monitor;
pub mod registry;
mod runner;
mod starved;
pub mod supervise;
/// The robot-file front end: the crate `situate_robotfile`, here under the
/// paths it has always had.
pub use situate_robotfile::{config, include, manifest, spec, yaml};

pub use config::{ClockKind, ExecutorKind, RobotFile};
pub use control::{
    CancelReason, Control, ControlError, Event, Handle, ManagerStats, MonitorInfo, Pending, PortInfo, Reply, Request,
    ResourceWinner, SignalReading, SkillInfo, SkillTiming, MAX_PHASE_TEXT,
};
pub use frame::{Frame, FrameValues};
pub use graph::Graph;
pub use manager::{Joiner, Manager, TapReceiver, MAX_MONITORS, MAX_MONITORS_PER_SESSION};
pub use monitor::{MonitorCondition, MonitorMode, MAX_ANY_CONDITIONS};
pub use registry::Registry;
pub use spec::{BuildError, Diagnostic, RobotSpec, Severity, SkillSpec};
