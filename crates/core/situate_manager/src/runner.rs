//! Running bodies: in the cycle, or on a thread of their own.
//!
//! A synchronous cskill's body runs in the cycle ([`Exec::run`]). The bodies
//! of asynchronous cskills and dskills run on their own threads
//! ([`Worker`]): the cycle only swaps values with them through a latest-value
//! mailbox whose lock is never held while a body runs, so a slow computation
//! or a hanging device never delays the cycle.
//!
//! Under a simulated clock the manager runs every body in the cycle instead
//! ("lockstep"), so a simulation replays exactly.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use situate_core::value::recycle;
use situate_core::{Context, Io, Skill, SkillKind, Value};

/// The runnable part of a skill instance: its body and reusable port buffers.
///
/// `Default` is the empty placeholder left in the manager while the real
/// one is out running on a cycle thread (see `manager::Core`), or after its
/// body was left behind: it has no body and its buffers hold nothing.
#[repr(C, align(64))]
pub(crate) struct Exec {
    // The first cache line holds what a run the short way touches (its
    // body, its context, its count of untimed runs): `repr(C)` keeps them
    // there, `align(64)` keeps them in one line.
    /// `None` once the body has moved to its worker thread.
    pub skill: Option<Box<dyn Skill>>,
    pub cx: Context,
    /// Runs not timed exactly since the last one that was: counted here,
    /// where the cycle looks anyway, and added to the skill's timing (in
    /// memory the cycle does not touch otherwise) at its next timed run, or
    /// when the timing is asked for (see `Manager::count_run`).
    pub untimed_runs: u64,
    pub inputs: Vec<Option<Value>>,
    pub outputs: Vec<Option<Value>>,
    pub result: Result<(), String>,
    /// How long the last run took, exactly when `timed`, else on the coarse clock.
    pub elapsed_ns: u64,
    /// Their times on the coarse clock, summed (see [`SkillTiming::add_untimed`]).
    pub untimed_ns: u64,
    pub timed: bool,
    /// The body [fills its outputs](Skill::fills_outputs): an output buffer
    /// holding the value its last output replaced is handed to the body as
    /// a spare instead of being recycled on entry.
    pub fills: bool,
    /// The body has been activated and not deactivated since
    /// ([`Skill::activate`]): a fresh body has not.
    pub on: bool,
}

impl Default for Exec {
    fn default() -> Self {
        Exec {
            skill: None,
            inputs: Vec::new(),
            outputs: Vec::new(),
            cx: Context::default(),
            result: Ok(()),
            elapsed_ns: 0,
            timed: false,
            untimed_runs: 0,
            untimed_ns: 0,
            fills: false,
            on: false,
        }
    }
}

impl Exec {
    pub fn new(skill: Box<dyn Skill>, inputs: usize, outputs: usize) -> Self {
        Exec {
            fills: skill.fills_outputs(),
            skill: Some(skill),
            inputs: vec![None; inputs],
            outputs: vec![None; outputs],
            cx: Context::default(),
            result: Ok(()),
            elapsed_ns: 0,
            timed: false,
            untimed_runs: 0,
            untimed_ns: 0,
            on: false,
        }
    }

    /// Runs the body once on the gathered inputs, catching panics, and times
    /// it from `start` on the same clock; returns the time it ended, so a
    /// caller running bodies back to back reads the clock once per body.
    ///
    /// A [`Stamp::Precise`] start times the body exactly (a sampled cycle,
    /// a short deadline); a [`Stamp::Coarse`] one costs a few nanoseconds
    /// and is enough to see a run past a long deadline (see [`coarse_ns`]).
    ///
    /// While the body runs, `clock` holds the run's mark (its number; see
    /// [`BodyClock`]), so a watchdog can see a body that does not return
    /// (`None` where no watchdog looks: a manager not spawned).
    ///
    /// Outputs are `None` on entry: the manager takes every produced output
    /// when it commits, and clears them when a body fails; an output buffer
    /// it left holding the value a committed output replaced in its slot
    /// (see `Manager::commit_plain`) is recycled here, or, when the body
    /// [fills its outputs](Skill::fills_outputs), left to it as a spare
    /// (a body that fails leaves its outputs to be cleared as before).
    pub fn run(&mut self, cycle: u64, time_s: f64, start: Stamp, clock: Option<(&BodyClock, u64)>) -> Stamp {
        self.run_on(None, cycle, time_s, start, clock)
    }

