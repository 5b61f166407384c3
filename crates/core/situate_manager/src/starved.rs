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
//! under way is in no sample. So a body whose thread is runnable (running, or ready and waiting
//! for a CPU) is never judged on the reading that found it over its deadline ([`judge`]): that
//! reading may miss a wait under way. It is judged at a later reading that shows the thread has
//! run since (its time on a CPU grew): the wait under way then has ended and is counted, so the
//! time it had run *by the first reading* is known, at least. A body that computes gets CPU time
//! and one that sleeps or blocks is not runnable (a reading of a thread that is not runnable
//! misses no wait): both are still judged. This holds however seldom the watchdog itself gets a
//! CPU on a busy machine: it never needs two readings close together.

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
    /// The open `schedstat` and `stat` of the thread `tid` (reopened when the cycle thread
    /// changes).
    file: Option<(i64, File, Option<File>)>,
    /// `(coarse ns, delay ns)`, oldest first from `next` on once full.
    ring: Box<[(u64, u64); SAMPLES]>,
    next: usize,
    len: usize,
}

/// One reading of the cycle thread: its time on a CPU and its run-queue delay (ns), and whether
/// it was runnable when read (then a wait under way may be missing from `delay`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Reading {
    pub cpu: u64,
    pub delay: u64,
    pub runnable: bool,
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

    /// One sample of the cycle thread's delay, now (the watchdog's tick): kept for [`Self::since`]
    /// and returned. `None` when the kernel does not say (or no cycle thread yet).
    pub fn sample(&self) -> Option<Reading> {
        let mut inner = self.inner.lock().unwrap_or_else(|p| p.into_inner());
        let reading = inner.reading(self.tid.load(Ordering::Acquire))?;
        let now = coarse_ns();
        let at = inner.next;
        inner.ring[at] = (now, reading.delay);
        inner.next = (at + 1) % SAMPLES;
        inner.len = (inner.len + 1).min(SAMPLES);
        Some(reading)
    }

    /// How long, ns, the thread waited for a CPU between the last sample at or before `since`
    /// (on the coarse clock) and `reading`.
    pub fn waited(&self, reading: &Reading, since: u64) -> u64 {
        self.base(since).map_or(0, |base| reading.delay.saturating_sub(base))
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
    /// The open files of thread `tid` (opened afresh for a new cycle thread, whose samples then
    /// start afresh).
    fn files(&mut self, tid: i64) -> Option<&(i64, File, Option<File>)> {
        if tid == 0 {
            return None;
        }
        if self.file.as_ref().is_none_or(|(t, _, _)| *t != tid) {
            self.len = 0;
            self.next = 0;
            self.file = File::open(format!("/proc/self/task/{tid}/schedstat"))
                .ok()
                .map(|f| (tid, f, File::open(format!("/proc/self/task/{tid}/stat")).ok()));
        }
        self.file.as_ref()
    }

    /// Thread `tid`'s time on a CPU and its run-queue delay now, ns.
    fn read(&mut self, tid: i64) -> Option<(u64, u64)> {
        read_schedstat(&self.files(tid)?.1)
    }

    /// [`Self::read`] with whether the thread is runnable (`R`: running, or ready and waiting
    /// for a CPU; taken as runnable when the kernel does not say). The state is read first: a
    /// thread found asleep that then wakes and waits has waited only since that first read.
    fn reading(&mut self, tid: i64) -> Option<Reading> {
        let (_, schedstat, stat) = self.files(tid)?;
        let state = stat.as_ref().and_then(read_state);
        let (cpu, delay) = read_schedstat(schedstat)?;
        Some(Reading { cpu, delay, runnable: state.is_none_or(|s| s == 'R') })
    }
}

/// What the watchdog saw of a body on an earlier reading: over its deadline, its thread runnable
/// (a wait under way may have been missing), its thread's time on a CPU then, and how long the
/// body had been running on the wall then.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Suspect {
    mark: u64,
    cpu: u64,
    wall: u64,
}

