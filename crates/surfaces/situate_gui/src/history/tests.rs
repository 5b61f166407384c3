//! The history's tests: the window, seeks, records assembled, marks, the byte budget.

use std::time::Instant;

use serde_json::{json, Value as Json};

use super::*;

fn layout() -> Layout {
    let port =
        |name: &str, signal: &str, leaves: Vec<usize>| PortLayout { name: name.into(), signal: signal.into(), leaves };
    Layout {
        leaves: vec![
            LeafLayout { path: "pose.x".into(), writers: vec![0] },
            LeafLayout { path: "pose.y".into(), writers: vec![0] },
            LeafLayout { path: "cmd".into(), writers: vec![0, 1] },
        ],
        skills: vec![
            SkillLayout {
                name: "a".into(),
                active: true,
                params: vec![("gain".into(), Value::F64(1.0))],
                inputs: vec![],
                outputs: vec![port("pose", "pose", vec![0, 1]), port("cmd", "cmd", vec![2])],
            },
            SkillLayout {
                name: "b".into(),
                active: false,
                params: vec![],
                inputs: vec![port("pose", "pose", vec![0, 1])],
                outputs: vec![port("cmd", "cmd", vec![2])],
            },
        ],
    }
}

fn frame(cycle: u64, values: Vec<(usize, Value)>) -> Frame {
    Frame { cycle, time_s: cycle as f64 * 0.01, values: values.into(), prints: vec![], winners: vec![] }
}

#[test]
fn a_series_spans_the_whole_history_on_robot_time_records_assembled_and_says_when_each_value_was_written() {
    let mut h = History::new(layout(), 100, 0);
    assert_eq!(h.series_json(&["pose".into()], &[], 10), Err(HistoryError::Empty));
    for c in 1..=50 {
        // pose.y is written every other cycle: its value then is the one of the cycle before.
        let mut values = vec![(0, Value::F64(c as f64))];
        if c % 2 == 1 {
            values.push((1, Value::F64(-(c as f64))));
        }
        h.push_frame(frame(c, values));
    }
    let all = h.series_json(&["pose".into(), "pose.x".into()], &[], 100).expect("series");
    assert_eq!(all["cycles"].as_array().map(Vec::len), Some(50), "every frame when they are fewer: {all}");
    assert_eq!(all["times"][9], json!(0.1));
    assert_eq!(all["signals"]["pose"]["values"][9], json!({"x": 10.0, "y": -9.0}));
    assert_eq!(all["signals"]["pose"]["written"][9], json!(9), "the oldest leaf's write");
    assert_eq!(all["signals"]["pose.x"]["values"][9], json!(10.0));
    let few = h.series_json(&["pose.x".into()], &[], 10).expect("series");
    let cycles: Vec<u64> = few["cycles"].as_array().expect("cycles").iter().filter_map(Json::as_u64).collect();
    assert_eq!(cycles, vec![1, 6, 11, 16, 21, 26, 31, 36, 41, 46, 50], "spread, the last among them");
    assert_eq!(h.series_json(&["pose.z".into()], &[], 10), Err(HistoryError::UnknownSignal("pose.z".into())));
    // Before its first write a signal is null.
    let cmd = h.series_json(&["cmd".into()], &[], 10).expect("series");
    assert_eq!(cmd["signals"]["cmd"]["values"][0], Json::Null);
}

#[test]
fn the_frame_past_the_capacity_evicts_the_first() {
    let mut h = History::new(layout(), 3, 0);
    assert!(h.span().is_none());
    assert_eq!(h.frame_json(0, &[]), Err(HistoryError::Empty));
    for c in 1..=3 {
        h.push_frame(frame(c, vec![(0, Value::F64(c as f64))]));
    }
    assert_eq!(h.span().map(|s| (s.first_cycle, s.last_cycle, s.frames)), Some((1, 3, 3)));
    h.push_frame(frame(4, vec![(0, Value::F64(4.0))]));
    let span = h.span().expect("frames");
    assert_eq!((span.first_cycle, span.last_cycle, span.frames), (2, 4, 3));
    assert_eq!(h.len(), 3);
    assert!(matches!(h.frame_json(1, &[]), Err(HistoryError::NotHeld { cycle: 1, first: 2, last: 4 })));
    // The evicted frames' values are folded: no more than one change per leaf before the window.
    assert_eq!(h.leaves[0].changes.len(), 3);
    assert_eq!(h.leaves[0].before, Some((1, Value::F64(1.0))));
    // Memory stays bounded however long the run.
    for c in 5..10_000 {
        h.push_frame(frame(c, vec![(0, Value::F64(c as f64)), (2, Value::F64(0.5))]));
    }
    assert_eq!(h.len(), 3);
    assert!(h.leaves.iter().all(|t| t.changes.len() <= 3), "tracks hold the window only");
    // An out-of-order frame is ignored.
    h.push_frame(frame(5, vec![(0, Value::F64(-1.0))]));
    assert_eq!(h.value_at(0, 9999), Some((9999, &Value::F64(9999.0))));
}