    /// [`Exec::run`] with the body's inputs read in place from `input`
    /// when it is `Some` (a step with one plain input reads it straight
    /// from its leaf slot: a one-element slice, nothing moved), else from
    /// the input buffers.
    #[inline(always)]
    pub fn run_on(
        &mut self,
        input: Option<&Option<Value>>,
        cycle: u64,
        time_s: f64,
        start: Stamp,
        clock: Option<(&BodyClock, u64)>,
    ) -> Stamp {
        self.run_body(input, cycle, time_s, clock);
        let end = start.again();
        self.elapsed_ns = end.since(start);
        self.timed = matches!(start, Stamp::Precise(_));
        end
    }

    /// [`Exec::run_on`] for a step run the short way (`plan::Fast`): the
    /// body reads its one input in place (or has none), and is not timed (its time is its
    /// stretch of such steps', checked by the walk). Its outputs are set as
    /// for a run on the coarse clock that read no time when the run is
    /// committed the usual way. Returns whether the run was clean (no
    /// error, no print): only then may its output be committed the short
    /// way, which looks at no time.
    #[inline(always)]
    pub fn run_untimed(&mut self, input: Option<&Option<Value>>, cycle: u64, time_s: f64) -> bool {
        self.run_body(input, cycle, time_s, None);
        let clean = self.result.is_ok() && !self.cx.has_prints();
        if !clean {
            self.elapsed_ns = 0;
            self.timed = false;
        }
        clean
    }
}

impl Exec {
    /// [`Exec::run_untimed`] with the body's one output written straight
    /// into `output`, its slot's value, where no body can be left behind
    /// (`plan::Fast::in_slot`: the body sets its output on every `Ok` run,
    /// and a run that fails writes none, see `Skill::writes_output`).
    /// Clean (true): the slot holds the run's output, counted as an untimed
    /// run; only its stamp and rank are left to set. A run that printed has
    /// its output moved into its buffer, to be committed the usual way; a
    /// failed one left the slot as it was.
    #[inline(always)]
    pub fn run_in_slot(
        &mut self,
        input: Option<&Option<Value>>,
        output: &mut Option<Value>,
        cycle: u64,
        time_s: f64,
    ) -> bool {
        self.run_short(input, Some(output), cycle, time_s)
    }

    /// [`Exec::run_in_slot`] where a body may be left behind (a spawned
    /// manager's): only the first half of the body's run, which writes no
    /// output (`Skill::writes_output`), so that its output is written into
    /// its slot only once the thread knows it was not left behind. Clean
    /// (true): its outputs are for [`Exec::write_into`] to write, counted
    /// as an untimed run. A run that printed has them written into its
    /// buffers, to be committed the usual way; a failed one wrote none.
    #[inline(always)]
    pub fn run_unwritten(&mut self, input: Option<&Option<Value>>, cycle: u64, time_s: f64) -> bool {
        self.run_short(input, None, cycle, time_s)
    }

    /// [`Exec::run_in_slot`] with `output`, else [`Exec::run_unwritten`].
    #[inline(always)]
    fn run_short(
        &mut self,
        input: Option<&Option<Value>>,
        mut output: Option<&mut Option<Value>>,
        cycle: u64,
        time_s: f64,
    ) -> bool {
        self.cx.set(cycle, time_s);
        let inputs = match input {
            Some(input) => std::slice::from_ref(input),
            None => &[],
        };
        let outcome = match self.skill.as_deref_mut() {
            Some(skill) => {
                let cx = &mut self.cx;
                let run = match output.as_deref_mut() {
                    Some(out) => catch_unwind(AssertUnwindSafe(|| {
                        skill.step(&mut Io { inputs, outputs: std::slice::from_mut(out), cx })
                    })),
                    None => {
                        catch_unwind(AssertUnwindSafe(|| skill.run_unwritten(&mut Io { inputs, outputs: &mut [], cx })))
                    }
                };
                match run {
                    Ok(Ok(())) => Ok(()),
                    Ok(Err(e)) => Err(e.message),
                    Err(panic) => Err(format!("panicked: {}", panic_message(&*panic))),
                }
            }
            None => Err(NOT_HERE.into()),
        };
        match outcome {
            // `result` is `Ok` between runs (a failed run's is taken when it
            // is accounted): nothing to write.
            Ok(()) if !self.cx.has_prints() => {
                self.untimed_runs += 1;
                return true;
            }
            // Printed: its output into its buffer, committed the usual way.
            Ok(()) => match output {
                Some(out) => {
                    if let Some(buf) = self.outputs.first_mut() {
                        std::mem::swap(buf, out);
                    }
                }
                None => self.write_into(None),
            },
            Err(e) => self.result = Err(e),
        }
        self.elapsed_ns = 0;
        self.timed = false;
        false
    }

