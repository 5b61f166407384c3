//! `#[derive(Skill)]`: the declaration it generates and the glue between the
//! struct's fields and the manager's slices.

use situate::prelude::*;
use situate::{Io, ParamType, SignalType};

/// A velocity command.
#[derive(Record, Clone, Debug, Default, PartialEq)]
pub struct Drive {
    pub speed: f64,
    pub turn: f64,
}

/// Keeps away from obstacles closer than `safe_distance`.
///
/// Turns in place while one is near.
#[derive(Skill, Default)]
#[skill(name = "toy.runaway", kind = "sync", priority = 20, claims = ["python", "sonar"])]
pub struct Runaway {
    /// Sonar ranges in metres.
    #[input(signal = "sonar.range")]
    sonar_range: Arc<[f32]>,
    /// Bumper pressed.
    #[input]
    bump: Option<bool>,
    /// The velocity command.
    #[output]
    drive: Drive,
    #[output(signal = "heading")]
    heading_out: Option<f64>,
    /// Distance under which the robot turns away.
    #[param(default = 0.5, min = 0.1, max = 3.0, unit = "m")]
    safe_distance: f64,
    /// Turn gain; an integer literal on an f64 field.
    #[param(default = 1, min = -2.5, max = 10)]
    gain: f64,
    #[param(default = -3, min = -10)]
    offset: i64,
    #[param(default = true)]
    verbose: bool,
    #[param(default = "left")]
    side: String,
    #[param]
    limit: i64,
    count: u32,
}

impl Body for Runaway {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.count += 1;
        let near = self.sonar_range.iter().any(|r| f64::from(*r) < self.safe_distance);
        self.drive = if near { Drive { speed: 0.0, turn: self.gain } } else { Drive { speed: 0.3, turn: 0.0 } };
        if near {
            self.heading_out = Some(1.5);
        }
        if self.verbose {
            sprint!(cx, "run {} bump {:?} side {}", self.count, self.bump, self.side);
        }
        Ok(())
    }
}

/// A probe of the glue: echoes what it sees through its outputs.
#[derive(Skill)]
struct Probe {
    #[input]
    level: f64,
    #[input]
    flag: Option<bool>,
    /// `level * gain`, every run.
    #[output]
    echo: f64,
    #[output]
    event: Option<String>,
    #[output]
    settings: String,
    #[param(default = 2)]
    gain: f64,
    #[param(default = 3)]
    times: i64,
    #[param(default = false)]
    loud: bool,
    #[param(default = "hi")]
    label: String,
}

/// Not what the declaration says: `create()` must override the params.
impl Default for Probe {
    fn default() -> Self {
        Probe {
            level: 0.0,
            flag: None,
            echo: 0.0,
            event: None,
            settings: String::new(),
            gain: 9.0,
            times: 9,
            loud: true,
            label: "default impl".into(),
        }
    }
}

impl Body for Probe {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        if self.level < 0.0 {
            return Err(SkillError::new("negative level"));
        }
        sprint!(cx, "flag {:?}, event before {:?}", self.flag, self.event);
        self.echo = self.level * self.gain;
        if self.flag == Some(true) {
            self.event = Some(format!("{} x{}", self.label, self.times));
        }
        self.settings = format!("{} {} {} {}", self.gain, self.times, self.loud, self.label);
        Ok(())
    }
}

#[derive(Skill, Default)]
struct RunAway {
    #[input]
    x: f64,
}

impl Body for RunAway {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        Ok(())
    }
}

/// Runs on its own thread.
#[derive(Skill, Default)]
#[skill(kind = "async", priority = -5)]
struct Planner {}

impl Body for Planner {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        Ok(())
    }
}

#[derive(Skill, Default)]
#[skill(kind = "device")]
struct Sonar {
    #[output]
    range: Arc<[f32]>,
}

impl Body for Sonar {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.range = vec![1.0, 2.0].into();
        Ok(())
    }
}

/// Generic skills work when the bounds are given.
#[derive(Skill, Default)]
struct Hold<T: SignalValue + Clone + Default + Send + 'static> {
    #[input]
    x: T,
    #[output]
    y: T,
}

impl<T: SignalValue + Clone + Default + Send + 'static> Body for Hold<T> {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = self.x.clone();
        Ok(())
    }
}

type Meters = f64;
type Count = i64;
const LIMIT: i64 = 12;

/// Params whose types are aliases, and constant defaults.
#[derive(Skill, Default)]
struct Aliased {
    #[param(default = 1, unit = "m")]
    reach: Meters,
    #[param(default = -5_000_000_000)]
    big: Count,
    #[param(default = 2.5)]
    half: Meters,
    #[param(default = LIMIT)]
    limit: i64,
    #[param(default = std::f64::consts::PI)]
    angle: f64,
}

