//! `situate-gen` as a program: the files it writes (C, C++ compile; Python
//! imports) and its errors (naming the manifest and the line).

mod common;

use std::process::Command;

use common::*;

#[test]
fn the_python_module_imports_and_its_dataclasses_have_the_defaults() {
    let dir = scratch("gen_python");
    gen("python", &repo().join("examples/c/runaway/runaway.yaml"), &dir);
    let script = "import sys\nsys.path.insert(0, sys.argv[1])\nimport c_runaway as m\n\
                  assert m.TYPE_NAME == 'c.runaway'\nassert m.Params().safe_distance == 0.5\n\
                  i = m.Inputs(sonar=m.Sonar(range=[1.0] * 24))\nassert m.Outputs().drive is None\n\
                  o = m.Outputs(drive=m.Drive(v=0.1, w=-0.2))\nprint(len(i.sonar.range), o.drive.w)\n";
    let out = Command::new("python3").arg("-c").arg(script).arg(&dir).output().expect("python3 runs");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "24 -0.2\n");
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
