//! One cycle's walk over the plan, written once for both ways a manager
//! runs: [`Manager::cycle`] on the caller's thread, and the spawned
//! manager's cycle thread (`spawned`), where a watchdog can leave a stuck
//! body behind and start the cycle again on a fresh thread.
//!
//! What differs between the two is only how a body runs, behind
//! [`Bodies`]; the walk — which steps are ready, how their inputs are
//! gathered, how each run is timed and committed, the levels, the parallel
//! batches, the devices' exchanges — is here, once.

use situate_core::value::recycle;

use super::plan::{Fast, Plan, Step, StepKind};
use super::slots::Slot;
use super::Manager;
use crate::runner::{coarse_ns, coarse_tick_ns, Exec, Stamp};

/// How the bodies of a cycle run.
pub(super) trait Bodies {
    /// Whether a body with one plain input may read it in its slot. Only
    /// where no body can be left behind: the slot is the manager's, written
    /// again by the next cycle while a body left behind may still read it.
    /// Otherwise it is lent, as the inputs of every step whose inputs are
    /// all plain: moved into the body's buffers for the run (which the body
    /// keeps if it is left behind) and back after.
    const IN_PLACE: bool;

    /// The manager; `None` once this thread is no longer its cycle (a body
    /// it ran was left behind).
    fn manager(&mut self) -> Option<&mut Manager>;

    /// Runs instance `i`'s body once on its gathered inputs, or on the
    /// value in slot `in_place` (only when [`Bodies::IN_PLACE`]), timed from
    /// `start`: the time it ended, on `start`'s clock, or `None` when this
    /// thread was left behind while it ran.
    fn run(&mut self, i: usize, in_place: Option<usize>, start: Stamp) -> Option<Stamp>;

    /// Runs the body of a step run the short way ([`Fast`]) once, untimed,
    /// on the value in its input's slot or on no input, and, if the run was
    /// clean (no error, no print), commits its output the short way
    /// ([`commit_fast`], or written in its slot where it may:
    /// [`Fast::in_slot`]). `Some(false)`: the run was not clean, its outcome
    /// is left for [`Manager::finish_step`]. `None` as for [`Bodies::run`].
    fn run_fast(&mut self, fast: &Fast) -> Option<bool>;

    /// Runs the bodies of `batch` (instances that share no claim, their
    /// inputs gathered) at the same time, on the pool. `None` as for
    /// [`Bodies::run`].
    fn run_batch(&mut self, batch: &[usize]) -> Option<()>;
}

/// Runs one cycle (the steps of [`Manager::cycle`]). `None`: this thread
/// was left behind during it, and the cycle is abandoned where it stood.
///
/// The plan is out of the manager while the cycle walks it: should the
/// walk be left behind, the watchdog marks the schedule to be compiled
/// again, so the next cycle never runs without one.
pub(super) fn cycle<B: Bodies>(b: &mut B) -> Option<()> {
    let m = b.manager()?;
    m.begin_cycle();
    // Out by its box (a pointer moved, nothing copied), an empty one in its
    // place (made once).
    let empty = m.empty_plan.take().unwrap_or_default();
    let plan = std::mem::replace(&mut m.schedule, empty);
    let mut ready = std::mem::take(&mut m.ready);
    // The coarse clock's reading at the end of the last body, carried to
    // the next one (see `run_steps`), and to the cycle's end.
    let mut t;
    if m.pool.is_none() {
        // Serial: one pass, levels make no difference (see `run_steps`).
        // An untimed cycle's coarse start is the first body's too.
        t = (!m.cycle_timed).then_some(Stamp::Coarse(m.cycle_start_coarse));
        t = run_steps(b, &plan, 0..plan.steps.len(), t)?;
    } else {
        t = None;
        for level in 0..plan.levels.len() {
            let Some(steps) = plan.level(level) else { break };
            if plan.parallel_level(level) {
                run_level(b, &plan, level, &mut ready)?;
                t = None;
            } else {
                // Each step committed as it runs.
                t = run_steps(b, &plan, steps, t)?;
            }
        }
    }
    let m = b.manager()?;
    m.ready = ready;
    m.empty_plan = Some(std::mem::replace(&mut m.schedule, plan));
    m.prepare_exchanges();
    let exchanging = std::mem::take(&mut m.exchanging);
    if !exchanging.is_empty() {
        t = None;
        let mut t = Stamp::now(true);
        for &d in &exchanging {
            t = b.run(d, None, t)?;
        }
    }
    let m = b.manager()?;
    for &d in &exchanging {
        m.finish_exchange(d);
    }
    m.exchanging = exchanging;
    m.end_cycle(match t {
        Some(Stamp::Coarse(ns)) => Some(ns),
        _ => None,
    });
    Some(())
}