impl Body for Aliased {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        Ok(())
    }
}

fn run(
    skill: &mut dyn situate::Skill,
    inputs: &[Option<Value>],
    n_outputs: usize,
) -> (Result<(), SkillError>, Vec<Option<Value>>, Vec<String>) {
    let mut outputs = vec![None; n_outputs];
    let mut cx = Context::new(0, 0.0);
    let r = skill.step(&mut Io { inputs, outputs: &mut outputs, cx: &mut cx });
    (r, outputs, cx.take_prints())
}

fn s(text: &str) -> Value {
    Value::Str(text.into())
}

#[test]
fn the_declaration_lists_name_kind_priority_claims_and_doc() {
    let d = Runaway::declaration();
    assert_eq!(d.type_name, "toy.runaway");
    assert_eq!(d.kind, SkillKind::Sync);
    assert_eq!(d.priority, 20);
    assert_eq!(d.claims, ["python", "sonar"]);
    assert_eq!(d.doc, "Keeps away from obstacles closer than `safe_distance`.\n\nTurns in place while one is near.");
}

#[test]
fn ports_are_declared_in_field_order_with_signals_types_and_docs() {
    let d = Runaway::declaration();
    let inputs: Vec<_> = d.inputs.iter().map(|p| (&*p.name, &*p.signal, p.optional, &*p.doc)).collect();
    assert_eq!(
        inputs,
        [("sonar_range", "sonar.range", false, "Sonar ranges in metres."), ("bump", "bump", true, "Bumper pressed.")]
    );
    assert_eq!(d.inputs[0].ty, SignalType::parse("f32[]").unwrap());
    assert_eq!(d.inputs[1].ty, SignalType::Bool);

    let outputs: Vec<_> = d.outputs.iter().map(|p| (&*p.name, &*p.signal, p.optional, &*p.doc)).collect();
    assert_eq!(outputs, [("drive", "drive", false, "The velocity command."), ("heading_out", "heading", false, "")]);
    assert_eq!(d.outputs[0].ty, SignalType::parse("{speed: f64, turn: f64}").unwrap());
    assert_eq!(d.outputs[1].ty, SignalType::F64);
}

#[test]
fn params_carry_types_defaults_ranges_units_and_docs() {
    let d = Runaway::declaration();
    let names: Vec<_> = d.params.iter().map(|p| &*p.name).collect();
    assert_eq!(names, ["safe_distance", "gain", "offset", "verbose", "side", "limit"]);

    let p = &d.params[0];
    assert_eq!((p.ty, &p.default, p.min, p.max), (ParamType::F64, &Value::F64(0.5), Some(0.1), Some(3.0)));
    assert_eq!((&*p.unit, &*p.doc), ("m", "Distance under which the robot turns away."));

    let p = &d.params[1];
    assert_eq!((p.ty, &p.default, p.min, p.max), (ParamType::F64, &Value::F64(1.0), Some(-2.5), Some(10.0)));
    assert_eq!((&*p.unit, &*p.doc), ("", "Turn gain; an integer literal on an f64 field."));

    let p = &d.params[2];
    assert_eq!((p.ty, &p.default, p.min, p.max), (ParamType::I64, &Value::I64(-3), Some(-10.0), None));

    let p = &d.params[3];
    assert_eq!((p.ty, &p.default, p.min, p.max), (ParamType::Bool, &Value::Bool(true), None, None));

    let p = &d.params[4];
    assert_eq!((p.ty, &p.default), (ParamType::Str, &s("left")));

    let p = &d.params[5];
    assert_eq!((p.ty, &p.default), (ParamType::I64, &Value::I64(0)));

    // Every declared default passes its own check.
    for p in &d.params {
        assert_eq!(p.check(&p.default).as_ref(), Ok(&p.default), "{}", p.name);
    }
}

#[test]
fn aliased_param_types_and_constant_defaults_are_declared() {
    let d = Aliased::declaration();
    let defaults: Vec<_> = d.params.iter().map(|p| (&*p.name, p.ty, p.default.clone())).collect();
    assert_eq!(
        defaults,
        [
            ("reach", ParamType::F64, Value::F64(1.0)),
            ("big", ParamType::I64, Value::I64(-5_000_000_000)),
            ("half", ParamType::F64, Value::F64(2.5)),
            ("limit", ParamType::I64, Value::I64(12)),
            ("angle", ParamType::F64, Value::F64(std::f64::consts::PI)),
        ]
    );
    assert_eq!(d.params[0].unit, "m");
}

