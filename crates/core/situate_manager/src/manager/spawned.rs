//! A manager on threads of its own: the cycle, the requests of handles, and
//! a watchdog that leaves a stuck body behind so the cycle goes on.
//!
//! The manager sits behind one lock shared by its *cycle thread* and the
//! watchdog. The cycle thread holds it while it cycles, and lets go of it
//! only to wait (for a request, or for the next cycle to be due). Each
//! body's [`BodyClock`] shows when it started. When one has been running
//! past its deadline (`budget_ms` of a sync cskill; `liveness_ms` of a
//! dskill or async cskill run in the cycle under the simulated clock), the
//! watchdog takes the body's mark from its clock, and with it the lock,
//! which the stuck thread still holds: the thread that runs a body in the
//! cycle forgets its guard first, and makes it again only if it takes the
//! mark back itself when the body returns (a compare-and-swap each; exactly
//! one of the two wins). The watchdog faults the skill, moves the body out
//! of the manager (to be dropped by its thread, never while it runs), puts
//! the inputs lent to it back in their slots as copies, bumps the manager's
//! `generation` and starts a new cycle thread. The stuck thread is left
//! behind with the body: should the body ever return, the thread finds its
//! mark gone, takes its body back to drop it, and ends. The cycle it was in
//! is abandoned where it stood (no commands for the devices that cycle);
//! the next one starts at once. Bodies run on a pool (a parallel batch)
//! run with the lock let go, as before: the watchdog takes the lock, and
//! the pool's thread sees the new generation when it returns. See
//! docs/decisions/0005-budgets-and-stuck-bodies.md.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};

use parking_lot::Mutex as Lock;
use std::thread::{self, Thread};
use std::time::{Duration, Instant};

use crossbeam_channel::{Receiver, RecvTimeoutError, Sender, TryRecvError};

use super::executor::run_parallel;
use super::pacing::raise_thread_priority;
use super::plan::Fast;
use super::slots::Slot;
use super::walk::{self, commit_fast, Bodies};
use super::Manager;
use crate::config::ClockKind;
use crate::control::{ControlError, Handle, Reply, Request};
use crate::handle::Envelope;
use crate::runner::{BodyClock, Exec, Stamp};
use crate::starved::Starvation;
use watchdog::watchdog;

mod watchdog;

type Guard<'a> = parking_lot::MutexGuard<'a, Option<Manager>>;

/// What a body left behind on a thread that held the lock may still be
/// using (see [`Manager::leave_behind_held`]).
struct LeftBehind {
    #[allow(dead_code, reason = "held until the body returns, then dropped")]
    exec: Box<Exec>,
    #[allow(dead_code, reason = "held until the body returns, then dropped")]
    slots: Vec<Slot>,
}

/// What the cycle threads and the watchdog share.
struct Core {
    /// `None` once the manager has been handed back (shutdown). A
    /// `parking_lot` lock: held by a cycle thread while a body runs, it is
    /// handed to the watchdog if the body gets stuck (see the module's
    /// documentation), which `std`'s lock cannot do.
    manager: Lock<Option<Manager>>,
    requests: Receiver<Envelope>,
    /// Where the manager goes when the last cycle thread ends.
    done: Mutex<Option<Sender<Manager>>>,
    /// Tells the watchdog to end.
    stop: AtomicBool,
    watchdog: Mutex<Option<Thread>>,
    robot: String,
    clocks: Arc<[BodyClock]>,
    pool: Option<Arc<rayon::ThreadPool>>,
    /// The bodies left behind on a cycle thread that held the lock, by
    /// instance and mark (one instance may have two: one that has returned
    /// and not been dropped yet, and a fresh one stuck since): each dropped
    /// by its thread once the body returns, never before (the body runs in
    /// it). The stuck thread holds the core, so they outlive it.
    left_behind: Mutex<Vec<(usize, u64, LeftBehind)>>,
    /// The reply to a `Step` being run: the watchdog answers it when it
    /// leaves the stepping thread behind.
    step_reply: Mutex<Option<Sender<Result<Reply, ControlError>>>>,
    /// A step on an external clock, and the requests that came while it runs.
    deferred: Mutex<Deferred>,
    /// The cycle thread's waits for a CPU, sampled by the watchdog (the simulated clock, serial).
    starved: Option<Arc<Starvation>>,
}

