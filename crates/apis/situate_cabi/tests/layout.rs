//! The generated C and C++ structs have exactly the layout the runtime
//! computes from the declaration: a compiled program prints every struct's
//! size and every field's offset and size, compared with `SkillLayout`.
//! Then a C skill echoes strings, variable arrays and records through those
//! buffers inside a manager.

mod common;

use std::fmt::Write as _;

use common::*;
use situate_cabi::{parse_manifest, FieldKind, SkillLayout, StructLayout};
use situate_core::{record_value, PortSpec, SkillDecl, SkillKind, Value};
use situate_manager::{Registry, Reply, Request, SkillSpec};

const MANIFEST: &str = r#"name: c.layout
inputs:
  flag: bool
  count: i64
  x: "f64?"
  name: string
  blob: "bytes?"
  ranges: f32[3]
  samples: f64[]
  ids: i64[2]
  pose: "{x: f64, ok: bool, inner: {a: f32[5], b: bool}}"
outputs:
  done: bool
  label: string
  pose: "{x: f64, ok: bool, inner: {a: f32[5], b: bool}}"
  list: f64[]
params:
  on: true
  n: 3
  gain: 2.0
  tag: "hi"
"#;

/// `(struct, c struct name)` pairs and the expected lines
/// `STRUCT FIELD OFFSET SIZE` / `STRUCT sizeof SIZE`.
fn expected(structs: &[(&StructLayout, String)]) -> String {
    let mut out = String::new();
    for (s, name) in structs {
        let _ = writeln!(out, "{name} sizeof {}", s.size);
        for f in &s.fields {
            let _ = writeln!(out, "{name} {} {} {}", f.name, f.offset, f.size);
        }
    }
    out
}

fn program(structs: &[(&StructLayout, String)], include: &str, cpp: bool) -> String {
    let mut p = format!("#include <stdio.h>\n#include <stddef.h>\n#include \"{include}\"\n");
    if cpp {
        p.push_str("using namespace c_layout;\n");
    }
    p.push_str("int main(void) {\n");
    for (s, name) in structs {
        let _ = writeln!(p, "    printf(\"%s sizeof %zu\\n\", \"{name}\", sizeof({name}));");
        for f in &s.fields {
            let _ = writeln!(
                p,
                "    printf(\"%s %s %zu %zu\\n\", \"{name}\", \"{0}\", offsetof({name}, {0}), sizeof((({name}*)0)->{0}));",
                f.name
            );
        }
    }
    p.push_str("    return 0;\n}\n");
    p
}

fn records<'a>(s: &'a StructLayout, out: &mut Vec<(&'a StructLayout, String)>) {
    for f in &s.fields {
        if let FieldKind::Record { c_name, layout } = &f.kind {
            records(layout, out);
            out.push((layout, c_name.clone()));
        }
    }
}

#[test]
fn generated_c_and_cpp_structs_match_the_runtime_layout() {
    let dir = scratch("layout");
    let manifest = dir.join("layout.yaml");
    std::fs::write(&manifest, MANIFEST).unwrap();
    gen("c", &manifest, &dir);
    gen("cpp", &manifest, &dir);
    let layout = SkillLayout::of(&parse_manifest(MANIFEST).unwrap()).unwrap();
    let mut c_structs = Vec::new();
    records(&layout.inputs, &mut c_structs);
    records(&layout.outputs, &mut c_structs);
    let mut seen = Vec::new();
    c_structs.retain(|(_, n)| {
        if seen.contains(n) {
            false
        } else {
            seen.push(n.clone());
            true
        }
    });
    assert_eq!(c_structs.len(), 2, "pose and pose.inner, each once");
    c_structs.push((&layout.inputs, "c_layout_inputs".into()));
    c_structs.push((&layout.outputs, "c_layout_outputs".into()));
    c_structs.push((&layout.params, "c_layout_params".into()));
    let want = expected(&c_structs);
    // Sanity: the layout has padding to check (the i64 after a bool, ...).
    assert!(want.contains("c_layout_inputs count 8 8"), "{want}");
    assert_eq!(run_program(&dir, "layout_c", &program(&c_structs, "c_layout.h", false), false), want);

    let cpp_name = |c: &str| format!("{}_t", c.trim_start_matches("c_layout_"));
    let cpp_structs: Vec<(&StructLayout, String)> = c_structs
        .iter()
        .map(|(s, n)| {
            let name = match n.as_str() {
                "c_layout_inputs" => "Inputs".to_string(),
                "c_layout_outputs" => "Outputs".to_string(),
                "c_layout_params" => "Params".to_string(),
                other => cpp_name(other),
            };
            (*s, name)
        })
        .collect();
    let want = expected(&cpp_structs);
    assert_eq!(run_program(&dir, "layout_cpp", &program(&cpp_structs, "c_layout.hpp", true), true), want);
}

