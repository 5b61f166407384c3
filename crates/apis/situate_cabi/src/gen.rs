//! `situate gen c|cpp MANIFEST`: typed I/O for a skill from its manifest, so
//! its author writes only the body.
//!
//! - C: `<prefix>.h` with `<prefix>_inputs`, `<prefix>_outputs` (a `has_`
//!   flag per output), `<prefix>_params`, `<prefix>_manifest`, and the glue
//!   from the generic ABI to `<prefix>_step(...)` that the author writes;
//! - C++: `<prefix>.hpp` with the same structs in `namespace <prefix>` and
//!   a base class `<prefix>::Skill` naming them for `situate.hpp`.
//!
//! The structs follow [`crate::layout`] field by field. Nothing is generated
//! for Python: a Python skill declares its ports in Python (`@situate.skill`,
//! `@situate.remote_skill`), so a manifest is never its source.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use situate_core::{ElemType, SkillDecl};

use crate::layout::{elem_c, Field, FieldKind, SkillLayout, StructLayout};
use crate::manifest::{parse_manifest, ManifestError};

/// A language the generator writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Lang {
    C,
    Cpp,
}

impl Lang {
    /// `c`, `cpp` (or `c++`, `cxx`).
    pub fn parse(text: &str) -> Option<Lang> {
        match text {
            "c" => Some(Lang::C),
            "cpp" | "c++" | "cxx" => Some(Lang::Cpp),
            _ => None,
        }
    }

    /// Why `text` names no language [`Lang::parse`] knows (Python: why none is generated).
    pub fn unknown(text: &str) -> String {
        match text {
            "python" | "py" => "nothing is generated for Python: a Python skill declares its ports in Python \
                                (`@situate.skill`, `@situate.remote_skill`; docs/python.md); gen writes c or cpp"
                .to_string(),
            _ => format!("unknown language `{text}` (c or cpp)"),
        }
    }
}

/// One generated file: a name relative to the output directory, and text.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GeneratedFile {
    pub path: PathBuf,
    pub contents: String,
}

/// Why nothing was generated.
#[derive(Debug, thiserror::Error)]
pub enum GenError {
    #[error("{path}: cannot read the manifest: {source}")]
    Read { path: String, source: std::io::Error },
    #[error("{path}: {source}")]
    Manifest { path: String, source: ManifestError },
    #[error("{path}: skill `{skill}`: {message}")]
    Layout { path: String, skill: String, message: String },
    #[error("{path}: cannot write: {source}")]
    Write { path: String, source: std::io::Error },
}

/// Writes generated files into `dir` (created if needed) and returns their
/// paths. A file whose contents are unchanged is left alone, so build
/// systems do not rebuild.
pub fn write_generated(files: &[GeneratedFile], dir: &Path) -> Result<Vec<PathBuf>, GenError> {
    let write_err = |path: &Path, source| GenError::Write { path: path.display().to_string(), source };
    std::fs::create_dir_all(dir).map_err(|e| write_err(dir, e))?;
    let mut written = Vec::new();
    for f in files {
        let path = dir.join(&f.path);
        if !std::fs::read_to_string(&path).is_ok_and(|old| old == f.contents) {
            std::fs::write(&path, &f.contents).map_err(|e| write_err(&path, e))?;
        }
        written.push(path);
    }
    Ok(written)
}

/// Generates the files of `lang` for the manifest at `manifest_path`.
pub fn generate(lang: Lang, manifest_path: &Path) -> Result<Vec<GeneratedFile>, GenError> {
    let path = manifest_path.display().to_string();
    let text =
        std::fs::read_to_string(manifest_path).map_err(|source| GenError::Read { path: path.clone(), source })?;
    generate_text(lang, &text, &path)
}

/// Generates from a manifest's text; `origin` names it in messages.
pub fn generate_text(lang: Lang, text: &str, origin: &str) -> Result<Vec<GeneratedFile>, GenError> {
    let decl = parse_manifest(text).map_err(|source| GenError::Manifest { path: origin.to_string(), source })?;
    let layout = SkillLayout::of(&decl).map_err(|message| GenError::Layout {
        path: origin.to_string(),
        skill: decl.type_name.clone(),
        message,
    })?;
    let origin_name = Path::new(origin).file_name().map_or(origin.to_string(), |n| n.to_string_lossy().into_owned());
    let (ext, contents) = match lang {
        Lang::C => ("h", c_header(&decl, &layout, text, &origin_name)),
        Lang::Cpp => ("hpp", cpp_header(&decl, &layout, text, &origin_name)),
    };
    Ok(vec![GeneratedFile { path: PathBuf::from(format!("{}.{ext}", layout.prefix)), contents }])
}

