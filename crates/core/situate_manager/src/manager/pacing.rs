//! Pacing: cycles run back to back or at the clock's rate (`run_cycles`),
//! when a spawned manager stops cycling, how fast it runs a simulated clock,
//! and the cycle thread's scheduling weight.

use std::time::{Duration, Instant};

use super::Manager;
use crate::config::ClockKind;

impl Manager {
    /// Runs `cycles` cycles paced by the clock (wall clock: at the set rate;
    /// simulated: as fast as possible).
    pub fn run_cycles(&mut self, cycles: u64) {
        let was = self.running;
        self.running = true;
        let period = Duration::from_secs_f64(self.period_s);
        let mut deadline = Instant::now();
        for _ in 0..cycles {
            self.cycle();
            if self.clock == ClockKind::Wall {
                deadline += period;
                let now = Instant::now();
                if deadline > now {
                    std::thread::sleep(deadline - now);
                } else {
                    deadline = now;
                }
            }
        }
        self.running = was;
    }

    /// When spawned, stop cycling (and keep serving requests) once cycle
    /// `cycle` has run.
    pub fn stop_after(&mut self, cycle: Option<u64>) {
        self.stop_at = cycle;
    }

    /// On the simulated clock, pace the cycle at `speed` × real time when
    /// spawned (`None`, the default: as fast as possible). The wall clock is
    /// always paced at its rate.
    pub fn set_speed(&mut self, speed: Option<f64>) {
        self.speed = speed.filter(|s| s.is_finite() && *s > 0.0);
    }

    /// How the cycle is paced when spawned: the period between cycle
    /// starts (`None`: as fast as possible).
    pub(crate) fn pacing(&self) -> Option<Duration> {
        let paced = match self.clock {
            ClockKind::Wall => Some(self.period_s),
            ClockKind::Simulated => self.speed.map(|s| self.period_s / s),
        };
        paced.map(|p| Duration::from_secs_f64(p.clamp(1e-6, 1e6)))
    }
}

/// Asks the OS to favour the cycle's thread over other work of the machine
/// (a higher CFS weight, `nice -10`), so that a busy machine delays its
/// wake-ups less. Best effort: without the privilege nothing changes.
pub(super) fn raise_thread_priority() {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: gettid has no preconditions; setpriority on our own thread id
        // only changes its scheduling weight and reports failure by its result.
        let result = unsafe {
            let tid = libc::syscall(libc::SYS_gettid) as libc::id_t;
            libc::setpriority(libc::PRIO_PROCESS, tid, -10)
        };
        if result != 0 {
            tracing::debug!("could not raise the cycle thread's priority (needs CAP_SYS_NICE)");
        }
    }
}
