//! A recording read back with the `mcap` crate: one channel per signal leaf
//! written, one per kind of event, JSON Schemas, a message per cycle with its
//! cycle, and as `log_time` the run's start in Unix time plus the manager's
//! clock.

use std::collections::BTreeMap;
use std::path::PathBuf;

use situate::manager::{ClockKind, Manager, Registry, Request, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_record::read::Recording;
use situate_record::{Options, RecordError, Recorder};

#[derive(Skill, Default)]
#[skill(name = "rec.count")]
struct Count {
    #[output]
    n: f64,
    #[output]
    ramp: [f32; 3],
}

impl Body for Count {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.n = cx.cycle() as f64;
        self.ramp = [0.0, 1.0, f32::NAN];
        if cx.cycle() == 3 {
            cx.print("three");
        }
        Ok(())
    }
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("situate-record-{}-{name}.mcap", std::process::id()))
}

fn manager() -> Manager {
    manager_on(ClockKind::Simulated)
}

fn manager_on(clock: ClockKind) -> Manager {
    let mut registry = Registry::new();
    registry.register::<Count>();
    let spec = RobotSpec::new("rec")
        .clock(clock)
        .period_s(0.1)
        .skill(SkillSpec::new("c", "rec.count").remap("n", "count").remap("ramp", "ramp").active(true))
        // A second writer of `count`, of higher priority, switched on later.
        .skill(SkillSpec::new("c2", "rec.count").remap("n", "count").remap("ramp", "ramp2").priority(2).active(false));
    match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

#[test]
fn a_recording_has_a_channel_per_written_leaf_and_per_event_kind_read_back_with_mcap() {
    let path = temp("channels");
    let mut m = manager();
    let unix_ns = || {
        let d = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).expect("after 1970");
        u64::try_from(d.as_nanos()).expect("ns fit")
    };
    let before = unix_ns();
    let recorder = Recorder::start(&path, &mut m).unwrap_or_else(|e| panic!("{e}"));
    let after = unix_ns();
    m.run_cycles(10);
    m.request(Request::Activate { skills: vec!["c2".into()], with_providers: false }).unwrap();
    m.run_cycles(10);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(summary.frames, 20, "{summary:?}");
    assert_eq!(summary.dropped, 0, "{summary:?}");
    assert_eq!(summary.cycles, Some((1, 20)), "{summary:?}");

    let bytes = std::fs::read(&path).unwrap();
    // The run's start in Unix time: when the recording started (the manager had run no cycle).
    let summary_section = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let index = summary_section.metadata_indexes.iter().find(|m| m.name == "situate").expect("the situate metadata");
    let metadata = mcap::read::metadata(&bytes, index).unwrap();
    let origin: u64 = metadata.metadata["time_origin_unix_ns"].parse().unwrap();
    assert!((before..=after).contains(&origin), "{before} <= {origin} <= {after}");
    let mut per_topic: BTreeMap<String, Vec<(u64, serde_json::Value)>> = BTreeMap::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        let channel = &message.channel;
        assert_eq!(channel.message_encoding, "json");
        let schema = channel.schema.as_ref().expect("every channel has a schema");
        assert_eq!(schema.encoding, "jsonschema");
        let schema: serde_json::Value = serde_json::from_slice(&schema.data).unwrap();
        assert_eq!(schema["type"], "object", "{schema}");
        let data: serde_json::Value = serde_json::from_slice(&message.data).unwrap();
        per_topic.entry(channel.topic.clone()).or_default().push((message.log_time, data));
    }
    let topics: Vec<&str> = per_topic.keys().map(String::as_str).collect();
    assert!(topics.contains(&"count") && topics.contains(&"ramp"), "{topics:?}");
    assert!(topics.contains(&"situate/prints"), "{topics:?}");

    // One message per cycle, the cycle in it, the run's start plus the manager's clock as log
    // time (Foxglove shows the run's date, not 1970).
    let count = &per_topic["count"];
    assert_eq!(count.len(), 20);
    for (k, (log_time, data)) in count.iter().enumerate() {
        let cycle = k as u64 + 1;
        assert_eq!(data["cycle"], cycle);
        assert_eq!(data["value"], cycle as f64);
        assert_eq!(*log_time, origin + cycle * 100_000_000, "cycle {cycle} at {} s", cycle as f64 * 0.1);
    }
    // Non-finite floats as the link writes them, and the schema allows them.
    assert_eq!(per_topic["ramp"][0].1["value"], serde_json::json!([0.0, 1.0, "nan"]));
    let print = &per_topic["situate/prints"];
    assert_eq!(print.len(), 1, "{print:?}");
    assert_eq!(print[0].1["line"], "three");
    assert_eq!(print[0].1["cycle"], 3);
    assert_eq!(print[0].0, origin + 300_000_000, "an event at its cycle's time");
    // Read back, a cycle's time is the manager's clock again.
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rec.cycles[&5].time_ns, 500_000_000);

    // Who holds the resource `count`, when that changes; the activation event.
    let winners: Vec<(u64, String)> = per_topic["situate/winners"]
        .iter()
        .map(|(_, d)| (d["cycle"].as_u64().unwrap(), d["skill"].as_str().unwrap().to_string()))
        .collect();
    assert_eq!(winners, vec![(1, "c".to_string()), (11, "c2".to_string())]);
    let activations = &per_topic["situate/events/activation_applied"];
    assert_eq!(activations.len(), 1, "{activations:?}");
    assert_eq!(activations[0].1["activated"], serde_json::json!(["c2"]));
    assert_eq!(activations[0].1["cycle"], 11);
    assert_eq!(activations[0].0, origin + 1_100_000_000);

    // Indexed: the summary section lists the channels and counts the messages.
    let index = mcap::Summary::read(&bytes).unwrap().expect("a summary section");
    let stats = index.stats.expect("statistics");
    assert_eq!(stats.message_count, summary.messages);
    assert_eq!(index.channels.len(), summary.channels);
    assert!(!index.chunk_indexes.is_empty(), "chunked, so readers can seek");
    std::fs::remove_file(&path).ok();
}

