//! Worker threads that never die silently.
//!
//! A thread started with [`supervise`] runs its body again after a panic,
//! with a report: a `tracing` error, and a [`Event::WorkerFailed`] on the
//! manager's event bus (also counted in `stats`' `worker_failures`), which
//! the link publishes like every event. A body that keeps panicking
//! (more than [`MAX_RESTARTS`] times within a minute) is not restarted: the
//! report says so and the robot is stopped (`stop`), since what the thread
//! did (answering requests, publishing events) is gone.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::control::{Event, Handle, Request};

/// The most restarts of one thread within [`RESTART_WINDOW`].
pub const MAX_RESTARTS: usize = 5;
pub const RESTART_WINDOW: Duration = Duration::from_secs(60);

/// A panic's message.
pub fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// Starts thread `name` running `body` until it returns; after a panic, it
/// is reported through `handle` and `body` runs again (see the module).
pub fn supervise(
    name: &str,
    handle: Handle,
    mut body: impl FnMut() + Send + 'static,
) -> std::io::Result<JoinHandle<()>> {
    let thread = name.to_string();
    std::thread::Builder::new().name(thread.clone()).spawn(move || {
        let mut failures: Vec<Instant> = Vec::new();
        loop {
            let panic = match catch_unwind(AssertUnwindSafe(&mut body)) {
                Ok(()) => return,
                Err(panic) => panic_message(&*panic),
            };
            let now = Instant::now();
            failures.retain(|t| now.duration_since(*t) < RESTART_WINDOW);
            failures.push(now);
            let restart = failures.len() <= MAX_RESTARTS;
            let action = if restart {
                "restarted".to_string()
            } else {
                format!(
                    "not restarted ({} panics within {} s): the robot is stopped",
                    failures.len(),
                    RESTART_WINDOW.as_secs()
                )
            };
            tracing::error!(thread = %thread, cause = %panic, %action, "a worker thread panicked");
            handle.report(Event::WorkerFailed {
                thread: thread.clone(),
                cause: format!("panicked: {panic}"),
                action: action.clone(),
            });
            if !restart {
                let _ = handle.request_timeout(Request::Stop, Duration::from_secs(5));
                return;
            }
        }
    })
}
