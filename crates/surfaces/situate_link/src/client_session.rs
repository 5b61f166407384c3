//! Client sessions: who holds a monitor, and when it is let go.
//!
//! A monitor belongs to the session that added it: only that session cancels
//! it, the session's monitors count against its own allowance
//! ([`situate_manager::MAX_MONITORS_PER_SESSION`]), and they are removed when
//! the session ends, so a sequencer that crashes leaves nothing behind.
//!
//! The link is a set of stateless Zenoh queries, so a session is made of two
//! things the client holds (docs/protocol.md, "Sessions"):
//! - a **secret**: 32 to 128 characters of `[0-9A-Za-z_-]`, random (at least
//!   128 bits), sent as `session` with `monitor_add` and `monitor_cancel`;
//! - a **liveliness token** on `situate/<robot>/session/<id>`, where `<id>`
//!   is the session's public id: the first 16 bytes of the secret's
//!   SHA3-256, in lowercase hex. The token lives as long as the client's Zenoh
//!   session; when it goes (closed, crashed, unplugged) the manager removes
//!   the session's monitors.
//!
//! The manager, lists and events only ever show the public id, from which the
//! secret cannot be found: knowing whose a monitor is does not let anyone
//! cancel it. Sessions are not authentication: a client may open as many as
//! it likes (each with its allowance); keep strangers off the link with
//! Zenoh's access control and TLS (the robot file's `link:`).

use std::collections::{HashSet, VecDeque};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use sha3::{Digest, Sha3_256};
use situate_manager::{Handle, Request};
use zenoh::sample::SampleKind;
use zenoh::{Session, Wait};

use crate::json::WireError;

/// The shortest secret taken, in characters.
pub const MIN_SECRET_CHARS: usize = 32;
/// The longest secret taken, in characters.
pub const MAX_SECRET_CHARS: usize = 128;
/// How long the link waits for a session's liveliness token it has not seen
/// yet (its declaration may still be on its way when the first request comes).
const TOKEN_WAIT: Duration = Duration::from_secs(2);
/// How many ended sessions the link remembers (a request of one of them that
/// arrives after it ended is refused, not taken as a new session's).
const ENDED_KEPT: usize = 4096;

/// A session's public id from its secret, or why the secret is not one.
pub fn public_id(secret: &str) -> Result<String, WireError> {
    let n = secret.chars().count();
    if !(MIN_SECRET_CHARS..=MAX_SECRET_CHARS).contains(&n)
        || !secret.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
    {
        return Err(WireError::bad_request(format!(
            "argument `session`: expected a secret of {MIN_SECRET_CHARS} to {MAX_SECRET_CHARS} characters \
             [0-9A-Za-z_-] (random, at least 128 bits), got {n} characters{}",
            if n > 0 && secret.bytes().any(|b| !(b.is_ascii_alphanumeric() || b == b'_' || b == b'-')) {
                " with others among them"
            } else {
                ""
            }
        )));
    }
    let digest = Sha3_256::digest(secret.as_bytes());
    Ok(digest[..16].iter().map(|b| format!("{b:02x}")).collect())
}

/// The key of the liveliness token that keeps session `id` of `robot` alive.
pub fn token_key(robot: &str, id: &str) -> String {
    format!("situate/{robot}/session/{id}")
}

/// A fresh secret: 32 hex characters of the OS's randomness (128 bits).
pub fn new_secret() -> Result<String, String> {
    let mut bytes = [0u8; 16];
    getrandom::fill(&mut bytes).map_err(|e| format!("no randomness for a session secret: {e}"))?;
    Ok(bytes.iter().map(|b| format!("{b:02x}")).collect())
}

/// The sessions the link knows: alive (their token seen) and recently ended.
#[derive(Default)]
struct Known {
    alive: HashSet<String>,
    ended: HashSet<String>,
    ended_order: VecDeque<String>,
}

impl Known {
    fn end(&mut self, id: &str) -> bool {
        let was = self.alive.remove(id);
        if self.ended.insert(id.to_string()) {
            self.ended_order.push_back(id.to_string());
            if self.ended_order.len() > ENDED_KEPT {
                if let Some(old) = self.ended_order.pop_front() {
                    self.ended.remove(&old);
                }
            }
        }
        was
    }
}

/// The link's view of its clients' sessions: it watches their tokens and
/// tells the manager when one ends.
#[derive(Clone)]
pub struct Sessions {
    robot: String,
    session: Session,
    handle: Handle,
    known: Arc<Mutex<Known>>,
}

