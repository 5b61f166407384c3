//! Fault paths of foreign skills inside a real manager: a C body returning
//! an error status, a C++ body throwing, a C++ `on_param` refusing a value,
//! a C++ constructor throwing. Each faults only its own skill, with the
//! message; the other skills keep running. Prints reach the skill's history.

mod common;

use common::*;
use situate_core::{PortSpec, SkillDecl, SkillKind, Value};
use situate_manager::{Registry, Reply, Request, SkillSpec};

const C_MANIFEST: &str = "name: c.faulty\ninputs: {x: f64}\noutputs: {y: f64}\nparams:\n  limit: 5.0\n";
const C_SOURCE: &str = r#"
#include "c_faulty.h"
struct c_faulty_state { int runs; };
situate_status c_faulty_step(c_faulty_state* s, const c_faulty_inputs* in, c_faulty_outputs* out,
                             const c_faulty_params* p, situate_context* cx) {
    s->runs++;
    if (in->x > p->limit) {
        return situate_fail(cx, "x = %.1f is over the limit %.1f after %d runs", in->x, p->limit, s->runs);
    }
    situate_print(cx, "x = %.1f at cycle %llu", in->x, (unsigned long long)cx->cycle);
    out->y = 2.0 * in->x;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_faulty))
"#;

const CPP_MANIFEST: &str = "name: cpp.faulty\ninputs: {x: f64}\noutputs: {y: f64}\nparams:\n  limit: 5.0\n";
const CPP_SOURCE: &str = r#"
#include <stdexcept>
#include <string>
#include "cpp_faulty.hpp"
#include "cpp_badinit.hpp"
class Faulty : public cpp_faulty::Skill {
 public:
  explicit Faulty(const Params& p) : limit_at_start_(p.limit) {}
  void step(const Inputs& in, Outputs& out, const Params& p, situate::Context& cx) {
    if (in.x > p.limit) throw std::out_of_range("x = " + std::to_string(int(in.x)) + " is too large");
    cx.print("cpp saw " + std::to_string(int(in.x)));
    out.y = 3.0 * in.x + 0.0 * limit_at_start_;
    out.has_y = true;
  }
  void on_param(uint32_t index, const Params& p) {
    if (index == cpp_faulty::param::limit && p.limit > 100.0) throw std::invalid_argument("limit above 100");
  }

 private:
  double limit_at_start_;
};
class BadInit : public cpp_badinit::Skill {
 public:
  BadInit() { throw std::runtime_error("cannot start: no device"); }
  void step(const Inputs&, Outputs&, const Params&, situate::Context&) {}
};
SITUATE_CPP_LIBRARY(Faulty, BadInit)
"#;

fn registry(test: &str) -> Registry {
    // One directory per test: tests run in parallel.
    let dir = scratch(test);
    std::fs::write(dir.join("c_faulty.yaml"), C_MANIFEST).unwrap();
    std::fs::write(dir.join("cpp_faulty.yaml"), CPP_MANIFEST).unwrap();
    gen("c", &dir.join("c_faulty.yaml"), &dir);
    gen("cpp", &dir.join("cpp_faulty.yaml"), &dir);
    std::fs::write(dir.join("cpp_badinit.yaml"), "name: cpp.badinit\ninputs: {x: f64}\n").unwrap();
    gen("cpp", &dir.join("cpp_badinit.yaml"), &dir);
    let c = shared_lib(&dir, "c_faulty", &[("c_faulty.c", C_SOURCE)], false);
    let cpp = shared_lib(&dir, "cpp_faulty", &[("cpp_faulty.cpp", CPP_SOURCE)], true);
    let mut r = Registry::new();
    for lib in [c, cpp] {
        for t in situate_cabi::load_library(&lib).expect("load") {
            r.add(t);
        }
    }
    r.add(source("test.x", "f64", "x", |c| Value::F64(c as f64)));
    let mut d = SkillDecl::new("test.healthy", SkillKind::Sync);
    d.inputs.push(PortSpec::new("x", ty("f64")));
    d.outputs.push(PortSpec::new("z", ty("f64")));
    r.add(fn_type(d, |io, _| {
        io.outputs[0] = Some(Value::F64(io.inputs[0].as_ref().and_then(Value::as_f64).ok_or("no x")? + 0.5));
        Ok(())
    }));
    r
}

