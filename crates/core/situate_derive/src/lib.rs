//! `#[derive(Skill)]` and `#[derive(Record)]`: skills and records written in
//! Rust. Use them through the `situate` crate (`situate::Skill`,
//! `situate::Record`, or `use situate::prelude::*`); this crate is its
//! implementation detail.
//!
//! # Skills
//!
//! A skill is one piece of a robot's reactive layer. Its author gives three
//! things:
//!
//! - **inputs**: the signals it reads (a sonar scan, a bumper state);
//! - **outputs**: the signals it writes (a velocity command);
//! - a **body**: the computation from inputs to outputs, run once per
//!   activation.
//!
//! Everything else — which skill feeds which, when a body runs, the link to
//! the sequencer, the debugging display — the skill manager derives from that
//! declaration. In Rust a skill is a struct: fields marked `#[input]`,
//! `#[output]` and `#[param]` are its ports and parameters, every other field
//! is the skill's own state, and the body is an implementation of
//! [`Body`](../situate/trait.Body.html). `#[derive(Skill)]` writes the
//! declaration and the glue between the fields and the manager.
//!
//! ```
//! use situate::prelude::*;
//!
//! /// A velocity command.
//! #[derive(Record, Clone, Debug, Default, PartialEq)]
//! pub struct Drive {
//!     /// Forward speed, m/s.
//!     pub speed: f64,
//!     /// Turn rate, rad/s (positive: left).
//!     pub turn: f64,
//! }
//!
//! /// Keeps away from obstacles closer than `safe_distance`.
//! #[derive(Skill, Default)]
//! #[skill(name = "toy.runaway", kind = "sync", priority = 20, claims = ["python"])]
//! pub struct Runaway {
//!     /// Sonar ranges in metres, evenly spread around the robot.
//!     #[input(signal = "sonar.range")]
//!     sonar_range: Arc<[f32]>,
//!     /// Whether the bumper is pressed (when a bumper skill runs).
//!     #[input]
//!     bump: Option<bool>,
//!     /// The velocity command, written every run.
//!     #[output]
//!     drive: Drive,
//!     /// Bearing of the obstacle fled from, in radians, when there is one.
//!     #[output(signal = "heading")]
//!     heading_out: Option<f64>,
//!     /// Distance under which the robot turns away.
//!     #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
//!     safe_distance: f64,
//!     /// Runs so far: the skill's own state, ignored by the derive.
//!     count: u32,
//! }
//!
//! impl Body for Runaway {
//!     fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
//!         self.count += 1;
//!         let n = self.sonar_range.len();
//!         let nearest = self.sonar_range.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1));
//!         self.drive = Drive { speed: 0.3, turn: 0.0 };
//!         if let Some((i, &range)) = nearest {
//!             if f64::from(range) < self.safe_distance || self.bump == Some(true) {
//!                 let bearing = i as f64 * std::f64::consts::TAU / n as f64;
//!                 self.drive = Drive { speed: 0.0, turn: 1.0 };
//!                 self.heading_out = Some(bearing);
//!                 sprint!(cx, "run {}: obstacle at {range} m, turning", self.count);
//!             }
//!         }
//!         Ok(())
//!     }
//! }
//!
//! // What the manager sees:
//! let decl = Runaway::declaration();
//! assert_eq!(decl.type_name, "toy.runaway");
//! assert_eq!(decl.doc, "Keeps away from obstacles closer than `safe_distance`.");
//! assert_eq!(decl.inputs[0].signal, "sonar.range");
//! assert!(decl.inputs[1].optional);
//! assert_eq!(decl.params[0].default, Value::F64(0.5));
//!
//! // One run, driven by hand the way the manager does it.
//! let mut skill = Runaway::create(&situate::Resources::new())?;
//! let inputs = [Some(Value::F32s(vec![2.0, 0.3, 1.0, 2.5].into())), None];
//! let mut outputs = [None, None];
//! let mut cx = Context::new(0, 0.0);
//! skill.step(&mut situate::Io { inputs: &inputs, outputs: &mut outputs, cx: &mut cx })?;
//! assert_eq!(outputs[0], Some(Drive { speed: 0.0, turn: 1.0 }.into_value()));
//! assert_eq!(outputs[1], Some(Value::F64(std::f64::consts::FRAC_PI_2)));
//! assert_eq!(cx.take_prints(), ["run 1: obstacle at 0.3 m, turning"]);
//! # Ok::<(), SkillError>(())
//! ```
//!
//! ## How the parts behave
//!
//! - **Required inputs** (`#[input] x: T`, any `T: SignalValue`) hold the
//!   skill back: a sync skill runs when a complete new set of them has been
//!   produced. Before each run the field is overwritten with the latest value;
//!   if one is missing the run fails with "input `x`: missing or not a …".
//! - **Optional inputs** (`#[input] x: Option<T>`) don't hold the skill back:
//!   the body sees `None` when nobody produced the signal this cycle.
//! - **Outputs** (`#[output] x: T`) are written after every run from the
//!   field (`SignalValue::write_output`: a clone, so `T: Clone`; `Arc`-backed
//!   values clone a pointer; a fixed-size array is copied straight into the
//!   buffer its last value left, when nobody else holds that). They are
//!   written only after the body returned `Ok`: a run that fails writes
//!   none. Where a step runs the short way, a required output is written
//!   straight into its slot's value (`Skill::writes_output`; decision 0018).
//!   An output of a built-in type is of its port's type by construction, so
//!   the manager does not check it (`Skill::output_typed`).
//!   An `Option<T>` output is written only in the runs where the body set it
//!   to `Some`, and is taken (left `None`) after each run, so a value is
//!   produced once.
//! - **Params** (`#[param] x: T`, `T` one of `f64`, `i64`, `bool`, `String`)
//!   are typed settings with a default, an optional range and unit, and the
//!   field's doc comment. The robot file or the sequencer set them; the
//!   manager checks type and range before the field changes.
//! - **Kind**: `"sync"` (default) runs in the cycle when its inputs are
//!   complete; `"async"` runs continuously on its own thread on the latest
//!   inputs, and the cycle takes its latest result without waiting; `"device"`
//!   wraps a device, doing the device I/O on its own thread (inputs are
//!   buffered commands, outputs the latest readings).
//! - **Priority** settles contention over a resource: higher wins.
//! - **Claims** name things a skill uses exclusively (a non-reentrant library,
//!   an interpreter lock): skills sharing a claim never run at the same time.
//! - The doc comments of the struct and of each port and param become the
//!   declaration's documentation, shown by the tools.
//!
//! # Records
//!
//! A record is a signal with named fields, written as a struct with
//! `#[derive(Record)]` whose fields are themselves signal values (numbers,
//! strings, arrays such as `[f32; 24]` or `Arc<[f32]>`, other records). See
//! [`Record`].

