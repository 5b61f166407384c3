//! The skill manager and its data-flow cycle (paper 3.2).
//!
//! One cycle ([`Manager::cycle`], the paper's *do-periodic-step*):
//! 1. apply what the sequencer asked between cycles (done by
//!    [`Manager::request`] at the boundary, so it is in force now);
//! 2. take the latest readings of every active dskill, never blocking;
//! 3. run the active cskills level by level in order of input readiness:
//!    a sync cskill runs when all its required inputs were written this
//!    cycle; an async cskill hands over its latest inputs and gives back its
//!    latest result at once. After each level its outputs are committed to
//!    the leaf slots (the paper's *update-record*); a leaf with several
//!    writers keeps the value of the highest-priority one (arbitration);
//! 4. hand every active dskill the commands written this cycle;
//! 5. evaluate monitors and send events;
//! 6. cleanup: count the cycle, record timing.
//!
//! The schedule (levels of active cskills) is recompiled only when the
//! active set changes, so inactive skills cost nothing per cycle.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use situate_core::value::recycle;
use situate_core::{SignalType, SkillKind, Value};

use crate::config::{ClockKind, ExecutorKind};
use crate::control::*;
use crate::expr::Lookup;
use crate::graph::{assemble, decompose, Graph};
use crate::monitor::Monitors;
use crate::registry::Registry;
use crate::runner::{coarse_tick_ns, BodyClock, Exec, Stamp, Worker, WorkerClock, WorkerStats};
use crate::spec::{BuildError, RobotSpec};

mod front;
mod plan;
mod requests;
mod spawned;
pub(crate) use front::prepare_boxed as prepare;
use front::PreparedMonitor;
/// A prepared monitor, boxed for the request queue.
pub(crate) type PreparedMonitorBox = Box<PreparedMonitor>;
pub use crate::control::EventBus;
use plan::{OutPort, Plan, Step, StepKind};
pub use spawned::Joiner;

/// The cycle times every body exactly once in this many cycles (and the
/// bodies with a short deadline always); in the others it reads only the
/// coarse clock, enough to see a run past its deadline.
pub const TIMING_SAMPLE: u64 = 32;

/// A level's expected work (from its skills' last timed runs) from which
/// the parallel executor hands it to the pool; below, the cycle's thread
/// runs it alone (waking a thread costs some µs, more after an idle spell).
pub const PARALLEL_WORTH_NS: u64 = 40_000;

const PRINT_HISTORY: usize = 64;

/// The most monitors one robot keeps at once (`monitor_add` refuses more);
/// more exactly, the most conditions its monitors watch, an `any` monitor
/// counting as many as it has. Every one may be evaluated each cycle: a bound on
/// their number is a bound on the cycle's cost, whatever the clients do.
pub const MAX_MONITORS: usize = 1000;
/// The most conditions the monitors of one client watch (its `client` name
/// on `monitor_add`; those added without one share one allowance), so that
/// one sequencer that forgets to cancel cannot take the whole robot's.
pub const MAX_MONITORS_PER_CLIENT: usize = 250;
/// One leaf slot of the cycle's data.
#[derive(Clone, Default)]
struct Slot {
    value: Option<Value>,
    /// The cycle it was last written in (0: never).
    stamp: u64,
    /// (priority, declaration rank) of the writer that holds it this cycle.
    rank: (i32, u32),
    writer: u32,
}

/// Runtime state of one instance besides its body.
struct Inst {
    active: bool,
    faulted: Option<String>,
    verbose: bool,
    priority: i32,
    params: Vec<Value>,
    timing: SkillTiming,
    prints: VecDeque<(u64, String)>,
    last_outputs: Vec<Option<Value>>,
    worker: Option<Worker>,
    /// Readings of a lockstep dskill, taken at the next cycle's start.
    lockstep_readings: Vec<Option<Value>>,
    /// Its body was left behind (it ran past its deadline and may never
    /// return): a fresh one is made when it is activated again.
    abandoned: bool,
    /// The cycle from which its parameters last changed (monitors reading
    /// one are evaluated again then).
    params_from: u64,
}

/// What a monitor condition can name: a leaf signal or a parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum RefTarget {
    Leaf(usize),
    Param(usize, usize),
    /// `time`: seconds on the manager's clock.
    Time,
    /// `cycle`: the cycle counter.
    Cycle,
}

