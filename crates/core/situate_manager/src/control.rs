//! The control API: what a sequencer can ask of the skill manager.
//!
//! Everything goes through one [`Request`] → [`Reply`] exchange, whether the
//! caller owns the [`Manager`](crate::Manager) or holds a [`Handle`] to one
//! running on its own thread. The sequencer link (over the network) serves
//! exactly this API, so anything the link can do is tested here first.
//!
//! Requests are handled between two cycles: changes (activation, parameters,
//! priorities) take effect from the next cycle on; queries see the state at
//! the end of the last cycle. A refused request changes nothing.

use situate_core::{ParamSpec, SignalType, SkillKind, Value};

pub use crate::handle::{EventBus, Handle, Pending};

use crate::monitor::{MonitorCondition, MonitorMode};

/// One request to the skill manager.
#[derive(Debug, Clone, PartialEq)]
pub enum Request {
    /// Activate skills from the next cycle on. With `with_providers`, also
    /// activate (recursively) a provider of every input nobody active provides.
    Activate {
        skills: Vec<String>,
        with_providers: bool,
    },
    Deactivate {
        skills: Vec<String>,
    },
    SetParam {
        skill: String,
        param: String,
        value: Value,
    },
    GetParam {
        skill: String,
        param: String,
    },
    SetPriority {
        skill: String,
        priority: i32,
    },
    /// Send the skill's own prints as events.
    SetVerbose {
        skill: String,
        verbose: bool,
    },
    /// The current value of a signal (a leaf or a whole record).
    QuerySignal {
        signal: String,
    },
    /// The current values of several signals, all of one moment (between two cycles): what
    /// [`Request::QuerySignal`] gives for each, in one request.
    QuerySignals {
        signals: Vec<String>,
    },
    QuerySkill {
        skill: String,
    },
    QuerySkills,
    QueryWinners,
    QueryGraph,
    QueryStats,
    /// Watch `condition` (see [`crate::expr`]): one condition, or any of
    /// several (a `&str` or `String` converts with `.into()`); with `pause`,
    /// also stop the cycle at the end of each cycle the monitor fires in.
    AddMonitor {
        condition: MonitorCondition,
        mode: MonitorMode,
        pause: bool,
        /// More names whose values the monitor's events carry besides those
        /// the condition reads: signal leaves, whole records (as their
        /// leaves), `skill.param`, `time`, `cycle`.
        report: Vec<String>,
        /// The session that will hold the monitor: only it cancels it, its
        /// monitors count against [`crate::MAX_MONITORS_PER_SESSION`], and they
        /// go when it ends ([`Request::EndSession`]). The link and the GUI fill
        /// it in for their clients (a link client proves its session with a
        /// secret, docs/protocol.md "Sessions"); `None` is the program itself
        /// (in-process requests), whose monitors share one allowance.
        session: Option<String>,
        /// A name the client gives itself, shown with its monitors; not an
        /// identity (anyone may give any name).
        client: Option<String>,
    },
    /// Remove a monitor: only its session may ([`Request::AddMonitor`]'s
    /// `session`, the same `None` for the program's own), unless `force`d
    /// (the GUI, after asking its user); the owner then gets a
    /// `monitor_cancelled` event saying so.
    CancelMonitor {
        monitor: u64,
        session: Option<String>,
        force: bool,
    },
    /// A session ended (its client went away): its monitors are removed, each
    /// with a `monitor_cancelled` event.
    EndSession {
        session: String,
    },
    ListMonitors,
    Run,
    Stop,
    /// Run this many cycles now, then stop.
    Step {
        cycles: u64,
    },
    /// Follow a clock outside the manager (ROS time: `situate_ros2`'s `/clock`): with `on`,
    /// `Run` no longer starts the manager's own clock; it lets [`Request::Tick`]s run cycles,
    /// and `Stop` (or a pausing monitor) holds them back. `Step` still runs cycles at once.
    /// `on: false` gives the cycle back to the manager's clock.
    ExternalClock {
        on: bool,
    },
    /// A tick of the external clock: run cycles until the cycle count is `until`, while the
    /// manager runs (a pausing monitor stops it where it fires; stopped, none run). Replies
    /// [`Reply::Ticked`]: the cycles it ran and the count after (below `until` when it stopped).
    Tick {
        until: u64,
    },
    /// The sequencer says which phase or step of its mission it is in (`leaving the lab`): a
    /// [`Event::Phase`] from the next cycle on, shown on the GUI's timeline, recorded, replayed.
    /// At most [`MAX_PHASE_TEXT`] characters, none of them a control character.
    Phase {
        text: String,
        /// A name the client gives itself (`deliver`); not an identity.
        client: Option<String>,
    },
    /// End the manager's thread (from a [`Handle`]).
    Shutdown,
}