    /// Writes the outputs of a clean [`Exec::run_unwritten`]: into `slot`,
    /// the value of its one output's slot (filled in place where nobody
    /// else holds it), or with `None` into its output buffers.
    #[inline(always)]
    pub fn write_into(&mut self, slot: Option<&mut Option<Value>>) {
        let Some(skill) = self.skill.as_deref_mut() else { return };
        let outputs = match slot {
            Some(slot) => std::slice::from_mut(slot),
            None => &mut self.outputs[..],
        };
        skill.write_outputs(outputs);
    }

    /// One run of the body, untimed: its outputs made ready (see [`Exec::run`]), the cycle
    /// and its time set, its mark held while it runs when `clock` is given, its outcome kept.
    #[inline(always)]
    fn run_body(&mut self, input: Option<&Option<Value>>, cycle: u64, time_s: f64, clock: Option<(&BodyClock, u64)>) {
        if !self.fills {
            for out in &mut self.outputs {
                if out.is_some() {
                    if let Some(old) = out.take() {
                        recycle(old);
                    }
                }
            }
        }
        self.cx.set(cycle, time_s);
        let mark = clock.map(|(c, run)| c.enter(run, false));
        let inputs = match input {
            Some(input) => std::slice::from_ref(input),
            None => &self.inputs[..],
        };
        match &mut self.skill {
            Some(skill) => run_body_into(skill.as_mut(), inputs, &mut self.outputs, &mut self.cx, &mut self.result),
            None => self.result = Err(NOT_HERE.into()),
        }
        if let (Some((clock, _)), Some(mark)) = (clock, mark) {
            // Left behind or not, a pool's thread finds out under the lock (`spawned`).
            let _ = clock.leave(mark);
        }
    }

    /// Drops the copies of its inputs the body was given, as soon as it has
    /// returned: the buffers they share are then again their slots' own
    /// when their producers next write them (reused, nothing allocated). A
    /// record made for the body is kept, to be written in place the next
    /// time (`slots::assemble_into`). (Dropped, not recycled: a copy is
    /// never the only holder of its buffer, its slot holds it too.)
    #[inline(always)]
    pub fn drop_copies(&mut self) {
        for input in &mut self.inputs {
            // Each kind's drop by name: a reference count let go of here,
            // not through the value's drop glue, called out of line.
            match input.take() {
                None | Some(Value::Bool(_) | Value::I64(_) | Value::F64(_)) => {}
                Some(Value::Str(a)) => drop(a),
                Some(Value::Bytes(a)) => drop(a),
                Some(Value::F32s(a)) => drop(a),
                Some(Value::F64s(a)) => drop(a),
                Some(Value::I64s(a)) => drop(a),
                record @ Some(Value::Record(_)) => *input = record,
            }
        }
    }
}

/// A run's error when its body is on its worker thread.
const NOT_HERE: &str = "the body is not here (it runs on its own thread)";

/// A time read from one of two clocks: exact, or the kernel's coarse
/// monotonic clock (the time of its last tick: about 3 ns to read instead
/// of 25–30, to within [`coarse_tick_ns`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Stamp {
    Precise(Instant),
    /// [`coarse_ns`].
    Coarse(u64),
}

impl Stamp {
    pub fn now(precise: bool) -> Stamp {
        if precise {
            Stamp::Precise(Instant::now())
        } else {
            Stamp::Coarse(coarse_ns())
        }
    }

    /// Now, on the same clock.
    pub fn again(self) -> Stamp {
        Stamp::now(matches!(self, Stamp::Precise(_)))
    }