/// The plan's steps `steps` one after the other: one level, or, with no
/// pool, all of them in one pass (the steps are in topological order, level
/// after level). Each step in order has its inputs checked and gathered (a
/// plain step's lent, or read in place from its one slot where the bodies
/// [may](Bodies::IN_PLACE)), runs at once, and has its outputs committed at
/// once. The same as running each level whole and committing after it: no
/// step of a level reads what another one of it writes (it would be a level
/// later), arbitration does not depend on the order of commits, and a lent
/// input is back in its slot before the next step looks. Committing at once
/// touches each step's data while it is still in the cache, and leaves no
/// list of ready steps to walk again.
///
/// `t`: a clock reading to time the first body from, `None` to read the
/// clock; returns the reading at the end of the last body (`None` if none
/// ran, or when the next body needs a fresh one). Back to back bodies on the
/// coarse clock share a reading, so each costs one clock read (its commit is
/// counted in the next body's coarse time, well within a tick). An exact
/// reading is never shared: a timed body's exact time holds no commits; nor
/// is one after a fault. The outer `None`: left behind.
///
/// A step that may run the short way ([`Fast`]: one required input read in
/// place or none, one output on a leaf no other skill writes, of its type by
/// construction) does, outside a sampled cycle's window, while it holds its
/// output's slot: checked, run untimed, its output swapped into its slot.
/// Back to back such steps are a *stretch*, timed as one on the coarse
/// clock ([`Manager::end_stretch`]): a body costs no clock reading.
#[inline(always)]
fn run_steps<B: Bodies>(
    b: &mut B,
    plan: &Plan,
    steps: std::ops::Range<usize>,
    mut t: Option<Stamp>,
) -> Option<Option<Stamp>> {
    let mut k = steps.start;
    while k < steps.end {
        // A sampled cycle times the steps of its window exactly, the usual
        // way; a stretch before the window ends where it starts.
        if let Some(f) = plan.steps[k].fast {
            let m = b.manager()?;
            if !m.timed_exactly(k) {
                let end = if m.sampled && k < m.exact.0 { steps.end.min(m.exact.0) } else { steps.end };
                let next;
                (next, t) = run_stretch(b, plan, &plan.fast[f as usize..], k..end, t)?;
                if next > k {
                    k = next;
                    continue;
                }
            }
        }
        t = run_step(b, plan, k, t)?;
        k += 1;
    }
    Some(t)
}

/// The steps from `steps.start` on that run the short way (`fast`: their
/// entries, from that step's), while they hold their outputs' slots (a
/// slot another writer holds, or none yet, is committed the usual way):
/// each checked, run untimed, its output committed the short way; a step
/// whose input is not fresh is passed over. Returns the first step it did
/// not take (`steps.start` if none), and the coarse clock's reading where
/// the stretch of those that ran ends (`t` if none ran). The outer `None`:
/// left behind.
#[inline(always)]
fn run_stretch<B: Bodies>(
    b: &mut B,
    plan: &Plan,
    fast: &[Fast],
    steps: std::ops::Range<usize>,
    t: Option<Stamp>,
) -> Option<(usize, Option<Stamp>)> {
    // When the stretch started on the coarse clock (where the body before
    // ended), and the shortest deadline of its steps.
    let mut start = None;
    let mut shortest = u32::MAX;
    let mut k = steps.start;
    for f in fast {
        // Its entries are in the order of the steps: the stretch ends at
        // the first step that is not one of them.
        if f.step as usize != k || k >= steps.end {
            break;
        }
        let m = b.manager()?;
        let out = &m.slots[f.output as usize];
        if out.writer != f.inst || out.stamp == 0 {
            break;
        }
        let fresh = match f.input() {
            Some(input) => {
                let input = &m.slots[input];
                input.value.is_some() && input.stamp == m.cycle
            }
            None => true,
        };
        if fresh {
            if start.is_none() {
                start = Some(match t {
                    Some(Stamp::Coarse(ns)) => ns,
                    _ => coarse_ns(),
                });
            }
            shortest = shortest.min(f.deadline_us);
            if !b.run_fast(f)? {
                b.manager()?.finish_step(plan, k);
            }
        }
        k += 1;
    }
    let t = match start {
        Some(start) => Some(b.manager()?.end_stretch(start, u64::from(shortest) * 1_000)),
        None => t,
    };
    Some((k, t))
}