/// A C (and C++) string literal, one source line per manifest line.
fn c_string(text: &str) -> String {
    let mut out = String::from("\"");
    for (i, b) in text.bytes().enumerate() {
        match b {
            b'\\' => out.push_str("\\\\"),
            b'"' => out.push_str("\\\""),
            b'\n' if i + 1 < text.len() => out.push_str("\\n\"\n    \""),
            b'\n' => out.push_str("\\n"),
            b'\t' => out.push_str("\\t"),
            b'?' => out.push_str("\\?"), // no trigraphs
            0x20..=0x7e => out.push(b as char),
            _ => {
                let _ = write!(out, "\\{b:03o}");
            }
        }
    }
    out.push('"');
    out
}

fn slice_c(elem: ElemType) -> &'static str {
    match elem {
        ElemType::F32 => "situate_f32_slice",
        ElemType::F64 => "situate_f64_slice",
        ElemType::I64 => "situate_i64_slice",
    }
}

/// `type name` (with `[N]` for fixed arrays) of a field; `record` names a
/// nested struct type.
fn c_field(f: &Field, record: &dyn Fn(&str) -> String) -> String {
    match &f.kind {
        FieldKind::Flag | FieldKind::Bool => format!("bool {}", f.name),
        FieldKind::I64 => format!("int64_t {}", f.name),
        FieldKind::F64 => format!("double {}", f.name),
        FieldKind::Str => format!("situate_str {}", f.name),
        FieldKind::Bytes => format!("situate_bytes {}", f.name),
        FieldKind::Fixed { elem, len } => format!("{} {}[{len}]", elem_c(*elem), f.name),
        FieldKind::Var { elem } => format!("{} {}", slice_c(*elem), f.name),
        FieldKind::Record { c_name, .. } => format!("{} {}", record(c_name), f.name),
    }
}

/// Every record struct, innermost first, each once.
fn records<'a>(layout: &'a StructLayout, out: &mut Vec<(&'a str, &'a StructLayout)>) {
    for f in &layout.fields {
        if let FieldKind::Record { c_name, layout } = &f.kind {
            records(layout, out);
            if !out.iter().any(|(n, _)| n == c_name) {
                out.push((c_name, layout));
            }
        }
    }
}

fn all_records(l: &SkillLayout) -> Vec<(&str, &StructLayout)> {
    let mut out = Vec::new();
    records(&l.inputs, &mut out);
    records(&l.outputs, &mut out);
    out
}

fn port_comment(decl: &SkillDecl, f: &Field, outputs: bool) -> String {
    let ports = if outputs { &decl.outputs } else { &decl.inputs };
    match ports.iter().find(|p| *p.name == *f.name) {
        Some(p) => {
            let opt = if p.optional { ", optional" } else { "" };
            let doc = if p.doc.is_empty() { String::new() } else { format!(": {}", p.doc) };
            format!(" /* {}{opt} (signal `{}`){doc} */", p.ty, p.signal)
        }
        None if f.name.starts_with("has_") => " /* set when present */".to_string(),
        None => String::new(),
    }
}

fn param_comment(decl: &SkillDecl, f: &Field) -> String {
    match decl.param(&f.name) {
        Some((_, p)) => {
            let unit = if p.unit.is_empty() { String::new() } else { format!(" {}", p.unit) };
            format!(" /* {}, default {}{unit}: {} */", p.ty.name(), p.default, p.expectation())
        }
        None => String::new(),
    }
}

fn c_struct(out: &mut String, name: &str, layout: &StructLayout, comment: &dyn Fn(&Field) -> String) {
    let _ = writeln!(out, "typedef struct {name} {{");
    for f in &layout.fields {
        let _ = writeln!(out, "    {};{}", c_field(f, &|n| n.to_string()), comment(f));
    }
    let _ = writeln!(out, "}} {name};\n");
}

