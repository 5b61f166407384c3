//! The parallel executor gives exactly the serial executor's results, and so
//! do bodies that let the manager run them the short way (`plan::Fast`),
//! their outputs written straight into their slots where they say so.

mod common;

use common::*;
use proptest::prelude::*;
use situate_core::{SkillKind, Value};
use situate_manager::{Control, ExecutorKind, Manager, Registry};

/// One random skill: which earlier signals it reads, whether it also writes
/// the shared resource (at which priority), how often it stays silent
/// (never: `None`).
#[derive(Debug, Clone)]
struct Node {
    reads: Vec<usize>,
    optional_read: Option<usize>,
    resource_priority: Option<i32>,
    silent_every: Option<u64>,
    active: bool,
    claim: bool,
}

fn node(max_reads: usize) -> impl Strategy<Value = Node> {
    (
        proptest::collection::vec(0..max_reads.max(1), 0..3),
        proptest::option::of(0..max_reads.max(1)),
        proptest::option::of(0..1000i32),
        proptest::option::of(1..4u64),
        proptest::bool::weighted(0.8),
        proptest::bool::weighted(0.3),
    )
        .prop_map(|(reads, optional_read, resource_priority, silent_every, active, claim)| Node {
            reads,
            optional_read,
            resource_priority,
            silent_every,
            active,
            claim,
        })
}

fn graph() -> impl Strategy<Value = Vec<Node>> {
    proptest::collection::vec(node(12), 1..14)
}

/// `way`: how its bodies let the manager run them ([`Way::InSlot`] only
/// for a body that is never silent and has one output: it sets it on
/// every run, as it then says).
fn build_robot(nodes: &[Node], executor: ExecutorKind, way: Way) -> Option<Manager> {
    let mut reg = Registry::new();
    let mut spec = simulated("prop").executor(executor, Some(2));
    let mut used_priorities = std::collections::HashSet::new();
    for (i, n) in nodes.iter().enumerate() {
        // Only earlier skills' outputs: the graph is acyclic.
        let reads: Vec<usize> = n.reads.iter().copied().filter(|&r| r < i).collect();
        let opt = n.optional_read.filter(|&r| r < i && !reads.contains(&r));
        let mut inputs: Vec<(String, String)> =
            reads.iter().enumerate().map(|(k, r)| (format!("in{k}"), format!("s{r}"))).collect();
        if let Some(r) = opt {
            inputs.push(("opt".into(), format!("s{r}")));
        }
        let prio = n.resource_priority.filter(|p| used_priorities.insert(*p));
        let mut outputs = vec![("out", "f64")];
        if prio.is_some() {
            outputs.push(("res", "f64"));
        }
        let in_decl: Vec<(&str, &str)> =
            inputs.iter().map(|(p, _)| (p.as_str(), if p == "opt" { "f64?" } else { "f64" })).collect();
        let mut d = decl(&format!("t{i}"), SkillKind::Sync, &in_decl, &outputs);
        d.priority = prio.unwrap_or(0);
        if n.claim {
            d.claims.push("shared-lib".into());
        }
        let silent_every = n.silent_every;
        let tag = i as f64;
        let way = match way {
            Way::InSlot if silent_every.is_some() || prio.is_some() => Way::Fast,
            way => way,
        };
        reg.add(body_type(d, way, move |io, _| {
            let cycle = io.cx.cycle();
            let sum: f64 = io.inputs.iter().flatten().filter_map(Value::as_f64).sum();
            // A little real arithmetic, so parallel runs overlap.
            let mut acc = sum;
            for k in 0..200 {
                acc = (acc * 1.000_001 + k as f64).sin() + sum;
            }
            let y = 0.5 * sum + tag + cycle as f64 + acc * 1e-3;
            if silent_every.is_none_or(|k| cycle % k != 0) {
                io.outputs[0] = Some(Value::F64(y));
                if io.outputs.len() > 1 {
                    io.outputs[1] = Some(Value::F64(y * 2.0 + tag));
                }
            }
            Ok(())
        }));
        let mut s = skill(&format!("k{i}"), &format!("t{i}")).active(n.active).remap("out", &format!("s{i}"));
        for (p, sig) in &inputs {
            s = s.remap(p, sig);
        }
        if prio.is_some() {
            s = s.remap("res", "resource");
        }
        spec = spec.skill(s);
    }
    Manager::build(&spec, &reg).ok()
}

