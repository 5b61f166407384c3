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
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread;
use std::time::{Duration, Instant};

use situate_core::{Context, Io, Skill, SkillKind, Value};

/// The runnable part of a skill instance: its body and reusable port buffers.
pub(crate) struct Exec {
    /// `None` once the body has moved to its worker thread.
    pub skill: Option<Box<dyn Skill>>,
    pub inputs: Vec<Option<Value>>,
    pub outputs: Vec<Option<Value>>,
    pub cx: Context,
    pub result: Result<(), String>,
    pub elapsed_ns: u64,
}

impl Exec {
    pub fn new(skill: Box<dyn Skill>, inputs: usize, outputs: usize) -> Self {
        Exec {
            skill: Some(skill),
            inputs: vec![None; inputs],
            outputs: vec![None; outputs],
            cx: Context::default(),
            result: Ok(()),
            elapsed_ns: 0,
        }
    }

    /// Runs the body once on the gathered inputs, catching panics, and times
    /// it from `start`; returns the time it ended, so a caller running bodies
    /// back to back reads the clock once per body.
    ///
    /// Outputs are `None` on entry: the manager takes every produced output
    /// when it commits, and clears them when a body fails.
    pub fn run(&mut self, cycle: u64, time_s: f64, start: Instant) -> Instant {
        self.cx.set(cycle, time_s);
        self.result = match &mut self.skill {
            Some(skill) => run_body(skill.as_mut(), &self.inputs, &mut self.outputs, &mut self.cx),
            None => Err("the body is not here (it runs on its own thread)".into()),
        };
        let end = Instant::now();
        self.elapsed_ns = end.duration_since(start).as_nanos() as u64;
        end
    }
}

/// Runs a body, turning a panic into an error.
pub(crate) fn run_body(
    skill: &mut dyn Skill,
    inputs: &[Option<Value>],
    outputs: &mut [Option<Value>],
    cx: &mut Context,
) -> Result<(), String> {
    let mut io = Io { inputs, outputs, cx };
    match catch_unwind(AssertUnwindSafe(|| skill.step(&mut io))) {
        Ok(Ok(())) => Ok(()),
        Ok(Err(e)) => Err(e.message),
        Err(panic) => Err(format!("panicked: {}", panic_message(&*panic))),
    }
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic without a message".to_string()
    }
}

/// Timing of a threaded body, kept by its worker.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct WorkerStats {
    pub runs: u64,
    pub last_ns: u64,
    pub total_ns: u64,
    pub max_ns: u64,
}

/// What the cycle and a worker exchange.
#[derive(Default)]
pub(crate) struct Mailbox {
    pub active: bool,
    pub stop: bool,
    /// Latest inputs (async) or pending commands (dskill; taken by the worker).
    pub inputs: Vec<Option<Value>>,
    pub inputs_new: bool,
    pub cycle: u64,
    pub time_s: f64,
    /// Latest value of each output, merged across runs.
    pub outputs: Vec<Option<Value>>,
    pub params: Vec<(usize, Value)>,
    pub fault: Option<String>,
    pub prints: Vec<String>,
    pub stats: WorkerStats,
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

/// The cycle's side of a threaded body.
pub(crate) struct Worker {
    pub shared: Arc<Shared>,
    started: bool,
}

impl Worker {
    pub fn new(inputs: usize, outputs: usize) -> Self {
        let mailbox = Mailbox { inputs: vec![None; inputs], outputs: vec![None; outputs], ..Mailbox::default() };
        Worker { shared: Arc::new(Shared { mailbox: Mutex::new(mailbox), wake: Condvar::new() }), started: false }
    }

    /// Starts the worker thread the first time the skill is activated,
    /// moving the body there.
    pub fn set_active(&mut self, active: bool, exec: &mut Exec, kind: SkillKind, name: &str, period: Duration) {
        {
            let mut mb = self.shared.lock();
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
                    .spawn(move || worker_loop(skill, shared, kind, period));
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

fn worker_loop(mut skill: Box<dyn Skill>, shared: Arc<Shared>, kind: SkillKind, period: Duration) {
    let mut cx = Context::default();
    let mut next = Instant::now();
    let (n_in, n_out) = {
        let mb = shared.lock();
        (mb.inputs.len(), mb.outputs.len())
    };
    let mut outputs: Vec<Option<Value>> = vec![None; n_out];
    loop {
        let (inputs, params) = {
            let mut mb = shared.lock();
            loop {
                if mb.stop {
                    return;
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
            mb.inputs_new = false;
            cx.set(mb.cycle, mb.time_s);
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
            mb.stats.runs += 1;
            mb.stats.last_ns = elapsed;
            mb.stats.total_ns += elapsed;
            mb.stats.max_ns = mb.stats.max_ns.max(elapsed);
            mb.prints.extend(cx.take_prints());
            match result {
                Ok(()) => {
                    for (slot, out) in mb.outputs.iter_mut().zip(&mut outputs) {
                        if let Some(v) = out.take() {
                            *slot = Some(v);
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