fn c_header(decl: &SkillDecl, l: &SkillLayout, text: &str, origin: &str) -> String {
    let p = &l.prefix;
    let guard = format!("SITUATE_GEN_{}_H", p.to_ascii_uppercase());
    let mut o = String::new();
    let _ = writeln!(o, "/* Generated by situate-gen from {origin}: skill `{}`. Do not edit. */", decl.type_name);
    let _ = writeln!(o, "#ifndef {guard}\n#define {guard}\n\n#include <situate.h>\n");
    let _ = writeln!(o, "#ifdef __cplusplus\nextern \"C\" {{\n#endif\n");
    for (name, layout) in all_records(l) {
        c_struct(&mut o, name, layout, &|_| String::new());
    }
    c_struct(&mut o, &format!("{p}_inputs"), &l.inputs, &|f| port_comment(decl, f, false));
    c_struct(&mut o, &format!("{p}_outputs"), &l.outputs, &|f| port_comment(decl, f, true));
    c_struct(&mut o, &format!("{p}_params"), &l.params, &|f| param_comment(decl, f));
    for (i, param) in decl.params.iter().enumerate() {
        let _ = writeln!(o, "#define {}_PARAM_{} {i}u", p.to_ascii_uppercase(), param.name.to_ascii_uppercase());
    }
    let _ = writeln!(o, "/* Every field as the compiler lays it out, checked by the host against the manifest. */");
    for (what, layout) in [("inputs", &l.inputs), ("outputs", &l.outputs), ("params", &l.params)] {
        let ty = format!("{p}_{what}");
        let _ = writeln!(o, "static const situate_field {ty}_fields[] = {{");
        field_table(&mut o, &ty, &format!("((const {ty}*)0)"), layout);
        let _ = writeln!(o, "}};");
    }
    let _ = writeln!(o, "\n/* The manifest this header was generated from. */");
    let _ = writeln!(o, "static const char {p}_manifest[] =\n    {};\n", c_string(text));
    let _ = writeln!(
        o,
        "/* You write: the state (any struct, zeroed before use) and the body. */\n\
         typedef struct {p}_state {p}_state;\n\
         situate_status {p}_step({p}_state* state, const {p}_inputs* in, {p}_outputs* out,\n    \
         const {p}_params* params, situate_context* cx);\n\n\
         /* With SITUATE_SKILL_HOOKS({p}) you also write these. */\n\
         situate_status {p}_init({p}_state* state, const {p}_params* params, situate_error* error);\n\
         void {p}_fini({p}_state* state);\n\
         situate_status {p}_set_param({p}_state* state, uint32_t index, const {p}_params* params,\n    \
         situate_error* error);\n\n\
         /* With SITUATE_SKILL_ALL_HOOKS({p}) you write all five; with SITUATE_SKILL_WITH({p}, init, fini,\n   \
         set_param, activate, deactivate) the ones you name (`{p}__activate`, ...; NULL for the others).\n   \
         activate: the skill was switched on; called once before its first step after that (an error\n   \
         status, `situate_fail(cx, ...)`, faults the skill). deactivate: it was switched off (by the\n   \
         sequencer or a fault); called once after its last step (an error status is only a warning).\n   \
         Both on the thread that runs the step; not at shutdown (then only fini). */\n\
         situate_status {p}_activate({p}_state* state, const {p}_params* params, situate_context* cx);\n\
         situate_status {p}_deactivate({p}_state* state, const {p}_params* params, situate_context* cx);\n\n\
         /* With SITUATE_SKILL_WITH_RESOURCES({p}, ...) you write this instead of {p}_init: the state made\n   \
         with the resources the program provides (`situate_resource(resources, \"bus\")`; a missing one:\n   \
         `return situate_missing_resource(error, \"bus\");`). */\n\
         situate_status {p}_init_with({p}_state* state, const {p}_params* params,\n    \
         const situate_resources* resources, situate_error* error);\n"
    );
    let _ = writeln!(
        o,
        "/* Glue from the generic ABI to your functions (used by SITUATE_SKILL). */\n\
         static inline situate_status {p}__step(void* s, const void* i, void* o, const void* p, situate_context* cx) {{\n    \
         return {p}_step(({p}_state*)s, (const {p}_inputs*)i, ({p}_outputs*)o, (const {p}_params*)p, cx);\n}}\n\
         static inline situate_status {p}__init(void* s, const void* p, situate_error* e) {{\n    \
         return {p}_init(({p}_state*)s, (const {p}_params*)p, e);\n}}\n\
         static inline void {p}__fini(void* s) {{\n    {p}_fini(({p}_state*)s);\n}}\n\
         static inline situate_status {p}__set_param(void* s, uint32_t i, const void* p, situate_error* e) {{\n    \
         return {p}_set_param(({p}_state*)s, i, (const {p}_params*)p, e);\n}}\n\
         static inline situate_status {p}__activate(void* s, const void* p, situate_context* cx) {{\n    \
         return {p}_activate(({p}_state*)s, (const {p}_params*)p, cx);\n}}\n\
         static inline situate_status {p}__deactivate(void* s, const void* p, situate_context* cx) {{\n    \
         return {p}_deactivate(({p}_state*)s, (const {p}_params*)p, cx);\n}}\n\
         static inline situate_status {p}__init_with(void* s, const void* p, const situate_resources* r,\n    \
         situate_error* e) {{\n    \
         return {p}_init_with(({p}_state*)s, (const {p}_params*)p, r, e);\n}}\n"
    );
    let _ = writeln!(o, "#ifdef __cplusplus\n}}\n#endif\n\n#endif /* {guard} */");
    o
}