    /// Nanoseconds from `earlier` to `self` (same clock; 0 if not).
    pub fn since(self, earlier: Stamp) -> u64 {
        match (self, earlier) {
            (Stamp::Precise(a), Stamp::Precise(b)) => a.saturating_duration_since(b).as_nanos() as u64,
            (Stamp::Coarse(a), Stamp::Coarse(b)) => a.saturating_sub(b),
            _ => 0,
        }
    }
}

/// The coarse monotonic clock in nanoseconds: `CLOCK_MONOTONIC_COARSE` on
/// Linux (the same clock as [`Instant`], as of its last tick), elsewhere
/// [`Instant`] since a process-wide epoch.
pub(crate) fn coarse_ns() -> u64 {
    #[cfg(target_os = "linux")]
    {
        let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
        // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
        if unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC_COARSE, &mut ts) } == 0 {
            return ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64;
        }
    }
    static EPOCH: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    EPOCH.get_or_init(Instant::now).elapsed().as_nanos() as u64
}

/// The resolution of [`coarse_ns`]: a coarse reading lags the exact time by
/// less than this (a few ms on Linux; 0 where it is exact).
pub(crate) fn coarse_tick_ns() -> u64 {
    static TICK: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *TICK.get_or_init(|| {
        #[cfg(target_os = "linux")]
        {
            let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
            // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
            if unsafe { libc::clock_getres(libc::CLOCK_MONOTONIC_COARSE, &mut ts) } == 0 {
                return ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64;
            }
            // Unknown: assume a slow tick (100 Hz).
            10_000_000
        }
        #[cfg(not(target_os = "linux"))]
        0
    })
}

/// When the body of one instance started running, for the watchdog.
///
/// Holds a *mark* while a body runs, and 0 when none does: the run's number
/// (never 0, never used twice by a manager), shifted left by one, and in the
/// low bit whether the thread running it holds the spawned manager's lock
/// meanwhile ([`BodyClock::held`]; see `manager::spawned`). The mark holds
/// no time, so that a body costs no clock reading: the watchdog times a run
/// from when it first saw its mark (it looks every tick of its own). The running thread sets it
/// before the body runs (a release store: what that thread wrote before is
/// seen by a watchdog that takes the mark) and takes it back after (a
/// compare-and-swap). The watchdog takes a stuck body's mark
/// ([`BodyClock::forget`]) by a compare-and-swap too, so exactly one of them
/// has it: a body that returns finds whether it was left behind, and a late
/// return never clears the mark of a fresh body.
///
/// It also counts the runs left behind that have not returned yet: a body
/// left behind still holds a thread (and, if it computes, a core), so no
/// fresh body of the skill is started while one is (see `Manager::activate`).
pub(crate) struct BodyClock {
    since: AtomicU64,
    behind: AtomicU32,
}

impl BodyClock {
    pub fn new() -> Self {
        BodyClock { since: AtomicU64::new(0), behind: AtomicU32::new(0) }
    }

    /// Marks run number `run` (≥ 1) of a body as started; `held`: its thread
    /// holds the manager's lock while it runs.
    #[inline(always)]
    pub fn enter(&self, run: u64, held: bool) -> u64 {
        debug_assert!(run > 0, "run numbers start at 1");
        let mark = (run << 1) | u64::from(held);
        self.since.store(mark, Ordering::Release);
        mark
    }

    /// The body with `mark` returned: whether it is still this run's (`false`:
    /// the watchdog left it behind meanwhile).
    #[inline(always)]
    pub fn leave(&self, mark: u64) -> bool {
        if self.since.compare_exchange(mark, 0, Ordering::AcqRel, Ordering::Acquire).is_ok() {
            return true;
        }
        // Not its mark any more: the watchdog left this run behind, and it has now returned.
        let _ = self.behind.fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| n.checked_sub(1));
        false
    }

    /// The mark of the body running now (0: none).
    pub fn mark(&self) -> u64 {
        self.since.load(Ordering::Relaxed)
    }

    /// Whether the thread running the body with `mark` holds the manager's
    /// lock while it runs: the watchdog that takes the mark has the lock.
    pub fn held(mark: u64) -> bool {
        mark & 1 == 1
    }

    /// Leaves the body with `mark` behind: it no longer counts as the
    /// running body, but as one left behind until it returns. `false` when it
    /// returned just now (it was not left behind).
    pub fn forget(&self, mark: u64) -> bool {
        // Counted before the mark is cleared: a return that finds its mark gone finds the count.
        self.behind.fetch_add(1, Ordering::AcqRel);
        if self.since.compare_exchange(mark, 0, Ordering::AcqRel, Ordering::Acquire).is_err() {
            // It returned just now: nothing left behind.
            let _ = self.behind.fetch_update(Ordering::AcqRel, Ordering::Acquire, |n| n.checked_sub(1));
            return false;
        }
        true
    }

    /// How many runs left behind have not returned yet.
    pub fn behind(&self) -> u32 {
        self.behind.load(Ordering::Acquire)
    }
}

