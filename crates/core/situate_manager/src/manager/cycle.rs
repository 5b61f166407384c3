//! One cycle of the manager, step by step (see the parent module): the
//! boundary, the dskills' readings, the plan's levels gathered, run and
//! committed, the dskills' commands, the monitors, the cycle's statistics;
//! and the exchanges with skills on threads of their own.

use std::sync::Arc;
use std::time::{Duration, Instant};

use situate_core::value::recycle;
use situate_core::{SignalType, Value};

use super::plan::{Plan, Step, StepKind};
use super::slots::{assemble_into, Slot};
use super::{fmt_duration, Frame, Inst, Manager, RefTarget, SAMPLED_STEPS, TIMING_SAMPLE};
use crate::config::ClockKind;
use crate::control::{Event, Request};
use crate::expr::Lookup;
use crate::runner::{coarse_ns, coarse_tick_ns, WorkerStats};

impl Manager {
    pub(super) fn compile_schedule(&mut self) {
        let insts = &self.insts;
        *self.schedule = Plan::compile(
            &self.graph,
            |i| insts[i].active,
            |i| insts[i].priority,
            |i| insts[i].worker.is_some(),
            |i| insts[i].outputs_by,
        );
        self.schedule_dirty = false;
        // Input buffers may hold copies from a run under the last plan (a
        // parallel level gathers copies); a step that now reads its input in
        // place leaves its buffer alone, and a query of the skill's inputs
        // must not show an old copy from there (it reads the slot instead).
        for step in &self.schedule.steps {
            for input in &mut self.execs[step.inst].inputs {
                if let Some(old) = input.take() {
                    recycle(old);
                }
            }
        }
    }

    /// A step that writes its fixed-size array into its slot keeps no spare
    /// of its own, but a sampled cycle whose window holds it (or a cycle
    /// where its slot was never written) runs it the usual way, writing into
    /// its output buffer, and its commit leaves there the value it replaced
    /// in the slot: none, the first time. A spare is made then, at the end
    /// of that cycle (the first one: not a steady cycle), so that neither
    /// way allocates again. Called at the end of a sampled cycle (a walk
    /// over the short way's steps at most once a tick of the coarse clock).
    fn spares_for_in_slot(&mut self) {
        for f in &self.schedule.fast {
            if !f.in_slot {
                continue;
            }
            let i = f.inst as usize;
            let (Some(port), Some(out)) = (self.graph.instances[i].outputs.first(), self.execs[i].outputs.first_mut())
            else {
                continue;
            };
            // Only a fixed-size array is written into its buffer; any other
            // value is made anew whatever the buffer holds.
            if out.is_none() && matches!(port.ty, SignalType::Array { len: Some(_), .. }) {
                *out = Some(Value::zero(&port.ty));
            }
        }
    }

    /// Runs one cycle (the steps in the parent module's docs; the walk
    /// itself is `walk::cycle`, shared with the spawned manager).
    pub fn cycle(&mut self) {
        let _ = super::walk::cycle(&mut super::executor::InPlace(self));
    }

    /// Whether a cycle due to be sampled by its number is (see
    /// [`TIMING_SAMPLE`]): the first, and then one at least a tick of the
    /// coarse clock after the last.
    fn sample_due(&mut self) -> bool {
        let now = coarse_ns();
        let due = self.last_sample_coarse == 0 || now.saturating_sub(self.last_sample_coarse) >= coarse_tick_ns();
        if due {
            self.last_sample_coarse = now.max(1);
        }
        due
    }

    /// The plan's steps a sampled cycle times exactly: all of them when
    /// `forced` (bodies ran late) or when they are few, else the next
    /// [`SAMPLED_STEPS`] of them, from where the last window ended.
    fn sample_window(&mut self, forced: bool) -> (usize, usize) {
        let n = self.schedule.steps.len();
        if forced || n <= SAMPLED_STEPS {
            return (0, n);
        }
        let from = if self.sample_from < n { self.sample_from } else { 0 };
        let to = (from + SAMPLED_STEPS).min(n);
        self.sample_from = if to < n { to } else { 0 };
        (from, to)
    }

