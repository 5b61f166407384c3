//! The C and C++ runaway examples, built with CMake through the situate
//! package, agree bit for bit with a Rust reference over 1,000 cycles of
//! varying sonar input inside a real manager; switched off, each says how
//! many cycles it ran away since it was switched on (their lifecycle hooks).

mod common;

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use common::*;
use situate_core::{ParamSpec, ParamType, PortSpec, SkillDecl, SkillKind, Value};
use situate_manager::{Control, Registry, SkillSpec};

/// The two examples' libraries, built once for this test binary (its tests run at once).
fn libraries() -> &'static [PathBuf; 2] {
    static LIBRARIES: OnceLock<[PathBuf; 2]> = OnceLock::new();
    LIBRARIES
        .get_or_init(|| [cmake_example("c", "runaway", "c_runaway"), cmake_example("cpp", "runaway", "cpp_runaway")])
}

/// A registry with the C and C++ runaways and `test.sonar` writing [`sonar_at`] each cycle.
fn registry() -> Registry {
    let mut registry = Registry::new();
    for lib in libraries() {
        for t in situate_cabi::load_library(lib).expect("load") {
            registry.add(t);
        }
    }
    registry.add(source("test.sonar", "f32[24]", "sonar.range", |c| Value::F32s(Arc::from(&sonar_at(c)[..]))));
    registry
}

/// The runaway algorithm every language implements (see examples/*/runaway).
fn reference(range: &[f32], safe_distance: f64) -> Option<(f64, f64)> {
    let two_pi = 2.0 * std::f64::consts::PI;
    let (mut r_min, mut k) = (f64::from(*range.first()?), 0usize);
    for (i, r) in range.iter().enumerate().skip(1) {
        let r = f64::from(*r);
        if r < r_min {
            r_min = r;
            k = i;
        }
    }
    if r_min >= safe_distance {
        return None;
    }
    let a = if k <= 12 { k as f64 * two_pi / 24.0 } else { k as f64 * two_pi / 24.0 - two_pi };
    // `-1.0 * sin(a)` in the spec: negation is exact, so `-sin(a)` is the same bits.
    Some((-0.3 * a.cos() * (1.0 - r_min / safe_distance), -a.sin()))
}

/// Sonar ranges for a cycle: a drifting base plus quantised noise (so the
/// minimum is often tied).
fn sonar_at(cycle: u64) -> [f32; 24] {
    let mut x = cycle.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
    let base = 0.2 + (cycle % 50) as f32 * 0.03;
    let mut r = [0.0f32; 24];
    for v in &mut r {
        x = x.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let u = (x >> 40) as f32 / (1u64 << 24) as f32;
        *v = base + (u * 20.0).floor() * 0.1;
    }
    r
}

fn rust_runaway() -> situate_core::SkillType {
    let mut d = SkillDecl::new("rust.runaway", SkillKind::Sync);
    d.inputs.push(PortSpec::new("range", ty("f32[24]")).signal("sonar.range"));
    d.outputs.push(PortSpec::new("drive", ty("{v: f64, w: f64}")));
    d.params.push(ParamSpec::new("safe_distance", ParamType::F64, Value::F64(0.5)).range(Some(0.1), Some(3.0)));
    d.priority = 50;
    fn_type(d, |io, params| {
        let Some(Value::F32s(range)) = &io.inputs[0] else { return Err("no sonar".into()) };
        let safe = params[0].as_f64().ok_or("no safe_distance")?;
        if let Some((v, w)) = reference(range, safe) {
            io.outputs[0] = Some(situate_core::record_value(vec![("v", Value::F64(v)), ("w", Value::F64(w))]));
        }
        Ok(())
    })
}

type Row = (u64, [Option<(u64, u64)>; 3]);

fn bits(v: &Option<Value>) -> Option<(u64, u64)> {
    let v = v.as_ref()?;
    Some((v.at_path(&["v"])?.as_f64()?.to_bits(), v.at_path(&["w"])?.as_f64()?.to_bits()))
}

