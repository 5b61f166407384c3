//! Loading errors are clear and name the library's path; a declaration that
//! does not match a robot file's entry fails the build at the entry's line.

mod common;

use std::path::Path;

use common::*;
use situate_cabi::{load_library, LoadError};
use situate_core::Value;
use situate_manager::{Manager, Registry, RobotFile, RobotSpec};

/// A library whose entry returns a hand-made table.
fn raw_lib(name: &str, body: &str) -> std::path::PathBuf {
    let dir = scratch(name);
    shared_lib(&dir, name, &[(&format!("{name}.c"), &format!("#include <situate.h>\n{body}\n"))], false)
}

const STEP: &str =
    "static situate_status step(void* s, const void* i, void* o, const void* p, situate_context* cx) {\n\
    (void)s; (void)i; (void)o; (void)p; (void)cx; return SITUATE_OK;\n}\n";

/// A hand-made table for a manifest whose inputs are `{x: f64}` (or that does not parse): the
/// inputs struct is `inputs_size` bytes, the field tables say what a compiler would.
fn table(manifest: &str, inputs_size: &str) -> String {
    format!(
        "{STEP}static const situate_field fin[] = {{{{ \"x\", SITUATE_FIELD_F64, 1, 0, 8 }}}};\n\
         static const situate_field fnone[] = {{{{ \"_situate_empty\", SITUATE_FIELD_BOOL, 1, 0, 1 }}}};\n\
         static const situate_skill_type types[] = {{{{ \"{manifest}\", {inputs_size}, 1, 1, 1, 1, NULL, NULL, step, NULL, \
         fin, fnone, fnone, 1, 1, 1, NULL, NULL, NULL }}}};\n\
         static const situate_library lib = {{ SITUATE_ABI_VERSION, sizeof(situate_skill_type), 1, types }};\n\
         SITUATE_EXPORT const situate_library* situate_library_entry(void) {{ return &lib; }}"
    )
}

#[test]
fn a_missing_file_is_named() {
    let e = load_library(Path::new("/nonexistent/libnothing.so")).unwrap_err();
    assert!(matches!(e, LoadError::Missing { .. }));
    assert_eq!(e.to_string(), "/nonexistent/libnothing.so: no such file");
}

#[test]
fn a_file_that_is_not_a_library_is_refused() {
    let dir = scratch("not_a_library");
    let path = dir.join("libtext.so");
    std::fs::write(&path, "robot: not a library\n").unwrap();
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::NotALibrary { .. }), "{e}");
    assert!(e.to_string().starts_with(&format!("{}: not a loadable shared library", path.display())), "{e}");
}

#[test]
fn a_library_without_the_entry_symbol_is_refused() {
    let path = raw_lib("nosymbol", "SITUATE_EXPORT int something_else(void);\nint something_else(void) { return 1; }");
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::MissingSymbol { .. }), "{e}");
    assert!(e.to_string().contains("does not export `situate_library_entry`"), "{e}");
    assert!(e.to_string().starts_with(&path.display().to_string()), "{e}");
}

#[test]
fn a_library_built_for_another_abi_version_is_refused() {
    let body = "static const situate_library lib = { 99, 0, 0, NULL };\n\
                SITUATE_EXPORT const situate_library* situate_library_entry(void);\n\
                const situate_library* situate_library_entry(void) { return &lib; }";
    let path = raw_lib("abi99", body);
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::AbiVersion { found: 99, expected: 2, .. }), "{e}");
    assert_eq!(
        e.to_string(),
        format!(
            "{}: built for ABI v99, this situate speaks v2: rebuild the library against this situate's headers",
            path.display()
        )
    );
}

#[test]
fn a_bad_manifest_is_reported_with_its_line() {
    let path = raw_lib("badmanifest", &table("name: c.bad\\ninputs: {x: f46}\\n", "8"));
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::Manifest { .. }), "{e}");
    let text = e.to_string();
    assert!(text.contains("skill type #0 (c.bad): manifest line 2, column 13: port `x`: unknown type `f46`"), "{text}");
}

#[test]
fn a_struct_size_that_differs_from_the_manifest_is_a_layout_mismatch() {
    let path = raw_lib("badlayout", &table("name: c.t\\ninputs: {x: f64}\\n", "4"));
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::Layout { .. }), "{e}");
    assert!(
        e.to_string()
            .contains("skill `c.t`: layout mismatch: sizeof(c_t_inputs) is 4 in the library, 8 from its manifest"),
        "{e}"
    );
    // The same table with the right size loads.
    let good = raw_lib("goodlayout", &table("name: c.t\\ninputs: {x: f64}\\n", "8"));
    let types = load_library(&good).expect("loads");
    assert_eq!(types[0].decl.type_name, "c.t");
}

fn runaway_registry() -> Registry {
    let dir = scratch("robot_mismatch");
    let manifest = repo().join("examples/c/runaway/runaway.yaml");
    gen("c", &manifest, &dir);
    let src = std::fs::read_to_string(repo().join("examples/c/runaway/runaway.c")).unwrap();
    let lib = shared_lib(&dir, "c_runaway", &[("runaway.c", &src)], false);
    let mut r = Registry::new();
    for t in load_library(&lib).unwrap() {
        r.add(t);
    }
    r.add(source("test.sonar", "f32[24]", "sonar.range", |_| Value::F32s(vec![1.0; 24].into())));
    r.add(source("test.sonar64", "f64[24]", "sonar.range", |_| Value::F64s(vec![1.0; 24].into())));
    r
}