mod record;
mod skill;
mod util;

use proc_macro::TokenStream;
use syn::{parse_macro_input, DeriveInput};

/// Makes a struct a skill: implements `Declare` (its declaration and
/// constructor) and `Skill` (the glue the manager runs) for it. The struct
/// must also implement `Body` (write it), and `Default` (derive it) unless it
/// has `#[resource]` fields.
///
/// See the [crate docs](../situate_derive/index.html) for what a skill is and a full example.
///
/// # Attributes
///
/// Every key is optional.
///
/// On the struct, `#[skill(...)]`:
///
/// | key        | value                                  | default                                 |
/// |------------|----------------------------------------|-----------------------------------------|
/// | `name`     | string: the type name robot files use  | the struct name in snake_case (`RunAway` → `run_away`) |
/// | `kind`     | `"sync"`, `"async"` or `"device"`      | `"sync"`                                |
/// | `priority` | integer (`i32`), higher wins           | `0`                                     |
/// | `claims`   | list of strings: `["python"]`          | none                                    |
///
/// On a field, one of:
///
/// - `#[input]` / `#[input(signal = "sonar.range")]`: an input port named
///   after the field, reading the given signal (default: the field name).
///   `Option<T>` makes it optional.
/// - `#[output]` / `#[output(signal = "heading")]`: an output port. A plain
///   `T` (which must be `Clone`) is written every run; an `Option<T>` when it
///   is `Some`, and taken after the run.
/// - `#[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]`: a
///   parameter of type `f64`, `i64`, `bool` or `String`. `default` is a
///   literal of the field's type (an integer literal is fine for an `f64`) or
///   a constant expression; without it the type's default (`0`, `0.0`,
///   `false`, `""`). `min` and `max` are number literals and apply to numeric
///   params; a literal default must lie within them.
///
/// - `#[resource]` / `#[resource(name = "can0")]`: what the program provides
///   to the skills it builds (`Registry::provide(name, value)`: a driver's
///   handle, the simulator's world), named after the field by default. The
///   field gets a clone of it when the instance is made; it must be of the
///   field's type. A missing one, or one of another type, is an error of
///   `create` (the robot is not built), naming the skill, the resource and
///   both types.
///
/// Fields with none of these are the skill's state. `create(resources)`
/// starts from the struct's `Default` (with resource fields: field by field,
/// each resource from `resources` and every other field its type's
/// `Default`) and then sets every param to its declared default, so a new
/// instance always matches its declaration.
///
/// # Errors
///
/// Mistakes are compile errors pointing at the offending tokens.
///
/// An unknown key (the message names the allowed ones):
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// struct Wander {
///     #[input(singal = "sonar.range")] // unknown key `singal` (did you mean `signal`?)
///     sonar: Arc<[f32]>,
/// }
/// impl Body for Wander {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// A kind other than sync, async or device:
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// #[skill(kind = "threaded")] // unknown kind `threaded`
/// struct Wander {
///     #[input] sonar: Arc<[f32]>,
/// }
/// impl Body for Wander {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// A field that is both an input and an output:
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// struct Echo {
///     #[input]
///     #[output] // field `x` is already #[input]
///     x: f64,
/// }
/// impl Body for Echo {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// A resource with an unknown key (its only key is `name`):
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill)]
/// struct Bumper {
///     #[output]
///     pressed: bool,
///     #[resource(nme = "can0")] // unknown key `nme` (did you mean `name`?)
///     bus: Arc<u8>,
/// }
/// impl Body for Bumper {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// A float default for an integer param:
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// struct Count {
///     #[param(default = 2.5)] // param `n` is an i64: its default must be an integer literal
///     n: i64,
/// }
/// impl Body for Count {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// A default outside the declared range:
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// struct Slow {
///     #[param(default = 5.0, min = 0.0, max = 1.0)] // default 5.0 is outside its range
///     speed: f64,
/// }
/// impl Body for Slow {
///     fn step(&mut self, _: &mut Context) -> Result<(), SkillError> { Ok(()) }
/// }
/// ```
///
/// Not a struct with named fields:
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Skill, Default)]
/// struct Tuple(f64);
/// ```
#[proc_macro_derive(Skill, attributes(skill, input, output, param, resource))]
pub fn derive_skill(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    skill::expand(&input).unwrap_or_else(syn::Error::into_compile_error).into()
}

