//! docs/conditions.md's examples, checked against the manager: its example robot is built here,
//! each condition of its table is registered as a monitor, and what the manager says (it holds, it
//! does not, or the error) must be what the table says. The robot's own table must describe the
//! robot built here, row for row.

mod common;

use std::path::PathBuf;
use std::sync::Arc;

use common::*;
use situate_core::{record_value, SkillKind, Value};
use situate_manager::{Control, ControlError, Manager, MonitorMode, Registry, Reply, Request};

fn doc() -> String {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../docs/conditions.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The table rows between `<!-- {marker}: ... -->` and `<!-- end of {marker} -->`, as cells, the
/// header and its rule left out. `\|` in a cell is a `|`.
fn table(doc: &str, marker: &str) -> Vec<Vec<String>> {
    let start = doc.find(&format!("<!-- {marker}:")).unwrap_or_else(|| panic!("no `{marker}` table"));
    let end = doc[start..].find(&format!("<!-- end of {marker} -->")).expect("the table's end") + start;
    doc[start..end]
        .lines()
        .filter(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .replace("\\|", "\u{0}")
                .split('|')
                .map(|c| c.trim().replace('\u{0}', "|"))
                .collect()
        })
        .collect()
}

/// The text inside a cell's backticks.
fn code(cell: &str) -> &str {
    cell.strip_prefix('`').and_then(|c| c.strip_suffix('`')).unwrap_or_else(|| panic!("`{cell}` is not code"))
}

/// The example robot at the end of its cycle 10, on the simulated clock at 10 Hz.
fn example_robot() -> Manager {
    let mut reg = Registry::new();
    let source = |name: &str, ty: &str, value: Value| {
        fn_type(decl(name, SkillKind::Sync, &[], &[(name, ty)]), move |io, _| {
            io.outputs[0] = Some(value.clone());
            Ok(())
        })
    };
    let mut ranges = vec![1.5f32; 24];
    ranges[0] = 0.2;
    let ranges: Arc<[f32]> = ranges.into();
    reg.add(source("sonar", "{range: f32[24]}", record_value(vec![("range", Value::F32s(ranges))])));
    reg.add(source(
        "odom",
        "{x: f64, y: f64, theta: f64, v: f64, w: f64}",
        record_value(vec![
            ("x", Value::F64(1.5)),
            ("y", Value::F64(-2.0)),
            ("theta", Value::F64(0.5)),
            ("v", Value::F64(0.3)),
            ("w", Value::F64(0.0)),
        ]),
    ));
    reg.add(source(
        "barcode",
        "{id: i64, visible: bool}",
        record_value(vec![("id", Value::I64(3)), ("visible", Value::Bool(true))]),
    ));
    reg.add(source("speaker", "{said: string}", record_value(vec![("said", Value::Str("hello".into()))])));
    // Declares `dock` and never writes it.
    reg.add(fn_type(decl("dock", SkillKind::Sync, &[], &[("dock", "{distance: f64}")]), |_, _| Ok(())));
    reg.add(fn_type(with_param(decl("runaway", SkillKind::Sync, &[], &[]), "safe_distance", 0.5, 0.1, 3.0), |_, _| {
        Ok(())
    }));
    let mut spec = simulated("example").period_s(0.1);
    for name in ["sonar", "odom", "barcode", "speaker", "dock", "runaway"] {
        spec = spec.skill(skill(name, name));
    }
    build(&spec, &reg)
}

#[test]
fn the_example_robot_is_the_one_the_page_describes() {
    let rows = table(&doc(), "robot");
    let described: Vec<[&str; 3]> = rows.iter().map(|r| [r[0].as_str(), r[1].as_str(), r[2].as_str()]).collect();
    assert_eq!(
        described,
        vec![
            ["`sonar.range`", "`f32[24]`", "`0.2` at index 0, `1.5` at the 23 others"],
            [
                "`odom`",
                "`{x: f64, y: f64, theta: f64, v: f64, w: f64}`",
                "x `1.5`, y `-2`, theta `0.5`, v `0.3`, w `0`"
            ],
            ["`barcode`", "`{id: i64, visible: bool}`", "id `3`, visible `true`"],
            ["`speaker.said`", "`string`", "`\"hello\"`"],
            ["`dock.distance`", "`f64`", "none: nobody wrote it"],
            ["`runaway.safe_distance`", "a parameter, `f64`", "`0.5`"],
            ["`time`", "seconds", "`1`"],
            ["`cycle`", "cycle number", "`10`"],
        ],
        "docs/conditions.md's example robot differs from the robot this test builds"
    );
    // `time` and `cycle` as the table gives them, at the end of cycle 10.
    let mut m = example_robot();
    let at = m.add_monitor("time == 1 && cycle == 10", MonitorMode::Level).unwrap();
    m.step(10).unwrap();
    assert!(holds(&mut m, at), "time is not 1 s at the end of cycle 10");
}

fn holds(m: &mut Manager, monitor: u64) -> bool {
    match m.request(Request::ListMonitors).unwrap() {
        Reply::Monitors(list) => list.iter().find(|i| i.monitor == monitor).expect("the monitor").holds,
        other => panic!("{other:?}"),
    }
}

#[test]
fn every_example_on_the_page_says_what_the_manager_does() {
    let rows = table(&doc(), "examples");
    assert!(rows.len() >= 20, "the examples table lost its rows ({})", rows.len());
    let mut m = example_robot();
    let mut registered = Vec::new();
    let mut wrong = Vec::new();
    for row in &rows {
        let (condition, expected) = (code(&row[0]), row[1].as_str());
        match m.add_monitor(condition, MonitorMode::Level) {
            Ok(id) => registered.push((condition, expected, id)),
            Err(ControlError::BadCondition { column, message, .. }) => {
                let said = format!("column {column}: {message}");
                if expected != said {
                    wrong.push(format!("`{condition}`: the page says {expected:?}, the manager {said:?}"));
                }
            }
            Err(e) => wrong.push(format!("`{condition}`: refused as {e}")),
        }
    }
    m.step(10).unwrap();
    for (condition, expected, id) in registered {
        let said = if holds(&mut m, id) { "holds" } else { "does not hold" };
        if expected != said {
            wrong.push(format!("`{condition}`: the page says {expected:?}, the manager {said:?}"));
        }
    }
    assert!(wrong.is_empty(), "docs/conditions.md's examples are wrong:\n{}", wrong.join("\n"));
}