/// [`run_body`] writing its outcome to `result`, and only when it differs
/// from what `result` holds: inlined, so the body's arguments and an `Ok`
/// outcome never go through the stack (a copy there, read back at once in
/// wider pieces than it was written, stalls the cycle's thread).
#[inline(always)]
fn run_body_into(
    skill: &mut dyn Skill,
    inputs: &[Option<Value>],
    outputs: &mut [Option<Value>],
    cx: &mut Context,
    result: &mut Result<(), String>,
) {
    let mut io = Io { inputs, outputs, cx };
    match catch_unwind(AssertUnwindSafe(|| skill.step(&mut io))) {
        Ok(Ok(())) => {
            if result.is_err() {
                *result = Ok(());
            }
        }
        Ok(Err(e)) => *result = Err(e.message),
        Err(panic) => *result = Err(format!("panicked: {}", panic_message(&*panic))),
    }
}

/// Runs a body, turning a panic into an error ([`run_body_into`] for a
/// caller that keeps no outcome of its own).
pub(crate) fn run_body(
    skill: &mut dyn Skill,
    inputs: &[Option<Value>],
    outputs: &mut [Option<Value>],
    cx: &mut Context,
) -> Result<(), String> {
    let mut result = Ok(());
    run_body_into(skill, inputs, outputs, cx, &mut result);
    result
}

use crate::supervise::panic_message;

/// A body's `deactivate` failed: the skill is off anyway, so this is no fault; it is said in a
/// warning and in one of the skill's prints.
pub(crate) fn deactivate_failed(cx: &mut Context, error: &str) {
    tracing::warn!(%error, "a skill's deactivate hook failed");
    cx.print(error.to_string());
}

/// Tells a body it was switched on (`on`) or off ([`Skill::activate`],
/// [`Skill::deactivate`]), turning a panic into an error. The error names the
/// hook.
pub(crate) fn run_hook(skill: &mut dyn Skill, on: bool, cx: &mut Context) -> Result<(), String> {
    let hook = if on { "activate" } else { "deactivate" };
    match catch_unwind(AssertUnwindSafe(|| if on { skill.activate(cx) } else { skill.deactivate(cx) })) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(format!("`{hook}` failed: {}", e.message)),
        Err(panic) => Err(format!("`{hook}` panicked: {}", panic_message(&*panic))),
    }
}

/// Timing of a threaded body, kept by its worker (every run is timed).
pub(crate) type WorkerStats = crate::control::SkillTiming;

/// What the cycle and a worker exchange.
#[derive(Default)]
pub(crate) struct Mailbox {
    pub active: bool,
    /// How many times the skill was switched on or off: the worker tells its
    /// body ([`run_hook`]) when this moved since it last looked.
    pub switches: u64,
    pub stop: bool,
    /// Latest inputs (async) or pending commands (dskill; taken by the worker).
    pub inputs: Vec<Option<Value>>,
    pub inputs_new: bool,
    pub cycle: u64,
    pub time_s: f64,
    /// Latest value of each output, merged across runs.
    pub outputs: Vec<Option<Value>>,
    /// Which outputs a run produced since the cycle last took them: a value
    /// is fresh in one cycle only, like a sync skill's (see
    /// [`Mailbox::take_fresh_into`]).
    pub fresh: Vec<bool>,
    /// When the body started the run it is in now (`None`: between runs).
    pub busy_since: Option<Instant>,
    pub params: Vec<(usize, Value)>,
    pub fault: Option<String>,
    pub prints: Vec<String>,
    pub stats: WorkerStats,
    /// The worker thread ended by a panic (see `worker`).
    pub dead: bool,
    /// Its thread has ended (returned or panicked): what a body left behind
    /// on it no longer holds.
    pub ended: bool,
}

