//! Building C and C++ skill libraries from tests, and small helpers.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Arc, Mutex};

use situate_core::{FnSkill, Io, PortSpec, SignalType, SkillDecl, SkillError, SkillKind, SkillType, Value};
use situate_manager::{ClockKind, Manager, Registry, RobotSpec};

/// The repository's root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../..").canonicalize().expect("repo root")
}

/// A fresh scratch directory for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("situate_cabi").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn run(cmd: &mut Command) -> String {
    let out = cmd.output().unwrap_or_else(|e| panic!("cannot run {cmd:?}: {e}"));
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "{cmd:?} failed:\n{text}");
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Runs `situate-gen lang manifest -o dir`.
pub fn gen(lang: &str, manifest: &Path, dir: &Path) {
    run(Command::new(env!("CARGO_BIN_EXE_situate-gen")).arg(lang).arg(manifest).arg("-o").arg(dir));
}

/// Compiles sources into a shared library with gcc (C) or g++ (C++), the
/// generated headers being in `dir`.
pub fn shared_lib(dir: &Path, name: &str, sources: &[(&str, &str)], cpp: bool) -> PathBuf {
    let mut files = Vec::new();
    for (file, text) in sources {
        let p = dir.join(file);
        std::fs::write(&p, text).expect("write source");
        files.push(p);
    }
    let out = dir.join(format!("lib{name}.so"));
    let mut cmd = Command::new(if cpp { "g++" } else { "gcc" });
    cmd.args(if cpp { ["-std=c++17", "-fvisibility=hidden"] } else { ["-std=c11", "-fvisibility=hidden"] })
        .args(["-O2", "-Wall", "-Wextra", "-Werror", "-Wno-unused-function", "-shared", "-fPIC"])
        .arg("-I")
        .arg(repo().join("include"))
        .arg("-I")
        .arg(dir)
        .args(&files)
        .arg("-o")
        .arg(&out)
        .arg("-lm");
    run(&mut cmd);
    out
}

/// A registry of skill types built from source in the scratch folder of `test`: each type
/// `(prefix, manifest after its name, "c" | "cpp")` has its header generated (its name: the
/// prefix with its first `_` a `.`, `c_x` → `c.x`), then each library `(name, file, source,
/// cpp)` is compiled and every type it exports registered.
pub fn registry_of(test: &str, types: &[(&str, &str, &str)], libs: &[(&str, &str, &str, bool)]) -> Registry {
    let dir = scratch(test);
    for (prefix, manifest, lang) in types {
        let path = dir.join(format!("{prefix}.yaml"));
        std::fs::write(&path, format!("name: {}\n{manifest}", prefix.replacen('_', ".", 1))).expect("write manifest");
        gen(lang, &path, &dir);
    }
    let mut r = Registry::new();
    for (name, file, source, cpp) in libs {
        let lib = shared_lib(&dir, name, &[(file, source)], *cpp);
        for t in situate_cabi::load_library(&lib).expect("load") {
            r.add(t);
        }
    }
    r
}

/// Compiles and runs a program (C or C++), returning its standard output.
pub fn run_program(dir: &Path, name: &str, source: &str, cpp: bool) -> String {
    let src = dir.join(if cpp { format!("{name}.cpp") } else { format!("{name}.c") });
    std::fs::write(&src, source).expect("write source");
    let exe = dir.join(name);
    let mut cmd = Command::new(if cpp { "g++" } else { "gcc" });
    cmd.args(if cpp { ["-std=c++17"] } else { ["-std=c11"] })
        .args(["-Wall", "-Werror", "-Wno-unused-function", "-Wno-unused-variable"])
        .arg("-I")
        .arg(repo().join("include"))
        .arg("-I")
        .arg(dir)
        .arg(&src)
        .arg("-o")
        .arg(&exe);
    run(&mut cmd);
    run(&mut Command::new(&exe))
}

/// Builds an example (`examples/<lang>/<name>`) with CMake through the
/// situate package, returning the built library.
pub fn cmake_example(lang: &str, name: &str, lib: &str) -> PathBuf {
    let build = scratch(&format!("cmake_{lang}_{name}"));
    let src = repo().join("examples").join(lang).join(name);
    run(Command::new("cmake")
        .arg("-S")
        .arg(&src)
        .arg("-B")
        .arg(&build)
        .arg(format!("-DCMAKE_PREFIX_PATH={}", repo().join("cmake").display()))
        .arg(format!("-DSITUATE_GEN={}", env!("CARGO_BIN_EXE_situate-gen")))
        .arg("-DCMAKE_BUILD_TYPE=Release"));
    run(Command::new("cmake").arg("--build").arg(&build));
    let out = build.join(format!("lib{lib}.so"));
    assert!(out.exists(), "{} was not built", out.display());
    out
}

pub fn ty(text: &str) -> SignalType {
    SignalType::parse(text).expect("type")
}

/// A skill type whose body is a closure over the raw ports.
pub fn fn_type<F>(d: SkillDecl, body: F) -> SkillType
where
    F: Fn(&mut Io<'_>, &[Value]) -> Result<(), SkillError> + Clone + Send + Sync + 'static,
{
    let decl = d.clone();
    SkillType::new(d, move || {
        let body = body.clone();
        Ok(Box::new(FnSkill::new(&decl, move |io: &mut Io<'_>, params: &[Value]| body(io, params))) as _)
    })
}

/// A source writing `f(cycle)` to `out` (signal `signal`) every cycle.
pub fn source(name: &str, out_ty: &str, signal: &str, f: impl Fn(u64) -> Value + Send + Sync + 'static) -> SkillType {
    let mut d = SkillDecl::new(name, SkillKind::Sync);
    d.outputs.push(PortSpec::new("out", ty(out_ty)).signal(signal));
    let f = Arc::new(f);
    fn_type(d, move |io, _| {
        io.outputs[0] = Some(f(io.cx.cycle()));
        Ok(())
    })
}

pub type Log<T> = Arc<Mutex<Vec<T>>>;

pub fn simulated(robot: &str) -> RobotSpec {
    RobotSpec::new(robot).clock(ClockKind::Simulated).period_s(0.01)
}

pub fn build(spec: &RobotSpec, registry: &Registry) -> Manager {
    match Manager::build(spec, registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

/// The faults reported so far: (skill, cause, cycle).
pub fn faults(events: &crossbeam_channel::Receiver<situate_manager::Event>) -> Vec<(String, String, u64)> {
    events
        .try_iter()
        .filter_map(|e| match e {
            situate_manager::Event::SkillFaulted { skill, cause, cycle } => Some((skill, cause, cycle)),
            _ => None,
        })
        .collect()
}
