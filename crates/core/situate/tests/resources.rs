//! Resources handed to a skill when it is made (`#[resource]`, `Registry::provide`): a body
//! has them from its first run, and a missing one is a build error naming the skill.

use std::sync::atomic::{AtomicU64, Ordering};

use situate::manager::{ClockKind, Control, Manager, Registry, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate::Resources;

/// Counts its runs into a counter the host keeps, scaled by a gain the host chose. No
/// `Default`: a struct with resource fields is made field by field.
#[derive(Skill)]
#[skill(name = "counting")]
struct Counting {
    /// Runs so far times the gain.
    #[output]
    total: f64,
    /// Added to the host's counter each run.
    #[param(default = 1, min = 0.0, max = 10.0)]
    step: i64,
    #[resource]
    counter: Arc<AtomicU64>,
    #[resource(name = "gain")]
    k: f64,
    runs: u64,
}

impl Body for Counting {
    fn step(&mut self, _cx: &mut Context) -> Result<(), SkillError> {
        self.runs += 1;
        self.counter.fetch_add(self.step as u64, Ordering::SeqCst);
        self.total = self.runs as f64 * self.k;
        Ok(())
    }
}

fn robot() -> RobotSpec {
    RobotSpec::new("res").clock(ClockKind::Simulated).period_s(0.1).skill(SkillSpec::new("c", "counting"))
}

#[test]
fn a_skill_is_made_with_the_resources_the_host_provides() {
    let counter = Arc::new(AtomicU64::new(0));
    let mut registry = Registry::new();
    registry.register::<Counting>().provide("counter", Arc::clone(&counter)).provide("gain", 2.5_f64);
    let mut manager = Manager::build(&robot(), &registry).expect("builds");
    manager.request(Request::Activate { skills: vec!["c".into()], with_providers: false }).unwrap();
    for _ in 0..3 {
        manager.cycle();
    }
    assert_eq!(counter.load(Ordering::SeqCst), 3);
    assert_eq!(manager.query("total").unwrap().value, Some(Value::F64(7.5)));
}

#[test]
fn a_missing_resource_is_a_build_error_naming_the_skill_and_the_resource() {
    let mut registry = Registry::new();
    registry.register::<Counting>().provide("counter", Arc::new(AtomicU64::new(0)));
    let e = Manager::build(&robot(), &registry).err().expect("refused");
    let text = e.to_string();
    assert!(
        text.contains(
            "skill `c`: could not create `counting`: `counting` needs the resource `gain` (a `f64`), and the \
             program provides none of that name (it provides `counter`)"
        ),
        "{text}"
    );
}

#[test]
fn a_resource_of_another_type_is_refused_naming_both_types() {
    let mut registry = Registry::new();
    registry.register::<Counting>().provide("counter", Arc::new(AtomicU64::new(0))).provide("gain", 2_i64);
    let e = Counting::create(registry.resources()).err().expect("refused");
    assert_eq!(e.to_string(), "`counting` needs the resource `gain` as a `f64`, and the program provides a `i64`");
}

#[test]
fn params_start_at_their_defaults_in_a_skill_made_field_by_field() {
    let mut resources = Resources::new();
    resources.insert("counter", Arc::new(AtomicU64::new(0))).insert("gain", 1.0_f64);
    let mut skill = Counting::create(&resources).expect("made");
    let mut outputs = [None];
    let mut cx = Context::new(1, 0.1);
    skill.step(&mut situate::Io { inputs: &[], outputs: &mut outputs, cx: &mut cx }).unwrap();
    let counter = resources.get::<Arc<AtomicU64>>("counter").unwrap();
    assert_eq!(counter.load(Ordering::SeqCst), 1, "the param `step` is 1 by default, not the i64's 0");
}