/// The entries of a field table: name, `SITUATE_FIELD_CODE` of the member
/// (of its first element for a fixed array), element count, offset, size;
/// `null` is `ty` as a null pointer expression (never evaluated).
fn field_table(o: &mut String, ty: &str, null: &str, layout: &StructLayout) {
    for f in layout.flat() {
        let n = &f.name;
        let (code, count) = if f.fixed {
            (
                format!("SITUATE_FIELD_CODE({null}->{n}[0])"),
                format!("(uint32_t)(sizeof({null}->{n}) / sizeof({null}->{n}[0]))"),
            )
        } else {
            (format!("SITUATE_FIELD_CODE({null}->{n})"), "1".to_string())
        };
        let _ = writeln!(o, "    {{\"{n}\", {code}, {count}, offsetof({ty}, {n}), sizeof({null}->{n})}},");
    }
}

fn cpp_record_name(prefix: &str, c_name: &str) -> String {
    format!("{}_t", c_name.strip_prefix(prefix).unwrap_or(c_name).trim_start_matches('_'))
}

fn cpp_struct(out: &mut String, name: &str, layout: &StructLayout, prefix: &str, comment: &dyn Fn(&Field) -> String) {
    let _ = writeln!(out, "struct {name} {{");
    for f in &layout.fields {
        let _ = writeln!(out, "    {};{}", c_field(f, &|n| cpp_record_name(prefix, n)), comment(f));
    }
    let _ = writeln!(out, "}};\n");
}

fn cpp_header(decl: &SkillDecl, l: &SkillLayout, text: &str, origin: &str) -> String {
    let p = &l.prefix;
    let mut o = String::new();
    let _ = writeln!(o, "// Generated by situate-gen from {origin}: skill `{}`. Do not edit.", decl.type_name);
    let _ = writeln!(o, "#pragma once\n\n#include <situate.hpp>\n\nnamespace {p} {{\n");
    for (name, layout) in all_records(l) {
        cpp_struct(&mut o, &cpp_record_name(p, name), layout, p, &|_| String::new());
    }
    cpp_struct(&mut o, "Inputs", &l.inputs, p, &|f| port_comment(decl, f, false));
    cpp_struct(&mut o, "Outputs", &l.outputs, p, &|f| port_comment(decl, f, true));
    cpp_struct(&mut o, "Params", &l.params, p, &|f| param_comment(decl, f));
    let _ = writeln!(o, "/// Parameter indices, as `on_param` receives them.\nnamespace param {{");
    for (i, param) in decl.params.iter().enumerate() {
        let _ = writeln!(o, "inline constexpr uint32_t {} = {i};", param.name);
    }
    let _ = writeln!(o, "}}  // namespace param\n");
    let _ = writeln!(
        o,
        "/// The manifest this header was generated from.\ninline constexpr char manifest[] =\n    {};\n",
        c_string(text)
    );
    let _ = writeln!(o, "/// Every field as the compiler lays it out, checked by the host against the manifest.");
    for (what, name, layout) in
        [("inputs", "Inputs", &l.inputs), ("outputs", "Outputs", &l.outputs), ("params", "Params", &l.params)]
    {
        let _ = writeln!(o, "inline const situate_field {what}_field_table[] = {{");
        field_table(&mut o, name, &format!("static_cast<const {name}*>(nullptr)"), layout);
        let _ = writeln!(o, "}};");
    }
    let _ = writeln!(o);
    let _ = writeln!(
        o,
        "/// Derive your skill class from this; it names the types `situate.hpp` needs.\n\
         ///\n\
         /// ```cpp\n\
         /// class MySkill : public {p}::Skill {{\n\
         ///  public:\n\
         ///   explicit MySkill(const Params& params);  // optional (else default-constructed)\n\
         ///   void step(const Inputs& in, Outputs& out, const Params& params, situate::Context& cx);\n\
         ///   void on_param(uint32_t index, const Params& params);  // optional\n\
         ///   void on_activate(const Params& params, situate::Context& cx);  // optional; or on_activate(cx)\n\
         ///   void on_deactivate(const Params& params, situate::Context& cx);  // optional; or on_deactivate(cx)\n\
         /// }};\n\
         /// SITUATE_CPP_LIBRARY(MySkill)\n\
         /// ```\n\
         /// `on_activate`: the skill was switched on, before its first `step` after that; `on_deactivate`:\n\
         /// it was switched off, after its last `step` (both on the thread that runs `step`; not at shutdown).\n\
         /// Throwing from any of them faults the skill with the exception's `what()` (from `on_deactivate`:\n\
         /// a warning only, the skill is off anyway).\n\
         struct Skill {{\n    \
         using Inputs = {p}::Inputs;\n    \
         using Outputs = {p}::Outputs;\n    \
         using Params = {p}::Params;\n    \
         static const char* manifest() {{ return {p}::manifest; }}\n    \
         static const situate_field* inputs_fields() {{ return {p}::inputs_field_table; }}\n    \
         static const situate_field* outputs_fields() {{ return {p}::outputs_field_table; }}\n    \
         static const situate_field* params_fields() {{ return {p}::params_field_table; }}\n    \
         static std::uint32_t inputs_field_count() {{ return static_cast<std::uint32_t>(std::size({p}::inputs_field_table)); }}\n    \
         static std::uint32_t outputs_field_count() {{ return static_cast<std::uint32_t>(std::size({p}::outputs_field_table)); }}\n    \
         static std::uint32_t params_field_count() {{ return static_cast<std::uint32_t>(std::size({p}::params_field_table)); }}\n\
         }};\n\n\
         }}  // namespace {p}"
    );
    o
}