    /// Whether this cycle times step `k` of its plan exactly (one flag
    /// read in a cycle that is not sampled).
    #[inline(always)]
    pub(super) fn timed_exactly(&self, k: usize) -> bool {
        self.sampled && (self.exact.0..self.exact.1).contains(&k)
    }

    /// Steps 0–2 of a cycle: the boundary and the dskills' readings.
    pub(super) fn begin_cycle(&mut self) {
        self.cycle += 1;
        let forced = std::mem::take(&mut self.sample_next);
        self.sampled = forced || (self.cycle % TIMING_SAMPLE == 1 && self.sample_due());
        self.cycle_timed = self.sampled || self.clock == ClockKind::Wall || self.speed.is_some() || self.due.is_some();
        if self.cycle_timed {
            self.cycle_start = Instant::now();
            if let Some(due) = self.due.take() {
                if self.cycle_start.saturating_duration_since(due).as_secs_f64() > self.period_s / 2.0 {
                    self.late_starts += 1;
                }
            }
            if let Some((last, at)) = self.last_start {
                let cycles = self.cycle.saturating_sub(at).max(1) as f64;
                let dt = self.cycle_start.saturating_duration_since(last).as_secs_f64() / cycles;
                // Over about the last 20 timed cycles.
                self.interval_s = Some(match self.interval_s {
                    Some(avg) => avg + (dt - avg) / 20.0,
                    None => dt,
                });
            }
            self.last_start = Some((self.cycle_start, self.cycle));
        } else {
            self.cycle_start_coarse = coarse_ns();
        }
        self.time_s = match self.clock {
            ClockKind::Simulated => self.cycle as f64 * self.period_s,
            ClockKind::Wall => self.started.elapsed().as_secs_f64(),
        };
        if !self.activated.is_empty() || !self.deactivated.is_empty() {
            let event = Event::ActivationApplied {
                activated: std::mem::take(&mut self.activated),
                deactivated: std::mem::take(&mut self.deactivated),
                cycle: self.cycle,
            };
            self.bus.send(event);
        }
        if !self.switched.is_empty() {
            self.switch_bodies();
        }
        if self.schedule_dirty {
            self.compile_schedule();
        }
        // Of the plan this cycle walks (read only when it is sampled).
        if self.sampled {
            self.exact = self.sample_window(forced);
        }
        let devices = std::mem::take(&mut self.schedule.devices);
        for &d in &devices {
            self.take_readings(d);
        }
        self.schedule.devices = devices;
    }

    /// Step 1b: tells the bodies in place that were switched on or off since
    /// the last cycle (`Skill::deactivate`, then `Skill::activate`), on this
    /// thread, before anything runs. A threaded body is told by its worker
    /// (`runner::Mailbox::switches`); a body left behind is not told.
    #[cold]
    fn switch_bodies(&mut self) {
        // A failed activation faults the skill, which switches it off again and lists it anew.
        let mut k = 0;
        while let Some(&i) = self.switched.get(k) {
            k += 1;
            self.insts[i].switched = false;
            let active = self.insts[i].active;
            let exec = &mut *self.execs[i];
            let Some(skill) = exec.skill.as_mut() else { continue };
            exec.cx.set(self.cycle, self.time_s);
            if std::mem::take(&mut exec.on) {
                if let Err(e) = crate::runner::run_hook(skill.as_mut(), false, &mut exec.cx) {
                    crate::runner::deactivate_failed(&mut exec.cx, &e);
                }
            }
            let result = if active { crate::runner::run_hook(skill.as_mut(), true, &mut exec.cx) } else { Ok(()) };
            exec.on = active && result.is_ok();
            let prints = exec.cx.take_prints();
            if !prints.is_empty() {
                self.record_prints(i, prints);
            }
            if let Err(cause) = result {
                self.fault(i, cause);
            }
        }
        self.switched.clear();
    }

    /// Gathers copies of the inputs of level `level`'s steps; those ready
    /// to run go to `ready`.
    pub(super) fn prepare_steps(&mut self, plan: &Plan, level: usize, ready: &mut Vec<usize>) {
        ready.clear();
        let Some(steps) = plan.level(level) else { return };
        for k in steps {
            let step = &plan.steps[k];
            match step.kind {
                StepKind::AsyncThreaded => self.exchange_async(step.inst),
                StepKind::AsyncInCycle => {
                    if self.gather_step(plan, step, false) {
                        ready.push(k);
                    }
                }
                StepKind::Sync => {
                    if self.gather_step(plan, step, true) {
                        ready.push(k);
                    }
                }
            }
        }
    }

