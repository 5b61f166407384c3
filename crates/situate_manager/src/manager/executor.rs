//! The executors of a level's ready steps: serial (in order, plain inputs
//! lent from their slots) and parallel (the cycle's thread and the pool
//! take the bodies one by one, never two sharing a claim at once).

use std::sync::{Arc, Mutex};

use situate_core::value::recycle;

use super::plan::{Plan, Step, StepKind};
use super::slots::Slot;
use super::Manager;
use crate::config::ExecutorKind;
use crate::runner::{Exec, Stamp};

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

    /// Runs a level's ready steps, their inputs gathered as copies: on the
    /// pool when worth it ([`Manager::worth_parallel`]), else in order.
    pub(super) fn run_ready(&mut self, plan: &Plan, ready: &[usize]) {
        let (cycle, time_s) = (self.cycle, self.time_s);
        if self.worth_parallel(plan, ready) {
            for batch in self.batches(plan, ready) {
                let Some(pool) = &self.pool else { return };
                let jobs: Vec<Mutex<&mut Exec>> =
                    pick_mut(&mut self.execs, &batch).into_iter().map(Mutex::new).collect();
                run_parallel(pool, &jobs, |job| {
                    let mut exec = job.lock().unwrap_or_else(|p| p.into_inner());
                    exec.run(cycle, time_s, Stamp::now(true), None);
                });
            }
        } else {
            let sampled = self.sampled;
            let mut t = Stamp::now(sampled);
            for &k in ready {
                let step = &plan.steps[k];
                let precise = sampled || step.precise;
                if precise != matches!(t, Stamp::Precise(_)) {
                    t = Stamp::now(precise);
                }
                t = self.execs[step.inst].run(cycle, time_s, t, None);
            }
        }
    }

    /// The serial executor on the plan's steps `steps`: one level, or, with
    /// no pool, all of them in one pass (the steps are in topological order,
    /// level after level). Each step in order has its inputs checked and
    /// gathered (a plain step's lent: see [`Manager::lend_inputs`], or read
    /// in place from its one slot), runs at once, and has its outputs
    /// committed at once. The same as running each level whole and
    /// committing after it: no step of a level reads what another one of it
    /// writes (it would be a level later), arbitration does not depend on
    /// the order of commits, and a lent input is back in its slot before the
    /// next step looks. Committing at once touches each step's data while it
    /// is still in the cache, and leaves no list of ready steps to walk again.
    ///
    /// `t`: a clock reading to time the first body from, `None` to read the
    /// clock; returns the reading at the end of the last body (`None` if
    /// none ran, or when the next body needs a fresh one). Back to back
    /// bodies on the coarse clock share a reading, so each costs one clock
    /// read (its commit is counted in the next body's coarse time, well
    /// within a tick). An exact reading is never shared: a timed body's
    /// exact time holds no commits; nor is one after a fault.
    pub(super) fn run_serial(
        &mut self,
        plan: &Plan,
        steps: std::ops::Range<usize>,
        mut t: Option<Stamp>,
    ) -> Option<Stamp> {
        let (cycle, time_s, sampled) = (self.cycle, self.time_s, self.sampled);
        for k in steps {
            let step = &plan.steps[k];
            let fresh = match step.kind {
                StepKind::AsyncThreaded => {
                    self.exchange_async(step.inst);
                    // Not the time of a body: the next one reads the clock.
                    t = None;
                    continue;
                }
                StepKind::AsyncInCycle => false,
                StepKind::Sync => true,
            };
            // One plain input, present: the body reads it where it is.
            let in_place = match step.one_input {
                Some(leaf) => {
                    let slot = &self.slots[leaf];
                    slot.value.is_some() && (!fresh || slot.stamp == cycle)
                }
                None => false,
            };
            let lent = step.plain_ins && !in_place;
            let ready_now =
                in_place || if lent { self.lend_inputs(plan, step, fresh) } else { self.gather(step.inst, fresh) };
            if !ready_now {
                continue;
            }
            let precise = sampled || step.precise;
            let start = match t {
                Some(t) if precise == matches!(t, Stamp::Precise(_)) => t,
                _ => Stamp::now(precise),
            };
            let exec = &mut self.execs[step.inst];
            let input = match step.one_input {
                Some(leaf) if in_place => Some(&self.slots[leaf].value),
                _ => None,
            };
            let end = exec.run_on(input, cycle, time_s, start, None);
            if lent {
                // Back to their slots, swapped (see `lend_inputs`).
                let ins = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
                for (port, input) in ins.iter().zip(exec.inputs.iter_mut()) {
                    if input.is_some() {
                        std::mem::swap(input, &mut self.slots[port.leaf].value);
                        if input.is_some() {
                            if let Some(old) = input.take() {
                                recycle(old);
                            }
                        }
                    }
                }
            }
            let ok = self.finish_step(plan, k);
            t = match end {
                Stamp::Coarse(_) if ok => Some(end),
                _ => None,
            };
        }
        t
    }

    /// Lends a plain step its inputs if it is ready: each present input is
    /// moved from its slot into the body's buffer (no reference counting;
    /// nothing else reads a slot while a serial level runs), to be put
    /// back after the run. `fresh`: as in [`Manager::gather_step`]. Returns
    /// whether the step is ready (if not, nothing was moved).
    #[inline]
    fn lend_inputs(&mut self, plan: &Plan, step: &Step, fresh: bool) -> bool {
        let ports = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
        let cycle = self.cycle;
        let slots = &mut self.slots;
        let present = |slot: &Slot| slot.value.is_some() && (!fresh || slot.stamp == cycle);
        if !ports.iter().all(|port| port.optional || present(&slots[port.leaf])) {
            return false;
        }
        let exec = &mut self.execs[step.inst];
        // Values are swapped between slot and buffer, never moved through a
        // temporary (whose copy in halves stalls the load that follows).
        for (port, input) in ports.iter().zip(exec.inputs.iter_mut()) {
            if input.is_some() {
                if let Some(old) = input.take() {
                    recycle(old);
                }
            }
            let slot = &mut slots[port.leaf];
            if present(slot) {
                std::mem::swap(input, &mut slot.value);
            }
        }
        true
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
