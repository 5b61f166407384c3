//! The skill manager and its data-flow cycle (paper 3.2).
//!
//! One cycle ([`Manager::cycle`], the paper's *do-periodic-step*):
//! 1. apply what the sequencer asked between cycles (done by
//!    [`Manager::request`] at the boundary, so it is in force now);
//! 2. take the latest readings of every active dskill, never blocking;
//! 3. run the active cskills level by level in order of input readiness:
//!    a sync cskill runs when all its required inputs were written this
//!    cycle; an async cskill hands over its latest inputs and gives back its
//!    latest result at once. A run's outputs are committed to the leaf
//!    slots (the paper's *update-record*) after its level, or, on the serial
//!    executor, as soon as it returns, which is the same since no skill of a
//!    level reads what another one of it writes; a leaf with several
//!    writers keeps the value of the highest-priority one (arbitration);
//! 4. hand every active dskill the commands written this cycle;
//! 5. evaluate monitors and send events;
//! 6. cleanup: count the cycle, record timing.
//!
//! The schedule (levels of active cskills) is recompiled only when the
//! active set changes, so inactive skills cost nothing per cycle.
//!
//! This module holds the manager, its build, activation and faults. The
//! rest, by concern: `walk` (a cycle's walk of the plan, written once for
//! both ways a manager runs: here, and spawned), `cycle` (the cycle's
//! steps around the walk: boundary, devices, monitors, statistics), `plan`
//! (the compiled schedule), `slots` (leaf slots and arbitration),
//! `executor` (serial and parallel; bodies run in place), `pacing`
//! (`run_cycles`, speed, the cycle thread's priority), `requests` and
//! `front` (the control API), `spawned` (threads, serving, watchdog; bodies
//! run outside the lock).

use std::collections::VecDeque;
use std::sync::Arc;
use std::time::{Duration, Instant};

use crossbeam_channel::Receiver;
use situate_core::{Resources, Skill, SkillKind, Value};

use crate::config::{ClockKind, ExecutorKind};
use crate::control::*;
pub use crate::frame::Frame;
use crate::graph::{Graph, InstanceDef};
use crate::monitor::Monitors;
use crate::registry::Registry;
use crate::runner::{BodyClock, Exec, Worker, WorkerClock};
use crate::spec::{BuildError, RobotSpec};

mod cycle;
mod executor;
mod front;
mod pacing;
mod plan;
mod requests;
mod slots;
mod spawned;
mod walk;
pub use executor::PARALLEL_WORTH_NS;
pub(crate) use front::prepare_boxed as prepare;
use front::PreparedMonitor;
/// A prepared monitor, boxed for the request queue.
pub(crate) type PreparedMonitorBox = Box<PreparedMonitor>;
pub use crate::control::EventBus;
use plan::{Outputs, Plan};
use slots::Slot;
pub use spawned::Joiner;

/// The cycle's end of a tap.
struct Tap {
    tx: crossbeam_channel::Sender<Frame>,
    when_full: crate::frame::WhenFull,
    /// Locked only when a frame is dropped, and by the reader.
    drops: Arc<std::sync::Mutex<crate::frame::Drops>>,
    /// Frames the reader is done with ([`TapReceiver::give_back`]).
    returns: Receiver<Frame>,
}

/// Frames a reader may have given back and not yet taken by the cycle.
const RETURNS: usize = 256;

/// The reader's end of a tap ([`Manager::tap`]): the frames, and how many
/// were dropped because it was full. It ends when the manager does.
pub struct TapReceiver {
    pub frames: Receiver<Frame>,
    drops: Arc<std::sync::Mutex<crate::frame::Drops>>,
    returns: crossbeam_channel::Sender<Frame>,
    /// The cycle waits for room instead of dropping (simulated clock).
    cycle_waits: bool,
}

impl TapReceiver {
    /// Whether the cycle waits for room when the receiver is full (a tap
    /// made [`WhenFull::WaitIfSimulated`](crate::frame::WhenFull) of a
    /// manager on the simulated clock): then a slow reader slows the robot,
    /// and it should not give way to other work.
    pub fn cycle_waits(&self) -> bool {
        self.cycle_waits
    }