    /// Step 4: hand every active dskill the commands written this cycle;
    /// the lockstep ones whose device exchange runs in the cycle go to
    /// `self.exchanging`.
    pub(super) fn prepare_exchanges(&mut self) {
        if self.schedule.devices.is_empty() {
            self.exchanging.clear();
            return;
        }
        let devices = std::mem::take(&mut self.schedule.devices);
        let mut exchanging = std::mem::take(&mut self.exchanging);
        exchanging.clear();
        for &d in &devices {
            if self.hand_commands(d) {
                exchanging.push(d);
            }
        }
        self.exchanging = exchanging;
        self.schedule.devices = devices;
    }

    /// Steps 5 and 6: monitors, then the cycle's statistics. `coarse`: the
    /// coarse clock's reading where the last body ended, if nothing that
    /// may take time (an exchange with a device) ran since.
    pub(super) fn end_cycle(&mut self, coarse: Option<u64>) {
        if self.sampled {
            self.spares_for_in_slot();
        }
        let watched = !self.monitors.list.is_empty() || !self.taps.is_empty();
        self.evaluate_monitors();
        self.tally_winners();
        if !self.taps.is_empty() {
            self.send_frame();
        }
        if !self.cycle_timed {
            // Between samples: the coarse clock catches a long cycle. The
            // last body's reading is as good where no monitor or tap ran
            // since (the rest of the cycle is well within a tick).
            let now = match coarse {
                Some(ns) if !watched => ns,
                _ => coarse_ns(),
            };
            let elapsed = now.saturating_sub(self.cycle_start_coarse);
            self.cycle_timing.seen(elapsed);
            return;
        }
        let elapsed = self.cycle_start.elapsed().as_nanos() as u64;
        self.cycle_timing.record(elapsed);
        if self.clock == ClockKind::Wall && elapsed as f64 > self.period_s * 1e9 {
            self.overruns += 1;
        }
    }

    /// Hands the values written this cycle to the tap (a full tap loses the
    /// frame, counted, or, if it asked to and the clock is simulated, is
    /// waited for; a closed one is removed).
    #[cold]
    fn send_frame(&mut self) {
        self.take_back_frames();
        let cycle = self.cycle;
        let (mut values, mut winners) = match self.spare_frame.take() {
            Some(f) => (f.values, f.winners),
            None => (crate::FrameValues::default(), Vec::new()),
        };
        values.reserve(self.slots.len());
        for (l, s) in self.slots.iter().enumerate() {
            if s.stamp == cycle {
                if let Some(v) = &s.value {
                    values.push(l, v);
                }
            }
        }
        winners.extend(
            self.tallies
                .iter()
                .filter(|t| self.slots[t.leaf].stamp == cycle)
                .map(|t| (t.leaf, self.slots[t.leaf].writer as usize)),
        );
        let prints = std::mem::take(&mut self.tap_prints);
        let frame = Frame { cycle, time_s: self.time_s, values, prints, winners };
        let simulated = self.clock == ClockKind::Simulated;
        let send = |tap: &super::Tap, frame: Frame| match tap.tx.try_send(frame) {
            Ok(()) => true,
            // No robot time passes while the cycle waits: the run is the
            // same, only slower, and the reader loses nothing.
            Err(crossbeam_channel::TrySendError::Full(frame))
                if simulated && tap.when_full == crate::frame::WhenFull::WaitIfSimulated =>
            {
                tap.tx.send(frame).is_ok()
            }
            Err(crossbeam_channel::TrySendError::Full(_)) => {
                tap.drops.lock().unwrap_or_else(|p| p.into_inner()).add(cycle);
                true
            }
            Err(crossbeam_channel::TrySendError::Disconnected(_)) => false,
        };
        // Each tap but the last gets a copy.
        let Some((last, others)) = self.taps.split_last() else { return };
        // Taps whose receiver is gone (`Vec::new` allocates nothing).
        let mut gone = Vec::new();
        for (k, tap) in others.iter().enumerate() {
            if !send(tap, frame.clone()) {
                gone.push(k);
            }
        }
        if !send(last, frame) {
            gone.push(others.len());
        }
        for k in gone.into_iter().rev() {
            self.taps.remove(k);
        }
    }

