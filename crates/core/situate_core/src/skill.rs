//! The skill traits.
//!
//! [`Skill`] is what the skill manager runs: an object-safe body that reads
//! its inputs from and writes its outputs to plain slices. Skill authors in
//! Rust never implement it by hand: they write a struct whose fields are the
//! ports and parameters, put `#[derive(Skill)]` on it and implement [`Body`]
//! (the computational body). The derive generates the declaration
//! ([`Declare`]) and the glue between fields and slices.

use std::fmt;
use std::sync::Arc;

use crate::decl::SkillDecl;
use crate::resources::Resources;
use crate::types::SignalType;
use crate::value::Value;

/// What a body sees of the world besides its ports.
#[derive(Debug, Default)]
pub struct Context {
    pub(crate) cycle: u64,
    pub(crate) time_s: f64,
    pub(crate) prints: Vec<String>,
}

impl Context {
    pub fn new(cycle: u64, time_s: f64) -> Self {
        Context { cycle, time_s, prints: Vec::new() }
    }

    /// The cycle this body runs in (for threaded bodies: the cycle that
    /// handed over the latest inputs).
    pub fn cycle(&self) -> u64 {
        self.cycle
    }

    /// Seconds since the manager started, on its clock (simulated or wall).
    pub fn time_s(&self) -> f64 {
        self.time_s
    }

    /// The skill's own print: shown live by the debugging display when the
    /// skill is verbose, and kept in a short per-skill history.
    pub fn print(&mut self, line: impl Into<String>) {
        self.prints.push(line.into());
    }

    /// The cycle and time of the run about to start (the manager's; not for
    /// skill authors).
    #[doc(hidden)]
    pub fn set(&mut self, cycle: u64, time_s: f64) {
        self.cycle = cycle;
        self.time_s = time_s;
    }

    /// Takes the prints made since the last call (the manager's; not for
    /// skill authors).
    #[doc(hidden)]
    pub fn take_prints(&mut self) -> Vec<String> {
        std::mem::take(&mut self.prints)
    }

    /// Whether a print was made since the prints were last taken (the
    /// manager's; not for skill authors).
    #[doc(hidden)]
    pub fn has_prints(&self) -> bool {
        !self.prints.is_empty()
    }
}

/// `sprint!(cx, "x = {}", x)`: a skill's own print (see [`Context::print`]).
#[macro_export]
macro_rules! sprint {
    ($cx:expr, $($arg:tt)*) => { $cx.print(::std::format!($($arg)*)) };
}

/// A body's failure. The skill is marked faulted and deactivated; the cycle
/// goes on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SkillError {
    pub message: String,
}

impl SkillError {
    pub fn new(message: impl Into<String>) -> Self {
        SkillError { message: message.into() }
    }
}

impl fmt::Display for SkillError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for SkillError {}

impl From<String> for SkillError {
    fn from(message: String) -> Self {
        SkillError { message }
    }
}

impl From<&str> for SkillError {
    fn from(message: &str) -> Self {
        SkillError { message: message.into() }
    }
}

/// The ports of one run of a body, as the manager hands them over.
///
/// `inputs[i]` belongs to the declaration's input `i`; it is `Some` for every
/// required input and `None` for an optional input nobody produced.
/// The body sets `outputs[j]` to `Some` for each output it produces (the
/// manager clears them before each run, unless the skill
/// [fills its outputs](Skill::fills_outputs): then an output may hold a
/// spare value on entry, which the body replaces).
pub struct Io<'a> {
    pub inputs: &'a [Option<Value>],
    pub outputs: &'a mut [Option<Value>],
    pub cx: &'a mut Context,
}

/// A runnable skill instance (object-safe). Implemented by `#[derive(Skill)]`.
pub trait Skill: Send + 'static {
    /// Runs the body once.
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError>;

    /// Applies parameter `index` of the declaration. The manager has already
    /// checked `value` against the parameter's type and range.
    fn set_param(&mut self, index: usize, value: &Value);

    /// The skill was switched on (at start, if it starts active, or by the
    /// sequencer): called once, before its first run after that, on the
    /// thread that runs its body. See [`Body::activate`].
    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let _ = cx;
        Ok(())
    }

    /// The skill was switched off (by the sequencer, or by a fault): called
    /// once, after its last run, on the thread that runs its body. See
    /// [`Body::deactivate`].
    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let _ = cx;
        Ok(())
    }

    /// Whether [`Skill::step`] sets every output (to `Some` or `None`)
    /// whenever it returns `Ok`, taking what an output held on entry as a
    /// spare buffer ([`SignalValue::into_output`](crate::SignalValue::into_output)).
    /// Then the manager may leave in an output, instead of `None`, the value
    /// its previous one replaced in its slot, and a fixed-size array is
    /// written into that buffer. `#[derive(Skill)]` says yes; by default
    /// outputs are `None` on entry.
    ///
    /// A performance hook between the derive and the manager, hidden from
    /// the author's API (a skill written by hand keeps the default).
    #[doc(hidden)]
    fn fills_outputs(&self) -> bool {
        false
    }

    /// Whether every run of [`Skill::step`] that returns `Ok` sets output
    /// `port` to `Some`, and whether a run splits in two:
    /// [`Skill::run_unwritten`], which reads the inputs and runs the body
    /// but writes no output, then [`Skill::write_outputs`], which writes
    /// them all. With [`Skill::fills_outputs`] and every output so, the
    /// manager may write a run's outputs straight into their slots (no
    /// spare, no move), once the body has returned clean. By default no.
    /// `#[derive(Skill)]` says yes for an output field that is not an
    /// `Option`.
    ///
    /// A performance hook between the derive and the manager, hidden from
    /// the author's API (a skill written by hand keeps the default).
    #[doc(hidden)]
    fn writes_output(&self, port: usize) -> bool {
        let _ = port;
        false
    }

    /// [`Skill::step`] without writing any output (see
    /// [`Skill::writes_output`]): they are written by
    /// [`Skill::write_outputs`] after it returned `Ok`. By default the whole
    /// [`Skill::step`] (for a skill that does not split its run).
    #[doc(hidden)]
    fn run_unwritten(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        self.step(io)
    }

    /// Writes the outputs of the last run of [`Skill::run_unwritten`] (see
    /// [`Skill::writes_output`]) into `outputs`, filling the buffers they
    /// hold. By default nothing.
    #[doc(hidden)]
    fn write_outputs(&mut self, outputs: &mut [Option<Value>]) {
        let _ = outputs;
    }

    /// Whether every value [`Skill::step`] puts in output `port` is, by
    /// construction, a value of type `ty` (the port's type in the robot
    /// being built). The manager then does not check that output's values
    /// (it reads this once per instance when it makes the body, never per
    /// run). Say yes only where it holds for every run: a wrongly typed
    /// value would then reach the output's signal unchecked. By default
    /// no, and every output is checked: a wrongly typed value faults the
    /// skill. `#[derive(Skill)]` says yes for an output field of a built-in
    /// signal type ([`SignalValue::ALWAYS_CONFORMS`](crate::SignalValue::ALWAYS_CONFORMS))
    /// whose type feeds `ty` ([`SignalType::feeds`]).
    ///
    /// A performance hook between the derive and the manager, hidden from
    /// the author's API, as [`Skill::fills_outputs`] is.
    #[doc(hidden)]
    fn output_typed(&self, port: usize, ty: &SignalType) -> bool {
        let _ = (port, ty);
        false
    }
}