/// The skill manager.
pub struct Manager {
    /// Never changes once built; shared with handles (see `front`).
    graph: Arc<Graph>,
    clock: ClockKind,
    period_s: f64,
    pool: Option<Arc<rayon::ThreadPool>>,
    slots: Vec<Slot>,
    insts: Vec<Inst>,
    execs: Vec<Exec>,
    /// The compiled schedule of the active skills.
    schedule: Plan,
    schedule_dirty: bool,
    cycle: u64,
    time_s: f64,
    started: Instant,
    /// When the cycle running now started.
    cycle_start: Instant,
    running: bool,
    last_cycle_ns: u64,
    max_cycle_ns: u64,
    total_cycle_ns: u64,
    overruns: u64,
    /// Cycles that started more than half a period after they were due, and
    /// periods skipped because the cycle could not keep up: whatever held the
    /// cycle back (a long body, requests, a busy machine).
    pub(crate) late_starts: u64,
    /// When the paced loop wanted this cycle to start (set before each cycle).
    pub(crate) due: Option<Instant>,
    /// How long requests served on the cycle's thread ran past the time the
    /// next cycle was due, in all (what link work held the cycle back).
    pub(crate) request_hold_ns: u64,
    /// The time lost to cycles that started so late that periods were
    /// skipped (the schedule restarts from then), whatever held them back:
    /// about `lost_ns / period` cycles short of the nominal rate.
    pub(crate) lost_ns: u64,
    /// The achieved rate: a moving average of the wall time between cycle
    /// starts while running (`None` until two cycles ran back to back).
    interval_s: Option<f64>,
    last_start: Option<Instant>,
    monitors: Monitors,
    refs: Vec<RefTarget>,
    bus: EventBus,
    /// Activation changes applied at this boundary, reported with the next cycle.
    activated: Vec<String>,
    deactivated: Vec<String>,
    /// When running on its own thread, stop after this cycle.
    stop_at: Option<u64>,
    /// Pacing of the simulated clock when spawned (see [`Manager::set_speed`]).
    speed: Option<f64>,
    /// A pausing monitor fired in the last cycle: a running cycle stops, a
    /// step ends early.
    paused: bool,
    /// This cycle times every body exactly (see [`TIMING_SAMPLE`]).
    sampled: bool,
    /// The ready steps of a level (kept to reuse its allocation).
    ready: Vec<usize>,
    /// The lockstep dskills whose device exchange runs this cycle.
    exchanging: Vec<usize>,
    /// Record outputs decomposed into leaves before a commit (reused).
    parts: Vec<Value>,
    /// When each instance's in-cycle body started running (for the watchdog).
    clocks: Arc<[BodyClock]>,
    /// Which cycle thread owns the manager when spawned: bumped when the
    /// watchdog leaves a stuck thread behind, so that thread, if its body
    /// ever returns, knows it is no longer the cycle.
    generation: u64,
}