    /// Frames dropped so far because the receiver was full.
    pub fn dropped(&self) -> u64 {
        self.drops().count
    }

    /// The cycles dropped so far because the receiver was full: how many,
    /// and which.
    pub fn drops(&self) -> crate::frame::Drops {
        self.drops.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }

    /// Hands a frame the reader is done with back to the cycle (never
    /// waits: when the cycle has not taken the last ones yet, it is just
    /// dropped). The cycle reuses the frame's buffers for a next frame, and
    /// lets go of its shared values (strings, records) on its own thread: a
    /// reader that gives every frame back makes a tapped cycle allocate
    /// nothing more.
    pub fn give_back(&self, frame: Frame) {
        let _ = self.returns.try_send(frame);
    }
}

/// The cycle times bodies exactly once in this many cycles (and the
/// bodies with a short deadline always), and at most once a tick of the
/// coarse clock (a few ms): cycles run back to back on a simulated clock
/// are sampled about as often in a second as a robot's 100–250 Hz cycles
/// are, so the exact timing costs them no more than it costs a robot. In
/// the others the cycle reads only the coarse clock, enough to see a run
/// past its deadline. Such a sampled cycle times at most
/// [`SAMPLED_STEPS`] of the plan's steps.
pub const TIMING_SAMPLE: u64 = 32;

/// The most steps a sampled cycle due by its number ([`TIMING_SAMPLE`])
/// times exactly: a window of the plan's steps that moves on at each, so
/// that in a plan of more steps each is timed once in ⌈steps / 64⌉ sampled
/// cycles, and a sampled cycle costs about the same whatever the robot's
/// size (an exact reading and the usual way cost some 50 ns a body: 50 µs
/// in a cycle of 1,000 that otherwise takes 12 µs). A cycle sampled because
/// bodies ran late (`walk::run_stretch`) times every step.
pub const SAMPLED_STEPS: usize = 64;

const PRINT_HISTORY: usize = 64;

/// The most monitors one robot keeps at once (`monitor_add` refuses more);
/// more exactly, the most conditions its monitors watch, an `any` monitor
/// counting as many as it has. Every one may be evaluated each cycle: a bound on
/// their number is a bound on the cycle's cost, whatever the clients do.
pub const MAX_MONITORS: usize = 1000;
/// The most conditions the monitors of one session watch (the program's own,
/// with no session, share one allowance), so that one sequencer that forgets
/// to cancel cannot take the whole robot's. Sessions are not authentication:
/// a client that opens several sessions gets several allowances (keep
/// strangers off the link with Zenoh's access control, docs/protocol.md).
pub const MAX_MONITORS_PER_SESSION: usize = 250;

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
    /// The outputs of a body that does not run in the walk of the plan,
    /// until they are committed: a lockstep dskill's readings (from its
    /// device exchange at the end of a cycle to the start of the next), or
    /// what a threaded body produced, taken from its mailbox. One entry per
    /// output, kept so that taking them allocates nothing.
    taken: Vec<Option<Value>>,
    /// Its body was left behind (it ran past its deadline and may never
    /// return): a fresh one is made when it is activated again, once the
    /// one left behind has returned (see [`Manager::still_running`]).
    abandoned: bool,
    /// The mailbox of a threaded body left behind (its thread says there
    /// when it has ended).
    behind_worker: Option<Arc<crate::runner::Shared>>,
    /// The cycle from which its parameters last changed (monitors reading
    /// one are evaluated again then).
    params_from: u64,
    /// The first cycle of its latest activation: while it is active, what it wrote before then
    /// (in an earlier activation) is missing to monitors until it writes again, so that a
    /// condition never holds on a restarted skill's old result (its first cycle may come
    /// before its inputs do, a ROS 2 robot's say).
    active_from: u64,
    /// How its body writes its outputs (asked when the body is made): the
    /// plan does not check those of their type by construction, and lets a
    /// body write straight into its output's slot where it may.
    outputs_by: Outputs,
    /// Switched on or off since the last cycle began: listed in `Manager::switched`.
    switched: bool,
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

