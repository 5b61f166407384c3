//! What the program knows of skill types: `situate types` lists them,
//! `situate gen` writes a manifest's typed I/O for C or C++, and `situate
//! cmake-dir` says where the CMake package for C/C++ skills is.

use std::path::{Path, PathBuf};

use serde_json::{json, Value as Json};
use situate::manager::Registry;

use crate::output::{problem, Exit, Out, Problem};
use crate::Extensions;

/// `situate gen LANG MANIFEST -o DIR`: the files written, one per line (a JSON list under `--json`).
/// A file whose contents are unchanged is left alone (build systems do not rebuild); a manifest's
/// problems are said as `FILE:LINE:COL: error: …`.
pub(crate) fn generate(lang: &str, manifest: &Path, out_dir: &Path, out: Out) -> anyhow::Result<()> {
    let lang =
        situate_cabi::Lang::parse(lang).ok_or_else(|| problem(Exit::Usage, situate_cabi::Lang::unknown(lang)))?;
    let files = situate_cabi::generate(lang, manifest).map_err(|e| match e {
        situate_cabi::GenError::Manifest { source, .. } => Problem::bad_file(
            manifest,
            source
                .problems
                .iter()
                .map(|p| format!("{}:{}:{}: error: {}", manifest.display(), p.line, p.col, p.message))
                .collect(),
        ),
        other => Problem::file_problem(other.to_string()),
    })?;
    let written = situate_cabi::write_generated(&files, out_dir).map_err(|e| problem(Exit::Failure, e.to_string()))?;
    let written: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    out.result(&json!(written), || written.join("\n"));
    Ok(())
}

/// The CMake package's directory (`situateConfig.cmake`; the headers are in its `../include`):
/// the host's package data (the wheel ships `cmake/` and `include/`), else the checkout this
/// program was built from, if it is still there.
pub(crate) fn cmake_dir(ext: &Extensions) -> Option<PathBuf> {
    let checkout = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../cmake");
    ext.data_dir
        .iter()
        .map(|d| d.join("cmake"))
        .chain(std::iter::once(checkout))
        .chain(std::iter::once(crate::packaged_data().join("cmake")))
        .find(|d| d.join("situateConfig.cmake").is_file() && d.join("../include/situate.h").is_file())
        .map(|d| d.canonicalize().unwrap_or(d))
}

/// `situate cmake-dir` (or `situate --cmake-dir`): where `find_package(situate)` finds the
/// package, for `cmake -Dsituate_DIR="$(situate cmake-dir)"`. Under `--json`:
/// `{"cmake_dir", "include_dir", "config", "abi_version"}`.
pub(crate) fn print_cmake_dir(ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let dir = cmake_dir(ext).ok_or_else(|| {
        problem(
            Exit::Failure,
            "no CMake package found: this program has no package data and was not built in a checkout; \
             install the Python package (it ships cmake/ and include/) or use a checkout's cmake/",
        )
    })?;
    let include = dir.parent().map_or_else(|| dir.join("../include"), |p| p.join("include"));
    out.result(
        &json!({
            "cmake_dir": dir.display().to_string(),
            "include_dir": include.display().to_string(),
            "config": dir.join("situateConfig.cmake").display().to_string(),
            "abi_version": situate_cabi::abi::SITUATE_ABI_VERSION,
        }),
        || dir.display().to_string(),
    );
    Ok(())
}

/// The directory holding `demo/`, `maps/` and `examples/`: the host's package data (the wheel
/// ships them), else the checkout this program was built from, if it is still there, else the
/// data of the published crate.
pub(crate) fn data_dir(ext: &Extensions) -> Option<PathBuf> {
    let checkout = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../..");
    ext.data_dir
        .iter()
        .cloned()
        .chain([checkout, crate::packaged_data()])
        .find(|d| d.join("demo/robot.yaml").is_file() && d.join("maps").is_dir() && d.join("examples").is_dir())
        .map(|d| d.canonicalize().unwrap_or(d))
}

/// `situate data-dir`: where the demo, the maps and the examples are. Under `--json`:
/// `{"data_dir", "demo", "maps", "examples"}`.
pub(crate) fn print_data_dir(ext: &Extensions, out: Out) -> anyhow::Result<()> {
    let dir = data_dir(ext).ok_or_else(|| {
        problem(
            Exit::Failure,
            "no demo, maps or examples found: this program has no package data and was not built in a \
             checkout; install the Python package (it ships them) or use a checkout",
        )
    })?;
    out.result(
        &json!({
            "data_dir": dir.display().to_string(),
            "demo": dir.join("demo").display().to_string(),
            "maps": dir.join("maps").display().to_string(),
            "examples": dir.join("examples").display().to_string(),
        }),
        || dir.display().to_string(),
    );
    Ok(())
}

/// One skill type's declaration as JSON (`situate types --json`).
pub(crate) fn decl_json(d: &situate_core::SkillDecl) -> Json {
    json!({
        "name": d.type_name,
        "kind": d.kind.to_string(),
        "priority": d.priority,
        "doc": d.doc,
        "inputs": d.inputs.iter().map(|p| json!({"name": p.name, "type": p.ty.to_string(), "optional": p.optional})).collect::<Vec<_>>(),
        "outputs": d.outputs.iter().map(|p| json!({"name": p.name, "type": p.ty.to_string()})).collect::<Vec<_>>(),
        "params": d.params.iter().map(|p| json!({
            "name": p.name,
            "type": p.ty.name(),
            "default": situate_link::json::value_to_json(&p.default),
            "expects": p.expectation().to_string(),
        })).collect::<Vec<_>>(),
    })
}

/// `situate types`.
pub(crate) fn types(registry: &Registry, out: Out) {
    // The simulator's devices too: they are registered only for a robot file with a
    // `simulator:` section (they need its world), but a person choosing types needs to see them.
    let sim = situate_sim::declarations();
    let mut decls: Vec<&situate_core::SkillDecl> =
        registry.names().filter_map(|n| registry.get(n)).map(|t| &*t.decl).collect();
    decls.extend(sim.iter().filter(|d| registry.get(&d.type_name).is_none()));
    decls.sort_by(|a, b| a.type_name.cmp(&b.type_name));
    out.result(&Json::Array(decls.iter().map(|d| decl_json(d)).collect()), || {
        use std::fmt::Write as _;
        let mut text = String::new();
        for d in &decls {
            let _ = writeln!(text, "{} ({}, priority {})", d.type_name, d.kind, d.priority);
            for line in d.doc.lines() {
                let _ = writeln!(text, "    {line}");
            }
            for p in &d.inputs {
                let _ = writeln!(text, "    in  {}: {}{}", p.name, p.ty, if p.optional { " (optional)" } else { "" });
            }
            for p in &d.outputs {
                let _ = writeln!(text, "    out {}: {}", p.name, p.ty);
            }
            for p in &d.params {
                let _ = writeln!(text, "    param {}: {} = {} ({})", p.name, p.ty.name(), p.default, p.expectation());
            }
        }
        text.trim_end().to_string()
    });
}