impl Sessions {
    /// Starts watching the session tokens of `robot` on `session`; each one
    /// that goes ends its session's monitors through `handle`.
    pub fn watch(robot: &str, session: &Session, handle: &Handle) -> Result<Sessions, crate::LinkError> {
        let sessions = Sessions {
            robot: robot.to_string(),
            session: session.clone(),
            handle: handle.clone(),
            known: Arc::new(Mutex::new(Known::default())),
        };
        let watcher = sessions.clone();
        let prefix = token_key(robot, "");
        session
            .liveliness()
            .declare_subscriber(token_key(robot, "*"))
            .history(true)
            .callback(move |sample| {
                let Some(id) = sample.key_expr().as_str().strip_prefix(&prefix) else { return };
                match sample.kind() {
                    SampleKind::Put => {
                        let mut known = watcher.lock();
                        if !known.ended.contains(id) {
                            known.alive.insert(id.to_string());
                        }
                    }
                    SampleKind::Delete => watcher.end(id),
                }
            })
            .background()
            .wait()
            .map_err(|e| crate::LinkError::Open(format!("cannot watch the clients' sessions: {e}")))?;
        Ok(sessions)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Known> {
        self.known.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Session `id` ended: the manager removes its monitors. The request is
    /// sent under the lock that [`Sessions::submit_for`] holds while it
    /// submits, so a request of the session queued before its end is handled
    /// before it, and none after.
    fn end(&self, id: &str) {
        let mut known = self.lock();
        known.end(id);
        if let Err(e) = self.handle.submit(Request::EndSession { session: id.to_string() }) {
            tracing::debug!(error = %e, session = id, "could not end a session");
        }
        drop(known);
        tracing::debug!(session = id, "a client's session ended");
    }

    /// Submits `request` (of session `id`) once the session is known alive:
    /// seen already, or its token found now (waiting at most a moment); a
    /// session whose token is not there, or that ended, is refused.
    pub fn submit_for(
        &self,
        id: &str,
        request: Request,
    ) -> Result<situate_manager::Pending, Result<WireError, situate_manager::ControlError>> {
        let seen = {
            let known = self.lock();
            if known.ended.contains(id) {
                return Err(Ok(self.refusal(id, "has ended (its liveliness token went away)")));
            }
            known.alive.contains(id)
        };
        if !seen && !self.token_exists(id) {
            return Err(Ok(self.refusal(id, "has no liveliness token")));
        }
        let mut known = self.lock();
        if known.ended.contains(id) {
            return Err(Ok(self.refusal(id, "has ended (its liveliness token went away)")));
        }
        known.alive.insert(id.to_string());
        self.handle.submit(request).map_err(Err)
    }

    fn refusal(&self, id: &str, why: &str) -> WireError {
        WireError {
            kind: "no_session",
            message: format!(
                "session `{id}` {why}: a client declares a liveliness token on `{}` for as long as it \
                 holds monitors (docs/protocol.md, \"Sessions\")",
                token_key(&self.robot, id)
            ),
        }
    }

    /// Whether session `id`'s token is there now (asked on the network).
    fn token_exists(&self, id: &str) -> bool {
        let replies = match self.session.liveliness().get(token_key(&self.robot, id)).timeout(TOKEN_WAIT).wait() {
            Ok(r) => r,
            Err(e) => {
                tracing::debug!(error = %e, "could not ask for a session's token");
                return false;
            }
        };
        let mut found = false;
        while let Ok(reply) = replies.recv() {
            found |= reply.result().is_ok();
        }
        found
    }
}

/// A client's own session: its secret, public id and liveliness token.
pub struct ClientSession {
    secret: String,
    id: String,
    _token: zenoh::liveliness::LivelinessToken,
}

impl ClientSession {
    /// Opens a session with `robot` on `session`: a fresh secret, and its token declared.
    pub fn open(session: &Session, robot: &str) -> Result<ClientSession, String> {
        let secret = new_secret()?;
        let id = public_id(&secret).map_err(|e| e.message)?;
        let token = session
            .liveliness()
            .declare_token(token_key(robot, &id))
            .wait()
            .map_err(|e| format!("cannot declare the session's liveliness token: {e}"))?;
        Ok(ClientSession { secret, id, _token: token })
    }

    /// What requests send as `session`.
    pub fn secret(&self) -> &str {
        &self.secret
    }

    /// The public id the manager shows.
    pub fn id(&self) -> &str {
        &self.id
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_public_id_is_the_secrets_sha3_and_bad_secrets_are_named() {
        // Computed independently: Python's hashlib.sha3_256(b"a" * 32).hexdigest()[:32].
        let id = public_id(&"a".repeat(32)).unwrap();
        assert_eq!(id, "2eee42b299cb44bb3d5dd0a02210ce29");
        assert_ne!(id, public_id(&"b".repeat(32)).unwrap());
        for (bad, says) in [
            ("short", "got 5 characters"),
            (&"x".repeat(129) as &str, "got 129 characters"),
            (&format!("{}/", "a".repeat(40)) as &str, "with others among them"),
        ] {
            let e = public_id(bad).unwrap_err();
            assert_eq!(e.kind, "bad_request");
            assert!(e.message.contains(says), "{}", e.message);
        }
    }

    #[test]
    fn fresh_secrets_are_valid_and_differ() {
        let a = new_secret().unwrap();
        let b = new_secret().unwrap();
        assert_ne!(a, b);
        assert!(public_id(&a).is_ok());
    }
}