/// Who has held one resource leaf (a contested signal such as `drive`): the
/// winner last seen, how often it changed hands, how many cycles anyone held it.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    leaf: usize,
    last: Option<u32>,
    switches: u64,
    held: u64,
}

/// The skill manager.
pub struct Manager {
    /// Never changes once built; shared with handles (see `front`).
    graph: Arc<Graph>,
    /// What its skills were made with: a body left behind is made again with them.
    resources: Resources,
    clock: ClockKind,
    period_s: f64,
    pool: Option<Arc<rayon::ThreadPool>>,
    slots: Vec<Slot>,
    insts: Vec<Inst>,
    /// Each boxed: a spawned manager takes a body out while it runs on a
    /// pool, and the watchdog moves a stuck one out (see `spawned`); a box
    /// moves as a pointer (moved by value, an `Exec`
    /// cost some 130 instructions per body run: copied out and back, an
    /// empty one made and dropped).
    #[allow(clippy::vec_box)]
    execs: Vec<Box<Exec>>,
    /// Empty bodies, put in the place of those taken out (`take_exec`) and
    /// kept again when they are put back. One is made at build, which is
    /// all a body left behind needs; a parallel batch makes the others it needs
    /// the first time (the vector has room for one a body from the start),
    /// so a steady cycle allocates nothing.
    #[allow(clippy::vec_box)]
    spare_execs: Vec<Box<Exec>>,
    /// The compiled schedule of the active skills.
    schedule: Box<Plan>,
    /// An empty plan left in `schedule`'s place while a cycle walks it (made
    /// once: the walk moves a pointer, not the plan).
    empty_plan: Option<Box<Plan>>,
    schedule_dirty: bool,
    cycle: u64,
    time_s: f64,
    started: Instant,
    /// When the cycle running now started (a timed cycle: `cycle_timed`).
    cycle_start: Instant,
    /// When it started on the coarse clock (a cycle not timed exactly).
    cycle_start_coarse: u64,
    /// This cycle is timed on the exact clock: every cycle of a paced
    /// manager (wall clock, or a simulated one at a set speed), the sampled
    /// ones ([`TIMING_SAMPLE`]) of an unpaced simulated clock, where cycles run back
    /// to back and two exact readings would be a noticeable part of a small
    /// cycle. The others are timed on the coarse clock, for the maximum.
    cycle_timed: bool,
    running: bool,
    /// The cycles' timing, as a skill's: the timed cycles counted
    /// ([`SkillTiming::record`]), the others seen only for the maximum.
    cycle_timing: SkillTiming,
    overruns: u64,
    /// Per resource leaf: who won it, counted at the end of every cycle.
    tallies: Vec<Tally>,
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
    /// When the last timed cycle started, and which it was.
    last_start: Option<(Instant, u64)>,
    monitors: Monitors,
    refs: Vec<RefTarget>,
    bus: EventBus,
    /// Activation changes applied at this boundary, reported with the next cycle.
    activated: Vec<String>,
    deactivated: Vec<String>,
    /// The instances switched on or off since the last cycle began, whose bodies are told so
    /// at the next (`Manager::switch_bodies`); room for all, so switching allocates nothing.
    switched: Vec<usize>,
    /// When running on its own thread, stop after this cycle.
    stop_at: Option<u64>,
    /// Pacing of the simulated clock when spawned (see [`Manager::set_speed`]).
    speed: Option<f64>,
    /// A pausing monitor fired in the last cycle: a running cycle stops, a
    /// step ends early.
    paused: bool,
    /// The cycle follows a clock outside the manager ([`Request::ExternalClock`]): running
    /// lets its ticks through, and the manager's own clock never runs a cycle.
    external_clock: bool,
    /// On an external clock, a client's step under way: the clock's ticks run cycles up to this
    /// one even while the manager is stopped (the spawned manager; see `spawned::Deferred`).
    step_until: Option<u64>,
    /// This cycle times bodies exactly (see [`TIMING_SAMPLE`]): those of
    /// the steps in `exact`.
    sampled: bool,
    /// The plan's steps this cycle times exactly, `from..to`, when it is
    /// sampled (see [`SAMPLED_STEPS`]; stale otherwise).
    exact: (usize, usize),
    /// Where the window of the next sampled cycle due by its number starts.
    sample_from: usize,
    /// When the last sampled cycle due by [`TIMING_SAMPLE`] started, on the
    /// coarse clock (0: none yet).
    last_sample_coarse: u64,
    /// The next cycle times every body exactly: a stretch of bodies run
    /// untimed took longer than the shortest of their deadlines
    /// (`walk::run_steps`).
    sample_next: bool,
    /// The number of the last run of a body on the cycle thread or its pool,
    /// for the watchdog's marks ([`BodyClock`]).
    runs: u64,
    /// The ready steps of a level (kept to reuse its allocation).
    ready: Vec<usize>,
    /// Where every cycle's written values go, when something records them
    /// (a recording, the GUI's history): empty, the usual case, costs one
    /// test per cycle.
    taps: Vec<Tap>,
    /// This cycle's prints, for the tap.
    tap_prints: Vec<(usize, String)>,
    /// A frame given back by a tap's reader, its lists reused for the next.
    spare_frame: Option<Frame>,
    /// The lockstep dskills whose device exchange runs this cycle.
    exchanging: Vec<usize>,
    /// Record outputs decomposed into leaves before a commit (reused).
    parts: Vec<Value>,
    /// When each instance's in-cycle body started running (for the watchdog).
    clocks: Arc<[BodyClock]>,
    /// On the simulated clock, spawned, serial: how long the cycle thread waited for a CPU, which
    /// does not count against a body's deadline (`crate::starved`).
    starved: Option<Arc<crate::starved::Starvation>>,
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
            let skill = (def.skill_type.make)(registry.resources()).map_err(|e| {
                // At the skill's type in the robot file: what it is made as.
                let at = spec.skills.iter().find(|s| s.name == def.name).and_then(|s| s.type_pos.or(s.pos));
                BuildError {
                    diagnostics: vec![spec.diag(
                        crate::spec::Severity::Error,
                        at,
                        format!("skill `{}`: could not create `{}`: {e}", def.name, def.skill_type.decl.type_name),
                    )],
                }
            })?;
            let outputs_by = outputs_by(skill.as_ref(), def);
            let mut exec = Exec::new(skill, def.inputs.len(), def.outputs.len());
            if let Some(skill) = exec.skill.as_mut() {
                for (i, v) in def.params.iter().enumerate() {
                    skill.set_param(i, v);
                }
            }
            let worker =
                (def.kind.is_threaded() && !lockstep).then(|| Worker::new(def.inputs.len(), def.outputs.len()));
            execs.push(Box::new(exec));
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
                taken: vec![None; def.outputs.len()],
                abandoned: false,
                behind_worker: None,
                params_from: 0,
                active_from: 0,
                outputs_by,
                switched: false,
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
            spare_execs: {
                let mut spares = Vec::with_capacity(execs.len());
                spares.push(Box::default());
                spares
            },
            execs,
            schedule: Box::default(),
            empty_plan: Some(Box::default()),
            schedule_dirty: true,
            cycle: 0,
            time_s: 0.0,
            started,
            cycle_start: started,
            cycle_start_coarse: 0,
            cycle_timed: false,
            running: false,
            cycle_timing: SkillTiming::default(),
            overruns: 0,
            tallies: graph
                .leaves
                .iter()
                .enumerate()
                .filter(|(_, l)| l.is_resource())
                .map(|(leaf, _)| Tally { leaf, ..Tally::default() })
                .collect(),
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
            switched: Vec::with_capacity(graph.instances.len()),
            stop_at: None,
            speed: None,
            paused: false,
            external_clock: false,
            step_until: None,
            sampled: true,
            exact: (0, usize::MAX),
            sample_from: 0,
            last_sample_coarse: 0,
            sample_next: false,
            runs: 0,
            ready: Vec::new(),
            exchanging: Vec::new(),
            taps: Vec::new(),
            tap_prints: Vec::new(),
            spare_frame: None,
            parts: Vec::new(),
            clocks,
            starved: None,
            generation: 0,
            graph,
            resources: registry.resources().clone(),
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