#[cfg(test)]
mod tests {
    use super::*;

    const MANIFEST: &str =
        "name: c.t\ninputs: {x: f64, pose: \"{x: f64, y: f64}\"}\noutputs: {y: f64}\nparams:\n  gain: 2.0\n";

    #[test]
    fn c_header_names_structs_after_the_prefix() {
        let files = generate_text(Lang::C, MANIFEST, "t.yaml").unwrap();
        assert_eq!(files[0].path, PathBuf::from("c_t.h"));
        let h = &files[0].contents;
        for needle in [
            "typedef struct c_t_pose {\n    double x;\n    double y;\n} c_t_pose;",
            "    c_t_pose pose;",
            "    bool has_y;",
            "    double gain;",
            "#define C_T_PARAM_GAIN 0u",
            "situate_status c_t_step(c_t_state* state",
            "situate_status c_t_activate(c_t_state* state, const c_t_params* params, situate_context* cx);",
            "situate_status c_t_deactivate(c_t_state* state, const c_t_params* params, situate_context* cx);",
            "static inline situate_status c_t__activate(void* s, const void* p, situate_context* cx) {",
            "static inline situate_status c_t__deactivate(void* s, const void* p, situate_context* cx) {",
        ] {
            assert!(h.contains(needle), "missing {needle:?} in\n{h}");
        }
    }

    #[test]
    fn cpp_header_documents_the_optional_members() {
        let files = generate_text(Lang::Cpp, MANIFEST, "t.yaml").unwrap();
        let h = &files[0].contents;
        for needle in [
            "void on_param(uint32_t index, const Params& params);  // optional",
            "void on_activate(const Params& params, situate::Context& cx);  // optional; or on_activate(cx)",
            "void on_deactivate(const Params& params, situate::Context& cx);  // optional; or on_deactivate(cx)",
        ] {
            assert!(h.contains(needle), "missing {needle:?} in\n{h}");
        }
    }

    #[test]
    fn strings_are_escaped_for_c() {
        assert_eq!(c_string("a: \"b\\\"\n"), "\"a: \\\"b\\\\\\\"\\n\"");
        assert_eq!(c_string("é"), "\"\\303\\251\"");
    }

    #[test]
    fn python_is_not_a_language_and_says_why() {
        assert_eq!(Lang::parse("python"), None);
        assert!(Lang::unknown("python").contains("@situate.skill"));
        assert_eq!(Lang::unknown("fortran"), "unknown language `fortran` (c or cpp)");
    }

    #[test]
    fn errors_name_the_manifest_and_line() {
        let e = generate_text(Lang::C, "name: c.t\ninputs: {int: f64}\n", "m.yaml").unwrap_err();
        assert_eq!(e.to_string(), "m.yaml: skill `c.t`: input `int` is a C/C++ keyword; rename it");
        let e = generate_text(Lang::C, "name: c.t\noutputs: {y: f46}\n", "m.yaml").unwrap_err();
        assert!(e.to_string().starts_with("m.yaml: line 2, column"), "{e}");
    }
}
