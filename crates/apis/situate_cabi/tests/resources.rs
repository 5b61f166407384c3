//! Resources handed to C and C++ skills when they are made (`init_with`, a C++ constructor
//! taking `situate::Resources`): the pointer the program provided, by name; a missing one is a
//! build error naming the skill and the resource.

mod common;

use std::ffi::c_void;

use common::*;
use situate_cabi::CResource;
use situate_core::Value;
use situate_manager::{Control, Manager, Registry, SkillSpec};

/// Counts its runs into the program's counter (`runs`) and writes the count to `y`.
const MANIFEST: &str = "outputs: {y: i64}\nparams:\n  step: {default: 1}\n";

const C_SOURCE: &str = r#"
#include "c_counting.h"

typedef struct counter { int64_t runs; } counter;

struct c_counting_state { counter* runs; };

situate_status c_counting_init_with(c_counting_state* s, const c_counting_params* p,
                                    const situate_resources* resources, situate_error* e) {
    (void)p;
    s->runs = (counter*)situate_resource(resources, "runs");
    if (s->runs == NULL) {
        return situate_missing_resource(e, "runs");
    }
    return SITUATE_OK;
}

situate_status c_counting_step(c_counting_state* s, const c_counting_inputs* in, c_counting_outputs* out,
                               const c_counting_params* p, situate_context* cx) {
    (void)in; (void)cx;
    s->runs->runs += p->step;
    out->y = s->runs->runs;
    out->has_y = true;
    return SITUATE_OK;
}

SITUATE_LIBRARY(SITUATE_SKILL_WITH_RESOURCES(c_counting, NULL, NULL, NULL, NULL))
"#;

const CPP_SOURCE: &str = r#"
#include "cpp_counting.hpp"

struct Counter { int64_t runs; };

// No default constructor: made only with the program's resources.
class Counting : public cpp_counting::Skill {
 public:
  Counting(const Params&, const situate::Resources& r) : runs_(r.need<Counter>("runs")) {}
  void step(const Inputs&, Outputs& out, const Params& p, situate::Context&) {
    runs_.runs += p.step;
    out.y = runs_.runs;
    out.has_y = true;
  }

 private:
  Counter& runs_;
};
SITUATE_CPP_LIBRARY(Counting)
"#;

/// The program's counter, as the skills see it (`struct counter`).
#[repr(C)]
struct Counter {
    runs: i64,
}

/// The two libraries, built in a directory of the test's own (tests run at once).
fn registry(test: &str) -> Registry {
    registry_of(
        test,
        &[("c_counting", MANIFEST, "c"), ("cpp_counting", MANIFEST, "cpp")],
        &[("c_counting", "c_counting.c", C_SOURCE, false), ("cpp_counting", "cpp_counting.cpp", CPP_SOURCE, true)],
    )
}

#[test]
fn c_and_cpp_skills_are_made_with_the_pointer_the_program_provides() {
    let mut r = registry("resources_given");
    for ty in ["c.counting", "cpp.counting"] {
        let mut counter = Box::new(Counter { runs: 100 });
        let ptr = std::ptr::from_mut::<Counter>(&mut counter).cast::<c_void>();
        // SAFETY: the counter outlives the manager (dropped after it, below), and the skill runs on
        // the simulated clock, in the cycle, one run at a time.
        r.provide("runs", unsafe { CResource::new(ptr) });
        let mut m = build(&simulated("res").skill(SkillSpec::new("c", ty)), &r);
        m.step(3).unwrap();
        assert_eq!(m.query("y").unwrap().value, Some(Value::I64(103)), "{ty}");
        m.set_param("c", "step", Value::I64(10)).unwrap();
        m.step(1).unwrap();
        drop(m);
        assert_eq!(counter.runs, 113, "{ty}: the skill wrote into the program's own counter");
    }
}

#[test]
fn a_missing_resource_is_a_build_error_naming_the_skill_and_the_resource() {
    let mut r = registry("resources_missing");
    // A resource of that name that is not a C one is as good as none to C.
    r.provide("runs", 5_i64);
    for ty in ["c.counting", "cpp.counting"] {
        let e = Manager::build(&simulated("res").skill(SkillSpec::new("c", ty)), &r).err().expect("refused");
        let text = e.to_string();
        assert!(
            text.contains(&format!(
                "skill `c`: could not create `{ty}`: {ty}: init failed: needs the resource `runs`, and the \
                 program provides no C resource of that name"
            )),
            "{ty}: {text}"
        );
    }
}
