//! The sequencer link (paper 3.2.2): the skill manager's control API, its
//! events and telemetry, and remote skills, over Zenoh. The wire protocol is
//! `docs/protocol.md`; this crate is its reference implementation.

pub mod client;
pub mod client_session;
pub mod flood;
pub mod json;
mod port;
pub mod remote;
pub mod server;
pub mod session;

pub use client::{Client, ClientError, RemoteError};
pub use port::free_loopback_port;
pub use remote::{serve_skill, HostError, HostStats, RemoteSkill};
pub use server::{Link, VerbFn, Verbs};
pub use session::{LinkConfig, DEFAULT_ENDPOINT};

/// Why the link could not be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinkError {
    #[error("link configuration: {0}")]
    Config(String),
    #[error("could not open the Zenoh session: {0}")]
    Open(String),
}
