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
//!
//! The kernel adds a wait to the delay only when the wait ends (the thread gets a CPU): a wait
//! under way is in no sample. So a thread that waits for a CPU *now* is not judged now
//! ([`Starvation::waiting_now`]: runnable, and its time on a CPU unchanged for at least
//! [`MIN_WAIT_NS`]); it is judged once it has run again, its wait then counted. A body that
//! computes gets CPU time, and one that sleeps or blocks is not runnable: both are still judged.

use std::fs::File;
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::Mutex;

use crate::runner::coarse_ns;

/// Samples kept: at the watchdog's slowest tick (25 ms) they reach 6.4 s back.
const SAMPLES: usize = 256;

/// How long a runnable thread's time on a CPU must have stood still for it to be taken as waiting
/// for a CPU now: a few scheduler ticks (the kernel updates a running thread's time at each tick,
/// every 1 to 10 ms), so a thread that runs is never taken for one that waits.
pub(crate) const MIN_WAIT_NS: u64 = 20_000_000;

/// The run-queue delay of the thread that runs the bodies (the cycle thread).
pub(crate) struct Starvation {
    /// The cycle thread's id (0: none yet).
    tid: AtomicI64,
    inner: Mutex<Inner>,
}

struct Inner {
    /// The open `schedstat` and `stat` of the thread `tid` (reopened when the cycle thread
    /// changes).
    file: Option<(i64, File, Option<File>)>,
    /// `(coarse ns, delay ns)`, oldest first from `next` on once full.
    ring: Box<[(u64, u64); SAMPLES]>,
    next: usize,
    len: usize,
    /// The thread's time on a CPU (ns) at the last sample, and since when (coarse ns) it has
    /// stood at that value.
    cpu: Option<(u64, u64)>,
}