impl Manager {
    /// Wires the robot, runs every static check and creates the skills.
    pub fn build(spec: &RobotSpec, registry: &Registry) -> Result<Manager, BuildError> {
        let graph = Arc::new(Graph::build(spec, registry)?);
        let mut execs = Vec::with_capacity(graph.instances.len());
        let mut insts = Vec::with_capacity(graph.instances.len());
        let lockstep = spec.clock == ClockKind::Simulated;
        for def in &graph.instances {
            let skill = (def.skill_type.make)().map_err(|e| BuildError {
                diagnostics: vec![spec.diag(
                    crate::spec::Severity::Error,
                    None,
                    format!("skill `{}`: could not create `{}`: {e}", def.name, def.skill_type.decl.type_name),
                )],
            })?;
            let mut exec = Exec::new(skill, def.inputs.len(), def.outputs.len());
            if let Some(skill) = exec.skill.as_mut() {
                for (i, v) in def.params.iter().enumerate() {
                    skill.set_param(i, v);
                }
            }
            let worker =
                (def.kind.is_threaded() && !lockstep).then(|| Worker::new(def.inputs.len(), def.outputs.len()));
            execs.push(exec);
            insts.push(Inst {
                active: false,
                faulted: None,
                verbose: false,
                priority: def.priority,
                params: def.params.clone(),
                timing: SkillTiming::default(),
                prints: VecDeque::new(),
                last_outputs: vec![None; def.outputs.len()],
                worker,
                lockstep_readings: vec![None; def.outputs.len()],
                abandoned: false,
                params_from: 0,
            });
        }
        let started = Instant::now();
        let clocks: Arc<[BodyClock]> = graph.instances.iter().map(|_| BodyClock::new()).collect();
        let pool = match spec.executor {
            ExecutorKind::Serial => None,
            ExecutorKind::Parallel => {
                let threads = spec
                    .threads
                    .unwrap_or_else(|| std::thread::available_parallelism().map(|n| n.get().min(4)).unwrap_or(2));
                // The cycle's own thread takes part in each parallel level, so
                // the pool holds one thread fewer.
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads.saturating_sub(1).max(1))
                    .thread_name(|i| format!("situate-exec-{i}"))
                    .build()
                    .map_err(|e| tracing::warn!(error = %e, "no thread pool: the serial executor runs instead"))
                    .ok()
                    .map(Arc::new)
            }
        };
        let mut manager = Manager {
            slots: vec![Slot::default(); graph.leaves.len()],
            clock: spec.clock,
            period_s: spec.period_s,
            pool,
            insts,
            execs,
            schedule: Plan::default(),
            schedule_dirty: true,
            cycle: 0,
            time_s: 0.0,
            started,
            cycle_start: started,
            running: false,
            last_cycle_ns: 0,
            max_cycle_ns: 0,
            total_cycle_ns: 0,
            overruns: 0,
            late_starts: 0,
            due: None,
            request_hold_ns: 0,
            lost_ns: 0,
            interval_s: None,
            last_start: None,
            monitors: Monitors::default(),
            refs: Vec::new(),
            bus: EventBus::default(),
            activated: Vec::new(),
            deactivated: Vec::new(),
            stop_at: None,
            speed: None,
            paused: false,
            sampled: true,
            ready: Vec::new(),
            exchanging: Vec::new(),
            parts: Vec::new(),
            clocks,
            generation: 0,
            graph,
        };
        let initially: Vec<usize> =
            (0..manager.graph.instances.len()).filter(|&i| manager.graph.instances[i].active).collect();
        for i in initially {
            manager.set_active(i, true);
        }
        manager.activated.clear();
        Ok(manager)
    }

    pub fn graph(&self) -> &Graph {
        &self.graph
    }

    pub fn cycle_count(&self) -> u64 {
        self.cycle
    }

    /// How many monitor conditions have been evaluated so far: one is
    /// evaluated only in a cycle where a name it reads changed.
    pub fn monitor_evaluations(&self) -> u64 {
        self.monitors.evaluations
    }

    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    pub fn events(&self) -> Receiver<Event> {
        self.bus.subscribe()
    }

    fn rank(&self, i: usize) -> (i32, u32) {
        (self.insts[i].priority, u32::MAX - i as u32)
    }

    fn set_active(&mut self, i: usize, active: bool) {
        if self.insts[i].active == active {
            return;
        }
        if active && self.insts[i].abandoned {
            if let Err(e) = self.revive(i) {
                let name = self.graph.instances[i].name.clone();
                let cause = format!("could not make a fresh `{}` to replace the one left behind: {e}", name);
                self.insts[i].faulted = Some(cause.clone());
                self.bus.send(Event::SkillFaulted { skill: name, cause, cycle: self.cycle });
                return;
            }
        }
        let inst = &mut self.insts[i];
        inst.active = active;
        if active {
            inst.faulted = None;
        }
        let def = &self.graph.instances[i];
        if let Some(worker) = inst.worker.as_mut() {
            let period = Duration::from_secs_f64(def.period_s.unwrap_or(self.period_s));
            let clock = match def.kind {
                SkillKind::Device => WorkerClock::Wall(self.started),
                _ => WorkerClock::Cycle,
            };
            worker.set_active(active, &mut self.execs[i], def.kind, &def.name, period, clock);
        }
        self.schedule_dirty = true;
        // The next `activation_applied` says each skill's final state once: a skill turned off
        // and on again before the cycle is listed as activated only (it was listed under both).
        let name = def.name.clone();
        self.activated.retain(|n| *n != name);
        self.deactivated.retain(|n| *n != name);
        if active {
            self.activated.push(name);
        } else {
            self.deactivated.push(name);
        }
    }

    /// A fresh body (and worker) for an instance whose body was left behind,
    /// with the parameters it has now.
    fn revive(&mut self, i: usize) -> Result<(), String> {
        let def = &self.graph.instances[i];
        let mut skill = (def.skill_type.make)()?;
        for (p, v) in self.insts[i].params.iter().enumerate() {
            skill.set_param(p, v);
        }
        self.execs[i] = Exec::new(skill, def.inputs.len(), def.outputs.len());
        let inst = &mut self.insts[i];
        if inst.worker.is_some() {
            inst.worker = Some(Worker::new(def.inputs.len(), def.outputs.len()));
        }
        inst.abandoned = false;
        Ok(())
    }

    /// Leaves instance `i`'s body behind: it has been running for `ran`,
    /// past its deadline, and may never return. The instance is faulted;
    /// whatever the body does when it returns is dropped.
    fn abandon(&mut self, i: usize, ran: Duration) {
        let def = &self.graph.instances[i];
        let (what, deadline) =
            if def.kind.is_threaded() { ("liveness deadline", def.liveness) } else { ("execution budget", def.budget) };
        let place = match (&self.insts[i].worker, def.kind) {
            (Some(_), SkillKind::Device) => "its device thread",
            (Some(_), _) => "its thread",
            (None, _) => "a cycle thread",
        };
        let cause = format!(
            "its body has been running for {} without returning, over its {what} of {} ({}); it is left \
             behind on {place} and the cycle goes on without it (activating it again makes a fresh one)",
            fmt_duration(ran),
            fmt_duration(deadline),
            if def.kind.is_threaded() { "`liveness_ms`" } else { "`budget_ms`" },
        );
        if let Some(worker) = &self.insts[i].worker {
            worker.stop();
        }
        self.insts[i].abandoned = true;
        self.fault(i, cause);
    }

    fn compile_schedule(&mut self) {
        let insts = &self.insts;
        self.schedule =
            Plan::compile(&self.graph, |i| insts[i].active, |i| insts[i].priority, |i| insts[i].worker.is_some());
        self.schedule_dirty = false;
    }

    /// Runs one cycle.
    pub fn cycle(&mut self) {
        self.begin_cycle();
        let plan = std::mem::take(&mut self.schedule);
        let mut ready = std::mem::take(&mut self.ready);
        for level in 0..plan.levels.len() {
            // A level that may go parallel gathers copies of its inputs.
            let lend = self.pool.is_none() || !plan.parallel_level(level);
            self.prepare_steps(&plan, level, &mut ready, lend);
            self.run_ready(&plan, &ready, lend);
            for &k in &ready {
                self.finish_step(&plan, k);
            }
        }
        self.ready = ready;
        self.schedule = plan;
        self.prepare_exchanges();
        let exchanging = std::mem::take(&mut self.exchanging);
        let mut t = Stamp::now(true);
        for &d in &exchanging {
            t = self.execs[d].run(self.cycle, self.time_s, t, None);
        }
        for &d in &exchanging {
            self.finish_exchange(d);
        }
        self.exchanging = exchanging;
        self.end_cycle();
    }

    /// Steps 0–2 of a cycle: the boundary and the dskills' readings.
    fn begin_cycle(&mut self) {
        self.cycle_start = Instant::now();
        if let Some(due) = self.due.take() {
            if self.cycle_start.saturating_duration_since(due).as_secs_f64() > self.period_s / 2.0 {
                self.late_starts += 1;
            }
        }
        if let Some(last) = self.last_start {
            let dt = self.cycle_start.saturating_duration_since(last).as_secs_f64();
            // Over about the last 20 cycles.
            self.interval_s = Some(match self.interval_s {
                Some(avg) => avg + (dt - avg) / 20.0,
                None => dt,
            });
        }
        self.last_start = Some(self.cycle_start);
        self.cycle += 1;
        self.sampled = self.cycle % TIMING_SAMPLE == 1;
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
        if self.schedule_dirty {
            self.compile_schedule();
        }
        let devices = std::mem::take(&mut self.schedule.devices);
        for &d in &devices {
            self.take_readings(d);
        }
        self.schedule.devices = devices;
    }

    /// Step 3 for level `level`: exchanges with threaded async cskills, and
    /// the steps ready to run in the cycle in `self.ready`. False when
    /// there is no such level.
    fn prepare_level(&mut self, level: usize) -> bool {
        if level >= self.schedule.levels.len() {
            return false;
        }
        let plan = std::mem::take(&mut self.schedule);
        let mut ready = std::mem::take(&mut self.ready);
        self.prepare_steps(&plan, level, &mut ready, false);
        self.ready = ready;
        self.schedule = plan;
        true
    }

    /// Gathers the inputs of level `level`'s steps; those ready to run go to `ready`.
    /// `lend`: the level runs serially on this thread (see [`Manager::run_lent`]).
    fn prepare_steps(&mut self, plan: &Plan, level: usize, ready: &mut Vec<usize>, lend: bool) {
        ready.clear();
        let Some(steps) = plan.level(level) else { return };
        for k in steps {
            let step = &plan.steps[k];
            match step.kind {
                StepKind::AsyncThreaded => self.exchange_async(step.inst),
                StepKind::AsyncInCycle => {
                    if self.gather_step(plan, step, false, lend) {
                        ready.push(k);
                    }
                }
                StepKind::Sync => {
                    if self.gather_step(plan, step, true, lend) {
                        ready.push(k);
                    }
                }
            }
        }
    }

    /// Step 4: hand every active dskill the commands written this cycle;
    /// the lockstep ones whose device exchange runs in the cycle go to
    /// `self.exchanging`.
    fn prepare_exchanges(&mut self) {
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

    /// Steps 5 and 6: monitors, then the cycle's statistics.
    fn end_cycle(&mut self) {
        self.evaluate_monitors();
        let elapsed = self.cycle_start.elapsed().as_nanos() as u64;
        self.last_cycle_ns = elapsed;
        self.max_cycle_ns = self.max_cycle_ns.max(elapsed);
        self.total_cycle_ns += elapsed;
        if self.clock == ClockKind::Wall && elapsed as f64 > self.period_s * 1e9 {
            self.overruns += 1;
        }
    }

    /// Collects a step's inputs into its buffers: plain ports straight from
    /// their slot, the others through the graph. `fresh`: every required
    /// input must have been written this cycle (sync cskills); otherwise the
    /// latest values do (async cskills). Returns whether the skill is ready.
    /// `lend`: only check readiness; the inputs are lent to the body when
    /// it runs ([`Manager::run_lent`]).
    fn gather_step(&mut self, plan: &Plan, step: &Step, fresh: bool, lend: bool) -> bool {
        let i = step.inst;
        let ports = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
        if !step.plain_ins {
            return self.gather(i, fresh);
        }
        if lend {
            let cycle = self.cycle;
            return ports.iter().all(|port| {
                let slot = &self.slots[port.leaf];
                port.optional || (slot.value.is_some() && (!fresh || slot.stamp == cycle))
            });
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
    fn gather(&mut self, i: usize, fresh: bool) -> bool {
        let def = &self.graph.instances[i];
        let exec = &mut self.execs[i];
        let cycle = self.cycle;
        for (p, port) in def.inputs.iter().enumerate() {
            let present = port.leaves.iter().all(|&l| {
                let s = &self.slots[l];
                s.value.is_some() && (!fresh || s.stamp == cycle)
            });
            exec.inputs[p] = if !present {
                if !port.optional {
                    return false;
                }
                None
            } else if port.leaves.len() == 1 && !matches!(port.ty, SignalType::Record(_)) {
                self.slots[port.leaves[0]].value.clone()
            } else {
                let slots = &self.slots;
                assemble(&port.ty, &mut port.leaves.iter().filter_map(|&l| slots[l].value.as_ref()))
            };
        }
        true
    }

    /// Splits a level's ready steps into batches of instances that may run
    /// at the same time: skills sharing a claim never do.
    fn batches(&self, plan: &Plan, ready: &[usize]) -> Vec<Vec<usize>> {
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
    fn worth_parallel(&self, plan: &Plan, ready: &[usize]) -> bool {
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

    /// `lent`: the inputs of plain steps are lent when they run.
    fn run_ready(&mut self, plan: &Plan, ready: &[usize], lent: bool) {
        let (cycle, time_s) = (self.cycle, self.time_s);
        if !lent && self.worth_parallel(plan, ready) {
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
                if lent && step.plain_ins {
                    t = self.run_lent(plan, step, t);
                } else {
                    t = self.execs[step.inst].run(cycle, time_s, t, None);
                }
            }
        }
    }

    /// Runs a step whose inputs are all plain ports on the slots' own
    /// values: each present input is moved from its slot into the body's
    /// buffer and back after the run (no reference counting; nothing else
    /// reads a slot while a serial level runs). The readiness was checked
    /// by [`Manager::gather_step`] and the slots have not changed since.
    fn run_lent(&mut self, plan: &Plan, step: &Step, t: Stamp) -> Stamp {
        let ports = &plan.ins[step.ins.0 as usize..step.ins.1 as usize];
        let exec = &mut self.execs[step.inst];
        let fresh = step.kind == StepKind::Sync;
        let cycle = self.cycle;
        for (port, input) in ports.iter().zip(exec.inputs.iter_mut()) {
            let slot = &mut self.slots[port.leaf];
            if slot.value.is_some() && (!fresh || slot.stamp == cycle) {
                *input = slot.value.take();
            }
        }
        let end = exec.run(cycle, self.time_s, t, None);
        for (port, input) in ports.iter().zip(exec.inputs.iter_mut()) {
            if let Some(v) = input.take() {
                self.slots[port.leaf].value = Some(v);
            }
        }
        end
    }

    /// Records a run's timing and prints; the cause of its fault if it failed
    /// or ran over its deadline (its outputs are then dropped).
    fn account(&mut self, i: usize) -> Result<(), String> {
        let deadline = self.graph.instances[i].in_cycle_deadline();
        self.account_by(i, deadline.as_nanos().min(u64::MAX as u128) as u64)
    }

    fn account_by(&mut self, i: usize, deadline_ns: u64) -> Result<(), String> {
        let exec = &mut self.execs[i];
        let elapsed = exec.elapsed_ns;
        let timed = exec.timed;
        let result = std::mem::replace(&mut exec.result, Ok(()));
        let inst = &mut self.insts[i];
        inst.timing.record(timed.then_some(elapsed));
        if exec.cx.has_prints() {
            let prints = exec.cx.take_prints();
            self.record_prints(i, prints);
        }
        // On the coarse clock a run is late only when it certainly is: its
        // reading can exceed the exact time by up to one tick.
        let late = if timed { elapsed > deadline_ns } else { elapsed > deadline_ns.saturating_add(coarse_tick_ns()) };
        let outcome = match result {
            Err(e) => Err(e),
            Ok(()) if late => {
                let def = &self.graph.instances[i];
                let (what, key) = if def.kind.is_threaded() {
                    ("liveness deadline", "liveness_ms")
                } else {
                    ("execution budget", "budget_ms")
                };
                Err(format!(
                    "its body ran for {}, over its {what} of {} (`{key}`); what it produced is dropped",
                    fmt_duration(Duration::from_nanos(elapsed)),
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

    /// Commits a step's outputs, or marks the skill faulted.
    fn finish_step(&mut self, plan: &Plan, k: usize) {
        let step = &plan.steps[k];
        let i = step.inst;
        if let Err(cause) = self.account_by(i, step.deadline_ns) {
            self.fault(i, cause);
            return;
        }
        let mut outputs = std::mem::take(&mut self.execs[i].outputs);
        let outcome = if step.plain_outs {
            self.commit_plain(step, &plan.outs[step.outs.0 as usize..step.outs.1 as usize], &mut outputs)
        } else {
            self.commit(i, &mut outputs)
        };
        self.execs[i].outputs = outputs;
        if let Err(cause) = outcome {
            self.fault(i, cause);
        }
    }

    /// Commits a run's outputs (for the spawned manager: step `k` of the
    /// current plan).
    fn finish(&mut self, k: usize) {
        let plan = std::mem::take(&mut self.schedule);
        self.finish_step(&plan, k);
        self.schedule = plan;
    }

    /// [`Manager::commit`] for a step whose outputs are all plain ports.
    fn commit_plain(&mut self, step: &Step, ports: &[OutPort], outputs: &mut [Option<Value>]) -> Result<(), String> {
        let i = step.inst;
        for (p, (port, value)) in ports.iter().zip(outputs.iter()).enumerate() {
            if let Some(value) = value {
                if !port.check.admits(value) {
                    let def = &self.graph.instances[i].outputs[p];
                    return Err(wrong_output(&def.name, &def.ty, value));
                }
            }
        }
        // A plain output's last value is its slot's while this skill holds
        // it, so a winning value is moved, not shared: `last_outputs` keeps
        // it only when it lost the slot (see `save_displaced`).
        let cycle = self.cycle;
        for (p, (port, out)) in ports.iter().zip(outputs.iter_mut()).enumerate() {
            let Some(value) = out.take() else { continue };
            let last = &mut self.insts[i].last_outputs[p];
            match write_leaf(&mut self.slots[port.leaf], value, cycle, step.rank, i) {
                Ok(displaced) => {
                    if let Some(old) = last.take() {
                        recycle(old);
                    }
                    if let Some((w, old)) = displaced {
                        self.save_displaced(port.leaf, w, old);
                    }
                }
                Err(lost) => *last = Some(lost),
            }
        }
        Ok(())
    }

    /// Writes instance `i`'s produced outputs to their leaves: all of them,
    /// or (when one is not of its port's type) none (update-record is atomic).
    fn commit(&mut self, i: usize, outputs: &mut [Option<Value>]) -> Result<(), String> {
        let graph = Arc::clone(&self.graph);
        let def = &graph.instances[i];
        let mut parts = std::mem::take(&mut self.parts);
        parts.clear();
        // First check every output (records are taken apart into their leaves).
        for (port, value) in def.outputs.iter().zip(outputs.iter()) {
            let Some(value) = value else { continue };
            let ok = if let ([_], false) = (&port.leaves[..], matches!(port.ty, SignalType::Record(_))) {
                value.conforms(&port.ty)
            } else {
                decompose(&port.ty, value, &mut parts)
            };
            if !ok {
                parts.clear();
                self.parts = parts;
                return Err(wrong_output(&port.name, &port.ty, value));
            }
        }
        // Then write them.
        let rank = self.rank(i);
        let cycle = self.cycle;
        let mut leaf_values = parts.drain(..);
        for (p, port) in def.outputs.iter().enumerate() {
            let Some(value) = outputs[p].take() else { continue };
            if let ([leaf], false) = (&port.leaves[..], matches!(port.ty, SignalType::Record(_))) {
                if let Ok(Some((w, old))) = write_leaf(&mut self.slots[*leaf], value.clone(), cycle, rank, i) {
                    self.save_displaced(*leaf, w, old);
                }
            } else {
                for (&leaf, part) in port.leaves.iter().zip(&mut leaf_values) {
                    if let Ok(Some((w, old))) = write_leaf(&mut self.slots[leaf], part, cycle, rank, i) {
                        self.save_displaced(leaf, w, old);
                    }
                }
            }
            if let Some(old) = self.insts[i].last_outputs[p].replace(value) {
                recycle(old);
            }
        }
        drop(leaf_values);
        self.parts = parts;
        Ok(())
    }

    /// Another skill took over `leaf` from writer `w`: the value `w` last
    /// produced there is kept as its last output (a plain port's last output
    /// is otherwise read from its slot).
    fn save_displaced(&mut self, leaf: usize, w: usize, old: Value) {
        let Some(&(_, p)) = self.graph.leaves[leaf].writers.iter().find(|&&(x, _)| x == w) else { return };
        let port = &self.graph.instances[w].outputs[p];
        if port.leaves.len() == 1 && !matches!(port.ty, SignalType::Record(_)) {
            if let Some(last) = self.insts[w].last_outputs.get_mut(p) {
                last.get_or_insert(old);
            }
        }
    }

    /// What instance `i` last produced on output `p`.
    pub(crate) fn last_output(&self, i: usize, p: usize) -> Option<Value> {
        if let Some(v) = &self.insts[i].last_outputs[p] {
            return Some(v.clone());
        }
        let port = &self.graph.instances[i].outputs[p];
        let [leaf] = port.leaves[..] else { return None };
        let slot = &self.slots[leaf];
        (slot.writer as usize == i && slot.stamp > 0).then(|| slot.value.clone()).flatten()
    }

    fn fault(&mut self, i: usize, cause: String) {
        let name = self.graph.instances[i].name.clone();
        tracing::warn!(skill = %name, %cause, "skill faulted");
        self.set_active(i, false);
        // The deactivation is reported as part of the fault.
        self.deactivated.retain(|n| *n != name);
        self.insts[i].faulted = Some(cause.clone());
        self.bus.send(Event::SkillFaulted { skill: name, cause, cycle: self.cycle });
    }

    fn record_prints(&mut self, i: usize, prints: Vec<String>) {
        let inst = &mut self.insts[i];
        for line in prints {
            if inst.verbose {
                self.bus.send(Event::Print {
                    skill: self.graph.instances[i].name.clone(),
                    line: line.clone(),
                    cycle: self.cycle,
                });
            }
            if inst.prints.len() == PRINT_HISTORY {
                inst.prints.pop_front();
            }
            inst.prints.push_back((self.cycle, line));
        }
    }

    /// Async cskill on its thread: hand over the latest inputs, take the
    /// latest result. Never waits for the body.
    fn exchange_async(&mut self, i: usize) {
        let ready = self.gather(i, false);
        let Some(worker) = self.insts[i].worker.as_ref() else { return };
        let shared = Arc::clone(&worker.shared);
        let (outputs, fault, prints, busy) = {
            let mut mb = shared.lock();
            if ready {
                for (slot, v) in mb.inputs.iter_mut().zip(&self.execs[i].inputs) {
                    slot.clone_from(v);
                }
                mb.inputs_new = true;
                mb.cycle = self.cycle;
                mb.time_s = self.time_s;
            }
            (mb.take_fresh(), mb.fault.take(), std::mem::take(&mut mb.prints), (mb.busy_since, Some(mb.stats)))
        };
        shared.notify();
        self.threaded_results(i, outputs, fault, prints, busy);
    }

    /// dskill readings at the start of a cycle: those produced since the
    /// last cycle took them.
    fn take_readings(&mut self, d: usize) {
        let (outputs, fault, prints, busy) = match self.insts[d].worker.as_ref() {
            Some(worker) => {
                let mut mb = worker.shared.lock();
                (mb.take_fresh(), mb.fault.take(), std::mem::take(&mut mb.prints), (mb.busy_since, Some(mb.stats)))
            }
            None => {
                (self.insts[d].lockstep_readings.iter_mut().map(Option::take).collect(), None, Vec::new(), (None, None))
            }
        };
        self.threaded_results(d, outputs, fault, prints, busy);
    }

    /// `busy` is when the body's current run began and the worker's run
    /// statistics, read under the same lock as `outputs` (so `runs` counts
    /// exactly the runs whose results have been taken).
    fn threaded_results(
        &mut self,
        i: usize,
        mut outputs: Vec<Option<Value>>,
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
        if let Err(cause) = self.commit(i, &mut outputs) {
            self.fault(i, cause);
        }
    }

    /// dskill commands at the end of a cycle: those written this cycle. A
    /// threaded dskill gets them in its mailbox; true for a lockstep one,
    /// whose device exchange then runs in the cycle.
    fn hand_commands(&mut self, d: usize) -> bool {
        if !self.insts[d].active {
            return false;
        }
        // Every command port is optional for a device: gather never refuses.
        let def = &self.graph.instances[d];
        let cycle = self.cycle;
        for (p, port) in def.inputs.iter().enumerate() {
            let fresh = port.leaves.iter().all(|&l| self.slots[l].stamp == cycle && self.slots[l].value.is_some());
            self.execs[d].inputs[p] = if fresh {
                let slots = &self.slots;
                assemble(&port.ty, &mut port.leaves.iter().filter_map(|&l| slots[l].value.as_ref()))
            } else {
                None
            };
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
    fn finish_exchange(&mut self, d: usize) {
        let outcome = self.account(d);
        let exec = &mut self.execs[d];
        for (slot, out) in self.insts[d].lockstep_readings.iter_mut().zip(&mut exec.outputs) {
            if let Some(v) = out.take() {
                *slot = Some(v);
            }
        }
        if let Err(cause) = outcome {
            self.fault(d, cause);
        }
    }

    fn evaluate_monitors(&mut self) {
        self.paused = false;
        if self.monitors.list.is_empty() {
            return;
        }
        let mut fired: Vec<Event> = Vec::new();
        let mut pause = false;
        let clock = [Value::F64(self.time_s), Value::I64(self.cycle as i64)];
        let env = Env { refs: &self.refs, slots: &self.slots, insts: &self.insts, clock: &clock };
        let (cycle, time_s) = (self.cycle, self.time_s);
        let changed = |r: usize| match self.refs.get(r) {
            Some(RefTarget::Leaf(l)) => self.slots.get(*l).is_some_and(|s| s.stamp == cycle),
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

    // ----- running ---------------------------------------------------------

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

    /// Whether anyone listens for events (the link uses this to skip work).
    pub fn has_subscribers(&self) -> bool {
        self.bus.has_subscribers()
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

impl Drop for Manager {
    fn drop(&mut self) {
        // Worker threads are told to stop and left to end on their own: one
        // may be stuck in a device call, and joining it would hang the caller.
        for inst in &self.insts {
            if let Some(w) = &inst.worker {
                w.stop();
            }
        }
    }
}

impl Control for Manager {
    fn request(&mut self, request: Request) -> Result<Reply, ControlError> {
        Manager::request(self, request)
    }
}

/// Arbitration: writes `value` to `slot` unless a higher-ranked writer
/// wrote it this cycle (then `Err` hands the value back). `Ok` holds the
/// value it displaced when another writer had written it.
#[inline]
fn write_leaf(
    slot: &mut Slot,
    value: Value,
    cycle: u64,
    rank: (i32, u32),
    writer: usize,
) -> Result<Option<(usize, Value)>, Value> {
    if slot.stamp != cycle || rank > slot.rank {
        let old = slot.value.replace(value);
        let displaced = match old {
            Some(old) if slot.writer as usize != writer && slot.stamp > 0 => Some((slot.writer as usize, old)),
            Some(old) => {
                recycle(old);
                None
            }
            None => None,
        };
        slot.stamp = cycle;
        slot.rank = rank;
        slot.writer = writer as u32;
        Ok(displaced)
    } else {
        Err(value)
    }
}

fn wrong_output(port: &str, ty: &SignalType, value: &Value) -> String {
    format!("output `{port}` expects {ty}, the body produced a {}", value.kind_name())
}

/// Asks the OS to favour the cycle's thread over other work of the machine
/// (a higher CFS weight, `nice -10`), so that a busy machine delays its
/// wake-ups less. Best effort: without the privilege nothing changes.
fn raise_thread_priority() {
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

/// A duration for people: `2.1 s`, `250 ms`, `40 µs`.
pub(crate) fn fmt_duration(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s >= 10.0 {
        format!("{s:.0} s")
    } else if s >= 1.0 {
        format!("{s:.1} s")
    } else if s >= 1e-3 {
        format!("{:.0} ms", s * 1e3)
    } else {
        format!("{:.0} µs", s * 1e6)
    }
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
            RefTarget::Leaf(l) => self.slots.get(*l)?.value.as_ref(),
            RefTarget::Param(i, p) => self.insts.get(*i)?.params.get(*p),
            RefTarget::Time => Some(&self.clock[0]),
            RefTarget::Cycle => Some(&self.clock[1]),
        }
    }
}