impl Mailbox {
    /// The outputs produced since the last call into `into` (one entry per
    /// output; the others `None`): a buffer the cycle keeps, so taking them
    /// allocates nothing.
    pub fn take_fresh_into(&mut self, into: &mut [Option<Value>]) {
        for ((v, fresh), out) in self.outputs.iter().zip(self.fresh.iter_mut()).zip(into.iter_mut()) {
            *out = if std::mem::take(fresh) { v.clone() } else { None };
        }
    }
}

pub(crate) struct Shared {
    mailbox: Mutex<Mailbox>,
    wake: Condvar,
}

impl Shared {
    /// Locks the mailbox. A worker never panics while holding the lock (bodies
    /// run outside it), but recover from poisoning anyway.
    pub fn lock(&self) -> MutexGuard<'_, Mailbox> {
        self.mailbox.lock().unwrap_or_else(|p| p.into_inner())
    }

    pub fn notify(&self) {
        self.wake.notify_all();
    }
}

/// How a worker's body sees time.
#[derive(Clone, Copy)]
pub(crate) enum WorkerClock {
    /// The time of the cycle that handed over its inputs (async cskills).
    Cycle,
    /// Seconds since the manager's epoch, read at each run: a device keeps
    /// real time even when the cycle stalls, so a base that gets no fresh
    /// command stops after its hold time.
    Wall(Instant),
}

/// The cycle's side of a threaded body.
pub(crate) struct Worker {
    pub shared: Arc<Shared>,
    started: bool,
}

impl Worker {
    pub fn new(inputs: usize, outputs: usize) -> Self {
        let mailbox = Mailbox {
            inputs: vec![None; inputs],
            outputs: vec![None; outputs],
            fresh: vec![false; outputs],
            ..Mailbox::default()
        };
        Worker { shared: Arc::new(Shared { mailbox: Mutex::new(mailbox), wake: Condvar::new() }), started: false }
    }

    /// Starts the worker thread the first time the skill is activated,
    /// moving the body there.
    pub fn set_active(
        &mut self,
        active: bool,
        exec: &mut Exec,
        kind: SkillKind,
        name: &str,
        period: Duration,
        clock: WorkerClock,
    ) {
        {
            let mut mb = self.shared.lock();
            if mb.active != active {
                mb.switches += 1;
            }
            mb.active = active;
            if !active {
                // A handoff not yet taken belongs to the cycles the skill was
                // active in: a reactivated body must not run on it.
                mb.inputs_new = false;
            }
        }
        self.shared.notify();
        if active && !self.started {
            if let Some(skill) = exec.skill.take() {
                let shared = Arc::clone(&self.shared);
                let spawned = thread::Builder::new()
                    .name(format!("skill-{name}"))
                    .spawn(move || worker(skill, shared, kind, period, clock));
                match spawned {
                    Ok(_) => self.started = true,
                    Err(e) => {
                        let mut mb = self.shared.lock();
                        mb.fault = Some(format!("could not start its thread: {e}"));
                        mb.active = false;
                    }
                }
            }
        }
    }

    pub fn stop(&self) {
        self.shared.lock().stop = true;
        self.shared.notify();
    }
}

/// A worker thread: the loop, and a report if it ends by a panic outside
/// the body (a skill's `set_param`): the skill is faulted with the cause and
/// its thread is gone, so activating it again makes a fresh body and thread.
fn worker(skill: Box<dyn Skill>, shared: Arc<Shared>, kind: SkillKind, period: Duration, clock: WorkerClock) {
    let mailbox = Arc::clone(&shared);
    if let Err(panic) = catch_unwind(AssertUnwindSafe(|| worker_loop(skill, shared, kind, period, clock))) {
        let cause = format!("its thread ended: panicked: {}", panic_message(&*panic));
        tracing::error!(%cause, "a skill's worker thread panicked");
        let mut mb = mailbox.lock();
        mb.busy_since = None;
        mb.fault = Some(cause);
        mb.active = false;
        mb.dead = true;
    }
    mailbox.lock().ended = true;
}