#[test]
fn a_path_that_cannot_be_written_is_an_error_naming_it_and_nothing_is_tapped() {
    let path = std::env::temp_dir().join("situate-no-such-dir").join("sub").join("x.mcap");
    let mut m = manager();
    match Recorder::start(&path, &mut m) {
        Err(e @ RecordError::Io { .. }) => assert!(e.to_string().contains("situate-no-such-dir"), "{e}"),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("a recording into a missing directory started"),
    }
    // The robot runs on.
    m.run_cycles(3);
}

#[test]
fn several_taps_get_every_frame_and_a_dropped_one_leaves_the_others() {
    let mut m = manager();
    let a = m.tap(64);
    let b = m.tap(64);
    m.run_cycles(3);
    drop(b);
    m.run_cycles(3);
    let cycles: Vec<u64> = a.frames.try_iter().map(|f| f.cycle).collect();
    assert_eq!(cycles, [1, 2, 3, 4, 5, 6]);
    assert_eq!(a.dropped(), 0);
}

#[test]
fn a_running_robot_is_recorded_from_its_next_cycle_through_its_handle() {
    use situate::manager::{Control as _, Reply};
    use std::time::{Duration, Instant};
    let path = temp("running");
    // Paced (100 cycles a second), so the writer never falls 4,096 cycles behind.
    let mut m = manager();
    m.set_speed(Some(10.0));
    let (mut handle, join) = m.spawn(true);
    let recorder = Recorder::start_running(&path, &handle, BTreeMap::new(), Duration::from_secs(30))
        .unwrap_or_else(|e| panic!("{e}"));
    // Wait (generously) until cycles have gone by: no timing is asserted.
    let deadline = Instant::now() + Duration::from_secs(120);
    while Instant::now() < deadline {
        match handle.request(Request::QueryStats) {
            Ok(Reply::Stats(s)) if s.cycle > 50 => break,
            _ => std::thread::sleep(Duration::from_millis(10)),
        }
    }
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    assert!(summary.frames > 0, "{summary:?}");
    let (first, last) = summary.cycles.expect("cycles");
    assert_eq!(last - first + 1, summary.frames, "no cycle missing: {summary:?}");
    assert_eq!(summary.dropped, 0);
}