#[test]
fn without_attributes_the_name_is_the_struct_name_in_snake_case() {
    let d = RunAway::declaration();
    assert_eq!(d.type_name, "run_away");
    assert_eq!(d.kind, SkillKind::Sync);
    assert_eq!(d.priority, 0);
    assert!(d.claims.is_empty());
    assert_eq!(d.doc, "");
    assert_eq!(d.inputs[0].signal, "x");
    assert!(d.outputs.is_empty() && d.params.is_empty());
}

#[test]
fn kinds_async_and_device_are_declared() {
    let d = Planner::declaration();
    assert_eq!((d.type_name.as_str(), d.kind, d.priority), ("planner", SkillKind::Async, -5));
    assert_eq!(d.doc, "Runs on its own thread.");
    assert_eq!(Sonar::declaration().kind, SkillKind::Device);
}

#[test]
fn create_applies_the_declared_defaults_over_the_struct_default() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let (r, out, _) = run(&mut *probe, &[Some(Value::F64(1.5)), None], 3);
    assert_eq!(r, Ok(()));
    assert_eq!(out[0], Some(Value::F64(3.0)));
    assert_eq!(out[2], Some(s("2 3 false hi")));
}

#[test]
fn plain_outputs_are_written_every_run_and_option_outputs_once() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();

    let (r, out, prints) = run(&mut *probe, &[Some(Value::F64(1.0)), Some(Value::Bool(true))], 3);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(Value::F64(2.0)), Some(s("hi x3")), Some(s("2 3 false hi"))]);
    assert_eq!(prints, ["flag Some(true), event before None"]);

    // The event was taken by the glue: not seen by the body, not re-emitted.
    let (r, out, prints) = run(&mut *probe, &[Some(Value::F64(4.0)), None], 3);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(Value::F64(8.0)), None, Some(s("2 3 false hi"))]);
    assert_eq!(prints, ["flag None, event before None"]);

    let (_, out, prints) = run(&mut *probe, &[Some(Value::F64(4.0)), Some(Value::Bool(false))], 3);
    assert_eq!(out[1], None);
    assert_eq!(prints, ["flag Some(false), event before None"]);
}

#[test]
fn the_runaway_turns_and_prints() {
    let mut skill = Runaway::create(&situate::Resources::new()).unwrap();
    let (r, out, prints) = run(&mut *skill, &[Some(Value::F32s(vec![2.0, 0.2].into())), Some(Value::Bool(true))], 2);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(Drive { speed: 0.0, turn: 1.0 }.into_value()), Some(Value::F64(1.5))]);
    assert_eq!(prints, ["run 1 bump Some(true) side left"]);

    let (_, out, prints) = run(&mut *skill, &[Some(Value::F32s(vec![2.0].into())), None], 2);
    assert_eq!(out, [Some(Drive { speed: 0.3, turn: 0.0 }.into_value()), None]);
    assert_eq!(prints, ["run 2 bump None side left"]);
}

#[test]
fn a_missing_or_mistyped_required_input_is_an_error_naming_it() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let (r, out, prints) = run(&mut *probe, &[None, None], 3);
    let e = r.unwrap_err();
    assert!(e.message.contains("input `level`"), "{e}");
    assert_eq!(e.message, "input `level`: missing or not a f64");
    assert_eq!(out, [None, None, None]);
    assert!(prints.is_empty());

    let (r, _, _) = run(&mut *probe, &[Some(s("high")), None], 3);
    assert!(r.unwrap_err().message.contains("input `level`"));

    // A short input slice is a missing input, not a panic.
    let (r, _, _) = run(&mut *probe, &[], 3);
    assert!(r.unwrap_err().message.contains("input `level`"));
}

#[test]
fn a_mistyped_optional_input_is_an_error_too() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let (r, _, _) = run(&mut *probe, &[Some(Value::F64(1.0)), Some(Value::I64(1))], 3);
    assert_eq!(r.unwrap_err().message, "input `flag`: not a bool");
}

#[test]
fn short_output_slices_are_tolerated() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let (r, out, _) = run(&mut *probe, &[Some(Value::F64(1.0)), Some(Value::Bool(true))], 1);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(Value::F64(2.0))]);
    // The event had no slot but was still taken: the next run doesn't emit it.
    let (_, out, _) = run(&mut *probe, &[Some(Value::F64(1.0)), None], 3);
    assert_eq!(out[1], None);
}

#[test]
fn a_body_error_is_returned_and_no_output_written() {
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let (r, out, _) = run(&mut *probe, &[Some(Value::F64(-1.0)), Some(Value::Bool(true))], 3);
    assert_eq!(r, Err(SkillError::new("negative level")));
    assert_eq!(out, [None, None, None]);
}

