//! The C and C++ examples' READMEs (`examples/{c,cpp}/runaway/README.md`, "A skill made with the
//! program's resources") show an emergency-stop guard made with the program's e-stop (`estop`):
//! their manifests and code build, a robot without the resource is refused, and with an e-stop the
//! program provides (a Rust `AtomicBool`, as the C README's provider does) the guard holds the
//! robot still while it is set and writes nothing otherwise.

mod common;

use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, Ordering};

use common::*;
use situate_cabi::CResource;
use situate_core::Value;
use situate_manager::{Control, Manager, SkillSpec};

const SECTION: &str = "## A skill made with the program's resources";

/// The first block fenced as `tag` in the README's section on resources.
fn block(readme: &str, tag: &str) -> String {
    let path = repo().join(readme);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let section = text.split(SECTION).nth(1).unwrap_or_else(|| panic!("{readme} has no section `{SECTION}`"));
    let fenced = section.split(&format!("```{tag}\n")).nth(1).and_then(|b| b.split("```").next());
    fenced.unwrap_or_else(|| panic!("{readme}: no ```{tag} block in `{SECTION}`")).to_string()
}

/// The README's manifest without its first line (`name: <type>`, which `registry_of` writes).
fn manifest(readme: &str, ty: &str) -> String {
    let text = block(readme, "yaml manifest");
    let rest = text.strip_prefix(&format!("name: {ty}\n"));
    rest.unwrap_or_else(|| panic!("{readme}: the manifest does not start with `name: {ty}`")).to_string()
}

#[test]
fn the_readmes_estop_guards_hold_the_robot_still_while_the_programs_estop_is_set() {
    let (c, cpp) = ("examples/c/runaway/README.md", "examples/cpp/runaway/README.md");
    let (c_manifest, cpp_manifest) = (manifest(c, "c.estop_guard"), manifest(cpp, "cpp.estop_guard"));
    let (c_source, cpp_source) = (block(c, "c"), block(cpp, "cpp"));
    let mut r = registry_of(
        "readme_estop_guard",
        &[("c_estop_guard", &c_manifest, "c"), ("cpp_estop_guard", &cpp_manifest, "cpp")],
        &[
            ("c_estop_guard", "c_estop_guard.c", &c_source, false),
            ("cpp_estop_guard", "cpp_estop_guard.cpp", &cpp_source, true),
        ],
    );
    let spec = |ty: &str| simulated("estop").skill(SkillSpec::new("guard", ty));
    for ty in ["c.estop_guard", "cpp.estop_guard"] {
        let e = Manager::build(&spec(ty), &r).err().expect("refused without the e-stop").to_string();
        let why = "needs the resource `estop`, and the program provides no C resource of that name";
        assert!(e.contains(&format!("skill `guard`: could not create `{ty}`")) && e.contains(why), "{ty}: {e}");
    }
    let zero = situate_core::record_value(vec![("v", Value::F64(0.0)), ("w", Value::F64(0.0))]);
    for ty in ["c.estop_guard", "cpp.estop_guard"] {
        let estop = Box::new(AtomicBool::new(false));
        // SAFETY: the e-stop outlives the manager (dropped first, below), and the guard only
        // loads it atomically.
        r.provide("estop", unsafe { CResource::new(estop.as_ptr().cast::<c_void>()) });
        let mut m = build(&spec(ty), &r);
        m.step(2).unwrap();
        assert_eq!(m.query("drive").unwrap().value, None, "{ty}: released, it writes nothing");
        estop.store(true, Ordering::Release);
        m.step(1).unwrap();
        let drive = m.query("drive").unwrap();
        assert_eq!((drive.value, drive.cycle), (Some(zero.clone()), 3), "{ty}: pressed, a zero drive");
        estop.store(false, Ordering::Release);
        m.step(2).unwrap();
        assert_eq!(m.query("drive").unwrap().cycle, 3, "{ty}: released again, it writes nothing");
        drop(m);
    }
}
