//! A derived skill's output written straight into its slot (`plan::Fast::in_slot`: a step run
//! the short way whose body sets its output on every `Ok` run and leaves it alone on a failed
//! one). The value is written in place only where nobody else holds it: a value a query, a
//! tap or another skill took is never changed under it; an `Option` output that is `None`
//! leaves the slot's last value and its cycle; a failed or panicking run commits nothing.

use situate::manager::{ClockKind, Control, Event, Manager, Registry, Request, RobotSpec, SkillSpec};
use situate::prelude::*;

/// Cycle number `t` as `[t, t, t, t]`.
#[derive(Skill, Default)]
#[skill(name = "t.src")]
struct Src {
    #[output]
    out: [f32; 4],
}

impl Body for Src {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.out = [cx.cycle() as f32; 4];
        Ok(())
    }
}

/// `y = x + 1`; with `mode` 1 it fails, 2 it panics (before writing anything).
#[derive(Skill, Default)]
#[skill(name = "t.inc")]
struct Inc {
    #[input]
    x: [f32; 4],
    #[output]
    y: [f32; 4],
    #[param(default = 0, min = 0.0, max = 2.0)]
    mode: i64,
}

impl Body for Inc {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        match self.mode {
            1 => return Err(SkillError::new("no can do")),
            2 => panic!("on purpose"),
            _ => {}
        }
        self.y = self.x.map(|v| v + 1.0);
        Ok(())
    }
}

/// `x` on even cycles, nothing on odd ones.
#[derive(Skill, Default)]
#[skill(name = "t.every_other")]
struct EveryOther {
    #[input]
    x: [f32; 4],
    #[output]
    y: Option<[f32; 4]>,
}

impl Body for EveryOther {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.y = cx.cycle().is_multiple_of(2).then_some(self.x);
        Ok(())
    }
}

fn build(spec: &RobotSpec) -> Manager {
    let mut registry = Registry::new();
    registry.register::<Src>().register::<Inc>().register::<EveryOther>();
    let mut m = Manager::build(spec, &registry).expect("builds");
    let skills = spec.skills.iter().map(|s| s.name.clone()).collect();
    m.request(Request::Activate { skills, with_providers: false }).unwrap();
    m
}

/// `src → a → b`, on `s0, s1, s2`, simulated clock. The budgets are the default (above the
/// exact-timing bound): every step runs the short way outside the sampled cycles.
fn chain() -> RobotSpec {
    RobotSpec::new("in-slot")
        .clock(ClockKind::Simulated)
        .period_s(0.01)
        .skill(SkillSpec::new("src", "t.src").remap("out", "s0"))
        .skill(SkillSpec::new("a", "t.inc").remap("x", "s0").remap("y", "s1"))
        .skill(SkillSpec::new("b", "t.inc").remap("x", "s1").remap("y", "s2"))
}

fn value(m: &mut Manager, path: &str) -> Option<Value> {
    m.query(path).unwrap().value
}

fn f32s(v: f32) -> Option<Value> {
    Some(Value::F32s(Arc::from([v; 4])))
}

#[test]
fn a_value_someone_holds_is_never_written_in_place() {
    let mut m = build(&chain());
    // Past the first cycles (the first is sampled): the short way, in place.
    for _ in 0..5 {
        m.cycle();
    }
    assert_eq!(value(&mut m, "s2"), f32s(7.0));
    // Held, as a query's reply, a tap's frame or a lent input hold them.
    let held: Vec<Option<Value>> = ["s0", "s1", "s2"].iter().map(|s| value(&mut m, s)).collect();
    for cycle in 6..=80u64 {
        m.cycle();
        let c = cycle as f32;
        assert_eq!(value(&mut m, "s0"), f32s(c), "cycle {cycle}");
        assert_eq!(value(&mut m, "s2"), f32s(c + 2.0), "cycle {cycle}");
        assert_eq!(held, vec![f32s(5.0), f32s(6.0), f32s(7.0)], "what was held changed in cycle {cycle}");
    }
}

#[test]
fn an_optional_output_that_is_none_leaves_the_slot_its_last_value_and_cycle() {
    let spec = chain().skill(SkillSpec::new("e", "t.every_other").remap("x", "s0").remap("y", "e"));
    let mut m = build(&spec);
    for cycle in 1..=70u64 {
        m.cycle();
        let reading = m.query("e").unwrap();
        let last_even = cycle - cycle % 2;
        assert_eq!(reading.value, if last_even == 0 { None } else { f32s(last_even as f32) }, "cycle {cycle}");
        if last_even > 0 {
            assert_eq!(reading.cycle, last_even, "cycle {cycle}: written then, not since");
        }
    }
}

#[test]
fn a_run_that_fails_or_panics_in_its_slot_commits_nothing() {
    for (mode, cause) in [(1, "no can do"), (2, "on purpose")] {
        let mut m = build(&chain());
        let events = m.events();
        for _ in 0..5 {
            m.cycle();
        }
        m.set_param("a", "mode", Value::I64(mode)).unwrap();
        m.cycle();
        assert_eq!(value(&mut m, "s1"), f32s(6.0), "mode {mode}: s1 keeps its value of cycle 5");
        assert_eq!(m.query("s1").unwrap().cycle, 5, "mode {mode}");
        let faults: Vec<String> = events
            .try_iter()
            .filter_map(|e| match e {
                Event::SkillFaulted { skill, cause, .. } if skill == "a" => Some(cause),
                _ => None,
            })
            .collect();
        assert!(faults.iter().any(|c| c.contains(cause)), "mode {mode}: {faults:?}");
    }
}