/// The `situate/gaps` markers of a file, (first, last), and its
/// `situate_drops` metadata record.
fn gaps_of(path: &std::path::Path) -> (Vec<(u64, u64)>, BTreeMap<String, String>) {
    let bytes = std::fs::read(path).unwrap();
    let mut gaps = Vec::new();
    for message in mcap::MessageStream::new(&bytes).unwrap() {
        let message = message.unwrap();
        if message.channel.topic == "situate/gaps" {
            let data: serde_json::Value = serde_json::from_slice(&message.data).unwrap();
            let (first, last) = (data["cycle"].as_u64().unwrap(), data["last"].as_u64().unwrap());
            assert_eq!(data["count"].as_u64(), Some(last - first + 1), "{data}");
            gaps.push((first, last));
        }
    }
    let mut drops = BTreeMap::new();
    for record in mcap::read::LinearReader::new(&bytes).unwrap() {
        if let mcap::records::Record::Metadata(m) = record.unwrap() {
            if m.name == "situate_drops" {
                drops = m.metadata;
            }
        }
    }
    (gaps, drops)
}

#[test]
fn on_the_simulated_clock_a_writer_that_falls_behind_holds_the_cycle_and_loses_nothing() {
    let path = temp("slow-writer");
    let mut m = manager();
    // A queue of one frame, and a writer that reads only when let.
    let (release, hold) = crossbeam_channel::bounded::<()>(0);
    let options = Options { queue_frames: 1, hold: Some(hold) };
    let recorder =
        Recorder::start_with_options(&path, &mut m, BTreeMap::new(), options).unwrap_or_else(|e| panic!("{e}"));
    let runner = std::thread::spawn(move || {
        for _ in 0..200 {
            m.cycle();
        }
        m
    });
    // The writer reads a round at a time, as long as the robot runs.
    while !runner.is_finished() {
        let _ = release.send_timeout((), std::time::Duration::from_millis(10));
    }
    let m = runner.join().unwrap_or_else(|_| panic!("the robot's thread panicked"));
    drop(release);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((summary.frames, summary.dropped), (200, 0), "{summary:?}");
    assert_eq!(summary.cycles, Some((1, 200)));
    let (gaps, drops) = gaps_of(&path);
    assert!(gaps.is_empty(), "{gaps:?}");
    assert_eq!(drops.get("dropped_cycles").map(String::as_str), Some("0"), "{drops:?}");
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_file(&path).ok();
    assert_eq!(rec.cycles.keys().copied().collect::<Vec<_>>(), (1..=200).collect::<Vec<_>>());
    assert_eq!((rec.dropped_count, rec.dropped.len()), (0, 0));
}

#[test]
fn on_the_wall_clock_dropped_cycles_are_counted_and_written_into_the_file() {
    let path = temp("wall-drops");
    let mut m = manager_on(ClockKind::Wall);
    let (release, hold) = crossbeam_channel::bounded::<()>(0);
    let options = Options { queue_frames: 4, hold: Some(hold) };
    let recorder =
        Recorder::start_with_options(&path, &mut m, BTreeMap::new(), options).unwrap_or_else(|e| panic!("{e}"));
    // The writer held: cycles 1-4 are queued, 5-50 dropped (the cycle never waits).
    for _ in 0..50 {
        m.cycle();
    }
    // One round of reading let (two messages: it starts, it has read).
    release.send(()).unwrap();
    release.send(()).unwrap();
    // Cycles 51-54 are queued, 55-60 dropped; the writer, let again, sees
    // cycle 51 after 4 and marks 5-50 there.
    for _ in 0..10 {
        m.cycle();
    }
    release.send(()).unwrap();
    release.send(()).unwrap();
    drop(release);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(summary.frames, 8, "{summary:?}");
    assert_eq!(summary.dropped, 52, "{summary:?}");
    assert_eq!(summary.dropped_ranges, [(5, 50), (55, 60)], "{summary:?}");
    // Durably: a marker per gap (the one in the middle written when cycle
    // 51 came, the last at the end) and the record at the end.
    let (gaps, drops) = gaps_of(&path);
    assert_eq!(gaps, [(5, 50), (55, 60)]);
    assert_eq!(drops.get("dropped_cycles").map(String::as_str), Some("52"), "{drops:?}");
    assert_eq!(drops.get("ranges").map(String::as_str), Some("[[5,50],[55,60]]"), "{drops:?}");
    // Read back: what the file lacks.
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    std::fs::remove_file(&path).ok();
    assert_eq!(rec.cycles.keys().copied().collect::<Vec<_>>(), [1, 2, 3, 4, 51, 52, 53, 54]);
    assert_eq!((rec.dropped_count, rec.dropped.clone()), (52, vec![(5, 50), (55, 60)]));
    assert_eq!(rec.first_dropped_from(0), Some(5));
    assert_eq!(rec.first_dropped_from(51), Some(55));
}