#[test]
fn c_and_cpp_runaway_equal_the_rust_reference_over_1000_cycles() {
    let mut registry = registry();
    let c_decl = registry.get("c.runaway").expect("c.runaway").decl.clone();
    assert_eq!(c_decl.priority, 50);
    assert_eq!(c_decl.params[0].expectation(), "a number in [0.1, 3.0]");
    assert!(registry.get("cpp.runaway").is_some());
    registry.add(rust_runaway());
    let rows: Log<Row> = Arc::new(Mutex::new(Vec::new()));
    let mut d = SkillDecl::new("test.check", SkillKind::Sync);
    for (port, signal) in [("c", "drive_c"), ("cpp", "drive_cpp"), ("rust", "drive_rust")] {
        d.inputs.push(PortSpec::new(port, ty("{v: f64, w: f64}")).signal(signal).optional());
    }
    let log = rows.clone();
    registry.add(fn_type(d, move |io, _| {
        let row = [bits(&io.inputs[0]), bits(&io.inputs[1]), bits(&io.inputs[2])];
        log.lock().unwrap().push((io.cx.cycle(), row));
        Ok(())
    }));
    let safe = Value::F64(0.8);
    let spec = simulated("runaway")
        .skill(SkillSpec::new("sonar", "test.sonar"))
        .skill(SkillSpec::new("c", "c.runaway").remap("drive", "drive_c").param("safe_distance", safe.clone()))
        .skill(SkillSpec::new("cpp", "cpp.runaway").remap("drive", "drive_cpp").param("safe_distance", safe.clone()))
        .skill(SkillSpec::new("rust", "rust.runaway").remap("drive", "drive_rust").param("safe_distance", safe))
        .skill(SkillSpec::new("check", "test.check"));
    let mut m = build(&spec, &registry);
    m.run_cycles(1000);
    let rows = rows.lock().unwrap().clone();
    assert_eq!(rows.len(), 1000);
    let mut wrote = 0;
    for (cycle, [c, cpp, rust]) in &rows {
        let expected = reference(&sonar_at(*cycle), 0.8).map(|(v, w)| (v.to_bits(), w.to_bits()));
        assert_eq!(*rust, expected, "cycle {cycle}: the Rust skill differs from the reference");
        assert_eq!(*c, expected, "cycle {cycle}: C differs from the Rust reference");
        assert_eq!(*cpp, expected, "cycle {cycle}: C++ differs from the Rust reference");
        wrote += usize::from(expected.is_some());
    }
    assert!(wrote > 100 && wrote < 900, "the input should exercise both branches: {wrote} of 1000 wrote");
}

#[test]
fn c_and_cpp_runaway_say_when_switched_off_how_long_they_ran_away_since_switched_on() {
    let safe = Value::F64(0.8);
    let spec = simulated("runaway_hooks")
        .skill(SkillSpec::new("sonar", "test.sonar"))
        .skill(SkillSpec::new("c", "c.runaway").remap("drive", "drive_c").param("safe_distance", safe.clone()))
        .skill(SkillSpec::new("cpp", "cpp.runaway").remap("drive", "drive_cpp").param("safe_distance", safe));
    let mut m = build(&spec, &registry());
    // Twice: run, switch off (the count since the switch on is said), switch on again (counted
    // afresh: the second count is not the sum of both).
    let mut last = 0; // the last cycle run
    for (round, cycles) in [(1, 300), (2, 200)] {
        m.step(cycles).unwrap();
        let ran = (last + 1..=last + cycles).filter(|&c| reference(&sonar_at(c), 0.8).is_some()).count();
        assert!(ran > 10 && ran < cycles as usize - 10, "round {round}: the input should exercise both branches");
        m.deactivate(&["c", "cpp"]).unwrap();
        m.step(1).unwrap();
        last += cycles + 1;
        for skill in ["c", "cpp"] {
            let info = m.skill(skill).unwrap();
            assert!(!info.active && info.faulted.is_none(), "round {round}, {skill}: {info:?}");
            let said = info.prints.last().map(|(_, line)| line.clone());
            let expected = format!("switched off after running away {ran} cycles");
            assert_eq!(said.as_deref(), Some(expected.as_str()), "round {round}, {skill}: {:?}", info.prints);
        }
        m.activate(&["c", "cpp"]).unwrap();
    }
}
