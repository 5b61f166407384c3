//! Robot files that compose (`include:`): merging, overriding, nesting,
//! cycles, missing files, and errors at their place in the included file.

use std::path::{Path, PathBuf};

use situate_core::value::Value;
use situate_manager::config::{LoadOptions, Section};
use situate_manager::RobotFile;

/// A directory of its own under the system's temporary directory, removed
/// when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("situate-include-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("a temporary directory");
        TempDir(dir)
    }

    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::create_dir_all(path.parent().expect("a parent")).expect("a directory");
        std::fs::write(&path, text).expect("the file is written");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn load(path: &Path) -> RobotFile {
    RobotFile::load(path)
        .unwrap_or_else(|e| panic!("{}", e.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n")))
}

fn errors(path: &Path) -> Vec<String> {
    match RobotFile::load(path) {
        Ok(_) => panic!("{} loads, but should not", path.display()),
        Err(e) => e.iter().map(ToString::to_string).collect(),
    }
}

fn names(file: &RobotFile, section: Section) -> Vec<&str> {
    file.section(section).map(|e| e.name.value.as_str()).collect()
}

const BASE: &str = "\
cycle: {rate_hz: 10}
devices:
  - name: sonar
    type: toy.sonar
skills:
  - name: wander
    type: toy.wander
  - name: runaway
    type: toy.runaway
    priority: 2
    params: {safe_distance: 0.5, gain: 1.0}
    remap: {range: sonar.range}
libraries: [libbase.so]
";

#[test]
fn included_entries_come_first_and_the_including_file_overrides_by_name() {
    let dir = TempDir::new("merge");
    dir.write("common/base.yaml", BASE);
    let main = dir.write(
        "robot.yaml",
        "\
robot: inc
include: [common/base.yaml]
cycle: {rate_hz: 50}
skills:
  - name: runaway
    params: {safe_distance: 0.3}
  - name: logger
    type: toy.logger
libraries: [libmine.so]
",
    );
    let r = load(&main);
    assert_eq!(r.robot.value, "inc");
    assert_eq!(names(&r, Section::Devices), ["sonar"]);
    assert_eq!(names(&r, Section::Skills), ["wander", "runaway", "logger"]);
    // The including file's `cycle:` replaces the included one as a whole.
    assert!((r.cycle.rate_hz() - 50.0).abs() < 1e-9);
    let runaway = r.skills.iter().find(|e| e.name.value == "runaway").expect("runaway");
    // Key by key: the type and priority stay, one parameter is replaced, the other stays.
    assert_eq!(runaway.type_name.value, "toy.runaway");
    assert_eq!(runaway.priority.as_ref().map(|p| p.value), Some(2));
    assert_eq!(runaway.param("safe_distance").map(|v| v.value.clone()), Some(Value::F64(0.3)));
    assert_eq!(runaway.param("gain").map(|v| v.value.clone()), Some(Value::F64(1.0)));
    assert_eq!(runaway.remap.len(), 1);
    // Positions keep their file: the override's value is in robot.yaml, the rest in base.yaml.
    assert_eq!(r.file_of(runaway.param("safe_distance").expect("set").pos), main.display().to_string());
    assert!(r.file_of(runaway.type_name.pos).ends_with("common/base.yaml"), "{}", r.file_of(runaway.type_name.pos));
    assert_eq!(runaway.type_name.pos.line, 9);
    // Paths are relative to the file they are written in; lists concatenate.
    let libs: Vec<PathBuf> = r.libraries.iter().map(|l| r.resolve_at(l.pos, &l.value)).collect();
    let abs = std::path::absolute(&dir.0).expect("absolute");
    assert_eq!(libs, [abs.join("common/libbase.so"), abs.join("libmine.so")]);
    // The files read.
    assert_eq!(r.sources.len(), 2);
    assert_eq!(r.sources[1].included_at.map(|p| (p.line, p.col)), Some((2, 11)));
}

#[test]
fn includes_nest_and_later_files_win() {
    let dir = TempDir::new("nest");
    dir.write("a.yaml", "robot: from_a\nskills:\n  - name: w\n    type: toy.wander\n    priority: 1\n");
    dir.write("sub/b.yaml", "include: [../a.yaml]\nskills:\n  - name: w\n    priority: 5\n");
    dir.write("c.yaml", "skills:\n  - name: x\n    type: toy.wander\n");
    let main = dir.write("main.yaml", "include:\n  - sub/b.yaml\n  - c.yaml\nrobot: main\n");
    let r = load(&main);
    assert_eq!(r.robot.value, "main");
    assert_eq!(names(&r, Section::Skills), ["w", "x"]);
    assert_eq!(r.skills[0].priority.as_ref().map(|p| p.value), Some(5));
    assert_eq!(r.sources.len(), 4);
    // An included file with a robot name and no including one: the included name is used.
    let only = dir.write("only.yaml", "include: [a.yaml]\n");
    assert_eq!(load(&only).robot.value, "from_a");
}

#[test]
fn a_type_replaces_a_remote_and_a_name_twice_in_one_file_stays_a_duplicate() {
    let dir = TempDir::new("replace");
    dir.write("base.yaml", "skills:\n  - name: planner\n    remote: {inputs: {}, outputs: {}}\n    timeout_ms: 50\n");
    let main = dir.write(
        "main.yaml",
        "robot: r\ninclude: [base.yaml]\nskills:\n  - name: planner\n    type: toy.wander\n    timeout_ms: 40\n",
    );
    let errs = errors(&main);
    // `remote` is gone (the type replaced it), so `timeout_ms` is now misplaced: reported in main.yaml.
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert!(errs[0].starts_with(&format!("{}:6:17: error: `timeout_ms`", main.display())), "{errs:?}");

    let twice = dir.write(
        "twice.yaml",
        "robot: r\ninclude: [base.yaml]\nskills:\n  - name: planner\n    timeout_ms: 60\n  - name: planner\n    type: toy.wander\n",
    );
    let r = load(&twice);
    assert_eq!(names(&r, Section::Skills), ["planner", "planner"], "the graph check reports the duplicate");
}

#[test]
fn a_cycle_of_includes_is_an_error_naming_the_chain() {
    let dir = TempDir::new("cycle");
    dir.write("a.yaml", "include: [b.yaml]\n");
    dir.write("b.yaml", "skills: []\ninclude: [a.yaml]\n");
    let main = dir.write("main.yaml", "robot: r\ninclude: [a.yaml]\n");
    let shown = main.display().to_string();
    let d = dir.0.display().to_string();
    assert_eq!(errors(&main), [format!("{d}/b.yaml:2:11: error: include cycle: {d}/a.yaml → {d}/b.yaml → {d}/a.yaml")]);
    let itself = dir.write("self.yaml", "robot: r\ninclude: [self.yaml]\n");
    let s = itself.display().to_string();
    assert_eq!(errors(&itself), [format!("{s}:2:11: error: include cycle: {s} → {d}/self.yaml")]);
    // The same file twice, not in a chain, is no cycle.
    dir.write("leaf.yaml", "cycle: {rate_hz: 5}\n");
    let diamond = dir.write("diamond.yaml", "robot: r\ninclude: [leaf.yaml, leaf.yaml]\n");
    assert!((load(&diamond).cycle.rate_hz() - 5.0).abs() < 1e-9);
    let _ = shown;
}

#[test]
fn a_missing_included_file_is_an_error_at_its_include_line() {
    let dir = TempDir::new("missing");
    let main = dir.write("main.yaml", "robot: r\ninclude:\n  - nothere.yaml\n  - [a.yaml]\n");
    let shown = main.display().to_string();
    let d = dir.0.display().to_string();
    assert_eq!(
        errors(&main),
        [
            format!("{shown}:3:5: error: cannot read the included file `{d}/nothere.yaml`: no such file"),
            format!("{shown}:4:5: error: `include` expects paths of robot files, got a list"),
        ]
    );
    let map = dir.write("map.yaml", "robot: r\ninclude: {a: b}\n");
    assert_eq!(
        errors(&map),
        [format!("{}:2:10: error: `include` expects a list of robot file paths, got a mapping", map.display())]
    );
}

#[test]
fn errors_in_an_included_file_name_that_file_and_line() {
    let dir = TempDir::new("errors");
    dir.write("parts/bad.yaml", "skills:\n  - name: w\n    type: toy.wander\n    priorty: 3\n");
    dir.write("parts/broken.yaml", "skills: [\n");
    dir.write("parts/list.yaml", "- a\n- b\n");
    let main = dir.write("main.yaml", "robot: r\ninclude: [parts/bad.yaml]\ncycle: {rate_hz: 0}\n");
    let d = dir.0.display().to_string();
    assert_eq!(
        errors(&main),
        [
            format!(
                "{}:3:18: error: `rate_hz` is out of range: expects a number > 0 and ≤ 100000, got 0",
                main.display()
            ),
            format!("{d}/parts/bad.yaml:4:5: error: unknown key `priorty` in skill `w` — did you mean `priority`?"),
        ]
    );
    let main = dir.write("main2.yaml", "robot: r\ninclude: [parts/broken.yaml, parts/list.yaml]\n");
    let errs = errors(&main);
    assert_eq!(errs.len(), 2, "{errs:?}");
    assert!(errs[0].starts_with(&format!("{d}/parts/broken.yaml:")), "{errs:?}");
    assert_eq!(errs[1], format!("{d}/parts/list.yaml:1:1: error: an included robot file is a mapping, got a list"));
}

#[test]
fn env_substitution_reaches_included_files_and_errors_there_name_them() {
    let dir = TempDir::new("env");
    dir.write("base.yaml", "cycle: {rate_hz: ${INC_RATE:-20}}\nskills:\n  - name: w\n    type: ${INC_TYPE}\n");
    let main = dir.write("main.yaml", "robot: r\ninclude: [base.yaml]\n");
    let env = |name: &str| (name == "INC_TYPE").then(|| "toy.wander".to_string());
    let r = RobotFile::load_with(&main, LoadOptions { env: Some(&env) }).expect("loads");
    assert_eq!(r.skills[0].type_name.value, "toy.wander");
    let none = |_: &str| None;
    let e = RobotFile::load_with(&main, LoadOptions { env: Some(&none) }).expect_err("INC_TYPE unset");
    assert_eq!(e.len(), 1);
    assert!(
        e[0].to_string().starts_with(&format!("{}/base.yaml:4:11: error: `${{INC_TYPE}}`", dir.0.display())),
        "{e:?}"
    );
}

#[test]
fn the_graph_check_names_the_included_file() {
    let dir = TempDir::new("graph");
    dir.write("base.yaml", "skills:\n  - name: w\n    type: toy.nosuchtype\n");
    let main = dir.write("main.yaml", "robot: r\ninclude: [base.yaml]\n");
    let file = load(&main);
    let spec = situate_manager::RobotSpec::from_file(&file);
    let Err(diag) = situate_manager::graph::Graph::build(&spec, &situate_manager::Registry::new()) else {
        panic!("an unknown type builds")
    };
    let text = diag.to_string();
    assert!(
        text.contains(&format!("{}/base.yaml:3:11: error: skill `w`: unknown skill type", dir.0.display())),
        "{text}"
    );
}
