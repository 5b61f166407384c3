//! Stopping on a signal. SIGINT (Ctrl-C), SIGTERM and SIGHUP all ask the
//! program for a clean stop; a second one of any of them ends it at once,
//! with status 128 + the signal's number (130 for SIGINT).
//!
//! The handlers are signal-hook's: they only store atomics, and a second
//! signal writes one line to stderr and calls `_exit`, all of which is
//! async-signal-safe. They are in place while a [`Stop`] lives.

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context as _;
use signal_hook::consts::{SIGINT, SIGTERM};
use signal_hook::SigId;

/// The signals that ask for a stop.
#[cfg(unix)]
const SIGNALS: &[i32] = &[SIGINT, SIGTERM, signal_hook::consts::SIGHUP];
#[cfg(not(unix))]
const SIGNALS: &[i32] = &[SIGINT, SIGTERM];

/// How long a stop may take, from the request, before the program gives up
/// on what has not stopped and exits without it: 2 s, or
/// `$SITUATE_STOP_TIMEOUT_S` seconds (for a robot whose parts take longer
/// to stop).
pub(crate) fn stop_bound() -> Duration {
    static BOUND: std::sync::OnceLock<Duration> = std::sync::OnceLock::new();
    *BOUND.get_or_init(|| {
        std::env::var("SITUATE_STOP_TIMEOUT_S")
            .ok()
            .and_then(|s| s.trim().parse::<f64>().ok())
            .filter(|s| s.is_finite() && *s >= 0.0)
            .map_or(Duration::from_secs(2), |s| Duration::from_secs_f64(s.min(86_400.0)))
    })
}

/// [`stop_bound`] for messages: `2 s`.
pub(crate) fn bound_text() -> String {
    format!("{} s", stop_bound().as_secs_f64())
}

#[derive(Default)]
struct State {
    /// A stop was asked for (what `situate_link::serve_skill` polls).
    requested: AtomicBool,
    /// The first signal received, 0 before.
    signal: AtomicI32,
}

/// SIGINT, SIGTERM and SIGHUP handled as stop requests, while this lives.
pub(crate) struct Stop {
    state: Arc<State>,
    ids: Vec<SigId>,
}

impl Stop {
    /// Installs the handlers.
    pub(crate) fn install() -> anyhow::Result<Stop> {
        let state = Arc::new(State::default());
        let mut ids = Vec::new();
        for &sig in SIGNALS {
            let s = Arc::clone(&state);
            // SAFETY: the action only touches atomics, write(2) and _exit, all
            // async-signal-safe; it allocates nothing and takes no lock.
            let id = unsafe { signal_hook::low_level::register(sig, move || on_signal(&s, sig)) }
                .with_context(|| format!("handling {}", name(sig)))?;
            ids.push(id);
        }
        Ok(Stop { state, ids })
    }

    /// The signal that asked for a stop, if one did.
    pub(crate) fn signal(&self) -> Option<i32> {
        match self.state.signal.load(Ordering::SeqCst) {
            0 => None,
            n => Some(n),
        }
    }

    /// Set once a stop is asked for.
    pub(crate) fn flag(&self) -> &AtomicBool {
        &self.state.requested
    }

    /// Once a stop is asked for, says so and gives the caller [`stop_bound`]
    /// to finish (to drop the returned guard); after that prints `why` and
    /// ends the process with status 1. For work that cannot be abandoned otherwise,
    /// such as a skill's body running on the caller's own thread.
    pub(crate) fn watchdog(&self, why: impl FnOnce() -> String + Send + 'static) -> Watchdog {
        let (done, until) = crossbeam_channel::bounded::<()>(0);
        let state = Arc::clone(&self.state);
        let spawned = std::thread::Builder::new().name("situate-stop".into()).spawn(move || {
            use crossbeam_channel::RecvTimeoutError::{Disconnected, Timeout};
            loop {
                match until.recv_timeout(Duration::from_millis(50)) {
                    Err(Disconnected) | Ok(()) => return,
                    Err(Timeout) if state.requested.load(Ordering::SeqCst) => {
                        let sig = state.signal.load(Ordering::SeqCst);
                        eprintln!("situate: {}: stopping (again to exit at once)", name(sig));
                        break;
                    }
                    Err(Timeout) => {}
                }
            }
            if let Err(Timeout) = until.recv_timeout(stop_bound()) {
                eprintln!("situate: {}", why());
                std::process::exit(1);
            }
        });
        if let Err(e) = spawned {
            tracing::warn!("no watchdog for the stop: {e}");
        }
        Watchdog { _done: done }
    }
}

impl Drop for Stop {
    fn drop(&mut self) {
        for id in self.ids.drain(..) {
            signal_hook::low_level::unregister(id);
        }
    }
}

/// The caller has finished: dropping this tells [`Stop::watchdog`].
pub(crate) struct Watchdog {
    _done: crossbeam_channel::Sender<()>,
}

/// `SIGINT`, `SIGTERM`, …
pub(crate) fn name(sig: i32) -> &'static str {
    signal_hook::low_level::signal_name(sig).unwrap_or("a signal")
}

/// The exit status of a process ended by a stop that `sig` asked for.
pub(crate) fn status(sig: i32) -> u8 {
    u8::try_from(128 + sig).unwrap_or(255)
}

fn on_signal(state: &State, sig: i32) {
    if state.signal.compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst).is_err() {
        write_stderr(b"\nsituate: ");
        write_stderr(name(sig).as_bytes());
        write_stderr(b" while stopping: exiting at once\n");
        signal_hook::low_level::exit(128 + sig);
    }
    state.requested.store(true, Ordering::SeqCst);
}

/// write(2) to stderr, which a signal handler may call (std's stderr takes a lock).
fn write_stderr(bytes: &[u8]) {
    #[cfg(unix)]
    {
        // SAFETY: `bytes` is valid for `len` bytes; write(2) is async-signal-safe.
        let _ = unsafe { libc::write(2, bytes.as_ptr().cast(), bytes.len()) };
    }
    #[cfg(not(unix))]
    let _ = bytes;
}