#[test]
fn a_running_simulated_robot_recorded_through_its_handle_waits_for_a_slow_writer() {
    use situate::manager::{Control as _, Reply};
    use std::time::{Duration, Instant};
    let path = temp("running-slow");
    // Not paced: the cycle runs as fast as it can, the queue holds one frame.
    let m = manager();
    let (mut handle, join) = m.spawn(true);
    let options = Options { queue_frames: 1, hold: None };
    let recorder =
        Recorder::start_running_with_options(&path, &handle, BTreeMap::new(), Duration::from_secs(30), options)
            .unwrap_or_else(|e| panic!("{e}"));
    let stats = |handle: &mut situate::manager::Handle| match handle.request(Request::QueryStats) {
        Ok(Reply::Stats(s)) => s.cycle,
        _ => 0,
    };
    let start = stats(&mut handle);
    let deadline = Instant::now() + Duration::from_secs(120);
    while Instant::now() < deadline && stats(&mut handle) < start + 300 {
        std::thread::sleep(Duration::from_millis(10));
    }
    let _ = handle.request(Request::Shutdown);
    let _ = join.join();
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    let _ = std::fs::remove_file(&path);
    assert!(summary.frames >= 300, "{summary:?}");
    let (first, last) = summary.cycles.expect("cycles");
    assert_eq!(last - first + 1, summary.frames, "no cycle missing: {summary:?}");
    assert_eq!(summary.dropped, 0, "{summary:?}");
}

#[test]
fn each_cycles_events_follow_its_frame_so_a_file_cut_short_keeps_the_events_of_the_cycles_it_holds() {
    let path = temp("events-in-order");
    let mut m = manager();
    // The writer let read only now and then: each round reads the hundreds of cycles queued
    // meanwhile, as when a fast simulated robot outruns it.
    let (release, hold) = crossbeam_channel::bounded::<()>(0);
    let options = Options { queue_frames: 512, hold: Some(hold) };
    let recorder =
        Recorder::start_with_options(&path, &mut m, BTreeMap::new(), options).unwrap_or_else(|e| panic!("{e}"));
    let runner = std::thread::spawn(move || {
        for k in 0..8000u64 {
            if k % 7 == 3 {
                let skills = vec!["c2".to_string()];
                let request = if (k / 7) % 2 == 0 {
                    Request::Activate { skills, with_providers: false }
                } else {
                    Request::Deactivate { skills }
                };
                m.request(request).unwrap_or_else(|e| panic!("{e}"));
            }
            m.cycle();
        }
    });
    while !runner.is_finished() {
        let _ = release.send_timeout((), std::time::Duration::from_millis(10));
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    runner.join().expect("the robot ran");
    let finishing = std::thread::spawn(move || recorder.finish());
    while !finishing.is_finished() {
        let _ = release.send_timeout((), std::time::Duration::from_millis(10));
    }
    finishing.join().expect("the writer").unwrap_or_else(|e| panic!("{e}"));
    let bytes = std::fs::read(&path).unwrap();
    let whole = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(whole.span(), Some((1, 8000)));
    let summary = mcap::Summary::read(&bytes).unwrap().expect("a summary");
    let chunks: Vec<usize> = summary.chunk_indexes.iter().map(|c| c.chunk_start_offset as usize).collect();
    assert!(chunks.len() >= 2, "{} chunks", chunks.len());
    let cycle_of = |e: &serde_json::Value| e["cycle"].as_u64().unwrap_or(0);
    // Cut inside each chunk after the first: the cycles kept have every event they had.
    let cut = path.with_extension("cut.mcap");
    for &at in &chunks[1..] {
        std::fs::write(&cut, &bytes[..at + 100]).unwrap();
        let rec = Recording::open_cut_short(&cut).unwrap_or_else(|e| panic!("{e}"));
        let last = rec.cut_short.as_ref().and_then(|c| c.last_cycle).expect("cycles kept");
        let expected: Vec<_> = whole.events.iter().filter(|(_, e)| cycle_of(e) <= last).collect();
        let kept: Vec<_> = rec.events.iter().collect();
        assert!(expected.len() > 100, "{} events up to cycle {last}", expected.len());
        assert_eq!(kept.len(), expected.len(), "the events of the cycles kept, up to cycle {last}");
        assert_eq!(kept, expected);
    }
    let _ = std::fs::remove_file(&path);
    let _ = std::fs::remove_file(&cut);
}