impl Starvation {
    pub fn new() -> Self {
        Starvation {
            tid: AtomicI64::new(0),
            inner: Mutex::new(Inner { file: None, ring: Box::new([(0, 0); SAMPLES]), next: 0, len: 0, cpu: None }),
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
        let Some((cpu, delay)) = inner.read(self.tid.load(Ordering::Acquire)) else { return };
        let now = coarse_ns();
        let at = inner.next;
        inner.ring[at] = (now, delay);
        inner.next = (at + 1) % SAMPLES;
        inner.len = (inner.len + 1).min(SAMPLES);
        inner.cpu = match inner.cpu {
            Some((c, since)) if c == cpu => Some((c, since)),
            _ => Some((cpu, now)),
        };
    }

    /// Whether the cycle thread is waiting for a CPU now: runnable (not asleep nor blocked), and
    /// its time on a CPU unchanged for at least [`MIN_WAIT_NS`] of the samples. Such a wait is in
    /// no sample yet (the kernel counts it when it ends), so a body on that thread must not be
    /// judged now. False when the kernel does not say.
    pub fn waiting_now(&self) -> bool {
        let mut inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        let Some((cpu, _)) = inner.read(self.tid.load(Ordering::Acquire)) else { return false };
        let Some((c, since)) = inner.cpu else { return false };
        c == cpu && coarse_ns().saturating_sub(since) >= MIN_WAIT_NS && inner.runnable()
    }

    /// How long, ns, the cycle thread has waited for a CPU since `since` (on the coarse clock):
    /// at most that, 0 when unknown.
    pub fn since(&self, since: u64) -> u64 {
        let now = {
            let mut inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
            inner.read(self.tid.load(Ordering::Acquire))
        };
        match (now, self.base(since)) {
            (Some((_, now)), Some(base)) => now.saturating_sub(base),
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
    /// Thread `tid`'s time on a CPU and its run-queue delay now, ns.
    fn read(&mut self, tid: i64) -> Option<(u64, u64)> {
        if tid == 0 {
            return None;
        }
        if self.file.as_ref().is_none_or(|(t, _, _)| *t != tid) {
            // A new cycle thread: its samples start afresh.
            self.len = 0;
            self.next = 0;
            self.cpu = None;
            self.file = File::open(format!("/proc/self/task/{tid}/schedstat"))
                .ok()
                .map(|f| (tid, f, File::open(format!("/proc/self/task/{tid}/stat")).ok()));
        }
        let (_, file, _) = self.file.as_ref()?;
        read_schedstat(file)
    }

    /// Whether the thread is runnable (`R`: running, or ready and waiting for a CPU).
    fn runnable(&self) -> bool {
        let Some((_, _, Some(stat))) = self.file.as_ref() else { return false };
        read_state(stat) == Some('R')
    }
}

/// A `schedstat` file's first two fields, read afresh.
#[cfg(unix)]
fn read_schedstat(file: &File) -> Option<(u64, u64)> {
    use std::os::unix::fs::FileExt;
    let mut buf = [0u8; 96];
    let n = file.read_at(&mut buf, 0).ok()?;
    parse_schedstat(std::str::from_utf8(buf.get(..n)?).ok()?)
}

#[cfg(not(unix))]
fn read_schedstat(_file: &File) -> Option<(u64, u64)> {
    None
}

/// A thread's state, from its `stat` file, read afresh.
#[cfg(unix)]
fn read_state(file: &File) -> Option<char> {
    use std::os::unix::fs::FileExt;
    let mut buf = [0u8; 512];
    let n = file.read_at(&mut buf, 0).ok()?;
    parse_state(std::str::from_utf8(buf.get(..n)?).ok()?)
}

#[cfg(not(unix))]
fn read_state(_file: &File) -> Option<char> {
    None
}

/// `schedstat`'s fields: time on a CPU, time waiting for one, timeslices (ns, ns, count): the
/// first two.
fn parse_schedstat(text: &str) -> Option<(u64, u64)> {
    let mut fields = text.split_ascii_whitespace();
    Some((fields.next()?.parse().ok()?, fields.next()?.parse().ok()?))
}

/// The state in a `stat` line, `PID (COMM) STATE …`: the first field after the last `)` (the
/// thread's name may hold spaces and parentheses).
fn parse_state(text: &str) -> Option<char> {
    text.get(text.rfind(')')? + 1..)?.split_ascii_whitespace().next()?.chars().next()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cpu_time_and_the_wait_are_schedstats_first_two_fields() {
        assert_eq!(parse_schedstat("50559 1234 7\n"), Some((50559, 1234)));
        assert_eq!(parse_schedstat("50559"), None);
        assert_eq!(parse_schedstat("a b c"), None);
    }

    #[test]
    fn the_state_is_the_field_after_the_threads_name_whatever_the_name() {
        assert_eq!(parse_state("1234 (situate-cycle) R 1 2 3"), Some('R'));
        assert_eq!(parse_state("1234 (a (b) c) S 1 2 3"), Some('S'));
        assert_eq!(parse_state("1234 (x)"), None);
        assert_eq!(parse_state("no parenthesis"), None);
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_thread_that_sleeps_is_not_waiting_for_a_cpu() {
        use std::sync::Arc;
        use std::time::Duration;
        let s = Arc::new(Starvation::new());
        let (s2, stop) = (Arc::clone(&s), Arc::new(std::sync::atomic::AtomicBool::new(false)));
        let stop2 = Arc::clone(&stop);
        let sleeper = std::thread::spawn(move || {
            s2.adopt_current_thread();
            while !stop2.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(5));
            }
        });
        while s.tid.load(Ordering::Acquire) == 0 {
            std::thread::yield_now();
        }
        for _ in 0..10 {
            s.sample();
            std::thread::sleep(Duration::from_millis(5));
        }
        assert!(!s.waiting_now(), "a sleeping thread is not runnable");
        stop.store(true, Ordering::Relaxed);
        sleeper.join().unwrap();
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
