//! Talking to a running robot: connecting as [`Remote`] says (`--connect`, `--zenoh`,
//! `--timeout`), finding the robot (`--robot`), and each client error said as one sentence
//! with its exit code (4 when no robot answered, 5 when the robot refused the request).

use std::time::Duration;

use serde_json::{json, Value as Json};
use situate_link::{Client, ClientError};

use super::command::Remote;
use crate::output::{Exit, Problem};

/// Connects, finds the robot and runs `f`; a client error becomes a
/// [`Problem`] of its kind (no robot answering, or the request refused).
pub(crate) fn client_verb(remote: &Remote, f: impl FnOnce(&Client, &str) -> anyhow::Result<()>) -> anyhow::Result<()> {
    let extra = match &remote.zenoh {
        None => None,
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| Problem::file_problem(format!("{}: cannot read: {e}", path.display())))?;
            Some(
                json5::from_str::<Json>(&text)
                    .map_err(|e| Problem::file_problem(format!("{}: {e}", path.display())))?,
            )
        }
    };
    let mut client = Client::connect_with(&remote.connect, extra.as_ref()).map_err(|e| client_problem(&e))?;
    // Clamped: `--timeout inf` or `nan` must not panic.
    client.timeout = Duration::from_secs_f64(if remote.timeout.is_finite() {
        remote.timeout.clamp(0.1, 86_400.0)
    } else {
        86_400.0
    });
    let robot = client.resolve_robot(remote.robot.as_deref()).map_err(|e| client_problem(&e))?;
    f(&client, &robot).map_err(|e| {
        if let Some(c) = e.downcast_ref::<ClientError>() {
            return client_problem(c);
        }
        if let Some(l) = e.downcast_ref::<situate_link::LinkError>() {
            return Problem::new(Exit::Failure, l.to_string()).said_by_situate().into();
        }
        e
    })
}

/// A client error, said as a sentence (`situate: …`): a manager's refusal
/// with its pointer line if any, never the link's raw data.
fn client_problem(e: &ClientError) -> anyhow::Error {
    let p = match e {
        ClientError::Remote(r) => Problem {
            after: r.detail.get("pointer").and_then(Json::as_str).map(str::to_string).into_iter().collect(),
            ..Problem::new(Exit::Refused, r.message.clone()).said_by_situate().with_detail(json!({"remote": r.detail}))
        },
        ClientError::NoAnswer { .. }
        | ClientError::TimedOut { .. }
        | ClientError::NotReachable { .. }
        | ClientError::Ambiguous(_)
        | ClientError::OtherRobots { .. } => Problem::new(Exit::NoRobot, e.to_string()).said_by_situate(),
        other => Problem::new(Exit::Failure, other.to_string()).said_by_situate(),
    };
    p.into()
}