/// On an external clock (ROS time from a simulator), a client's `Step` runs the next cycles as
/// the clock gives them, not ahead of it: a cycle run ahead would read no new readings, or the
/// readings of a tick that happened to arrive first, and a lock-stepped run would not be the
/// same twice. Its reply waits until they have run (or a `Stop`, another step, or the end of
/// the external clock ends it); other requests are served meanwhile. A client that steps and
/// then asks for a value waits for the step's reply first: `Handle::request` does, and so does
/// the link (`situate_link`), which sends nothing after a step before its reply.
#[derive(Default)]
struct Deferred {
    step: Option<Sender<Result<Reply, ControlError>>>,
}

impl Core {
    fn step_reply(&self) -> MutexGuard<'_, Option<Sender<Result<Reply, ControlError>>>> {
        self.step_reply.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn deferred(&self) -> MutexGuard<'_, Deferred> {
        self.deferred.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Drops the box of body `i`'s run `mark` once the watchdog has left it
    /// (see `OnThreads::run`).
    #[cold]
    fn drop_left_behind(&self, i: usize, mark: u64) {
        let until = Instant::now() + Duration::from_secs(10);
        loop {
            let mut left = self.left_behind.lock().unwrap_or_else(|p| p.into_inner());
            if let Some(at) = left.iter().position(|&(j, m, _)| (j, m) == (i, mark)) {
                let (_, _, body) = left.swap_remove(at);
                drop(left);
                // Its drop may block: with no lock held.
                drop(body);
                return;
            }
            drop(left);
            if Instant::now() > until {
                // Never left (the watchdog ended first): nothing to drop.
                return;
            }
            thread::sleep(Duration::from_millis(1));
        }
    }

    #[inline(always)]
    fn lock(&self) -> Guard<'_> {
        self.manager.lock()
    }

    /// Hands the manager back to whoever joins, and ends the watchdog.
    fn finish(&self, g: &mut Guard<'_>) {
        let manager = g.take();
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.watchdog.lock().unwrap_or_else(|p| p.into_inner()).as_ref() {
            t.unpark();
        }
        let done = self.done.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let (Some(done), Some(m)) = (done, manager) {
            let _ = done.send(m);
        }
    }
}

/// The manager when this thread is still its cycle thread.
fn current<'g>(g: &'g mut Guard<'_>, generation: u64) -> Option<&'g mut Manager> {
    g.as_mut().filter(|m| m.generation == generation)
}

/// Waits for a spawned manager to end (after [`Request::Shutdown`], or when
/// every [`Handle`] is gone) and gives it back.
pub struct Joiner {
    done: Receiver<Manager>,
    core: Arc<Core>,
}

impl Joiner {
    /// Waits for the manager. An error when its cycle thread panicked.
    pub fn join(self) -> thread::Result<Manager> {
        self.done.recv().map_err(|_| Box::new("the skill manager's thread panicked") as Box<_>)
    }

    /// Waits at most `timeout`; the joiner back if the manager has not ended.
    pub fn join_timeout(self, timeout: Duration) -> Result<thread::Result<Manager>, Joiner> {
        match self.done.recv_timeout(timeout) {
            Ok(m) => Ok(Ok(m)),
            Err(RecvTimeoutError::Disconnected) => Ok(Err(Box::new("the skill manager's thread panicked") as Box<_>)),
            Err(RecvTimeoutError::Timeout) => Err(self),
        }
    }

    /// Whether the manager has ended (`join` will not wait).
    pub fn is_finished(&self) -> bool {
        !self.done.is_empty() || self.core.stop.load(Ordering::Acquire)
    }
}

/// Ends the joiner's wait with an error if a cycle thread panics.
struct PanicGuard<'a>(&'a Core);

impl Drop for PanicGuard<'_> {
    fn drop(&mut self) {
        if thread::panicking() {
            // A bug in the manager itself (bodies' panics are caught): never silent.
            tracing::error!(robot = %self.0.robot, "the skill manager's cycle thread panicked: the robot is stopped");
            // Bounded: never a second hang on top of the panic.
            if let Some(m) = self.0.manager.try_lock_for(Duration::from_secs(1)).as_ref().and_then(|g| g.as_ref()) {
                m.bus.report(crate::control::Event::WorkerFailed {
                    thread: thread::current().name().unwrap_or("cycle").to_string(),
                    cause: "panicked (see the log)".into(),
                    action: "not restarted: the robot is stopped (its manager has ended)".into(),
                });
            }
            self.0.stop.store(true, Ordering::Release);
            drop(self.0.done.lock().unwrap_or_else(|p| p.into_inner()).take());
        }
    }
}