    /// Takes back the frames the taps' readers are done with
    /// ([`TapReceiver::give_back`](super::TapReceiver::give_back)): their
    /// shared values are let go of here, on the cycle's thread; one frame's
    /// buffers are kept, emptied, for the next frame.
    fn take_back_frames(&mut self) {
        for tap in &self.taps {
            // A few per cycle: the work is bounded whatever the reader does.
            for _ in 0..4 {
                let Ok(mut frame) = tap.returns.try_recv() else { break };
                frame.values.clear(recycle);
                frame.winners.clear();
                frame.prints.clear();
                if self.spare_frame.is_none() {
                    self.spare_frame = Some(frame);
                }
            }
        }
    }

    /// Counts, per resource, whether a skill won it this cycle and whether
    /// that was another skill than the last winner (a handful of leaves: the
    /// cycle's cost does not change).
    fn tally_winners(&mut self) {
        for t in &mut self.tallies {
            let slot = &self.slots[t.leaf];
            if slot.stamp != self.cycle || slot.stamp == 0 {
                continue;
            }
            t.held += 1;
            if t.last.is_some_and(|w| w != slot.writer) {
                t.switches += 1;
            }
            t.last = Some(slot.writer);
        }
    }

    /// Collects a step's inputs into its buffers: plain ports straight from
    /// their slot, the others through the graph. `fresh`: every required
    /// input must have been written this cycle (sync cskills); otherwise the
    /// latest values do (async cskills). Returns whether the skill is ready.
    pub(super) fn gather_step(&mut self, plan: &Plan, step: &Step, fresh: bool) -> bool {
        let i = step.inst;
        let ports = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
        if !step.plain_ins {
            return self.gather(i, fresh);
        }
        let exec = &mut self.execs[i];
        let cycle = self.cycle;
        for (port, input) in ports.iter().zip(exec.inputs.iter_mut()) {
            let slot = &self.slots[port.leaf];
            let present = slot.value.is_some() && (!fresh || slot.stamp == cycle);
            if !present && !port.optional {
                return false;
            }
            let new = if present { slot.value.clone() } else { None };
            if let Some(old) = std::mem::replace(input, new) {
                recycle(old);
            }
        }
        true
    }

    /// Collects instance `i`'s inputs into its buffers. `fresh`: every
    /// required input must have been written this cycle (sync cskills,
    /// dskill commands); otherwise the latest values do (async cskills).
    /// Returns whether the skill is ready.
    pub(super) fn gather(&mut self, i: usize, fresh: bool) -> bool {
        let def = &self.graph.instances[i];
        let exec = &mut self.execs[i];
        let cycle = self.cycle;
        for (p, port) in def.inputs.iter().enumerate() {
            let present = port.leaves.iter().all(|&l| {
                let s = &self.slots[l];
                s.value.is_some() && (!fresh || s.stamp == cycle)
            });
            let input = &mut exec.inputs[p];
            if !present {
                if !port.optional {
                    return false;
                }
                *input = None;
            } else if port.leaves.len() == 1 && !matches!(port.ty, SignalType::Record(_)) {
                input.clone_from(&self.slots[port.leaves[0]].value);
            } else {
                // A record: written into the last one in place (see `assemble_into`).
                let slots = &self.slots;
                assemble_into(&port.ty, &mut port.leaves.iter().filter_map(|&l| slots[l].value.as_ref()), input);
            }
        }
        true
    }

    /// Records a run's timing and prints; the cause of its fault if it failed
    /// or ran over its deadline (its outputs are then dropped).
    pub(super) fn account(&mut self, i: usize) -> Result<(), String> {
        let deadline = self.graph.instances[i].in_cycle_deadline();
        self.account_by(i, deadline.as_nanos().min(u64::MAX as u128) as u64)
    }

