//! How long the cycle thread was kept from running by a busy machine: its *run-queue delay*, the
//! time it was ready to run but waited for a CPU (the kernel's scheduler statistics, the second
//! field of `/proc/self/task/TID/schedstat`, in ns; Linux only).
//!
//! On the simulated clock a run is the same every time for a seed, whatever the machine: time
//! there is the cycle's, not the wall's. A body's deadline must then not depend on how loaded the
//! machine is, or a body preempted for a moment by other programs is faulted in one run and not
//! in the next, and the two runs go different ways. So under the simulated clock a body's time
//! against its deadline is its wall time *less the time its thread waited for a CPU*: what it
//! spent running or blocked (a sleep, I/O, a lock) still counts, so a body that blocks is still
//! faulted and left behind; one that only waited for a busy machine is not.
//! See docs/decisions/0005-budgets-and-stuck-bodies.md.
//!
//! The watchdog samples the cycle thread's delay every tick (off the cycle: the cycle pays
//! nothing); the delay since a body started is the delay now less the last sample taken before
//! that start (or, when none reaches back that far, the oldest one: less time discounted, never
//! more). Where the kernel does not say (no `schedstat`), nothing is discounted: budgets are wall
//! time, as on the wall clock.

use std::fs::File;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::Mutex;

use crate::runner::coarse_ns;

/// Samples kept: at the watchdog's slowest tick (25 ms) they reach 6.4 s back.
const SAMPLES: usize = 256;

/// The run-queue delay of the thread that runs the bodies (the cycle thread).
pub(crate) struct Starvation {
    /// The cycle thread's id (0: none yet).
    tid: AtomicI64,
    inner: Mutex<Inner>,
}

struct Inner {
    /// The open `schedstat` of the thread `tid` (reopened when the cycle thread changes).
    file: Option<(i64, File)>,
    /// `(coarse ns, delay ns)`, oldest first from `next` on once full.
    ring: Box<[(u64, u64); SAMPLES]>,
    next: usize,
    len: usize,
}

impl Starvation {
    pub fn new() -> Self {
        Starvation {
            tid: AtomicI64::new(0),
            inner: Mutex::new(Inner { file: None, ring: Box::new([(0, 0); SAMPLES]), next: 0, len: 0 }),
        }
    }

    /// The calling thread runs the bodies from now on (a new cycle thread). Its first sample is
    /// taken now, before it runs a body: on a machine so busy that the watchdog itself rarely
    /// runs, the first body still has a sample from before its start to count from.
    pub fn adopt_current_thread(&self) {
        #[cfg(target_os = "linux")]
        {
            // SAFETY: gettid has no preconditions and cannot fail.
            let tid = i64::from(unsafe { libc::gettid() });
            self.tid.store(tid, Ordering::Release);
            self.sample();
        }
    }

    /// One sample of the cycle thread's delay, now (the watchdog's tick).
    pub fn sample(&self) {
        let mut inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        let Some(delay) = inner.read(self.tid.load(Ordering::Acquire)) else { return };
        let at = inner.next;
        inner.ring[at] = (coarse_ns(), delay);
        inner.next = (at + 1) % SAMPLES;
        inner.len = (inner.len + 1).min(SAMPLES);
    }

    /// How long, ns, the cycle thread has waited for a CPU since `since` (on the coarse clock):
    /// at most that, 0 when unknown.
    pub fn since(&self, since: u64) -> u64 {
        let now = {
            let mut inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
            inner.read(self.tid.load(Ordering::Acquire))
        };
        match (now, self.base(since)) {
            (Some(now), Some(base)) => now.saturating_sub(base),
            _ => 0,
        }
    }

    /// The delay sampled last at or before `since`; the oldest sample's when none is.
    fn base(&self, since: u64) -> Option<u64> {
        let inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        let oldest = (inner.next + SAMPLES - inner.len) % SAMPLES;
        let mut base = None;
        for k in 0..inner.len {
            let (t, d) = inner.ring[(oldest + k) % SAMPLES];
            if t <= since || base.is_none() {
                base = Some(d);
            }
            if t > since {
                break;
            }
        }
        base
    }
}

impl Inner {
    /// The run-queue delay of thread `tid` now, ns.
    fn read(&mut self, tid: i64) -> Option<u64> {
        if tid == 0 {
            return None;
        }
        if self.file.as_ref().is_none_or(|(t, _)| *t != tid) {
            // A new cycle thread: its samples start afresh.
            self.len = 0;
            self.next = 0;
            self.file = File::open(format!("/proc/self/task/{tid}/schedstat")).ok().map(|f| (tid, f));
        }
        let (_, file) = self.file.as_ref()?;
        read_delay(file)
    }
}

/// The second field of a `schedstat` file, read afresh.
#[cfg(unix)]
fn read_delay(file: &File) -> Option<u64> {
    use std::os::unix::fs::FileExt;
    let mut buf = [0u8; 96];
    let n = file.read_at(&mut buf, 0).ok()?;
    parse_delay(std::str::from_utf8(buf.get(..n)?).ok()?)
}

#[cfg(not(unix))]
fn read_delay(_file: &File) -> Option<u64> {
    None
}

/// `schedstat`'s fields: time on a CPU, time waiting for one, timeslices (ns, ns, count).
fn parse_delay(text: &str) -> Option<u64> {
    text.split_ascii_whitespace().nth(1)?.parse().ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_wait_is_schedstats_second_field() {
        assert_eq!(parse_delay("50559 1234 7\n"), Some(1234));
        assert_eq!(parse_delay("50559"), None);
        assert_eq!(parse_delay("a b c"), None);
    }

    #[test]
    fn the_wait_since_a_time_is_from_the_last_sample_before_it_or_the_oldest() {
        let s = Starvation::new();
        {
            let mut inner = s.inner.lock().unwrap();
            inner.ring[0] = (100, 10);
            inner.ring[1] = (200, 50);
            inner.ring[2] = (300, 90);
            inner.len = 3;
            inner.next = 3;
        }
        // No thread to read: nothing is discounted.
        assert_eq!(s.since(250), 0);
        assert_eq!(s.base(250), Some(50));
        assert_eq!(s.base(200), Some(50));
        assert_eq!(s.base(50), Some(10), "before every sample: the oldest, never more");
        assert_eq!(s.base(1000), Some(90));
    }
}