fn query_skill(m: &mut situate_manager::Manager, name: &str) -> situate_manager::SkillInfo {
    match m.request(Request::QuerySkill { skill: name.into() }) {
        Ok(Reply::Skill(info)) => *info,
        other => panic!("query {name}: {other:?}"),
    }
}

fn signal(m: &mut situate_manager::Manager, name: &str) -> (Option<Value>, u64) {
    match m.request(Request::QuerySignal { signal: name.into() }) {
        Ok(Reply::Signal(r)) => (r.value, r.cycle),
        other => panic!("query {name}: {other:?}"),
    }
}

#[test]
fn a_c_error_status_and_a_cpp_exception_fault_only_their_skill() {
    let r = registry("faults_status");
    let spec = simulated("faults")
        .skill(SkillSpec::new("x", "test.x"))
        .skill(SkillSpec::new("c", "c.faulty").remap("y", "y_c"))
        .skill(SkillSpec::new("cpp", "cpp.faulty").remap("y", "y_cpp"))
        .skill(SkillSpec::new("healthy", "test.healthy"));
    let mut m = build(&spec, &r);
    let events = m.events();
    m.run_cycles(5);
    assert_eq!(signal(&mut m, "y_c"), (Some(Value::F64(10.0)), 5));
    assert_eq!(signal(&mut m, "y_cpp"), (Some(Value::F64(15.0)), 5));
    assert!(faults(&events).is_empty());
    m.run_cycles(5);
    let f = faults(&events);
    assert_eq!(
        f,
        [
            ("c".to_string(), "x = 6.0 is over the limit 5.0 after 6 runs".to_string(), 6),
            ("cpp".to_string(), "x = 6 is too large".to_string(), 6),
        ]
    );
    let c = query_skill(&mut m, "c");
    assert!(!c.active);
    assert_eq!(c.faulted.as_deref(), Some("x = 6.0 is over the limit 5.0 after 6 runs"));
    assert_eq!(c.prints.last().map(|(cy, l)| (*cy, l.as_str())), Some((5, "x = 5.0 at cycle 5")));
    assert_eq!(query_skill(&mut m, "cpp").prints.last().map(|p| p.1.as_str()), Some("cpp saw 5"));
    assert_eq!(signal(&mut m, "z"), (Some(Value::F64(10.5)), 10), "the healthy skill keeps running");
    assert_eq!(signal(&mut m, "y_c").1, 5, "nothing written once faulted");
}

#[test]
fn a_cpp_on_param_refusal_faults_at_the_next_step() {
    let r = registry("faults_param");
    let spec = simulated("param").skill(SkillSpec::new("x", "test.x")).skill(SkillSpec::new("cpp", "cpp.faulty"));
    let mut m = build(&spec, &r);
    let events = m.events();
    m.run_cycles(2);
    m.request(Request::SetParam { skill: "cpp".into(), param: "limit".into(), value: Value::F64(50.0) }).unwrap();
    m.run_cycles(1);
    assert!(faults(&events).is_empty());
    m.request(Request::SetParam { skill: "cpp".into(), param: "limit".into(), value: Value::F64(500.0) }).unwrap();
    m.run_cycles(1);
    let f = faults(&events);
    assert_eq!(f.len(), 1);
    assert_eq!(f[0].1, "refused parameter `limit`: limit above 100");
}

#[test]
fn a_cpp_constructor_that_throws_fails_the_build_with_its_message() {
    let r = registry("faults_init");
    let spec = simulated("init").skill(SkillSpec::new("x", "test.x")).skill(SkillSpec::new("bad", "cpp.badinit"));
    let e = situate_manager::Manager::build(&spec, &r).err().expect("the build fails");
    assert!(e.to_string().contains("cannot start: no device"), "{e}");
}
