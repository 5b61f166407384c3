//! Runs one skill through its real glue (`Skill::step` with an `Io`), with
//! ports and parameters named as in its declaration, and switched on and off
//! as the manager does (`Skill::activate` before the first run after a switch
//! on, `Skill::deactivate` when switched off).

use situate::{Context, Declare, Io, SignalValue, Skill, SkillDecl, Value};

pub struct Harness {
    skill: Box<dyn Skill>,
    decl: SkillDecl,
    cycle: u64,
    /// Activated, not deactivated since.
    on: bool,
    /// Simulated seconds per cycle.
    pub dt: f64,
    pub prints: Vec<String>,
}

pub struct Outputs {
    names: Vec<String>,
    values: Vec<Option<Value>>,
}

impl Outputs {
    /// Output port `name` as a `T`, when written.
    pub fn get<T: SignalValue>(&self, name: &str) -> Option<T> {
        let k = self.names.iter().position(|n| n == name).unwrap_or_else(|| panic!("no output `{name}`"));
        self.values[k].as_ref().map(|v| T::from_value(v).unwrap_or_else(|| panic!("output `{name}`: bad type {v:?}")))
    }
}

impl Harness {
    pub fn new<T: Declare>() -> Self {
        Harness {
            skill: T::create(&situate::Resources::new()).unwrap(),
            decl: T::declaration(),
            cycle: 1,
            on: false,
            dt: 0.05,
            prints: Vec::new(),
        }
    }

    pub fn decl(&self) -> &SkillDecl {
        &self.decl
    }

    /// Sets a parameter, checked against the declaration.
    pub fn param(mut self, name: &str, value: Value) -> Self {
        self.set(name, value);
        self
    }

    /// Sets a parameter between runs.
    pub fn set(&mut self, name: &str, value: Value) {
        let (k, spec) = self.decl.param(name).unwrap_or_else(|| panic!("no param `{name}`"));
        let v = spec.check(&value).unwrap_or_else(|e| panic!("param `{name}`: {e}"));
        self.skill.set_param(k, &v);
    }

    /// The skill is switched off for `cycles` cycles (deactivated; activated
    /// again before its next run).
    pub fn skip(&mut self, cycles: u64) {
        let mut cx = Context::new(self.cycle, self.cycle as f64 * self.dt);
        self.skill.deactivate(&mut cx).expect("the body is deactivated");
        self.prints.extend(cx.take_prints());
        self.on = false;
        self.cycle += cycles;
    }

    /// The skill stays on but does not run for `cycles` cycles (an input it
    /// needs was not written in them).
    pub fn gap(&mut self, cycles: u64) {
        self.cycle += cycles;
    }

    /// One run with the inputs given by port name; missing ones are absent.
    pub fn run(&mut self, inputs: &[(&str, Value)]) -> Outputs {
        for (name, _) in inputs {
            assert!(self.decl.inputs.iter().any(|p| p.name == *name), "no input `{name}`");
        }
        let ins: Vec<Option<Value>> = self
            .decl
            .inputs
            .iter()
            .map(|p| inputs.iter().find(|(n, _)| *n == p.name).map(|(_, v)| v.clone()))
            .collect();
        let mut outs = vec![None; self.decl.outputs.len()];
        let mut cx = Context::new(self.cycle, self.cycle as f64 * self.dt);
        if !std::mem::replace(&mut self.on, true) {
            self.skill.activate(&mut cx).expect("the body is activated");
        }
        self.skill.step(&mut Io { inputs: &ins, outputs: &mut outs, cx: &mut cx }).expect("the body runs");
        self.prints.extend(cx.take_prints());
        self.cycle += 1;
        Outputs { names: self.decl.outputs.iter().map(|p| p.name.clone()).collect(), values: outs }
    }
}

pub fn val<T: SignalValue>(x: T) -> Value {
    x.into_value()
}