/// The longest a [`Request::Phase`]'s text may be, in characters.
pub const MAX_PHASE_TEXT: usize = 200;

/// The answer to a [`Request`].
#[derive(Debug, Clone, PartialEq)]
pub enum Reply {
    Done,
    /// The skills whose activation changed, and the cycle it applies at.
    Activation {
        changed: Vec<String>,
        at_cycle: u64,
    },
    Param(Value),
    Signal(SignalReading),
    /// The readings of a [`Request::QuerySignals`], in its order.
    Signals(Vec<SignalReading>),
    Skill(Box<SkillInfo>),
    Skills(Vec<SkillInfo>),
    Winners(Vec<ResourceWinner>),
    Graph(GraphInfo),
    Stats(ManagerStats),
    MonitorAdded(u64),
    Monitors(Vec<MonitorInfo>),
    /// The monitors an [`Request::EndSession`] removed.
    MonitorsCancelled(Vec<u64>),
    /// What a [`Request::Tick`] did: the cycles it ran, and the cycle count after.
    Ticked {
        ran: u64,
        cycle: u64,
    },
}

/// Why a request was refused. Every message names the thing and, where it
/// can, suggests the likely intended name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlError {
    #[error("unknown skill `{name}`{suggestion}")]
    UnknownSkill { name: String, suggestion: String },
    #[error("skill `{skill}`: unknown parameter `{param}`{suggestion}")]
    UnknownParam { skill: String, param: String, suggestion: String },
    #[error("skill `{skill}`: parameter `{param}` {reason}")]
    BadParam { skill: String, param: String, reason: String },
    #[error("cannot activate `{skill}`: {}", missing_text(signals, providers))]
    MissingProviders { skill: String, signals: Vec<String>, providers: Vec<String> },
    #[error("unknown signal `{name}`{suggestion}")]
    UnknownSignal { name: String, suggestion: String },
    /// `index`: which of an `any` monitor's conditions (`None` for a
    /// monitor on one condition); `column` is within that condition.
    #[error("{}bad condition at column {column}: {message}\n{pointer}", any_prefix(*index))]
    BadCondition { index: Option<usize>, column: usize, message: String, pointer: String },
    #[error("`report`: {0}")]
    BadReport(String),
    #[error("no monitor {0}")]
    UnknownMonitor(u64),
    /// A request about something another session holds (a monitor).
    #[error("{0}")]
    NotOwner(String),
    #[error("{0}")]
    Invalid(String),
    /// A request cut short because a skill's body got stuck and was left
    /// behind (its `skill_faulted` event names it): a `step` that ended
    /// early, or a request that arrived while the cycle restarted. The
    /// cycle goes on; the request may be sent again.
    #[error("{0}")]
    Interrupted(String),
    #[error("the skill manager is not running (its thread has ended)")]
    Disconnected,
}

/// `any[2]: ` for an `any` monitor's condition 2, nothing for a lone condition.
pub(crate) fn any_prefix(index: Option<usize>) -> String {
    index.map(|i| format!("any[{i}]: ")).unwrap_or_default()
}

fn missing_text(signals: &[String], providers: &[String]) -> String {
    let sig = signals.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ");
    let mut text = format!("no active skill provides {sig}");
    if providers.is_empty() {
        text.push_str(" (and no skill of this robot can)");
    } else {
        let p = providers.iter().map(|s| format!("`{s}`")).collect::<Vec<_>>().join(", ");
        text.push_str(&format!(" (activate {p} too, or ask to activate providers)"));
    }
    text
}

