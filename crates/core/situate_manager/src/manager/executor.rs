//! The executors: serial (steps in order, plain inputs lent from their
//! slots) and parallel (the cycle's thread and the pool take a level's
//! bodies one by one, never two sharing a claim at once); and how a
//! manager not spawned runs its bodies ([`InPlace`], for the walk in
//! `walk`).

use std::sync::{Arc, Mutex};

use super::plan::{Fast, Plan};
use super::walk::{commit_fast, Bodies};
use super::Manager;
use crate::config::ExecutorKind;
use crate::runner::{Exec, Stamp};

/// The bodies of a manager run on the caller's thread ([`Manager::cycle`]):
/// each in place in the manager, nothing watching (no body can be left
/// behind, so a body may read its inputs where they are).
pub(super) struct InPlace<'m>(pub &'m mut Manager);

impl Bodies for InPlace<'_> {
    const IN_PLACE: bool = true;

    #[inline(always)]
    fn manager(&mut self) -> Option<&mut Manager> {
        Some(self.0)
    }

    #[inline(always)]
    fn run(&mut self, i: usize, in_place: Option<usize>, start: Stamp) -> Option<Stamp> {
        let m = &mut *self.0;
        let input = in_place.map(|leaf| &m.slots[leaf].value);
        Some(m.execs[i].run_on(input, m.cycle, m.time_s, start, None))
    }

    #[inline(always)]
    fn run_fast(&mut self, fast: &Fast) -> Option<bool> {
        let m = &mut *self.0;
        let (cycle, time_s) = (m.cycle, m.time_s);
        let exec = &mut m.execs[fast.inst as usize];
        let output = fast.output as usize;
        if fast.in_slot {
            // No body is left behind here: its output's slot is its buffer.
            let clean = match fast.input() {
                Some(input) if input != output => {
                    let Ok([input, slot]) = m.slots.get_disjoint_mut([input, output]) else { return None };
                    exec.run_in_slot(Some(&input.value), &mut slot.value, cycle, time_s)
                }
                None => exec.run_in_slot(None, &mut m.slots[output].value, cycle, time_s),
                // It reads the leaf it writes: written after the run.
                Some(_) => {
                    let clean = exec.run_unwritten(Some(&m.slots[output].value), cycle, time_s);
                    if clean {
                        exec.write_into(Some(&mut m.slots[output].value));
                    }
                    clean
                }
            };
            if clean {
                let slot = &mut m.slots[output];
                slot.stamp = cycle;
                slot.rank = fast.rank;
            }
            return Some(clean);
        }
        let clean = exec.run_untimed(fast.input().map(|leaf| &m.slots[leaf].value), cycle, time_s);
        if clean {
            commit_fast(exec, &mut m.slots[output], cycle, fast.rank);
        }
        Some(clean)
    }

    fn run_batch(&mut self, batch: &[usize]) -> Option<()> {
        let m = &mut *self.0;
        let (cycle, time_s) = (m.cycle, m.time_s);
        let Some(pool) = &m.pool else { return Some(()) };
        let jobs: Vec<Mutex<&mut Exec>> =
            pick_mut(&mut m.execs, batch).into_iter().map(|e| Mutex::new(&mut **e)).collect();
        run_parallel(pool, &jobs, |job| {
            let mut exec = job.lock().unwrap_or_else(|p| p.into_inner());
            exec.run(cycle, time_s, Stamp::now(true), None);
        });
        Some(())
    }
}

/// A level's expected work (from its skills' last timed runs) from which
/// the parallel executor hands it to the pool; below, the cycle's thread
/// runs it alone (waking a thread costs some µs, more after an idle spell).
pub const PARALLEL_WORTH_NS: u64 = 40_000;

impl Manager {
    /// Splits a level's ready steps into batches of instances that may run
    /// at the same time: skills sharing a claim never do.
    pub(super) fn batches(&self, plan: &Plan, ready: &[usize]) -> Vec<Vec<usize>> {
        let mut rest: Vec<usize> = ready.iter().map(|&k| plan.steps[k].inst).collect();
        let mut batches = Vec::new();
        while !rest.is_empty() {
            let mut batch = Vec::new();
            let mut claims: Vec<&str> = Vec::new();
            rest.retain(|&i| {
                let c = &self.graph.instances[i].skill_type.decl.claims;
                if c.iter().any(|x| claims.contains(&x.as_str())) {
                    return true;
                }
                claims.extend(c.iter().map(String::as_str));
                batch.push(i);
                false
            });
            batches.push(batch);
        }
        batches
    }