impl Manager {
    /// Leaves behind body `i`, stuck on a cycle thread that holds the lock
    /// (the caller has it now). Out of the manager, for that thread to drop
    /// once the body returns (`Core::left_behind`): its box, an empty one in
    /// its place, and the slots as they are, a copy of them in their place
    /// (a reference count a value), since the body may be reading its input
    /// in its slot, which the next cycle writes. The inputs lent to it are
    /// put back in their slots as copies (the body may still read them).
    fn leave_behind_held(&mut self, i: usize) -> LeftBehind {
        let slots = self.slots.clone();
        let old_slots = std::mem::replace(&mut self.slots, slots);
        let def = &self.graph.instances[i];
        for (port, input) in def.inputs.iter().zip(&self.execs[i].inputs) {
            // A lent input's slot is empty (a gathered copy's is not, nor a record's leaves).
            if let (Some(value), &[leaf]) = (input, &port.leaves[..]) {
                let slot = &mut self.slots[leaf];
                if slot.value.is_none() && !matches!(port.ty, situate_core::SignalType::Record(_)) {
                    slot.value = Some(value.clone());
                }
            }
        }
        let empty = self.spare_execs.pop().unwrap_or_default();
        LeftBehind { exec: std::mem::replace(&mut self.execs[i], empty), slots: old_slots }
    }

    /// Takes body `i` out to run it with the lock let go, an empty one in
    /// its place (from the spares: one is made only when none is left, the
    /// first time a parallel batch takes several bodies out, or after a body
    /// left behind kept its stand-in's place).
    #[inline(always)]
    fn take_exec(&mut self, i: usize) -> Box<Exec> {
        let empty = self.spare_execs.pop().unwrap_or_default();
        std::mem::replace(&mut self.execs[i], empty)
    }

    /// Puts body `i` back after it ran, its empty stand-in a spare again.
    #[inline(always)]
    fn put_exec(&mut self, i: usize, exec: Box<Exec>) {
        let empty = std::mem::replace(&mut self.execs[i], exec);
        if self.spare_execs.len() < self.spare_execs.capacity() {
            self.spare_execs.push(empty);
        }
    }
}

impl Manager {
    /// Moves the manager to threads of its own — the cycle and a watchdog —
    /// serving requests from handles. With `running`, the cycle starts at
    /// once. [`Joiner::join`] gives the manager back after a shutdown.
    pub fn spawn(mut self, running: bool) -> (Handle, Joiner) {
        let (tx, rx) = crossbeam_channel::unbounded::<Envelope>();
        // A first wait on the requests, now: the channel grows its list of
        // waiting receivers the first time one waits, and that must not be
        // the running cycle thread. Nothing can be queued yet (the handle is
        // not out), so nothing is taken.
        let _ = rx.recv_timeout(Duration::from_millis(1));
        let (done_tx, done_rx) = crossbeam_channel::bounded(1);
        let handle = Handle { tx, bus: self.bus.clone(), graph: Arc::clone(&self.graph) };
        if running {
            let _ = self.request(Request::Run);
        }
        let deadlines: Vec<Duration> = self.graph.instances.iter().map(|d| d.in_cycle_deadline()).collect();
        // On the simulated clock a busy machine must not fault a body (`crate::starved`); every
        // body runs on the cycle thread unless a pool runs them.
        if self.clock == ClockKind::Simulated && self.pool.is_none() {
            self.starved = Some(Arc::new(Starvation::new()));
        }
        let core = Arc::new(Core {
            requests: rx,
            done: Mutex::new(Some(done_tx)),
            stop: AtomicBool::new(false),
            watchdog: Mutex::new(None),
            robot: self.graph.robot.clone(),
            clocks: Arc::clone(&self.clocks),
            pool: self.pool.clone(),
            step_reply: Mutex::new(None),
            left_behind: Mutex::new(Vec::new()),
            deferred: Mutex::new(Deferred::default()),
            starved: self.starved.clone(),
            manager: Lock::new(Some(self)),
        });
        start_cycle_thread(&core, 0);
        let watch = Arc::clone(&core);
        let name = format!("situate-{}-watchdog", core.robot);
        match thread::Builder::new().name(name).spawn(move || watchdog(watch, deadlines)) {
            Ok(t) => *core.watchdog.lock().unwrap_or_else(|p| p.into_inner()) = Some(t.thread().clone()),
            Err(e) => tracing::warn!(error = %e, "no watchdog thread: a stuck body will stall the cycle"),
        }
        (handle, Joiner { done: done_rx, core })
    }
}

