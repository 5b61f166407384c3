//! `Skill::output_typed`: a derived skill says its built-in outputs are of
//! their ports' types by construction (the manager then skips their check);
//! anything else is still checked, and a wrongly typed value still faults.

use situate::manager::{ClockKind, Control, Event, Manager, Registry, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate::{FnSkill, Io, PortSpec, SignalType, SkillDecl, SkillType};

#[derive(Record, Clone, Default, Debug, PartialEq)]
struct Pair {
    a: f64,
    b: f64,
}

#[derive(Skill, Default)]
#[skill(name = "test.typed")]
struct Typed {
    #[output]
    y: [f32; 3],
    #[output]
    n: f64,
    #[output]
    maybe: Option<i64>,
    #[output]
    v: Arc<[f32]>,
    #[output]
    pair: Pair,
}

impl Body for Typed {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = [1.0, 2.0, 3.0];
        Ok(())
    }
}

/// Only plain outputs: the manager's plan skips their check.
#[derive(Skill, Default)]
#[skill(name = "test.array")]
struct Array {
    #[output]
    y: [f32; 3],
}

impl Body for Array {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = [1.0, 2.0, 3.0];
        Ok(())
    }
}

/// A skill written by hand: it says nothing, so its outputs are checked.
struct ByHand;

impl SkillTrait for ByHand {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        io.outputs[0] = Some(Value::Str("not a number".into()));
        Ok(())
    }
    fn set_param(&mut self, _: usize, _: &Value) {}
}

fn ty(text: &str) -> SignalType {
    SignalType::parse(text).expect("a signal type")
}

#[test]
fn a_derived_skill_reports_its_built_in_outputs_typed() {
    let s = Typed::create(&situate::Resources::new()).unwrap();
    assert!(s.output_typed(0, &ty("f32[3]")));
    assert!(s.output_typed(0, &ty("f32[]")), "a fixed array feeds a variable-length port");
    assert!(!s.output_typed(0, &ty("f32[4]")));
    assert!(!s.output_typed(0, &ty("f64")));
    assert!(s.output_typed(1, &ty("f64")));
    assert!(s.output_typed(2, &ty("i64")), "an optional output, when written, is of its type");
    assert!(s.output_typed(3, &ty("f32[]")));
    assert!(!s.output_typed(3, &ty("f32[3]")), "an Arc<[f32]> may have any length");
    assert!(!s.output_typed(4, &Pair::signal_type()), "records are checked as they are taken apart");
    assert!(!s.output_typed(5, &ty("f64")), "no such output");
}

#[test]
fn a_hand_written_skill_does_not() {
    assert!(!SkillTrait::output_typed(&ByHand, 0, &ty("f64")));
    let mut d = SkillDecl::new("test.fn", SkillKind::Sync);
    d.outputs.push(PortSpec::new("y", ty("f64")));
    let f = FnSkill::new(&d, |_: &mut Io<'_>, _: &[Value]| Ok(()));
    assert!(!f.output_typed(0, &ty("f64")));
}

fn faults(m: &mut Manager, cycles: u64) -> Vec<(String, String)> {
    let events = m.events();
    for _ in 0..cycles {
        m.cycle();
    }
    events
        .try_iter()
        .filter_map(|e| match e {
            Event::SkillFaulted { skill, cause, .. } => Some((skill, cause)),
            _ => None,
        })
        .collect()
}

#[test]
fn the_manager_still_checks_outputs_not_typed_by_construction() {
    let mut hand = SkillDecl::new("test.by_hand", SkillKind::Sync);
    hand.outputs.push(PortSpec::new("y", ty("f64")));
    // A derived skill under a declaration its fields do not match: its
    // array output is then checked, and refused.
    let mut wrong = Array::declaration();
    wrong.type_name = "test.array_wrong".into();
    wrong.outputs[0].ty = ty("f32[4]");
    assert!(Array::create(&situate::Resources::new()).unwrap().output_typed(0, &ty("f32[3]")));
    let mut reg = Registry::new();
    reg.register::<Array>();
    reg.add(SkillType::new(hand, || Ok(Box::new(ByHand) as Box<dyn SkillTrait>)));
    reg.add(SkillType::new(wrong, || Ok(Array::create(&situate::Resources::new()).unwrap())));
    let spec = RobotSpec::new("typed")
        .clock(ClockKind::Simulated)
        .period_s(0.01)
        .skill(SkillSpec::new("t", "test.array"))
        .skill(SkillSpec::new("h", "test.by_hand").remap("y", "hy"))
        .skill(SkillSpec::new("w", "test.array_wrong").remap("y", "wy"));
    let mut m = Manager::build(&spec, &reg).unwrap_or_else(|e| panic!("build failed:\n{e}"));
    m.activate(&["t", "h", "w"]).unwrap();
    let mut got = faults(&mut m, 3);
    got.sort();
    assert_eq!(
        got,
        vec![
            ("h".to_string(), "output `y` expects f64, the body produced a string".to_string()),
            ("w".to_string(), "output `y` expects f32[4], the body produced a f32 array".to_string()),
        ]
    );
    assert_eq!(m.query("y").unwrap().value, Some(Value::F32s(vec![1.0, 2.0, 3.0].into())));
    assert_eq!(m.query("wy").unwrap().value, None, "nothing of a refused run is written");
    assert_eq!(m.query("hy").unwrap().value, None);
}