    /// Taps the cycle: from now on, at the end of every cycle, the values
    /// written in it (leaf by leaf, as [`Frame`]s) go to the returned
    /// receiver, which holds up to `options.capacity` frames (a plain
    /// number: that capacity). By default the cycle never waits for it: a
    /// frame that finds it full is dropped and counted (see
    /// [`TapReceiver::drops`]); with
    /// [`WhenFull::WaitIfSimulated`](crate::frame::WhenFull) the cycle on the
    /// simulated clock waits for room instead. Several taps get the same
    /// frames; one goes when its receiver is dropped. The leaves are those
    /// of [`Manager::graph`] (`leaves[i]`).
    ///
    /// A tap whose cycle waits holds at most
    /// [`WAITING_CAPACITY`](crate::frame::WAITING_CAPACITY) frames.
    pub fn tap(&mut self, options: impl Into<crate::frame::TapOptions>) -> TapReceiver {
        let options = options.into();
        let cycle_waits =
            options.when_full == crate::frame::WhenFull::WaitIfSimulated && self.clock == ClockKind::Simulated;
        let capacity =
            if cycle_waits { options.capacity.min(crate::frame::WAITING_CAPACITY) } else { options.capacity };
        let (tx, rx) = crossbeam_channel::bounded(capacity.max(1));
        let (returns_tx, returns) = crossbeam_channel::bounded(RETURNS);
        let drops = Arc::new(std::sync::Mutex::new(crate::frame::Drops::default()));
        self.taps.push(Tap { tx, when_full: options.when_full, drops: Arc::clone(&drops), returns });
        TapReceiver { frames: rx, drops, returns: returns_tx, cycle_waits }
    }