    #[inline]
    pub(super) fn account_by(&mut self, i: usize, deadline_ns: u64) -> Result<(), String> {
        self.count_run(i);
        let exec = &mut self.execs[i];
        let (elapsed, timed) = (exec.elapsed_ns, exec.timed);
        if exec.cx.has_prints() {
            let prints = exec.cx.take_prints();
            self.record_prints(i, prints);
        }
        // On the coarse clock a run is late only when it certainly is: its
        // reading can exceed the exact time by up to one tick.
        let late = elapsed > deadline_ns && (timed || elapsed > deadline_ns.saturating_add(coarse_tick_ns()));
        if !late && self.execs[i].result.is_ok() {
            // Nothing moved (a `Result` moved through a temporary costs more
            // than the test).
            return Ok(());
        }
        self.failed_run(i, elapsed, deadline_ns, late)
    }

    /// Counts instance `i`'s last run in its timing: a timed one there at
    /// once, with the untimed ones before it; an untimed one only in its
    /// `Exec` (see [`Exec::untimed_runs`](crate::runner::Exec)), so that the
    /// cycle does not touch the instance's other state on most runs.
    #[inline(always)]
    pub(super) fn count_run(&mut self, i: usize) {
        let exec = &mut self.execs[i];
        if exec.timed {
            let timing = &mut self.insts[i].timing;
            timing.add_untimed(std::mem::take(&mut exec.untimed_runs), std::mem::take(&mut exec.untimed_ns));
            timing.record(exec.elapsed_ns);
        } else {
            exec.untimed_runs += 1;
            exec.untimed_ns += exec.elapsed_ns;
        }
    }

    /// [`Manager::account_by`] for a run that failed or was late: the cause,
    /// its outputs dropped.
    #[cold]
    fn failed_run(&mut self, i: usize, elapsed: u64, deadline_ns: u64, late: bool) -> Result<(), String> {
        // On the simulated clock the time its thread waited for a CPU does not count: a run is
        // late only on the time it ran or blocked (`crate::starved`).
        let waited = match &self.starved {
            Some(s) if late => s.since(crate::runner::coarse_ns().saturating_sub(elapsed)),
            _ => 0,
        };
        let late = late && elapsed.saturating_sub(waited) > deadline_ns;
        let result = std::mem::replace(&mut self.execs[i].result, Ok(()));
        let outcome = match result {
            Err(e) => Err(e),
            Ok(()) if late => {
                let def = &self.graph.instances[i];
                let (what, key) = if def.kind.is_threaded() {
                    ("liveness deadline", "liveness_ms")
                } else {
                    ("execution budget", "budget_ms")
                };
                let ran = fmt_duration(Duration::from_nanos(elapsed.saturating_sub(waited)));
                let waiting = if waited > 0 {
                    format!(" (and {} waiting for a CPU)", fmt_duration(Duration::from_nanos(waited)))
                } else {
                    String::new()
                };
                Err(format!(
                    "its body ran for {ran}{waiting}, over its {what} of {} (`{key}`); what it produced is dropped",
                    fmt_duration(Duration::from_nanos(deadline_ns))
                ))
            }
            Ok(()) => Ok(()),
        };
        if outcome.is_err() {
            self.execs[i].outputs.fill(None);
        }
        outcome
    }

    /// Commits a step's outputs, or marks the skill faulted (then false).
    ///
    /// The usual run (on time, no error, no prints, plain outputs) is
    /// accounted here and its outputs committed; any other goes the long
    /// way ([`Manager::finish_step_slow`], out of line, so this stays small).
    pub(super) fn finish_step(&mut self, plan: &Plan, k: usize) -> bool {
        let step = &plan.steps[k];
        let i = step.inst;
        let exec = &self.execs[i];
        // Within its deadline it is on time on either clock (`account_by`).
        if !step.plain_outs || exec.elapsed_ns > step.deadline_ns || exec.result.is_err() || exec.cx.has_prints() {
            return self.finish_step_slow(plan, k);
        }
        self.count_run(i);
        match self.commit_plain(step, &plan.outs[step.outs.0 as usize..step.outs.1 as usize]) {
            Ok(()) => true,
            Err(cause) => {
                self.fault(i, cause);
                false
            }
        }
    }