/// Whether the body with `mark`, running for `wall` ns on the wall, is certainly over `limit` ns
/// of running or blocking, given `reading` of its thread and `waited`, the thread's counted waits
/// for a CPU since the body started: `Some(ns it ran, at least)` when it is. `suspect` carries
/// what an earlier reading saw of this body (see the module's documentation).
pub(crate) fn judge(
    suspect: &mut Option<Suspect>,
    mark: u64,
    wall: u64,
    waited: u64,
    reading: Reading,
    limit: u64,
) -> Option<u64> {
    let ran = wall.saturating_sub(waited);
    if !reading.runnable {
        // Asleep or blocked: no wait under way, every wait is counted.
        *suspect = None;
        return (ran > limit).then_some(ran);
    }
    let mut earlier = suspect.take().filter(|s| s.mark == mark);
    if let Some(s) = earlier {
        if reading.cpu > s.cpu {
            // It ran since that reading: a wait under way then has ended and is counted now,
            // so by then it had run at least this (less, if it waited again since: never more).
            let ran_then = s.wall.saturating_sub(waited);
            if ran_then > limit {
                return Some(ran_then);
            }
            earlier = None;
        }
    }
    // Not run since the earlier reading: that one stands, still to be judged. Otherwise this
    // reading is the one to judge later, if it looks over.
    *suspect = earlier.or((ran > limit).then_some(Suspect { mark, cpu: reading.cpu, wall }));
    None
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

    /// Waits, with a generous bound, for a reading of the thread `s` watches that satisfies `ok`.
    #[cfg(target_os = "linux")]
    fn until_read(s: &Starvation, what: &str, ok: impl Fn(&Reading) -> bool) {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        loop {
            if s.sample().is_some_and(|r| ok(&r)) {
                return;
            }
            assert!(std::time::Instant::now() < deadline, "no reading showed {what}");
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn a_blocked_thread_reads_as_not_runnable_and_a_spinning_one_as_runnable() {
        use std::sync::atomic::AtomicBool;
        use std::sync::Arc;
        let s = Arc::new(Starvation::new());
        let (s2, (tx, rx)) = (Arc::clone(&s), std::sync::mpsc::channel::<()>());
        let blocked = std::thread::spawn(move || {
            s2.adopt_current_thread();
            rx.recv().ok();
        });
        until_read(&s, "the blocked thread asleep", |r| !r.runnable);
        tx.send(()).unwrap();
        blocked.join().unwrap();

        let (s2, stop) = (Arc::clone(&s), Arc::new(AtomicBool::new(false)));
        let stop2 = Arc::clone(&stop);
        let blocked_tid = s.tid.load(Ordering::Acquire);
        let spinner = std::thread::spawn(move || {
            s2.adopt_current_thread();
            while !stop2.load(Ordering::Relaxed) {
                std::hint::spin_loop();
            }
        });
        // Once adopted (not the ended thread's readings), every reading of a thread that never
        // sleeps is runnable; and it computes.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        while s.tid.load(Ordering::Acquire) == blocked_tid {
            assert!(std::time::Instant::now() < deadline, "the spinning thread never adopted");
            std::thread::yield_now();
        }
        until_read(&s, "the spinning thread on a CPU", |r| r.cpu > 0);
        let first = s.sample().unwrap();
        for _ in 0..20 {
            assert!(s.sample().unwrap().runnable, "a spinning thread is runnable");
        }
        until_read(&s, "the spinning thread's CPU time growing", |r| r.cpu > first.cpu);
        stop.store(true, Ordering::Relaxed);
        spinner.join().unwrap();
    }

    const MS: u64 = 1_000_000;

    fn r(cpu: u64, delay: u64, runnable: bool) -> Reading {
        Reading { cpu, delay, runnable }
    }

    #[test]
    fn a_body_whose_threads_wait_is_not_counted_yet_is_judged_once_it_has_run_again() {
        // The flake hunt's case: the watchdog itself got a CPU seldom, and found the body 159 ms
        // into its run, 20 ms of it computing and 139 ms waiting, only 40 ms of the waits counted.
        // It must not be faulted then (a limit of 100 ms).
        let mut suspect = None;
        assert_eq!(judge(&mut suspect, 7, 159 * MS, 40 * MS, r(20 * MS, 40 * MS, true), 100 * MS), None);
        assert!(suspect.is_some(), "remembered, to be judged later");
        // Later, still waiting (its CPU time unchanged): still not judged, however long on the wall.
        assert_eq!(judge(&mut suspect, 7, 400 * MS, 40 * MS, r(20 * MS, 40 * MS, true), 100 * MS), None);
        // It ran again: the whole wait is counted now; by the first reading it had run 20 ms.
        assert_eq!(judge(&mut suspect, 7, 420 * MS, 390 * MS, r(22 * MS, 390 * MS, true), 100 * MS), None);
        assert_eq!(suspect, None, "30 ms ran: nothing to remember");
        // It returned (its thread asleep, waiting for the next cycle): nothing to judge.
        assert_eq!(judge(&mut suspect, 7, 420 * MS, 390 * MS, r(22 * MS, 390 * MS, false), 100 * MS), None);
    }

    #[test]
    fn a_body_that_sleeps_or_blocks_past_its_limit_is_judged_at_once() {
        let mut suspect = None;
        // Not runnable: no wait under way, the reading is exact.
        assert_eq!(judge(&mut suspect, 3, 150 * MS, 10 * MS, r(5 * MS, 10 * MS, false), 100 * MS), Some(140 * MS));
        assert_eq!(judge(&mut suspect, 3, 90 * MS, 0, r(5 * MS, 0, false), 100 * MS), None);
    }

    #[test]
    fn a_body_that_computes_past_its_limit_is_judged_at_the_next_reading() {
        let mut suspect = None;
        // 130 ms into a run of computing, 10 ms waited: over, but a wait may be under way.
        assert_eq!(judge(&mut suspect, 5, 130 * MS, 10 * MS, r(120 * MS, 10 * MS, true), 100 * MS), None);
        // The next tick: it computed on, so by the first reading it had run 120 ms.
        assert_eq!(judge(&mut suspect, 5, 135 * MS, 10 * MS, r(125 * MS, 10 * MS, true), 100 * MS), Some(120 * MS));
    }

    #[test]
    fn what_was_seen_of_one_run_is_not_held_against_the_next() {
        let mut suspect = None;
        assert_eq!(judge(&mut suspect, 5, 130 * MS, 0, r(10 * MS, 0, true), 100 * MS), None);
        // Another run (another mark), 50 ms in: the earlier run's reading does not count.
        assert_eq!(judge(&mut suspect, 9, 50 * MS, 0, r(60 * MS, 0, true), 100 * MS), None);
        assert_eq!(suspect, None);
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