    pub fn events(&self) -> Receiver<Event> {
        self.bus.subscribe()
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
        let next_cycle = self.cycle + 1;
        let inst = &mut self.insts[i];
        inst.active = active;
        if !std::mem::replace(&mut inst.switched, true) {
            self.switched.push(i);
        }
        if active {
            inst.faulted = None;
            inst.active_from = next_cycle;
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
        let mut skill = (def.skill_type.make)(&self.resources)?;
        for (p, v) in self.insts[i].params.iter().enumerate() {
            skill.set_param(p, v);
        }
        let outputs_by = outputs_by(skill.as_ref(), def);
        *self.execs[i] = Exec::new(skill, def.inputs.len(), def.outputs.len());
        let inst = &mut self.insts[i];
        inst.outputs_by = outputs_by;
        if inst.worker.is_some() {
            inst.worker = Some(Worker::new(def.inputs.len(), def.outputs.len()));
        }
        inst.abandoned = false;
        inst.behind_worker = None;
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
            self.insts[i].behind_worker = Some(Arc::clone(&worker.shared));
        }
        self.insts[i].abandoned = true;
        self.fault(i, cause);
    }

    /// Whether a body of instance `i` left behind is still running (on a
    /// cycle thread, or on its own thread): it holds that thread and, if it
    /// computes, a core, so no fresh body is started beside it.
    pub(super) fn still_running(&self, i: usize) -> bool {
        let inst = &self.insts[i];
        inst.abandoned
            && (self.clocks[i].behind() > 0 || inst.behind_worker.as_ref().is_some_and(|shared| !shared.lock().ended))
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
            if !self.taps.is_empty() {
                self.tap_prints.push((i, line.clone()));
            }
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

    /// Whether anyone listens for events (the link uses this to skip work).
    pub fn has_subscribers(&self) -> bool {
        self.bus.has_subscribers()
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

/// How `skill` writes its outputs: whether every one is of its port's type
/// by construction ([`Skill::output_typed`]), and whether its slots may be
/// its buffers ([`Skill::fills_outputs`], [`Skill::writes_output`]); asked
/// once per body made, never per run.
fn outputs_by(skill: &dyn Skill, def: &InstanceDef) -> Outputs {
    Outputs {
        typed: def.outputs.iter().enumerate().all(|(p, port)| skill.output_typed(p, &port.ty)),
        in_slot: skill.fills_outputs() && (0..def.outputs.len()).all(|p| skill.writes_output(p)),
    }
}
