//! A C skill declared `kind: async` runs on its own thread behind the
//! manager's mailbox, like any asynchronous cskill.

mod common;

use common::*;
use situate_core::{SkillKind, Value};
use situate_manager::{Registry, Reply, Request, SkillSpec};

const MANIFEST: &str = "name: c.double\nkind: async\ninputs: {x: f64}\noutputs: {y: f64}\n";
const SOURCE: &str = r#"
#include "c_double.h"
struct c_double_state { double last; };
situate_status c_double_step(c_double_state* s, const c_double_inputs* in, c_double_outputs* out,
                             const c_double_params* p, situate_context* cx) {
    (void)p; (void)cx;
    s->last = in->x;
    out->y = 2.0 * in->x;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_double))
"#;

#[test]
fn an_async_c_skill_runs_on_its_thread() {
    let dir = scratch("kinds_async");
    std::fs::write(dir.join("double.yaml"), MANIFEST).unwrap();
    gen("c", &dir.join("double.yaml"), &dir);
    let lib = shared_lib(&dir, "c_double", &[("double.c", SOURCE)], false);
    let mut r = Registry::new();
    for t in situate_cabi::load_library(&lib).unwrap() {
        assert_eq!(t.decl.kind, SkillKind::Async);
        r.add(t);
    }
    r.add(source("t.x", "f64", "x", |c| Value::F64(c as f64)));
    let spec = simulated("async").skill(SkillSpec::new("x", "t.x")).skill(SkillSpec::new("double", "c.double"));
    let mut m = build(&spec, &r);
    m.run_cycles(20);
    let y = match m.request(Request::QuerySignal { signal: "y".into() }) {
        Ok(Reply::Signal(s)) => s.value,
        other => panic!("{other:?}"),
    };
    let y = y.and_then(|v| v.as_f64()).expect("the async skill produced y");
    assert!((2.0..=40.0).contains(&y) && y % 2.0 == 0.0, "y = 2 x for some cycle's x, got {y}");
    match m.request(Request::QuerySkill { skill: "double".into() }) {
        Ok(Reply::Skill(info)) => assert!(info.faulted.is_none() && info.active, "{info:?}"),
        other => panic!("{other:?}"),
    }
}