    /// [`Manager::finish_step`] for any run: accounted (faulted if it failed
    /// or ran late), then committed.
    #[inline(never)]
    fn finish_step_slow(&mut self, plan: &Plan, k: usize) -> bool {
        let step = &plan.steps[k];
        let i = step.inst;
        if let Err(cause) = self.account_by(i, step.deadline_ns) {
            self.fault(i, cause);
            return false;
        }
        let outcome = if step.plain_outs {
            self.commit_plain(step, &plan.outs[step.outs.0 as usize..step.outs.1 as usize])
        } else {
            let mut outputs = std::mem::take(&mut self.execs[i].outputs);
            let outcome = self.commit(i, &mut outputs);
            self.execs[i].outputs = outputs;
            outcome
        };
        match outcome {
            Ok(()) => true,
            Err(cause) => {
                self.fault(i, cause);
                false
            }
        }
    }

    /// Async cskill on its thread: hand over the latest inputs, take the
    /// latest result. Never waits for the body.
    pub(super) fn exchange_async(&mut self, i: usize) {
        let ready = self.gather(i, false);
        let Some(worker) = self.insts[i].worker.as_ref() else { return };
        let shared = Arc::clone(&worker.shared);
        let mut outputs = std::mem::take(&mut self.insts[i].taken);
        let (fault, prints, busy) = {
            let mut mb = shared.lock();
            if ready {
                for (slot, v) in mb.inputs.iter_mut().zip(&self.execs[i].inputs) {
                    slot.clone_from(v);
                }
                mb.inputs_new = true;
                mb.cycle = self.cycle;
                mb.time_s = self.time_s;
            }
            mb.take_fresh_into(&mut outputs);
            (mb.fault.take(), std::mem::take(&mut mb.prints), (mb.busy_since, Some(mb.stats)))
        };
        shared.notify();
        self.threaded_results(i, &mut outputs, fault, prints, busy);
        outputs.fill(None);
        self.insts[i].taken = outputs;
    }

    /// dskill readings at the start of a cycle: those produced since the
    /// last cycle took them (from its mailbox; a lockstep one's are already
    /// in `taken`).
    pub(super) fn take_readings(&mut self, d: usize) {
        let mut outputs = std::mem::take(&mut self.insts[d].taken);
        let (fault, prints, busy) = match self.insts[d].worker.as_ref() {
            Some(worker) => {
                let mut mb = worker.shared.lock();
                mb.take_fresh_into(&mut outputs);
                (mb.fault.take(), std::mem::take(&mut mb.prints), (mb.busy_since, Some(mb.stats)))
            }
            None => (None, Vec::new(), (None, None)),
        };
        self.threaded_results(d, &mut outputs, fault, prints, busy);
        if self.insts[d].worker.is_none() {
            // A lockstep device's body gets back the records its readings
            // replaced (see `commit`), to write the next ones in place.
            for (spare, out) in outputs.iter_mut().zip(self.execs[d].outputs.iter_mut()) {
                if out.is_none() {
                    *out = spare.take();
                }
            }
        }
        // Committed (or dropped with a fault): nothing is carried over.
        outputs.fill(None);
        self.insts[d].taken = outputs;
    }

    /// `busy` is when the body's current run began and the worker's run
    /// statistics, read under the same lock as `outputs` (so `runs` counts
    /// exactly the runs whose results have been taken).
    pub(super) fn threaded_results(
        &mut self,
        i: usize,
        outputs: &mut [Option<Value>],
        fault: Option<String>,
        prints: Vec<String>,
        busy: (Option<Instant>, Option<WorkerStats>),
    ) {
        let (busy_since, stats) = busy;
        if let Some(stats) = stats {
            self.insts[i].timing = stats;
        }
        if !prints.is_empty() {
            self.record_prints(i, prints);
        }
        if let Some(cause) = fault {
            if self.insts[i].worker.as_ref().is_some_and(|w| w.shared.lock().dead) {
                // Its thread is gone: activating it again makes a fresh body and thread.
                self.insts[i].abandoned = true;
            }
            self.fault(i, cause);
            return;
        }
        if let Some(since) = busy_since {
            let ran = since.elapsed();
            if ran > self.graph.instances[i].liveness {
                self.abandon(i, ran);
                return;
            }
        }
        if let Err(cause) = self.commit(i, outputs) {
            self.fault(i, cause);
        }
    }