fn snapshot(m: &mut Manager, n: usize) -> Vec<String> {
    let mut out = Vec::new();
    for i in 0..n {
        if let Ok(r) = m.query(&format!("s{i}")) {
            out.push(format!("s{i}={:?}@{}", r.value, r.cycle));
        }
    }
    if let Ok(r) = m.query("resource") {
        out.push(format!("resource={:?}@{} by {:?}", r.value, r.cycle, r.writer));
    }
    for s in m.skills().unwrap() {
        out.push(format!("{}: runs {} active {} fault {:?}", s.name, s.timing.runs, s.active, s.faulted));
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    #[test]
    fn random_graphs_give_identical_results_serial_and_parallel(nodes in graph(), toggles in proptest::collection::vec(0..14usize, 0..4)) {
        let Some(mut serial) = build_robot(&nodes, ExecutorKind::Serial, Way::Usual) else { return Ok(()) };
        let mut parallel = build_robot(&nodes, ExecutorKind::Parallel, Way::Usual).expect("same spec builds");
        let mut short = build_robot(&nodes, ExecutorKind::Serial, Way::InSlot).expect("same spec builds");
        prop_assert_eq!(parallel.executor(), ExecutorKind::Parallel);
        for cycle in 0..6 {
            // Flip some activations midway, identically on both.
            if cycle == 3 {
                for &t in &toggles {
                    let name = format!("k{}", t % nodes.len());
                    let a = serial.activate_with(&[&name], true).is_ok();
                    let b = parallel.activate_with(&[&name], true).is_ok();
                    let c = short.activate_with(&[&name], true).is_ok();
                    prop_assert_eq!(a, b);
                    prop_assert_eq!(a, c);
                }
            }
            serial.step(1).unwrap();
            parallel.step(1).unwrap();
            short.step(1).unwrap();
            let expected = snapshot(&mut serial, nodes.len());
            prop_assert_eq!(&expected, &snapshot(&mut parallel, nodes.len()));
            prop_assert_eq!(&expected, &snapshot(&mut short, nodes.len()), "the short way");
        }
    }
}

/// A skill whose level stops going parallel (a sibling is deactivated) has
/// its inputs lent from then on. An optional input absent in that cycle is
/// absent to its body: not the copy gathered for it in the parallel level
/// before, and that copy is not written back to the signal.
#[test]
fn an_optional_input_absent_after_a_level_stops_being_parallel_is_absent() {
    let seen = log();
    let mut reg = Registry::new();
    // Writes `s` in cycle 1 only.
    reg.add(fn_type(decl("once", SkillKind::Sync, &[], &[("out", "f64")]), |io, _| {
        if io.cx.cycle() == 1 {
            io.outputs[0] = Some(Value::F64(7.0));
        }
        Ok(())
    }));
    for name in ["reader", "sibling"] {
        let seen = seen.clone();
        let tag = name.to_string();
        reg.add(fn_type(decl(name, SkillKind::Sync, &[("x", "f64?")], &[("y", "f64")]), move |io, _| {
            let x = io.inputs[0].as_ref().and_then(Value::as_f64);
            seen.lock().unwrap().push(format!("{tag} {} {x:?}", io.cx.cycle()));
            io.outputs[0] = Some(Value::F64(x.unwrap_or(-1.0)));
            Ok(())
        }));
    }
    let spec = simulated("lend")
        .executor(ExecutorKind::Parallel, Some(2))
        .skill(skill("once", "once").remap("out", "s"))
        .skill(skill("reader", "reader").remap("x", "s").remap("y", "r"))
        .skill(skill("sibling", "sibling").remap("x", "s").remap("y", "q"));
    let mut m = Manager::build(&spec, &reg).unwrap();
    assert_eq!(m.executor(), ExecutorKind::Parallel);
    m.step(1).unwrap();
    m.deactivate(&["sibling"]).unwrap();
    m.step(1).unwrap();
    let reader: Vec<String> = entries(&seen).into_iter().filter(|e| e.starts_with("reader")).collect();
    assert_eq!(reader, ["reader 1 Some(7.0)", "reader 2 None"]);
    assert_eq!(m.query("r").unwrap().value, Some(Value::F64(-1.0)));
    // `s` still holds what `once` wrote in cycle 1, written then.
    let s = m.query("s").unwrap();
    assert_eq!((s.value, s.cycle), (Some(Value::F64(7.0)), 1));
}