#[test]
fn the_value_at_cycle_k_is_the_latest_written_at_or_before_k() {
    let mut h = History::new(layout(), 100, 0);
    h.push_frame(frame(10, vec![(0, Value::F64(1.0)), (1, Value::F64(2.0))]));
    h.push_frame(frame(11, vec![(0, Value::F64(3.0))]));
    h.push_frame(frame(12, vec![]));
    // A dropped frame: cycle 13 is missing.
    h.push_frame(frame(14, vec![(1, Value::F64(5.0))]));
    assert_eq!(h.value_at(0, 10), Some((10, &Value::F64(1.0))));
    assert_eq!(h.value_at(0, 12), Some((11, &Value::F64(3.0))));
    assert_eq!(h.value_at(1, 13), Some((10, &Value::F64(2.0))));
    assert_eq!(h.value_at(1, 14), Some((14, &Value::F64(5.0))));
    assert_eq!(h.value_at(2, 14), None, "never written");
    let f = h.frame_json(13, &["pose"]).expect("held");
    assert_eq!(f["exact"], false, "cycle 13 has no frame of its own");
    assert_eq!(f["time_s"], json!(12.0 * 0.01), "the time of the frame before");
    assert_eq!(f["signals"]["pose.x"]["value"], 3.0);
    assert_eq!(f["signals"]["pose.x"]["cycle"], 11);
    assert_eq!(f["signals"]["pose"]["value"], json!({"x": 3.0, "y": 2.0}), "the record assembled: {f}");
    assert_eq!(f["signals"]["pose"]["cycle"], 10, "the oldest field's cycle");
    assert!(f["signals"].get("cmd").is_none());
    let a = &f["skills"][0];
    assert_eq!(a["outputs"][0]["value"], json!({"x": 3.0, "y": 2.0}));
    assert_eq!(a["outputs"][1]["value"], Json::Null, "cmd never written");
    let f = h.frame_json(10, &[]).expect("held");
    assert_eq!(f["skills"][1]["inputs"][0]["value"], json!({"x": 1.0, "y": 2.0}));
    assert_eq!(f["exact"], true);
}

#[test]
fn marks_activations_parameters_faults_and_winners_follow_the_cycle() {
    let mut h = History::new(layout(), 100, 0);
    for c in 1..=5 {
        h.push_frame(Frame {
            cycle: c,
            time_s: c as f64,
            values: vec![(2, Value::F64(c as f64))].into(),
            prints: if c == 3 { vec![(0, "hello".into())] } else { vec![] },
            winners: vec![(2, 0)],
        });
    }
    h.push_event(&Event::ActivationApplied { activated: vec!["b".into()], deactivated: vec![], cycle: 6 });
    h.push_event(&Event::ParamChanged { skill: "a".into(), param: "gain".into(), value: Value::F64(2.5), cycle: 7 });
    h.push_event(&Event::Print { skill: "a".into(), line: "not a mark".into(), cycle: 7 });
    for c in 6..=10 {
        h.push_frame(Frame {
            cycle: c,
            time_s: c as f64,
            values: Default::default(),
            prints: vec![],
            winners: vec![(2, 1)],
        });
    }
    h.push_event(&Event::SkillFaulted { skill: "b".into(), cause: "panicked".into(), cycle: 9 });
    let marks: Vec<_> = h.marks().map(|m| (m.cycle, m.kind)).collect();
    assert_eq!(marks, vec![(6, "activation"), (7, "param"), (9, "fault")]);
    let summary = h.summary_json();
    assert_eq!(summary["marks"][1]["text"], "a.gain = 2.5");
    assert_eq!(summary["marks"][0]["text"], "activated b");
    assert_eq!((summary["first_cycle"].as_u64(), summary["last_cycle"].as_u64()), (Some(1), Some(10)));
    assert_eq!(h.active_at(1, 5), Some(false), "b inactive as built");
    assert_eq!(h.active_at(1, 6), Some(true));
    assert_eq!(h.active_at(1, 9), Some(false), "faulted");
    assert_eq!(h.param_at(0, 0, 6), Some(&Value::F64(1.0)));
    assert_eq!(h.param_at(0, 0, 7), Some(&Value::F64(2.5)));
    assert_eq!(h.winner_at(2, 5), Some(0));
    assert_eq!(h.winner_at(2, 6), Some(1));
    let f = h.frame_json(3, &[]).expect("held");
    assert_eq!(f["prints"], json!([{"skill": "a", "line": "hello"}]));
    assert_eq!(f["winners"], json!([{"signal": "cmd", "writers": ["a", "b"], "winner": "a", "cycle": 3}]));
    assert_eq!(f["skills"][1]["active"], false);
    assert_eq!(f["activity"]["changed"], json!({}));
    let f = h.frame_json(9, &[]).expect("held");
    assert_eq!(f["skills"][1]["faulted"], "panicked");
    assert_eq!(f["skills"][0]["params"], json!([{"name": "gain", "value": 2.5}]));
    assert_eq!(f["activity"]["changed"], json!({"b": 9}));
    assert_eq!(f["winners"][0]["winner"], "b");
    assert_eq!(f["prints"], json!([]));
    // Marks go with the frames they fall before.
    let mut small = History::new(layout(), 2, 0);
    small.push_event(&Event::ManagerStarted { cycle: 1 });
    for c in 1..=4 {
        small.push_frame(frame(c, vec![]));
    }
    assert_eq!(small.marks().count(), 0, "the mark of cycle 1 left with its frame");
}

