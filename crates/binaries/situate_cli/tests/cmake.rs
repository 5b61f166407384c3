//! C/C++ authors with the `situate` program alone: `situate cmake-dir` says
//! where the CMake package is, and that package builds a C skill with
//! `situate gen` when no `situate-gen` exists (the wheel's case).

mod common;

use std::path::Path;
use std::process::Command;

use common::*;

fn situate(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_situate")).args(args).env_remove("RUST_LOG").output().expect("situate runs")
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &to.join(entry.file_name()));
        } else {
            std::fs::copy(entry.path(), to.join(entry.file_name())).unwrap();
        }
    }
}

#[test]
fn cmake_dir_names_the_checkouts_package_as_text_and_json() {
    let out = situate(&["cmake-dir"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let dir = repo().join("cmake");
    assert_eq!(stdout(&out).trim(), dir.display().to_string());
    // The conventional spelling of such a query works too.
    assert_eq!(stdout(&situate(&["--cmake-dir"])).trim(), dir.display().to_string());
    let json: serde_json::Value = serde_json::from_str(&stdout(&situate(&["cmake-dir", "--json"]))).unwrap();
    assert_eq!(json["cmake_dir"], dir.display().to_string());
    assert_eq!(json["include_dir"], repo().join("include").display().to_string());
    assert_eq!(json["abi_version"], situate_cabi::abi::SITUATE_ABI_VERSION);
    // The CMake package's ABI version is the ABI's.
    let config = std::fs::read_to_string(dir.join("situateConfig.cmake")).unwrap();
    let line = format!("set(situate_ABI_VERSION {})", situate_cabi::abi::SITUATE_ABI_VERSION);
    assert!(config.contains(&line), "situateConfig.cmake does not say `{line}`");
}

#[test]
fn data_dir_names_the_checkout_holding_the_demo_maps_and_examples() {
    let out = situate(&["data-dir"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let dir = repo();
    assert_eq!(stdout(&out).trim(), dir.display().to_string());
    assert_eq!(stdout(&situate(&["--data-dir"])).trim(), dir.display().to_string());
    let json: serde_json::Value = serde_json::from_str(&stdout(&situate(&["data-dir", "--json"]))).unwrap();
    assert_eq!(json["data_dir"], dir.display().to_string());
    for part in ["demo", "maps", "examples"] {
        assert_eq!(json[part], dir.join(part).display().to_string());
    }
    assert!(dir.join("examples/toybot.yaml").is_file());
}

#[test]
fn a_c_skill_builds_with_the_situate_program_alone() {
    let tmp = tempfile::tempdir().unwrap();
    // The package laid out as the wheel ships it: cmake/ and include/ side by side, no checkout
    // around them (so no target/ with a situate-gen), and only `situate` on PATH.
    let data = tmp.path().join("_data");
    copy_dir(&repo().join("cmake"), &data.join("cmake"));
    copy_dir(&repo().join("include"), &data.join("include"));
    let source = tmp.path().join("runaway");
    copy_dir(&repo().join("examples/c/runaway"), &source);
    let bin = tmp.path().join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let program = bin.join("situate");
    std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_situate"), &program).unwrap();
    let path = format!("{}:/usr/local/bin:/usr/bin:/bin", bin.display());
    for dir in std::env::split_paths(&path) {
        assert!(!dir.join("situate-gen").exists(), "a situate-gen in {}", dir.display());
    }

    let build = tmp.path().join("build");
    let cmake = |args: &[&std::ffi::OsStr]| {
        let out = Command::new("cmake")
            .args(args)
            .env("PATH", &path)
            .env_remove("CARGO_TARGET_DIR")
            .env_remove("SITUATE_PROGRAM")
            .output()
            .expect("cmake runs");
        let text = format!("{}{}", stdout(&out), stderr(&out));
        assert!(out.status.success(), "cmake {args:?} failed:\n{text}");
        text
    };
    let configured = cmake(&[
        "-S".as_ref(),
        source.as_os_str(),
        "-B".as_ref(),
        build.as_os_str(),
        format!("-Dsituate_DIR={}", data.join("cmake").display()).as_ref(),
    ]);
    assert!(
        configured.contains(&format!("situate: C/C++ skill structs by `{} -q gen`", program.display())),
        "{configured}"
    );
    cmake(&["--build".as_ref(), build.as_os_str()]);
    assert!(build.join("c_runaway_situate/c_runaway.h").is_file());
    let lib = build.join("libc_runaway.so");

    // The library loads, and declares what its manifest says.
    let out = situate(&["types", "--library", &lib.display().to_string(), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let types: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    let runaway = types.as_array().unwrap().iter().find(|t| t["name"] == "c.runaway").expect("c.runaway");
    assert_eq!(runaway["params"][0]["name"], "safe_distance");
}

#[test]
fn the_manifests_in_the_docs_generate_and_compile() {
    let doc = std::fs::read_to_string(repo().join("docs/manifests.md")).unwrap();
    let blocks: Vec<&str> =
        doc.split("```yaml manifest\n").skip(1).map(|rest| rest.split("```").next().unwrap()).collect();
    assert!(!blocks.is_empty(), "docs/manifests.md has a `yaml manifest` block");
    let tmp = tempfile::tempdir().unwrap();
    for (i, block) in blocks.iter().enumerate() {
        let manifest = tmp.path().join(format!("m{i}.yaml"));
        std::fs::write(&manifest, block).unwrap();
        for lang in ["c", "cpp"] {
            let out = situate(&["gen", lang, &manifest.display().to_string(), "-o", &tmp.path().display().to_string()]);
            assert!(out.status.success(), "docs/manifests.md block {i}, {lang}:\n{}", stderr(&out));
            let header = stdout(&out).trim().to_string();
            let compiler = if lang == "c" { ["gcc", "-xc", "-std=c11"] } else { ["g++", "-xc++", "-std=c++17"] };
            run_ok(
                Command::new(compiler[0])
                    .args(&compiler[1..])
                    .arg("-fsyntax-only")
                    .arg("-I")
                    .arg(repo().join("include"))
                    .arg(&header),
            );
        }
    }
}
