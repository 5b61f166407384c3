//! The spawned manager's watchdog: it looks at the bodies running on the
//! cycle thread and its pool every tick of its own, and leaves behind one
//! that ran past its deadline (decisions 0005 and 0016), then starts a new
//! cycle thread.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::thread;
use std::time::Duration;

use super::{start_cycle_thread, Core};
use crate::control::ControlError;
use crate::runner::{coarse_ns, coarse_tick_ns, BodyClock};
use crate::starved::{self, Suspect};

/// Watches the bodies running on cycle threads; leaves behind one past its
/// deadline and starts a new cycle thread.
pub(super) fn watchdog(core: Arc<Core>, deadlines: Vec<Duration>) {
    let shortest = deadlines.iter().min().copied().unwrap_or(Duration::from_secs(1));
    let tick = (shortest / 4).clamp(Duration::from_millis(1), Duration::from_millis(25));
    // Room for every body up front: a body seen past its deadline for a
    // moment (its thread preempted on a loaded machine) must not make the
    // watchdog allocate while the robot runs.
    let mut stale: Vec<(usize, u64, Duration)> = Vec::with_capacity(core.clocks.len());
    // On the simulated clock, what an earlier reading saw of each body (`crate::starved::judge`).
    let mut suspects: Vec<Option<Suspect>> = vec![None; core.clocks.len()];
    // Each body's mark as last seen, and when (coarse clock) it was first seen: a run is timed
    // from then (a mark holds no time; see `BodyClock`).
    let mut seen: Vec<(u64, u64)> = vec![(0, 0); core.clocks.len()];
    loop {
        thread::park_timeout(tick);
        if core.stop.load(Ordering::Acquire) {
            return;
        }
        stale.clear();
        let reading = core.starved.as_ref().and_then(|s| s.sample());
        // Runs are timed on the coarse clock from when this thread first saw them, no earlier
        // than they started: a body is stuck only when it certainly ran past its deadline (the
        // time before it was first seen, up to a tick of this loop, is not counted).
        let slack = Duration::from_nanos(coarse_tick_ns());
        let now = coarse_ns();
        for (i, clock) in core.clocks.iter().enumerate() {
            let mark = clock.mark();
            if mark == 0 {
                suspects[i] = None;
                seen[i] = (0, 0);
                continue;
            }
            if seen[i].0 != mark {
                seen[i] = (mark, now);
            }
            let since = seen[i].1;
            let wall = Duration::from_nanos(now.saturating_sub(since));
            let limit = deadlines[i] + slack;
            let over = match (&core.starved, reading) {
                // On the simulated clock the time its thread waited for a CPU does not count
                // (`crate::starved`).
                (Some(s), Some(reading)) => {
                    let waited = s.waited(&reading, since);
                    let ns = |d: Duration| u64::try_from(d.as_nanos()).unwrap_or(u64::MAX);
                    starved::judge(&mut suspects[i], mark, ns(wall), waited, reading, ns(limit))
                        .map(Duration::from_nanos)
                }
                _ => (wall > limit).then_some(wall),
            };
            if let Some(ran) = over {
                stale.push((i, mark, ran));
            }
        }
        if stale.is_empty() {
            continue;
        }
        // A body run by a thread that holds the lock (the cycle thread, one body at a time): its
        // mark taken, the lock is the watchdog's (see `OnThreads::run`).
        let held = stale.iter().position(|&(_, mark, _)| BodyClock::held(mark));
        let mut g = match held {
            Some(k) => {
                let (i, mark, _) = stale[k];
                if !core.clocks[i].forget(mark) {
                    // It returned just now.
                    continue;
                }
                // SAFETY: the thread that runs the body held the lock and forgot its guard; it
                // makes it again only if it takes the mark back, which the watchdog now has.
                unsafe { core.manager.make_guard_unchecked() }
            }
            // Bodies run with the lock let go (a pool's). Never a wait without bound: the cycle
            // thread may be running a body holding it meanwhile, stuck or not.
            None => match core.manager.try_lock_for(tick) {
                Some(g) => g,
                None => continue,
            },
        };
        let Some(m) = g.as_mut() else { return };
        let mut left = false;
        for (k, &(i, mark, ran)) in stale.iter().enumerate() {
            let clock = &core.clocks[i];
            if Some(k) == held {
                suspects[i] = None;
                let body = m.leave_behind_held(i);
                core.left_behind.lock().unwrap_or_else(|p| p.into_inner()).push((i, mark, body));
                m.abandon(i, ran);
                left = true;
            } else if !BodyClock::held(mark) && clock.mark() == mark && clock.forget(mark) {
                // Still in that same run: its thread is stuck in the body.
                suspects[i] = None;
                m.abandon(i, ran);
                left = true;
            }
        }
        if left {
            // The stuck thread holds the plan (see `cycle`).
            m.schedule_dirty = true;
            m.generation += 1;
            let generation = m.generation;
            if let Some(reply) = core.step_reply().take() {
                let _ = reply.send(Err(ControlError::Interrupted(
                    "a body got stuck during the step and was left behind; the cycle goes on".into(),
                )));
            }
            drop(g);
            start_cycle_thread(&core, generation);
        }
    }
}