/// Step `k` the usual way: its inputs checked and gathered (a plain step's
/// lent, or read in place from its one slot where the bodies
/// [may](Bodies::IN_PLACE)), run timed from `t` (see [`run_steps`]), its
/// outputs committed. Returns the clock's reading to time the next body
/// from, as [`run_steps`] does.
#[inline(always)]
fn run_step<B: Bodies>(b: &mut B, plan: &Plan, k: usize, t: Option<Stamp>) -> Option<Option<Stamp>> {
    let step = &plan.steps[k];
    let m = b.manager()?;
    let fresh = match step.kind {
        StepKind::AsyncThreaded => {
            m.exchange_async(step.inst);
            // Not the time of a body: the next one reads the clock.
            return Some(None);
        }
        StepKind::AsyncInCycle => false,
        StepKind::Sync => true,
    };
    // One plain input, present: the body reads it where it is.
    let in_place = match step.one_input {
        Some(leaf) if B::IN_PLACE => {
            let slot = &m.slots[leaf];
            slot.value.is_some() && (!fresh || slot.stamp == m.cycle)
        }
        _ => false,
    };
    let lent = step.plain_ins && !in_place;
    let ready_now = in_place || if lent { m.lend_inputs(plan, step, fresh) } else { m.gather_step(plan, step, fresh) };
    if !ready_now {
        return Some(t);
    }
    let start = m.start_of(t, step, k);
    let end = b.run(step.inst, if in_place { step.one_input } else { None }, start)?;
    let m = b.manager()?;
    if lent {
        m.return_lent(plan, step);
    } else if !in_place {
        m.execs[step.inst].drop_copies();
    }
    let ok = m.finish_step(plan, k);
    Some(match end {
        Stamp::Coarse(_) if ok => Some(end),
        _ => None,
    })
}

/// A level that may go parallel: copies of its steps' inputs gathered, its
/// ready bodies run (on the pool when worth it, see
/// [`Manager::worth_parallel`], else in order), then committed in order.
fn run_level<B: Bodies>(b: &mut B, plan: &Plan, level: usize, ready: &mut Vec<usize>) -> Option<()> {
    let m = b.manager()?;
    m.prepare_steps(plan, level, ready);
    if m.worth_parallel(plan, ready) {
        for batch in m.batches(plan, ready) {
            b.run_batch(&batch)?;
        }
    } else {
        let mut t = None;
        for &k in ready.iter() {
            let step = &plan.steps[k];
            let start = b.manager()?.start_of(t, step, k);
            t = Some(b.run(step.inst, None, start)?);
        }
    }
    let m = b.manager()?;
    for &k in ready.iter() {
        m.execs[plan.steps[k].inst].drop_copies();
        m.finish_step(plan, k);
    }
    Some(())
}

impl Manager {
    /// Ends a stretch of steps run the short way that started at `start`
    /// (coarse clock): the time now, for the next body to start from. A body
    /// of the stretch may have run past its deadline only if the whole
    /// stretch did; then the next cycle is a sampled one, timing every body
    /// exactly, so that a body late every run is faulted from then on (the
    /// watchdog of a spawned manager leaves one past its deadline behind
    /// while it runs, in any cycle).
    #[inline(never)]
    fn end_stretch(&mut self, start: u64, shortest: u64) -> Stamp {
        let now = coarse_ns();
        if now.saturating_sub(start) > shortest.saturating_add(coarse_tick_ns()) {
            self.sample_next = true;
        }
        Stamp::Coarse(now)
    }

    /// The clock reading to time `step`'s body (step `k` of the plan) from:
    /// `t`, the end of the body before, when it is on the clock this one
    /// needs (exact in a sampled cycle's window or for a short deadline,
    /// else coarse); else now.
    #[inline(always)]
    fn start_of(&self, t: Option<Stamp>, step: &Step, k: usize) -> Stamp {
        let precise = step.precise || self.timed_exactly(k);
        match t {
            Some(t) if precise == matches!(t, Stamp::Precise(_)) => t,
            _ => Stamp::now(precise),
        }
    }

    /// Lends a plain step its inputs if it is ready: each present input is
    /// moved from its slot into the body's buffer (no reference counting;
    /// nothing else reads a slot while a serial level runs), to be put back
    /// after the run ([`Manager::return_lent`]). `fresh`: as in
    /// [`Manager::gather_step`]. Returns whether the step is ready (if not,
    /// nothing was moved).
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

    /// Puts a step's lent inputs back in their slots, swapped (see
    /// [`Manager::lend_inputs`]).
    #[inline]
    fn return_lent(&mut self, plan: &Plan, step: &Step) {
        let ins = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
        for (port, input) in ins.iter().zip(self.execs[step.inst].inputs.iter_mut()) {
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
}

/// Commits the output of a step run the short way ([`Fast`]) whose run was
/// clean: moved into its slot, which it holds, with no check (it is of its
/// type by construction, and no other skill writes the leaf).
#[inline(always)]
pub(super) fn commit_fast(exec: &mut Exec, slot: &mut Slot, cycle: u64, rank: (i32, u32)) {
    exec.untimed_runs += 1;
    if let Some(out) = exec.outputs.first_mut() {
        if out.is_some() {
            // Swapped, as in `commit_plain_port`: the output buffer then
            // holds the value it replaced, recycled (or filled) next run.
            std::mem::swap(&mut slot.value, out);
            slot.stamp = cycle;
            slot.rank = rank;
        }
    }
}