fn start_cycle_thread(core: &Arc<Core>, generation: u64) {
    let c = Arc::clone(core);
    let name = if generation == 0 {
        format!("situate-{}", core.robot)
    } else {
        format!("situate-{}-{generation}", core.robot)
    };
    let body = move || {
        warm_channel_waits();
        serve(&c, generation)
    };
    if let Err(e) = thread::Builder::new().name(name).spawn(body) {
        // Without a cycle thread nothing can go on: hand the manager back.
        tracing::error!(error = %e, "could not start a cycle thread");
        core.finish(&mut core.lock());
    }
}

/// Makes this thread's first wait on a channel now. `crossbeam-channel`
/// allocates a thread's wait context the first time that thread blocks (a
/// wait long enough to block, not only spin), and the cycle thread may first
/// block on its requests at any moment of a run (whenever a request is late
/// for the first time): then the running robot would allocate.
/// The wait is the kind the cycle thread makes (`recv_timeout` on a channel
/// of requests): a wait of another kind was seen to leave the later one to
/// set up its context again.
fn warm_channel_waits() {
    let (_tx, rx) = crossbeam_channel::unbounded::<Envelope>();
    let _ = rx.recv_timeout(Duration::from_millis(1));
}

/// What serving one request has taken lately: a maximum that decays by a
/// sixteenth per request. Between two cycles, a request is started only
/// while the time left before the next one is due is longer than this.
struct RequestCost(Duration);

impl RequestCost {
    fn note(&mut self, took: Duration, cap: Duration) {
        self.0 = (self.0 - self.0 / 16).max(took).min(cap);
    }
}

/// At most this many requests are served between two cycles of a clock
/// that is not paced (the simulated clock as fast as possible).
const UNPACED_BURST: usize = 64;

