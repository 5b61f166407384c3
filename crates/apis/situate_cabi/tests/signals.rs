//! A manifest's `signal:` gives a port its default signal, so a C skill is
//! wired without a remap; a robot file's remap still overrides it.

mod common;

use common::*;
use situate_core::Value;
use situate_manager::{Manager, Registry, Reply, Request, SkillSpec};

const MANIFEST: &str = "name: c.scale\ninputs:\n  x: {type: f64, signal: sensor.x, doc: The reading.}\n\
                        outputs:\n  y: {type: f64, signal: cmd.y}\n";
const SOURCE: &str = r#"
#include "c_scale.h"
struct c_scale_state { int unused; };
situate_status c_scale_step(c_scale_state* s, const c_scale_inputs* in, c_scale_outputs* out,
                            const c_scale_params* p, situate_context* cx) {
    (void)s; (void)p; (void)cx;
    out->y = 3.0 * in->x;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_scale))
"#;

fn signal(m: &mut Manager, name: &str) -> Option<f64> {
    match m.request(Request::QuerySignal { signal: name.into() }) {
        Ok(Reply::Signal(s)) => s.value.and_then(|v| v.as_f64()),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_manifest_signal_wires_the_port_and_a_remap_overrides_it() {
    let dir = scratch("signals_default");
    std::fs::write(dir.join("scale.yaml"), MANIFEST).unwrap();
    gen("c", &dir.join("scale.yaml"), &dir);
    let header = std::fs::read_to_string(dir.join("c_scale.h")).unwrap();
    assert!(header.contains("(signal `sensor.x`): The reading."), "{header}");
    let lib = shared_lib(&dir, "c_scale", &[("scale.c", SOURCE)], false);
    let mut r = Registry::new();
    for t in situate_cabi::load_library(&lib).unwrap() {
        assert_eq!((t.decl.inputs[0].signal.as_str(), t.decl.outputs[0].signal.as_str()), ("sensor.x", "cmd.y"));
        r.add(t);
    }
    r.add(source("t.x", "f64", "sensor.x", |_| Value::F64(2.0)));
    r.add(source("t.z", "f64", "other.x", |_| Value::F64(5.0)));

    // No remap: the manifest's signals.
    let spec = simulated("default").skill(SkillSpec::new("x", "t.x")).skill(SkillSpec::new("scale", "c.scale"));
    let mut m = build(&spec, &r);
    m.run_cycles(3);
    assert_eq!(signal(&mut m, "cmd.y"), Some(6.0));

    // A remap wins over the manifest's signal, for the input and the output.
    let spec = simulated("remapped")
        .skill(SkillSpec::new("x", "t.x"))
        .skill(SkillSpec::new("z", "t.z"))
        .skill(SkillSpec::new("scale", "c.scale").remap("x", "other.x").remap("y", "mine.y"));
    let mut m = build(&spec, &r);
    m.run_cycles(3);
    assert_eq!(signal(&mut m, "mine.y"), Some(15.0));
}