/// The computational body of a Rust skill.
pub trait Body {
    /// One run: read the input fields, write the output fields.
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError>;

    /// The skill was switched on: called once before its first run after
    /// that, on the thread that runs its body, at the start of the cycle the
    /// activation takes effect in (a threaded body: on its thread, before its
    /// next run). The place to reset what a run of the skill remembers (a
    /// turn measured from the heading at activation). Skills that start
    /// active are activated before their first run. A skill switched off
    /// and on again between two cycles is deactivated, then activated. An
    /// error faults the skill. By default nothing.
    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let _ = cx;
        Ok(())
    }

    /// The skill was switched off (by the sequencer, or because it
    /// faulted): called once, after its last run, at the start of the next
    /// cycle (a threaded body: on its thread, when it next waits). Not
    /// called for a body left behind (it never returned), nor at shutdown
    /// (the body is dropped: `Drop`). The skill is off whatever this
    /// returns: an error is said in a warning and in the skill's prints. By
    /// default nothing.
    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        let _ = cx;
        Ok(())
    }
}

/// A skill type that can declare itself and make instances.
pub trait Declare {
    fn declaration() -> SkillDecl;
    /// A new instance, its parameters at their declared defaults and its
    /// resources (`#[resource]` fields) taken from `resources`: an error
    /// when one is missing or of another type.
    fn create(resources: &Resources) -> Result<Box<dyn Skill>, SkillError>;
}

/// A constructor for instances of one skill type, given the host's resources.
pub type SkillMaker = Arc<dyn Fn(&Resources) -> Result<Box<dyn Skill>, String> + Send + Sync>;

/// A skill type as the registry keeps it: its declaration and a constructor.
#[derive(Clone)]
pub struct SkillType {
    pub decl: Arc<SkillDecl>,
    pub make: SkillMaker,
}

impl SkillType {
    /// The skill type of a Rust type with `#[derive(Skill)]`.
    pub fn of<T: Declare>() -> Self {
        SkillType {
            decl: Arc::new(T::declaration()),
            make: Arc::new(|resources| T::create(resources).map_err(|e| e.to_string())),
        }
    }

    /// A skill type from a declaration and any constructor that needs no
    /// resource (used by foreign language bindings and tests).
    pub fn new(decl: SkillDecl, make: impl Fn() -> Result<Box<dyn Skill>, String> + Send + Sync + 'static) -> Self {
        SkillType { decl: Arc::new(decl), make: Arc::new(move |_| make()) }
    }

    /// A skill type from a declaration and a constructor given the host's
    /// [`Resources`] (foreign language bindings whose skills ask for some).
    pub fn with_resources(
        decl: SkillDecl,
        make: impl Fn(&Resources) -> Result<Box<dyn Skill>, String> + Send + Sync + 'static,
    ) -> Self {
        SkillType { decl: Arc::new(decl), make: Arc::new(make) }
    }
}

impl fmt::Debug for SkillType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SkillType").field("decl", &self.decl).finish_non_exhaustive()
    }
}

/// A skill written as a closure over the raw [`Io`]: handy for tests and for
/// bindings that bring their own declaration.
pub struct FnSkill<F> {
    body: F,
    params: Vec<Value>,
}

impl<F> FnSkill<F>
where
    F: FnMut(&mut Io<'_>, &[Value]) -> Result<(), SkillError> + Send + 'static,
{
    pub fn new(decl: &SkillDecl, body: F) -> Self {
        FnSkill { body, params: decl.params.iter().map(|p| p.default.clone()).collect() }
    }
}

impl<F> Skill for FnSkill<F>
where
    F: FnMut(&mut Io<'_>, &[Value]) -> Result<(), SkillError> + Send + 'static,
{
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        (self.body)(io, &self.params)
    }

    fn set_param(&mut self, index: usize, value: &Value) {
        if let Some(slot) = self.params.get_mut(index) {
            *slot = value.clone();
        }
    }
}