/// The cycle thread: cycles paced by the clock, requests between cycles.
///
/// Requests are served in the time left before the next cycle is due, and a
/// request is only started when that time is longer than what requests took
/// lately: the cycle does not wait for link work. At least one is served
/// after each cycle, so that requests (a `stop`) get through even when the
/// cycle cannot keep up; the time a request still runs past the due time is
/// counted (`request_hold_ns`), as is the time lost when a cycle started so
/// late that periods were skipped (`lost_ns`).
fn serve(core: &Core, generation: u64) {
    let _guard = PanicGuard(core);
    raise_thread_priority();
    if let Some(s) = &core.starved {
        s.adopt_current_thread();
    }
    let mut deadline = Instant::now();
    // When the next cycle is due, for the manager's count of late starts.
    let mut next_due: Option<Instant> = None;
    let mut cost = RequestCost(Duration::from_micros(50));
    let mut g = core.lock();
    loop {
        let Some(m) = current(&mut g, generation) else { return };
        if m.running && m.stop_at.is_some_and(|n| m.cycle >= n) {
            let _ = m.request(Request::Stop);
        }
        if !m.running || m.external_clock {
            // A step on the external clock that has run its cycles is answered.
            if m.step_until.is_none() {
                if let Some(reply) = core.deferred().step.take() {
                    let _ = reply.send(Ok(Reply::Done));
                }
            }
            // Stopped, or the cycle follows an external clock (its ticks are requests): wait
            // for a request without holding the lock.
            drop(g);
            // `recv_timeout`, as `warm_channel_waits` does (see there).
            let received = loop {
                match core.requests.recv_timeout(Duration::from_secs(3600)) {
                    Ok(e) => break Ok(e),
                    Err(crossbeam_channel::RecvTimeoutError::Timeout) => continue,
                    Err(crossbeam_channel::RecvTimeoutError::Disconnected) => break Err(crossbeam_channel::RecvError),
                }
            };
            g = core.lock();
            match received {
                Ok(envelope) => {
                    let ends_step = envelope.tap.is_none()
                        && matches!(
                            envelope.request,
                            Request::Stop | Request::Step { .. } | Request::ExternalClock { .. }
                        );
                    if let (true, Some(m)) = (ends_step, current(&mut g, generation)) {
                        // A stop ends a step where it is; so do another step and the end of the
                        // clock it waits for.
                        if m.step_until.take().is_some() {
                            if let Some(reply) = core.deferred().step.take() {
                                let _ = reply.send(Ok(Reply::Done));
                            }
                        }
                    }
                    match serve_one(core, g, generation, envelope) {
                        Served::Go(back) => g = back,
                        Served::End => return,
                    }
                }
                Err(_) => return core.finish(&mut g),
            }
            deadline = Instant::now();
            next_due = None;
            continue;
        }
        let pacing = m.pacing();
        m.due = next_due.take();
        g = match cycle(core, g, generation) {
            Some(g) => g,
            None => return,
        };
        match pacing {
            Some(period) => {
                deadline += period;
                // Already due: the cycle (or what held it back) ran past the next start.
                let skipped = deadline < Instant::now();
                let mut served = 0usize;
                loop {
                    let left = deadline.saturating_duration_since(Instant::now());
                    if served > 0 && left <= cost.0 {
                        break;
                    }
                    drop(g);
                    let received = if left.is_zero() {
                        core.requests.try_recv().map_err(|e| match e {
                            TryRecvError::Empty => RecvTimeoutError::Timeout,
                            TryRecvError::Disconnected => RecvTimeoutError::Disconnected,
                        })
                    } else {
                        core.requests.recv_deadline(deadline)
                    };
                    g = core.lock();
                    let envelope = match received {
                        Ok(envelope) => envelope,
                        Err(RecvTimeoutError::Timeout) => break,
                        Err(RecvTimeoutError::Disconnected) => return core.finish(&mut g),
                    };
                    let stepping = matches!(envelope.request, Request::Step { .. });
                    let start = Instant::now();
                    match serve_one(core, g, generation, envelope) {
                        Served::Go(back) => g = back,
                        Served::End => return,
                    }
                    let end = Instant::now();
                    served += 1;
                    if !stepping {
                        cost.note(end - start, period / 4);
                    }
                    let Some(m) = current(&mut g, generation) else { return };
                    if !m.running {
                        break;
                    }
                    if end > deadline {
                        m.request_hold_ns += end.duration_since(start.max(deadline)).as_nanos() as u64;
                    }
                }
                let now = Instant::now();
                if let (true, Some(m)) = (skipped, current(&mut g, generation)) {
                    // The next cycle starts late, and the missed periods are skipped.
                    m.late_starts += 1;
                    m.lost_ns += now.saturating_duration_since(deadline).as_nanos() as u64;
                    deadline = now;
                } else {
                    next_due = Some(deadline);
                }
            }
            None => {
                for _ in 0..UNPACED_BURST {
                    match core.requests.try_recv() {
                        Ok(envelope) => match serve_one(core, g, generation, envelope) {
                            Served::Go(back) => g = back,
                            Served::End => return,
                        },
                        Err(TryRecvError::Empty) => break,
                        Err(TryRecvError::Disconnected) => return core.finish(&mut g),
                    }
                }
            }
        }
    }
}

enum Served<'a> {
    Go(Guard<'a>),
    /// Shut down, or this thread was left behind.
    End,
}