#[test]
fn set_param_changes_the_field_and_ignores_wrong_types() {
    let d = Probe::declaration();
    let mut probe = Probe::create(&situate::Resources::new()).unwrap();
    let idx = |name: &str| d.param(name).map(|(i, _)| i).unwrap();

    probe.set_param(idx("gain"), &Value::F64(4.0));
    probe.set_param(idx("times"), &Value::I64(7));
    probe.set_param(idx("loud"), &Value::Bool(true));
    probe.set_param(idx("label"), &s("yo"));
    let (_, out, _) = run(&mut *probe, &[Some(Value::F64(1.0)), Some(Value::Bool(true))], 3);
    assert_eq!(out, [Some(Value::F64(4.0)), Some(s("yo x7")), Some(s("4 7 true yo"))]);

    // An integer for an f64 param is a number.
    probe.set_param(idx("gain"), &Value::I64(5));
    // Wrong types and unknown indices change nothing and don't panic.
    probe.set_param(idx("gain"), &s("fast"));
    probe.set_param(idx("times"), &Value::F64(1.5));
    probe.set_param(idx("loud"), &Value::I64(0));
    probe.set_param(idx("label"), &Value::Bool(false));
    probe.set_param(99, &Value::F64(1.0));
    let (_, out, _) = run(&mut *probe, &[Some(Value::F64(1.0)), None], 3);
    assert_eq!(out, [Some(Value::F64(5.0)), None, Some(s("5 7 true yo"))]);
}

#[test]
fn skill_types_built_from_derived_skills_make_working_instances() {
    let t = situate::SkillType::of::<Sonar>();
    assert_eq!(t.decl.type_name, "sonar");
    let mut sonar = (t.make)(&situate::Resources::new()).unwrap();
    let (r, out, _) = run(&mut *sonar, &[], 1);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(Value::F32s(vec![1.0, 2.0].into()))]);
}

#[test]
fn generic_skills_declare_the_type_they_are_instantiated_with() {
    let d = Hold::<i64>::declaration();
    assert_eq!(d.type_name, "hold");
    assert_eq!((d.inputs[0].ty.clone(), d.outputs[0].ty.clone()), (SignalType::I64, SignalType::I64));
    let mut hold = Hold::<Drive>::create(&situate::Resources::new()).unwrap();
    let v = Drive { speed: 1.0, turn: 2.0 }.into_value();
    let (r, out, _) = run(&mut *hold, &[Some(v.clone())], 1);
    assert_eq!(r, Ok(()));
    assert_eq!(out, [Some(v)]);
}

/// The generated code names everything by full path, so odd names in scope
/// don't break it.
mod shadowed {
    #![allow(dead_code, non_camel_case_types, unused_macros)]
    use situate::{Body, Context, Declare, Skill, SkillError};

    struct Option;
    struct Some;
    struct None;
    struct Result;
    struct Ok;
    struct Err;
    struct String;
    struct Vec;
    struct Box;
    struct usize;
    trait Default {}
    trait Clone {}
    macro_rules! vec {
        () => {
            compile_error!("the user's vec!")
        };
    }
    macro_rules! format {
        () => {
            compile_error!("the user's format!")
        };
    }
    mod std {}
    mod core {}

    // Locals of the generated code don't capture names in default expressions.
    #[allow(non_upper_case_globals)]
    const skill: f64 = 2.0;
    #[allow(non_upper_case_globals)]
    const decl: f64 = 3.0;

    #[derive(Skill, ::std::default::Default)]
    #[skill(claims = ["a"])]
    pub struct Odd {
        /// In.
        #[input]
        a: f64,
        #[input]
        b: ::std::option::Option<bool>,
        #[output]
        c: ::std::string::String,
        #[output]
        d: ::std::option::Option<i64>,
        #[param(default = "x")]
        e: ::std::string::String,
        #[param(default = 1)]
        f: f64,
        #[param(default = skill)]
        g: f64,
        #[param(default = decl)]
        h: f64,
    }

    impl Body for Odd {
        fn step(&mut self, _: &mut Context) -> ::std::result::Result<(), SkillError> {
            self.d = ::std::option::Option::Some(1);
            ::std::result::Result::Ok(())
        }
    }

    #[test]
    fn still_derives() {
        let d = Odd::declaration();
        assert_eq!(d.type_name, "odd");
        assert!(d.inputs[1].optional);
        assert_eq!(d.params[2].default, situate::Value::F64(2.0));
        assert_eq!(d.params[3].default, situate::Value::F64(3.0));
        let _ = Odd::create(&situate::Resources::new()).unwrap();
    }
}