    /// Whether the ready steps of a level are worth handing to the pool:
    /// more than one, and together (by their last timed runs) well above
    /// what a hand-off costs.
    pub(super) fn worth_parallel(&self, plan: &Plan, ready: &[usize]) -> bool {
        if self.pool.is_none() || ready.len() < 2 {
            return false;
        }
        let mut total = 0u64;
        let mut longest = 0u64;
        for &k in ready {
            let t = &self.insts[plan.steps[k].inst].timing;
            // Never timed yet: try it in parallel once to learn.
            let ns = if t.timed_runs == 0 { PARALLEL_WORTH_NS } else { t.last_ns };
            total += ns;
            longest = longest.max(ns);
        }
        // What the other threads could take off the cycle's thread.
        total - longest >= PARALLEL_WORTH_NS / 2 && total >= PARALLEL_WORTH_NS
    }

    /// The executor in use (parallel falls back to serial if no pool could be made).
    pub fn executor(&self) -> ExecutorKind {
        if self.pool.is_some() {
            ExecutorKind::Parallel
        } else {
            ExecutorKind::Serial
        }
    }
}

/// Runs one parallel batch: the calling thread (the cycle's) and up to
/// `threads − 1` of the pool's take the next job until none is left.
///
/// The cycle's thread never waits for a helper that has not started: a
/// helper woken late (after an idle spell the pool's threads sleep, and a
/// halted vCPU takes long to wake) finds the batch closed and leaves without
/// touching it. The cycle's thread only waits for the helpers already in a
/// job, so the batch never takes longer than running it alone plus the end
/// of one job; it is never slower than serial by more than a hand-off.
pub(crate) fn run_parallel<J: Sync>(pool: &rayon::ThreadPool, jobs: &[J], run: impl Fn(&J) + Sync) {
    use std::sync::atomic::{AtomicUsize, Ordering};
    /// Set in `state` once the batch is closed; `state >> 1` counts the
    /// helpers inside it.
    const CLOSED: usize = 1;
    struct Batch {
        next: AtomicUsize,
        state: AtomicUsize,
    }
    /// Leaves the batch (also when a job unwinds).
    struct Inside<'a>(&'a Batch);
    impl Drop for Inside<'_> {
        fn drop(&mut self) {
            self.0.state.fetch_sub(2, Ordering::AcqRel);
        }
    }
    /// Closes the batch and waits for the helpers inside (also when the
    /// cycle's thread unwinds): they borrow `jobs` and `run`.
    struct Close<'a>(&'a Batch);
    impl Drop for Close<'_> {
        fn drop(&mut self) {
            self.0.state.fetch_or(CLOSED, Ordering::AcqRel);
            let mut spins = 0u32;
            while self.0.state.load(Ordering::Acquire) >> 1 != 0 {
                if spins < 1000 {
                    std::hint::spin_loop();
                    spins += 1;
                } else {
                    std::thread::yield_now();
                }
            }
        }
    }

    let batch = Arc::new(Batch { next: AtomicUsize::new(0), state: AtomicUsize::new(0) });
    let drain = |b: &Batch| loop {
        let k = b.next.fetch_add(1, Ordering::Relaxed);
        let Some(job) = jobs.get(k) else { break };
        run(job);
    };
    let work: &(dyn Fn(&Batch) + Sync) = &drain;
    // SAFETY: the lifetime is erased only so the pool's threads can hold the
    // reference. A helper dereferences it only after entering the batch
    // (a CAS on `state` that fails once `CLOSED` is set), and this function
    // does not return (nor unwind) before `Close` has set `CLOSED` and seen
    // every helper that entered leave: no use outlives `jobs` and `run`.
    let work: &'static (dyn Fn(&Batch) + Sync) = unsafe { std::mem::transmute(work) };
    let helpers = pool.current_num_threads().min(jobs.len().saturating_sub(1));
    let close = Close(&batch);
    for _ in 0..helpers {
        let b = Arc::clone(&batch);
        pool.spawn(move || {
            let mut s = b.state.load(Ordering::Acquire);
            loop {
                if s & CLOSED != 0 {
                    return;
                }
                match b.state.compare_exchange_weak(s, s + 2, Ordering::AcqRel, Ordering::Acquire) {
                    Ok(_) => break,
                    Err(now) => s = now,
                }
            }
            let _inside = Inside(&b);
            work(&b);
        });
    }
    drain(&batch);
    drop(close);
}

/// Disjoint mutable references to `v[i]` for sorted, distinct `indices`.
fn pick_mut<'a, T>(v: &'a mut [T], indices: &[usize]) -> Vec<&'a mut T> {
    let mut out = Vec::with_capacity(indices.len());
    let mut rest = v;
    let mut offset = 0;
    for &i in indices {
        let (_, tail) = rest.split_at_mut(i - offset);
        let (item, tail) = tail.split_first_mut().expect("index in range");
        out.push(item);
        rest = tail;
        offset = i + 1;
    }
    out
}