/// Answers one request. `Step` runs its cycles here, so a body that gets
/// stuck in one is left behind like in a running cycle.
fn serve_one<'a>(core: &'a Core, mut g: Guard<'a>, generation: u64, envelope: Envelope) -> Served<'a> {
    let Envelope { request, monitor, tap, reply } = envelope;
    let Some(m) = current(&mut g, generation) else {
        // Not the cycle any more: the request goes back to the queue's
        // new owner only if we could; answer that the manager moved on.
        let _ = reply.send(Err(ControlError::Interrupted(
            "the request arrived while the cycle was restarting; send it again".into(),
        )));
        return Served::End;
    };
    if let Some((capacity, to)) = tap {
        let _ = to.send(m.tap(capacity));
        let _ = reply.send(Ok(Reply::Done));
        return Served::Go(g);
    }
    match request {
        Request::Shutdown => {
            let _ = reply.send(Ok(Reply::Done));
            core.finish(&mut g);
            Served::End
        }
        Request::Step { cycles } => {
            if let Err(e) = m.check_step(cycles) {
                let _ = reply.send(Err(e));
                return Served::Go(g);
            }
            m.halt();
            if m.external_clock {
                // The clock's next ticks run them (see `Deferred`).
                m.step_until = Some(m.cycle + cycles);
                core.deferred().step = Some(reply);
                return Served::Go(g);
            }
            *core.step_reply() = Some(reply);
            for _ in 0..cycles {
                g = match cycle(core, g, generation) {
                    Some(g) => g,
                    // Left behind: the watchdog answered the step.
                    None => return Served::End,
                };
                if current(&mut g, generation).is_some_and(|m| m.paused) {
                    break;
                }
            }
            if let Some(reply) = core.step_reply().take() {
                let _ = reply.send(Ok(Reply::Done));
            }
            Served::Go(g)
        }
        Request::Tick { until } => {
            if let Err(e) = m.check_tick(until) {
                let _ = reply.send(Err(e));
                return Served::Go(g);
            }
            let from = m.cycle;
            *core.step_reply() = Some(reply);
            loop {
                let Some(m) = current(&mut g, generation) else { return Served::End };
                if m.running && m.stop_at.is_some_and(|n| m.cycle >= n) {
                    // `--cycles N`: the external clock stops there too.
                    let _ = m.request(Request::Stop);
                }
                let stepping = m.step_until.is_some_and(|s| m.cycle < s);
                if !(m.running || stepping) || m.cycle >= until {
                    break;
                }
                g = match cycle(core, g, generation) {
                    Some(g) => g,
                    // Left behind: the watchdog answered the tick.
                    None => return Served::End,
                };
                if let Some(m) = current(&mut g, generation) {
                    // A step's last cycle, or a pausing monitor (which ends a step where it
                    // fires, as it stops a run).
                    if m.step_until.is_some_and(|s| m.cycle >= s) || m.paused {
                        m.step_until = None;
                    }
                }
            }
            let cycle = current(&mut g, generation).map_or(from, |m| m.cycle);
            if let Some(reply) = core.step_reply().take() {
                let _ = reply.send(Ok(Reply::Ticked { ran: cycle.saturating_sub(from), cycle }));
            }
            Served::Go(g)
        }
        request => {
            let _ = reply.send(m.request_prepared(request, monitor));
            Served::Go(g)
        }
    }
}

/// One cycle with every body run outside the lock (the walk is
/// `walk::cycle`). `None`: this thread was left behind while a body ran.
fn cycle<'a>(core: &'a Core, g: Guard<'a>, generation: u64) -> Option<Guard<'a>> {
    let mut bodies = OnThreads { core, g: Some(g), generation };
    walk::cycle(&mut bodies)?;
    bodies.g
}

/// The bodies of a spawned manager: each taken out of the manager and run
/// with its lock let go, its [`BodyClock`] showing the watchdog when it
/// started; then the lock is taken back and the body returned, unless this
/// thread was left behind meanwhile (its late result is then dropped with
/// it).
///
/// A body on the cycle thread runs where it is, in the manager, with the
/// lock held (see the module's documentation), and reads its one input in
/// its slot or its inputs lent, as in `Manager::cycle`: a body left behind
/// takes the slots' vector with it (`Manager::leave_behind_held`), so the
/// next cycles never write what it may still be reading.
struct OnThreads<'a> {
    core: &'a Core,
    /// `Some` but while a body runs.
    g: Option<Guard<'a>>,
    generation: u64,
}