fn build_file(text: &str, r: &Registry) -> Result<(), String> {
    let file = RobotFile::parse("robot.yaml", text).map_err(|e| format!("{e:?}"))?;
    Manager::build(&RobotSpec::from_file(&file), r).map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn a_robot_file_entry_that_does_not_match_the_declaration_fails_at_its_line() {
    let r = runaway_registry();
    let ok = "robot: t\ncycle: {clock: simulated}\nskills:\n  - name: sonar\n    type: test.sonar\n  - name: runaway\n    type: c.runaway\n    params: {safe_distance: 1.0}\n";
    build_file(ok, &r).expect("a matching entry builds");
    let typo = ok.replace("safe_distance: 1.0", "safe_distanse: 1.0");
    let e = build_file(&typo, &r).unwrap_err();
    assert!(e.contains("robot.yaml:8:") && e.contains("safe_distanse"), "{e}");
    assert!(e.contains("safe_distance"), "the message suggests the declared name: {e}");
    let range = ok.replace("safe_distance: 1.0", "safe_distance: 7.0");
    let e = build_file(&range, &r).unwrap_err();
    assert!(e.contains("robot.yaml:8:") && e.contains("[0.1, 3.0]"), "{e}");
    let wrong_type = ok.replace("type: test.sonar", "type: test.sonar64");
    let e = build_file(&wrong_type, &r).unwrap_err();
    // Line 6 is the consuming entry's `name: runaway`.
    assert!(e.starts_with("robot.yaml:6:") && e.contains("`runaway` (input `sonar`) expects f32[24]"), "{e}");
}

/// Builds a library for manifest `{x: i64, y: f64}` from its generated header, edited by `edit`
/// as a user might edit it (the header says "Do not edit"; a hand-written struct is the same).
fn edited_lib(name: &str, edit: impl Fn(String) -> String) -> std::path::PathBuf {
    let dir = scratch(name);
    let manifest = dir.join("wf.yaml");
    std::fs::write(&manifest, "name: c.wf\ninputs: {x: i64, y: f64}\noutputs: {z: f64}\n").unwrap();
    gen("c", &manifest, &dir);
    let header = dir.join("c_wf.h");
    let text = std::fs::read_to_string(&header).unwrap();
    std::fs::write(&header, edit(text)).unwrap();
    let src = "#include \"c_wf.h\"\nstruct c_wf_state { int unused; };\n\
               situate_status c_wf_step(c_wf_state* s, const c_wf_inputs* in, c_wf_outputs* out,\n\
               const c_wf_params* p, situate_context* cx) {\n\
               (void)s; (void)p; (void)cx; out->has_z = true; out->z = (double)in->x + in->y; return SITUATE_OK;\n}\n\
               SITUATE_LIBRARY(SITUATE_SKILL(c_wf))\n";
    shared_lib(&dir, name, &[("wf.c", src)], false)
}

#[test]
fn a_struct_of_the_right_size_with_a_wrong_field_type_is_refused_by_field() {
    // It once loaded and the skill read the i64 input's bits as a double (1.023e-321).
    let path = edited_lib("wrongfield", |h| h.replacen("    int64_t x;", "    double x;", 1));
    let e = load_library(&path).unwrap_err();
    assert!(matches!(e, LoadError::Layout { .. }), "{e}");
    assert!(
        e.to_string().contains(
            "skill `c.wf`: layout mismatch: `c_wf_inputs` field #0: the manifest says `x` int64_t at offset 0 \
             (8 bytes), the library has `x` double at offset 0 (8 bytes)"
        ),
        "{e}"
    );
    // The header as generated loads.
    let good = edited_lib("rightfield", |h| h);
    assert_eq!(load_library(&good).expect("loads")[0].decl.type_name, "c.wf");
}

#[test]
fn fields_of_the_right_types_in_another_order_are_refused() {
    let path =
        edited_lib("reordered", |h| {
            h.replacen("    int64_t x;", "    double y_tmp;", 1)
                .replacen("    double y;", "    int64_t x;", 1)
                .replacen("    double y_tmp;", "    double y;", 1)
        });
    let e = load_library(&path).unwrap_err();
    assert!(
        e.to_string().contains(
            "`c_wf_inputs` field #0: the manifest says `x` int64_t at offset 0 (8 bytes), the library has `x` \
             int64_t at offset 8 (8 bytes)"
        ),
        "{e}"
    );
}

#[test]
fn a_library_without_field_tables_is_refused() {
    let body = format!(
        "{STEP}static const situate_skill_type types[] = {{ {{ \"name: c.t\\ninputs: {{x: f64}}\\n\", 8, 1, 1, 1, 1, \
         NULL, NULL, step, NULL, NULL, NULL, NULL, 0, 0, 0, NULL, NULL, NULL }} }};\n\
         static const situate_library lib = {{ SITUATE_ABI_VERSION, sizeof(situate_skill_type), 1, types }};\n\
         SITUATE_EXPORT const situate_library* situate_library_entry(void) {{ return &lib; }}"
    );
    let e = load_library(&raw_lib("nofields", &body)).unwrap_err();
    assert!(e.to_string().contains("the library gives no field table for `c_t_inputs`"), "{e}");
}