/// Something that happened, sent to every subscriber.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    MonitorFired {
        monitor: u64,
        /// The condition, or an `any` monitor's as one disjunction: `(a) || (b)`.
        condition: String,
        cycle: u64,
        time_s: f64,
        /// Every name the conditions read (each once), then the `report` names.
        values: Vec<(String, Option<Value>)>,
        /// The indexes, in order, of the conditions that held in `cycle`
        /// (`[0]` for a monitor on one condition).
        held: Vec<usize>,
    },
    ActivationApplied {
        activated: Vec<String>,
        deactivated: Vec<String>,
        cycle: u64,
    },
    ParamChanged {
        skill: String,
        param: String,
        value: Value,
        cycle: u64,
    },
    /// A skill's priority changed (`set_priority`), in force from `cycle`.
    PriorityChanged {
        skill: String,
        priority: i32,
        cycle: u64,
    },
    SkillFaulted {
        skill: String,
        cause: String,
        cycle: u64,
    },
    /// A verbose skill's own print.
    Print {
        skill: String,
        line: String,
        cycle: u64,
    },
    /// A monitor was removed before it fired for good: by its session, by
    /// someone else (`reason` says who), or because its session ended.
    MonitorCancelled {
        monitor: u64,
        condition: String,
        session: Option<String>,
        reason: CancelReason,
        cycle: u64,
    },
    ManagerStarted {
        cycle: u64,
    },
    ManagerStopped {
        cycle: u64,
    },
    /// A worker thread (the link's, a telemetry sampler, …) panicked; what
    /// was done about it: `restarted`, or that the robot is stopped.
    WorkerFailed {
        thread: String,
        cause: String,
        action: String,
    },
    /// The sequencer's mission entered a phase ([`Request::Phase`]), from `cycle` on.
    Phase {
        text: String,
        client: Option<String>,
        cycle: u64,
    },
}

/// A signal's current value.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalReading {
    pub signal: String,
    pub ty: SignalType,
    /// `None` until first written (for a record: until every field has been).
    pub value: Option<Value>,
    /// The cycle it was last written in (the oldest field's, for a record).
    pub cycle: u64,
    /// Who wrote it last (for a record: the writer of its first field).
    pub writer: Option<String>,
}

/// A port and its latest value.
#[derive(Debug, Clone, PartialEq)]
pub struct PortInfo {
    pub name: String,
    pub signal: String,
    pub ty: SignalType,
    pub optional: bool,
    pub value: Option<Value>,
}

/// Per-skill timing of its body: how often it ran, and how long its timed
/// runs took. The cycle times a sample of the runs of in-cycle bodies (one
/// cycle in [`TIMING_SAMPLE`](crate::manager::TIMING_SAMPLE), at most one a
/// tick of the coarse clock, each such cycle a window of at most
/// [`SAMPLED_STEPS`](crate::manager::SAMPLED_STEPS) of the plan's steps, and
/// every run of a body with a short deadline); threaded bodies are timed at each run.
/// The manager keeps its cycles' timing in one too (see [`ManagerStats`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SkillTiming {
    pub runs: u64,
    pub last_ns: u64,
    pub max_ns: u64,
    /// The time of all runs: the timed ones exactly, the others as the
    /// coarse clock read them. A coarse reading is the kernel's tick (a few
    /// ms) times the ticks that fell within the run, so it is right on
    /// average (a 1 µs run reads 0, or one tick once in thousands): one slow
    /// run counts once, as long as it was, whether or not it was timed.
    pub total_ns: u64,
    /// How many runs were timed (`runs` when every run is).
    pub timed_runs: u64,
}

impl SkillTiming {
    pub fn mean_ns(&self) -> f64 {
        if self.runs == 0 {
            0.0
        } else {
            self.total_ns as f64 / self.runs as f64
        }
    }

    /// Counts `runs` runs that were not timed exactly, which took `coarse_ns`
    /// in all on the coarse clock.
    pub fn add_untimed(&mut self, runs: u64, coarse_ns: u64) {
        self.runs += runs;
        self.total_ns = self.total_ns.saturating_add(coarse_ns);
    }

    /// The mean of the runs timed exactly (0 with none).
    pub fn mean_timed_ns(&self) -> f64 {
        if self.timed_runs == 0 {
            0.0
        } else {
            self.total_ns as f64 / self.timed_runs as f64
        }
    }