impl Bodies for OnThreads<'_> {
    const IN_PLACE: bool = true;

    #[inline(always)]
    fn manager(&mut self) -> Option<&mut Manager> {
        current(self.g.as_mut()?, self.generation)
    }

    /// The lock is held throughout, by whichever of this thread and the
    /// watchdog holds the body's mark: the guard is forgotten before the
    /// body runs and made again only when this thread takes its mark back.
    #[inline(always)]
    fn run(&mut self, i: usize, in_place: Option<usize>, start: Stamp) -> Option<Stamp> {
        self.held(i, in_place, |exec, input, cycle, time_s| exec.run_on(input, cycle, time_s, start, None))
    }

    #[inline(always)]
    fn run_fast(&mut self, fast: &Fast) -> Option<bool> {
        let i = fast.inst as usize;
        if fast.in_slot {
            // Its output is written into its slot only once this thread has
            // its mark back: a body left behind writes nothing a later cycle
            // reads, and the slot keeps its last value meanwhile.
            let clean =
                self.held(i, fast.input(), |exec, input, cycle, time_s| exec.run_unwritten(input, cycle, time_s))?;
            if clean {
                let m = self.manager()?;
                let slot = &mut m.slots[fast.output as usize];
                m.execs[i].write_into(Some(&mut slot.value));
                slot.stamp = m.cycle;
                slot.rank = fast.rank;
            }
            return Some(clean);
        }
        let clean = self.held(i, fast.input(), |exec, input, cycle, time_s| exec.run_untimed(input, cycle, time_s))?;
        if clean {
            let m = self.manager()?;
            commit_fast(&mut m.execs[i], &mut m.slots[fast.output as usize], m.cycle, fast.rank);
        }
        Some(clean)
    }

    /// Batch by batch; each body goes back to the manager as soon as it
    /// returns, so one stuck body holds no other.
    fn run_batch(&mut self, batch: &[usize]) -> Option<()> {
        let core = self.core;
        let pool = core.pool.as_ref()?;
        let generation = self.generation;
        let m = self.manager()?;
        let (cycle, time_s) = (m.cycle, m.time_s);
        // Each run its own number (see `BodyClock`).
        let first = m.runs + 1;
        m.runs += batch.len() as u64;
        // Each job: the instance, its run's number, its body (taken by the thread that runs it).
        type Job = (usize, u64, Mutex<Option<Box<Exec>>>);
        let jobs: Vec<Job> =
            batch.iter().zip(first..).map(|(&i, number)| (i, number, Mutex::new(Some(m.take_exec(i))))).collect();
        self.g = None;
        run_parallel(pool, &jobs, |(i, number, job)| {
            let Some(mut exec) = job.lock().unwrap_or_else(|p| p.into_inner()).take() else { return };
            exec.run(cycle, time_s, Stamp::now(true), Some((&core.clocks[*i], *number)));
            let mut g = core.lock();
            if let Some(m) = current(&mut g, generation) {
                m.put_exec(*i, exec);
            }
        });
        self.g = Some(core.lock());
        self.manager()?;
        Some(())
    }
}

impl OnThreads<'_> {
    /// Runs instance `i`'s body by `run` (given its box, its input in slot
    /// `in_place` if any, the cycle and its time) holding the lock, which
    /// the watchdog takes with the body's mark if it leaves the body behind.
    #[inline(always)]
    fn held<R>(
        &mut self,
        i: usize,
        in_place: Option<usize>,
        run: impl FnOnce(&mut Exec, Option<&Option<situate_core::Value>>, u64, f64) -> R,
    ) -> Option<R> {
        let core = self.core;
        let m = self.manager()?;
        let (cycle, time_s) = (m.cycle, m.time_s);
        m.runs += 1;
        let number = m.runs;
        let input: Option<*const Option<situate_core::Value>> = in_place.map(|leaf| &m.slots[leaf].value as *const _);
        let exec: *mut Exec = &mut *m.execs[i];
        let clock = &core.clocks[i];
        std::mem::forget(self.g.take());
        // Released: what this thread wrote to the manager is seen by a watchdog that takes the mark.
        let mark = clock.enter(number, true);
        // SAFETY: `exec` is the body's box in the manager, and `input` a value in the manager's
        // slots, which this thread owns while it holds the mark. A watchdog that takes the mark
        // meanwhile only reads the box's `inputs` (which the body only reads), and moves the
        // box and the slots' vector, not what they point to, to `left_behind`, never dropped
        // but by this thread (below), and never written again.
        let out = unsafe { run(&mut *exec, input.map(|p| &*p), cycle, time_s) };
        if clock.leave(mark) {
            // SAFETY: this thread held the lock when it forgot its guard above, and the watchdog
            // did not take the mark (the only way the lock could have moved): it still holds it.
            self.g = Some(unsafe { core.manager.make_guard_unchecked() });
            return Some(out);
        }
        // Left behind: the watchdog has the lock, and moves the body's box out of the manager
        // for this thread to drop, now that the body returned (a moment's wait if it returned
        // as the watchdog took the mark).
        core.drop_left_behind(i, mark);
        None
    }
}