fn worker_loop(mut skill: Box<dyn Skill>, shared: Arc<Shared>, kind: SkillKind, period: Duration, clock: WorkerClock) {
    let mut cx = Context::default();
    let mut next = Instant::now();
    let (n_in, n_out) = {
        let mb = shared.lock();
        (mb.inputs.len(), mb.outputs.len())
    };
    let mut outputs: Vec<Option<Value>> = vec![None; n_out];
    // Whether the body has been activated (and not deactivated since), and the switches seen.
    let (mut on, mut seen) = (false, 0);
    loop {
        let (inputs, params) = {
            let mut mb = shared.lock();
            loop {
                if mb.stop {
                    return;
                }
                if mb.switches != seen {
                    break;
                }
                if mb.active {
                    if kind == SkillKind::Device {
                        let now = Instant::now();
                        if now >= next {
                            break;
                        }
                        mb = shared
                            .wake
                            .wait_timeout(mb, next - now)
                            .map(|(g, _)| g)
                            .unwrap_or_else(|p| p.into_inner().0);
                        continue;
                    } else if mb.inputs_new {
                        break;
                    }
                }
                mb = shared.wake.wait(mb).unwrap_or_else(|p| p.into_inner());
            }
            if mb.switches != seen {
                // Switched since the body last heard: off (if it was on), then on (if it is).
                // Any switch while on went off at some point; the hooks run outside the lock.
                let active = mb.active;
                seen = mb.switches;
                cx.set(mb.cycle, mb.time_s);
                drop(mb);
                if std::mem::take(&mut on) {
                    if let Err(e) = run_hook(skill.as_mut(), false, &mut cx) {
                        deactivate_failed(&mut cx, &e);
                    }
                }
                let result = if active { run_hook(skill.as_mut(), true, &mut cx) } else { Ok(()) };
                on = active && result.is_ok();
                let mut mb = shared.lock();
                mb.prints.extend(cx.take_prints());
                if let Err(e) = result {
                    // Unless it was switched again meanwhile (that says what it is now).
                    if mb.switches == seen {
                        mb.fault = Some(e);
                        mb.active = false;
                        mb.inputs_new = false;
                    }
                }
                continue;
            }
            mb.inputs_new = false;
            let started = Instant::now();
            mb.busy_since = Some(started);
            match clock {
                WorkerClock::Cycle => cx.set(mb.cycle, mb.time_s),
                WorkerClock::Wall(epoch) => cx.set(mb.cycle, started.saturating_duration_since(epoch).as_secs_f64()),
            }
            let inputs: Vec<Option<Value>> = if kind == SkillKind::Device {
                // Commands are consumed: each is handed to the device once.
                mb.inputs.iter_mut().map(Option::take).collect()
            } else {
                mb.inputs.clone()
            };
            (inputs, std::mem::take(&mut mb.params))
        };
        debug_assert_eq!(inputs.len(), n_in);
        for (index, value) in &params {
            skill.set_param(*index, value);
        }
        outputs.fill(None);
        let start = Instant::now();
        let result = run_body(skill.as_mut(), &inputs, &mut outputs, &mut cx);
        let elapsed = start.elapsed().as_nanos() as u64;
        {
            let mut mb = shared.lock();
            mb.busy_since = None;
            if mb.stop {
                // Left behind (it ran past its liveness deadline) or shut
                // down: what it produced late belongs to no cycle.
                return;
            }
            mb.stats.record(elapsed);
            mb.prints.extend(cx.take_prints());
            match result {
                Ok(()) => {
                    let mb = &mut *mb;
                    for ((slot, fresh), out) in mb.outputs.iter_mut().zip(mb.fresh.iter_mut()).zip(&mut outputs) {
                        if let Some(v) = out.take() {
                            *slot = Some(v);
                            *fresh = true;
                        }
                    }
                }
                Err(e) => {
                    mb.fault = Some(e);
                    mb.active = false;
                    // As for a deactivation (see `set_active`).
                    mb.inputs_new = false;
                }
            }
        }
        if kind == SkillKind::Device {
            next += period;
            let now = Instant::now();
            if next < now {
                next = now;
            }
        }
    }
}