/// Makes a struct with named fields a record signal value: implements
/// `SignalValue` for it. Every field must be a `SignalValue` itself (`bool`,
/// `i64`, `f64`, `String`, `Arc<str>`, `Arc<[f32]>`, `[f32; N]`, …, or
/// another record).
///
/// The record's type lists the fields by name in declaration order
/// (`{x: f64, y: f64, ranges: f32[24]}`). Reading a value finds each field by
/// name and gives `None` when one is missing or of the wrong type.
///
/// ```
/// use situate::prelude::*;
///
/// #[derive(Record, Clone, Debug, PartialEq)]
/// struct Pose {
///     x: f64,
///     y: f64,
///     theta: f64,
/// }
///
/// #[derive(Record, Clone, Debug, PartialEq)]
/// struct Scan {
///     pose: Pose,
///     ranges: [f32; 4],
/// }
///
/// assert_eq!(Scan::signal_type().to_string(), "{pose: {x: f64, y: f64, theta: f64}, ranges: f32[4]}");
/// let scan = Scan { pose: Pose { x: 1.0, y: 2.0, theta: 0.5 }, ranges: [1.0, 2.0, 3.0, 4.0] };
/// let value = scan.clone().into_value();
/// assert!(value.conforms(&Scan::signal_type()));
/// assert_eq!(Scan::from_value(&value), Some(scan));
/// assert_eq!(Scan::from_value(&Value::F64(1.0)), None);
/// ```
///
/// ```compile_fail
/// use situate::prelude::*;
/// #[derive(Record)]
/// struct Pair(f64, f64); // needs named fields
/// ```
#[proc_macro_derive(Record)]
pub fn derive_record(input: TokenStream) -> TokenStream {
    let input = parse_macro_input!(input as DeriveInput);
    record::expand(&input).unwrap_or_else(syn::Error::into_compile_error).into()
}