    /// dskill commands at the end of a cycle: those written this cycle. A
    /// threaded dskill gets them in its mailbox; true for a lockstep one,
    /// whose device exchange then runs in the cycle.
    pub(super) fn hand_commands(&mut self, d: usize) -> bool {
        if !self.insts[d].active {
            return false;
        }
        // Every command port is optional for a device: gather never refuses.
        let def = &self.graph.instances[d];
        let cycle = self.cycle;
        for (p, port) in def.inputs.iter().enumerate() {
            let fresh = port.leaves.iter().all(|&l| self.slots[l].stamp == cycle && self.slots[l].value.is_some());
            let input = &mut self.execs[d].inputs[p];
            if fresh {
                let slots = &self.slots;
                assemble_into(&port.ty, &mut port.leaves.iter().filter_map(|&l| slots[l].value.as_ref()), input);
            } else {
                *input = None;
            }
        }
        match self.insts[d].worker.as_ref() {
            Some(worker) => {
                let mut mb = worker.shared.lock();
                for (slot, v) in mb.inputs.iter_mut().zip(&self.execs[d].inputs) {
                    if v.is_some() {
                        slot.clone_from(v);
                    }
                }
                mb.cycle = cycle;
                mb.time_s = self.time_s;
                false
            }
            None => true,
        }
    }

    /// After a lockstep dskill's device exchange: its readings are taken at
    /// the start of the next cycle; a failed exchange's are dropped.
    pub(super) fn finish_exchange(&mut self, d: usize) {
        let outcome = self.account(d);
        let exec = &mut self.execs[d];
        for (slot, out) in self.insts[d].taken.iter_mut().zip(&mut exec.outputs) {
            if let Some(v) = out.take() {
                *slot = Some(v);
            }
        }
        if let Err(cause) = outcome {
            self.fault(d, cause);
        }
    }

    pub(super) fn evaluate_monitors(&mut self) {
        self.paused = false;
        if self.monitors.list.is_empty() {
            return;
        }
        let mut fired: Vec<Event> = Vec::new();
        let mut pause = false;
        let clock = [Value::F64(self.time_s), Value::I64(self.cycle as i64)];
        let env = Env { refs: &self.refs, slots: &self.slots, insts: &self.insts, clock: &clock };
        let (cycle, time_s) = (self.cycle, self.time_s);
        // A leaf changes when written, and when its writer is switched on again (what it wrote
        // before goes missing: `Env::value`).
        let changed = |r: usize| match self.refs.get(r) {
            Some(RefTarget::Leaf(l)) => self.slots.get(*l).is_some_and(|s| {
                s.stamp == cycle || self.insts.get(s.writer as usize).is_some_and(|w| w.active_from == cycle)
            }),
            Some(RefTarget::Param(i, _)) => self.insts.get(*i).is_some_and(|s| s.params_from >= cycle),
            Some(RefTarget::Time | RefTarget::Cycle) | None => true,
        };
        self.monitors.evaluate(&env, &changed, |m| {
            pause |= m.pause;
            let values =
                m.reads.iter().chain(&m.report).map(|(name, r)| (name.clone(), env.value(*r).cloned())).collect();
            fired.push(Event::MonitorFired {
                monitor: m.id,
                condition: m.source.clone(),
                cycle,
                time_s,
                values,
                held: m.held_indexes(),
            });
        });
        for e in fired {
            self.bus.send(e);
        }
        self.paused = pause;
        if pause && self.running {
            let _ = self.request(Request::Stop);
        }
    }
}

struct Env<'a> {
    refs: &'a [RefTarget],
    slots: &'a [Slot],
    insts: &'a [Inst],
    /// `[time, cycle]`.
    clock: &'a [Value; 2],
}

impl Lookup for Env<'_> {
    fn value(&self, id: usize) -> Option<&Value> {
        match self.refs.get(id)? {
            RefTarget::Leaf(l) => {
                let slot = self.slots.get(*l)?;
                // Written by a skill in an earlier activation, and not yet in this one: missing.
                let old = self.insts.get(slot.writer as usize).is_some_and(|w| w.active && slot.stamp < w.active_from);
                if old {
                    return None;
                }
                slot.value.as_ref()
            }
            RefTarget::Param(i, p) => self.insts.get(*i)?.params.get(*p),
            RefTarget::Time => Some(&self.clock[0]),
            RefTarget::Cycle => Some(&self.clock[1]),
        }
    }
}