    /// A run not counted, seen (on the coarse clock) to take `elapsed_ns`:
    /// only the maximum may change.
    pub fn seen(&mut self, elapsed_ns: u64) {
        self.max_ns = self.max_ns.max(elapsed_ns);
    }

    /// Counts one run timed exactly.
    pub fn record(&mut self, elapsed_ns: u64) {
        self.runs += 1;
        self.timed_runs += 1;
        self.last_ns = elapsed_ns;
        self.max_ns = self.max_ns.max(elapsed_ns);
        self.total_ns = self.total_ns.saturating_add(elapsed_ns);
    }
}

/// Everything about one skill instance.
#[derive(Debug, Clone, PartialEq)]
pub struct SkillInfo {
    pub name: String,
    pub type_name: String,
    pub kind: SkillKind,
    pub doc: String,
    pub active: bool,
    pub faulted: Option<String>,
    pub verbose: bool,
    pub priority: i32,
    pub params: Vec<(ParamSpec, Value)>,
    pub inputs: Vec<PortInfo>,
    pub outputs: Vec<PortInfo>,
    pub timing: SkillTiming,
    /// The skill's latest prints (a short history), oldest first.
    pub prints: Vec<(u64, String)>,
}

/// Who holds a resource (a signal leaf with several writers).
#[derive(Debug, Clone, PartialEq)]
pub struct ResourceWinner {
    pub signal: String,
    pub writers: Vec<String>,
    /// The writer whose value stands this cycle, if any wrote.
    pub winner: Option<String>,
    pub cycle: u64,
    /// How often the winner changed to another skill since the start (cycles
    /// nobody wrote it in do not count): arbitration's hand-overs.
    pub switches: u64,
    /// Cycles in which some skill wrote it.
    pub held_cycles: u64,
}

/// The wiring, as built.
#[derive(Debug, Clone, PartialEq)]
pub struct GraphInfo {
    pub skills: Vec<GraphSkill>,
    pub signals: Vec<GraphSignal>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct GraphSkill {
    pub name: String,
    pub kind: SkillKind,
    pub active: bool,
    pub priority: i32,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct GraphSignal {
    pub signal: String,
    pub ty: SignalType,
    pub writers: Vec<String>,
    pub readers: Vec<String>,
}

/// Cycle statistics.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ManagerStats {
    pub robot: String,
    pub cycle: u64,
    pub time_s: f64,
    pub running: bool,
    pub period_s: f64,
    pub last_cycle_ns: u64,
    pub mean_cycle_ns: f64,
    pub max_cycle_ns: u64,
    pub overruns: u64,
    /// Cycles that started late, or periods skipped (see `docs/protocol.md`).
    pub late_starts: u64,
    /// How long requests served between cycles ran past the time the next
    /// cycle was due, in all: what link work held the cycle back.
    pub request_hold_ns: u64,
    /// Time lost to cycles that started so late that periods were skipped,
    /// whatever the cause (a long body, a busy machine, requests): the
    /// achieved count falls short of the nominal by about `lost_ns / period`.
    pub lost_ns: u64,
    /// Worker threads that panicked (each reported as `worker_failed`).
    pub worker_failures: u64,
    /// The achieved cycle rate while running (0 when stopped).
    pub rate_hz: f64,
    pub active: Vec<String>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MonitorInfo {
    pub monitor: u64,
    /// The condition, or an `any` monitor's as one disjunction: `(a) || (b)`.
    pub condition: String,
    /// An `any` monitor's conditions, as given (`None` for one condition).
    pub any: Option<Vec<String>>,
    pub mode: MonitorMode,
    pub fired: u64,
    pub holds: bool,
    pub pause: bool,
    pub report: Vec<String>,
    /// The session that holds it (`None`: the program itself).
    pub session: Option<String>,
    /// The name its client gave, if any (a label, not an identity).
    pub client: Option<String>,
}

/// Why a monitor was removed before it fired for good.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CancelReason {
    /// Its own session cancelled it.
    Owner,
    /// Someone else did, with `force` (the GUI, after asking its user).
    Forced,
    /// Its session ended (the client closed it or went away).
    SessionEnded,
}

impl CancelReason {
    pub fn name(self) -> &'static str {
        match self {
            CancelReason::Owner => "owner",
            CancelReason::Forced => "forced",
            CancelReason::SessionEnded => "session_ended",
        }
    }
}

