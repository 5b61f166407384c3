//! `situate-gen` as a program: its errors (naming the manifest and the line),
//! and Python refused with the reason (the C and C++ files it writes are
//! compiled by the other tests).

mod common;

use std::process::Command;

use common::*;

#[test]
fn python_is_refused_with_the_reason() {
    let dir = scratch("gen_python");
    let manifest = repo().join("examples/c/runaway/runaway.yaml");
    let out = Command::new(env!("CARGO_BIN_EXE_situate-gen"))
        .arg("python")
        .arg(&manifest)
        .arg("-o")
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("nothing is generated for Python") && err.contains("@situate.skill"), "{err}");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0, "nothing written");
}

#[test]
fn errors_name_the_manifest_and_exit_non_zero() {
    let dir = scratch("gen_errors");
    let bad = dir.join("bad.yaml");
    std::fs::write(&bad, "name: c.bad\ninputs:\n  x: f64\n  y: f46\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_situate-gen")).arg("c").arg(&bad).arg("-o").arg(&dir).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("{}: line 4, column 6: port `y`: unknown type `f46`", bad.display())), "{err}");
    assert!(!dir.join("c_bad.h").exists(), "nothing written");
    let out = Command::new(env!("CARGO_BIN_EXE_situate-gen")).arg("fortran").arg(&bad).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown language `fortran`"));
}