const ECHO_MANIFEST: &str = r#"name: c.echo
inputs:
  name: string
  samples: f64[]
  pose: "{x: f64, ok: bool, inner: {a: f32[2], b: bool}}"
  extra: "i64?"
outputs:
  label: string
  list: f64[]
  moved: "{x: f64, ok: bool, inner: {a: f32[2], b: bool}}"
  extra10: i64
params:
  prefix: "id:"
"#;

const ECHO_SOURCE: &str = r#"
#include <string.h>
#include "c_echo.h"
struct c_echo_state { char label[64]; double list[8]; };
situate_status c_echo_step(c_echo_state* s, const c_echo_inputs* in, c_echo_outputs* out,
                           const c_echo_params* p, situate_context* cx) {
    (void)cx;
    size_t n = p->prefix.len + in->name.len;
    if (n > sizeof s->label || in->samples.len > 8) return situate_fail(cx, "too long");
    memcpy(s->label, p->prefix.ptr, p->prefix.len);
    memcpy(s->label + p->prefix.len, in->name.ptr, in->name.len);
    out->label.ptr = s->label;
    out->label.len = n;
    out->has_label = true;
    for (size_t i = 0; i < in->samples.len; i++) s->list[i] = 2.0 * in->samples.ptr[i];
    out->list.ptr = s->list;
    out->list.len = in->samples.len;
    out->has_list = true;
    /* Same layout, different generated types: copy the bytes. */
    memcpy(&out->moved, &in->pose, sizeof out->moved);
    out->moved.x += 1.0;
    out->has_moved = true;
    if (in->has_extra) {
        out->extra10 = in->extra * 10;
        out->has_extra10 = true;
    }
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_echo))
"#;

fn pose(x: f64) -> Value {
    record_value(vec![
        ("x", Value::F64(x)),
        ("ok", Value::Bool(true)),
        ("inner", record_value(vec![("a", Value::F32s(vec![1.5, -2.5].into())), ("b", Value::Bool(false))])),
    ])
}

#[test]
fn strings_arrays_records_and_optional_inputs_cross_both_ways() {
    let dir = scratch("echo");
    let manifest = dir.join("echo.yaml");
    std::fs::write(&manifest, ECHO_MANIFEST).unwrap();
    gen("c", &manifest, &dir);
    let lib = shared_lib(&dir, "c_echo", &[("echo.c", ECHO_SOURCE)], false);
    let mut r = Registry::new();
    for t in situate_cabi::load_library(&lib).unwrap() {
        r.add(t);
    }
    r.add(source("t.name", "string", "name", |c| Value::Str(format!("robot{c}").into())));
    r.add(source("t.samples", "f64[]", "samples", |c| Value::F64s(vec![0.5; c as usize % 4].into())));
    r.add(source("t.pose", "{x: f64, ok: bool, inner: {a: f32[2], b: bool}}", "pose", |c| pose(c as f64)));
    let mut d = SkillDecl::new("t.extra", SkillKind::Sync);
    d.outputs.push(PortSpec::new("out", ty("i64")).signal("extra"));
    r.add(fn_type(d, |io, _| {
        // Only on even cycles: the C skill sees `has_extra` false otherwise.
        if io.cx.cycle() % 2 == 0 {
            io.outputs[0] = Some(Value::I64(io.cx.cycle() as i64));
        }
        Ok(())
    }));
    let spec = simulated("echo")
        .skill(SkillSpec::new("name", "t.name"))
        .skill(SkillSpec::new("samples", "t.samples"))
        .skill(SkillSpec::new("pose", "t.pose"))
        .skill(SkillSpec::new("extra", "t.extra"))
        .skill(
            SkillSpec::new("echo", "c.echo")
                .param("prefix", Value::Str("#".into()))
                .remap("moved", "pose_out")
                .remap("extra10", "extra_out"),
        );
    let mut m = build(&spec, &r);
    let query = |m: &mut situate_manager::Manager, s: &str| match m.request(Request::QuerySignal { signal: s.into() }) {
        Ok(Reply::Signal(r)) => (r.value, r.cycle),
        other => panic!("{other:?}"),
    };
    m.run_cycles(3);
    assert_eq!(query(&mut m, "label"), (Some(Value::Str("#robot3".into())), 3));
    assert_eq!(query(&mut m, "list"), (Some(Value::F64s(vec![1.0; 3].into())), 3));
    assert_eq!(query(&mut m, "pose_out"), (Some(pose(4.0)), 3));
    assert_eq!(query(&mut m, "extra_out"), (Some(Value::I64(20)), 2), "cycle 3 had no extra");
    m.run_cycles(1);
    assert_eq!(query(&mut m, "list"), (Some(Value::F64s(vec![].into())), 4));
    assert_eq!(query(&mut m, "extra_out"), (Some(Value::I64(40)), 4));
}