#[test]
fn large_values_keep_fewer_frames_within_the_byte_budget() {
    let mut h = History::new(layout(), 1000, 0);
    h.set_byte_budget(100_000);
    let image = |c: u64| Value::Bytes(vec![c as u8; 10_000].into());
    for c in 0..100 {
        h.push_frame(frame(c, vec![(2, image(c)), (0, Value::F64(c as f64))]));
        assert!(h.bytes() <= 100_000, "over budget at cycle {c}: {} bytes", h.bytes());
    }
    let span = h.span().expect("frames");
    assert!(span.frames >= 5 && span.frames < 10, "about 100 kB of 10 kB frames: {span:?}");
    assert_eq!(span.last_cycle, 99);
    assert_eq!(h.value_at(2, 99), Some((99, &image(99))));
    // Tracks hold the window only (and one value from before it).
    assert_eq!(h.leaves[2].changes.len(), span.frames);
    // A frame larger than the whole budget is kept alone.
    h.push_frame(frame(100, vec![(2, Value::Bytes(vec![0; 200_000].into()))]));
    assert_eq!(h.len(), 1);
    assert_eq!(h.span().map(|s| s.first_cycle), Some(100));
    assert_eq!(h.value_at(0, 100), Some((99, &Value::F64(99.0))), "the value before the window stays");
}

#[test]
fn marks_are_bounded_too() {
    let mut h = History::new(layout(), 10, 0);
    for c in 0..(MAX_MARKS as u64 + 50) {
        h.push_event(&Event::ManagerStopped { cycle: c });
    }
    assert_eq!(h.marks().count(), MAX_MARKS);
    assert_eq!(h.marks().next().map(|m| m.cycle), Some(50));
}

/// Ten minutes at 100 Hz: the time of a seek is reported (not asserted: it depends on the
/// machine and the build).
#[test]
fn a_seek_in_ten_minutes_at_100_hz() {
    let leaves = 40;
    let layout = Layout {
        leaves: (0..leaves).map(|i| LeafLayout { path: format!("s{i}"), writers: vec![0] }).collect(),
        skills: vec![SkillLayout {
            name: "a".into(),
            active: true,
            params: vec![("p".into(), Value::I64(0))],
            inputs: vec![],
            outputs: (0..leaves)
                .map(|i| PortLayout { name: format!("o{i}"), signal: format!("s{i}"), leaves: vec![i] })
                .collect(),
        }],
    };
    let frames = 60_000;
    let mut h = History::new(layout, frames, 0);
    let started = Instant::now();
    for c in 0..frames as u64 {
        // Every leaf every cycle, but one written every 1000 cycles only.
        let values =
            (0..leaves).filter(|&i| i != 0 || c % 1000 == 0).map(|i| (i, Value::F64((c * i as u64) as f64))).collect();
        h.push_frame(Frame { cycle: c, time_s: c as f64 / 100.0, values, prints: vec![], winners: vec![] });
    }
    let fill = started.elapsed();
    let mut worst = std::time::Duration::ZERO;
    for k in [0, 12_345, 29_999, 59_999] {
        let t = Instant::now();
        let f = h.frame_json(k, &[]).expect("held");
        worst = worst.max(t.elapsed());
        assert_eq!(f["cycle"], k);
        assert_eq!(f["signals"]["s3"]["value"], json!((k * 3) as f64));
        assert_eq!(f["signals"]["s0"]["cycle"], k / 1000 * 1000);
    }
    eprintln!("history: {frames} frames of {leaves} leaves filled in {fill:?}; the slowest of 4 seeks {worst:?}");
}