/// Anything that answers requests: the manager itself, or a handle to it.
/// The typed methods are conveniences over [`Control::request`].
pub trait Control {
    fn request(&mut self, request: Request) -> Result<Reply, ControlError>;

    /// Activates skills; returns those whose state changed.
    fn activate(&mut self, skills: &[&str]) -> Result<Vec<String>, ControlError> {
        self.activate_with(skills, false)
    }

    fn activate_with(&mut self, skills: &[&str], with_providers: bool) -> Result<Vec<String>, ControlError> {
        let skills = skills.iter().map(|s| s.to_string()).collect();
        match self.request(Request::Activate { skills, with_providers })? {
            Reply::Activation { changed, .. } => Ok(changed),
            other => Err(unexpected(other)),
        }
    }

    fn deactivate(&mut self, skills: &[&str]) -> Result<Vec<String>, ControlError> {
        let skills = skills.iter().map(|s| s.to_string()).collect();
        match self.request(Request::Deactivate { skills })? {
            Reply::Activation { changed, .. } => Ok(changed),
            other => Err(unexpected(other)),
        }
    }

    fn set_param(&mut self, skill: &str, param: &str, value: Value) -> Result<(), ControlError> {
        self.request(Request::SetParam { skill: skill.into(), param: param.into(), value }).map(|_| ())
    }

    fn get_param(&mut self, skill: &str, param: &str) -> Result<Value, ControlError> {
        match self.request(Request::GetParam { skill: skill.into(), param: param.into() })? {
            Reply::Param(v) => Ok(v),
            other => Err(unexpected(other)),
        }
    }

    fn query(&mut self, signal: &str) -> Result<SignalReading, ControlError> {
        match self.request(Request::QuerySignal { signal: signal.into() })? {
            Reply::Signal(r) => Ok(r),
            other => Err(unexpected(other)),
        }
    }

    fn skill(&mut self, skill: &str) -> Result<SkillInfo, ControlError> {
        match self.request(Request::QuerySkill { skill: skill.into() })? {
            Reply::Skill(s) => Ok(*s),
            other => Err(unexpected(other)),
        }
    }

    fn skills(&mut self) -> Result<Vec<SkillInfo>, ControlError> {
        match self.request(Request::QuerySkills)? {
            Reply::Skills(s) => Ok(s),
            other => Err(unexpected(other)),
        }
    }

    fn winners(&mut self) -> Result<Vec<ResourceWinner>, ControlError> {
        match self.request(Request::QueryWinners)? {
            Reply::Winners(w) => Ok(w),
            other => Err(unexpected(other)),
        }
    }

    fn stats(&mut self) -> Result<ManagerStats, ControlError> {
        match self.request(Request::QueryStats)? {
            Reply::Stats(s) => Ok(s),
            other => Err(unexpected(other)),
        }
    }

    fn add_monitor(&mut self, condition: &str, mode: MonitorMode) -> Result<u64, ControlError> {
        self.add_monitor_on(condition.into(), mode)
    }

    /// A monitor that holds when any of `conditions` holds; its events'
    /// `held` says which did.
    fn add_monitor_any(&mut self, conditions: &[&str], mode: MonitorMode) -> Result<u64, ControlError> {
        self.add_monitor_on(MonitorCondition::Any(conditions.iter().map(|c| c.to_string()).collect()), mode)
    }

    /// A monitor on `condition` (one, or any of several).
    fn add_monitor_on(&mut self, condition: MonitorCondition, mode: MonitorMode) -> Result<u64, ControlError> {
        match self.request(Request::AddMonitor {
            condition,
            mode,
            pause: false,
            report: Vec::new(),
            session: None,
            client: None,
        })? {
            Reply::MonitorAdded(id) => Ok(id),
            other => Err(unexpected(other)),
        }
    }

    fn cancel_monitor(&mut self, monitor: u64) -> Result<(), ControlError> {
        self.request(Request::CancelMonitor { monitor, session: None, force: false }).map(|_| ())
    }

    fn step(&mut self, cycles: u64) -> Result<(), ControlError> {
        self.request(Request::Step { cycles }).map(|_| ())
    }
}

fn unexpected(reply: Reply) -> ControlError {
    ControlError::Invalid(format!("unexpected reply {reply:?}"))
}
