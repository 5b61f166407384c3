//! Recordings damaged or doctored after they were written: each is refused
//! when read, with an error naming the problem and where it is, in time and
//! memory bounded by the file. Each bad file is made from a real recording
//! (written, then changed).

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::Value as Json;
use situate::manager::{ClockKind, Manager, Registry, RobotSpec, SkillSpec};
use situate::prelude::*;
use situate_record::read::{ReadError, Recording};
use situate_record::Recorder;

#[derive(Skill, Default)]
#[skill(name = "bad.count")]
struct Count {
    #[output]
    n: f64,
    #[output]
    ring: [f32; 32],
}

impl Body for Count {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.n = cx.cycle() as f64;
        // Values that compress poorly, so the file has several chunks.
        let mut x = cx.cycle().wrapping_mul(0x9e37_79b9_7f4a_7c15);
        for r in &mut self.ring {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            *r = (x >> 40) as f32;
        }
        Ok(())
    }
}

const CYCLES: u64 = 3000;

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("situate-bad-{}-{name}.mcap", std::process::id()))
}

/// A real recording of `CYCLES` cycles, with a `--set` in its metadata.
fn recording(name: &str) -> PathBuf {
    let path = temp(name);
    let mut registry = Registry::new();
    registry.register::<Count>();
    let spec = RobotSpec::new("bad")
        .clock(ClockKind::Simulated)
        .period_s(0.01)
        .skill(SkillSpec::new("c", "bad.count").remap("n", "count").remap("ring", "ring"));
    let mut m = Manager::build(&spec, &registry).unwrap_or_else(|e| panic!("{e}"));
    let meta = BTreeMap::from([("sets".to_string(), r#"["c.x=1"]"#.to_string())]);
    let recorder = Recorder::start_with(&path, &mut m, meta).unwrap_or_else(|e| panic!("{e}"));
    m.run_cycles(CYCLES);
    drop(m);
    let summary = recorder.finish().unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(summary.frames, CYCLES);
    // As written, it reads back whole.
    let rec = Recording::open(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(rec.span(), Some((1, CYCLES)));
    assert_eq!(rec.sets, ["c.x=1"]);
    path
}

/// Writes `src` again to `dst` as a valid MCAP file (CRCs and summary
/// right), its metadata and messages changed by `meta` and `message`.
fn rewrite(
    src: &Path,
    dst: &Path,
    meta: impl Fn(&str, &mut BTreeMap<String, String>),
    message: impl Fn(&str, &mut Json),
) {
    let bytes = std::fs::read(src).unwrap();
    let file = std::io::BufWriter::new(std::fs::File::create(dst).unwrap());
    let mut w = mcap::WriteOptions::new().compression(Some(mcap::Compression::Zstd)).create(file).unwrap();
    for record in mcap::read::LinearReader::new(&bytes).unwrap() {
        if let mcap::records::Record::Metadata(mut m) = record.unwrap() {
            meta(&m.name, &mut m.metadata);
            w.write_metadata(&m).unwrap();
        }
    }
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let mut m = m.unwrap();
        let mut data: Json = serde_json::from_slice(&m.data).unwrap();
        message(&m.channel.topic, &mut data);
        m.data = Cow::Owned(serde_json::to_vec(&data).unwrap());
        w.write(&m).unwrap();
    }
    w.finish().unwrap();
}

/// The error reading `path`, as said (the file's name first).
fn refused(path: &Path) -> String {
    let started = std::time::Instant::now();
    let outcome = Recording::open(path);
    let error = match outcome {
        Ok(rec) => panic!("{} was read: {} cycles, span {:?}", path.display(), rec.cycles.len(), rec.span()),
        Err(e) => e,
    };
    assert!(matches!(error, ReadError::Bad { .. }), "{error:?}");
    let text = error.to_string();
    assert!(text.starts_with(&path.display().to_string()), "{text}");
    // Not a timing test: a bound far above the few milliseconds it takes.
    assert!(started.elapsed() < std::time::Duration::from_secs(60), "{text}");
    text
}

#[test]
fn a_cycle_far_past_the_recorded_ones_is_refused_naming_it() {
    // The last cycle renumbered 10^15: a replay would run that many cycles.
    let src = recording("huge-src");
    let dst = temp("huge");
    rewrite(
        &src,
        &dst,
        |_, _| {},
        |topic, data| {
            if topic != "situate/winners" && data["cycle"] == CYCLES {
                data["cycle"] = Json::from(1_000_000_000_000_000u64);
            }
        },
    );
    let text = refused(&dst);
    assert!(text.contains(&format!("cycle 1000000000000000 follows cycle {}", CYCLES - 1)), "{text}");
    assert!(text.contains("neither in the file nor marked as dropped"), "{text}");
    // Only the fingerprint renumbered: the cycle's leaves have none.
    rewrite(
        &src,
        &dst,
        |_, _| {},
        |topic, data| {
            if topic == "situate/cycles" && data["cycle"] == CYCLES {
                data["cycle"] = Json::from(1_000_000_000_000_000u64);
            }
        },
    );
    let text = refused(&dst);
    assert!(text.contains(&format!("cycle {CYCLES}: leaves recorded but no `situate/cycles`")), "{text}");
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}

/// Each of `bads` as the `situate` metadata's `key` makes a file refused, naming the key and the
/// value.
fn each_refused_as_metadata(name: &str, key: &str, bads: &[&str]) {
    let src = recording(&format!("{name}-src"));
    let dst = temp(name);
    for bad in bads {
        rewrite(
            &src,
            &dst,
            |record, m| {
                if record == "situate" {
                    m.insert(key.into(), (*bad).into());
                }
            },
            |_, _| {},
        );
        let text = refused(&dst);
        assert!(text.contains(&format!("`{key}`")) && text.contains(&format!("`{bad}`")), "{text}");
    }
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}

#[test]
fn a_period_that_is_not_a_number_is_refused_naming_it() {
    each_refused_as_metadata("nan", "period_s", &["nan", "inf", "-0.01", "0", "1e300", "ten"]);
}

#[test]
fn a_time_origin_that_is_not_a_time_is_refused_naming_it() {
    each_refused_as_metadata("origin", "time_origin_unix_ns", &["-1", "1.5e18", "yesterday", "18446744073709551616"]);
}

#[test]
fn recorded_parameter_sets_that_are_not_json_are_refused_naming_them() {
    let src = recording("sets-src");
    let dst = temp("sets");
    for bad in ["c.x=1", "[1, 2]", "{\"c.x\": 1}", "[\"c.x=1\""] {
        rewrite(
            &src,
            &dst,
            |name, m| {
                if name == "situate" {
                    m.insert("sets".into(), bad.into());
                }
            },
            |_, _| {},
        );
        let text = refused(&dst);
        assert!(text.contains("`sets`") && text.contains("not a JSON list"), "{bad}: {text}");
    }
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}

/// Where each chunk record starts, from the file's summary.
fn chunk_offsets(bytes: &[u8]) -> Vec<usize> {
    let summary = mcap::Summary::read(bytes).unwrap().expect("a summary");
    summary.chunk_indexes.iter().map(|c| c.chunk_start_offset as usize).collect()
}

#[test]
fn a_damaged_chunk_is_refused_naming_where_it_is() {
    let src = recording("chunk-src");
    let bytes = std::fs::read(&src).unwrap();
    let chunks = chunk_offsets(&bytes);
    assert!(chunks.len() >= 2, "{} chunks: a chunk in the middle is damaged", chunks.len());
    let at = chunks[1];
    let dst = temp("chunk");
    // The chunk's header zeroed, its opcode and length kept: it says it
    // holds nothing, and would be skipped.
    let mut zeroed = bytes.clone();
    zeroed[at + 9..at + 9 + 40].fill(0);
    std::fs::write(&dst, &zeroed).unwrap();
    let text = refused(&dst);
    assert!(text.contains(&format!("at byte {at} (chunk)")) && text.contains("damaged chunk header"), "{text}");
    // The whole record's start zeroed, opcode and length too.
    let mut zeroed = bytes.clone();
    zeroed[at..at + 9 + 40].fill(0);
    std::fs::write(&dst, &zeroed).unwrap();
    let text = refused(&dst);
    assert!(text.contains(&format!("at byte {at} (unknown record type 0x00)")), "{text}");
    // A byte of its compressed data changed: the decompression or the
    // chunk's CRC says so.
    let mut flipped = bytes.clone();
    flipped[at + 9 + 60] ^= 0x55;
    std::fs::write(&dst, &flipped).unwrap();
    let text = refused(&dst);
    assert!(text.contains(&format!("at byte {at} (chunk)")) && text.contains("damaged chunk"), "{text}");
    // A chunk whose header claims a huge size: refused before anything is
    // allocated for it.
    let mut huge = bytes.clone();
    huge[at + 9 + 16..at + 9 + 24].copy_from_slice(&u64::MAX.to_le_bytes());
    std::fs::write(&dst, &huge).unwrap();
    let text = refused(&dst);
    assert!(text.contains(&format!("at byte {at} (chunk)")) && text.contains("uncompressed"), "{text}");
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}

#[test]
fn a_file_cut_short_or_not_a_recording_is_refused() {
    let src = recording("cut-src");
    let bytes = std::fs::read(&src).unwrap();
    let dst = temp("cut");
    for len in [bytes.len() / 2, bytes.len() - 3, 12, 3] {
        std::fs::write(&dst, &bytes[..len]).unwrap();
        let text = refused(&dst);
        assert!(text.contains("cut short") || text.contains("MCAP magic"), "{len}: {text}");
    }
    std::fs::write(&dst, b"just some text, not a recording\n").unwrap();
    assert!(refused(&dst).contains("not an MCAP file"));
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}

#[test]
fn a_device_or_a_directory_is_refused_before_it_is_read() {
    // /dev/zero never ends: it must not be read at all.
    for path in [Path::new("/dev/zero"), Path::new("/dev/urandom")] {
        if path.exists() {
            assert!(refused(path).contains("not a regular file"));
        }
    }
    assert!(refused(&std::env::temp_dir()).contains("not a regular file"));
}

#[test]
fn a_file_cut_short_is_read_up_to_its_last_complete_cycle_when_asked() {
    let src = recording("recover-src");
    let bytes = std::fs::read(&src).unwrap();
    let whole = Recording::open(&src).unwrap_or_else(|e| panic!("{e}"));
    assert!(whole.cut_short.is_none());
    // Read whole, a complete file is what `open` reads.
    let same = Recording::open_cut_short(&src).unwrap_or_else(|e| panic!("{e}"));
    assert!(same.cut_short.is_none());
    assert_eq!(same.span(), whole.span());
    let chunks = chunk_offsets(&bytes);
    assert!(chunks.len() >= 2, "{} chunks", chunks.len());
    let dst = temp("recover");
    // Cut inside the second chunk, at the first chunk's end, inside it with
    // zeros after (a power cut's unwritten blocks), and past the data section
    // (the summary lost, the data whole): at the footer, and inside it.
    let footer = bytes.len() - 8 - 9 - 20; // the footer record (20 bytes) and the closing magic
    let zeros = |cut: usize| [&bytes[..cut], &[0u8; 4096][..]].concat();
    for (cut, file, whole_data) in [
        (chunks[1] + 100, bytes[..chunks[1] + 100].to_vec(), false),
        (chunks[1], bytes[..chunks[1]].to_vec(), false),
        (chunks[1] + 100 + 4096, zeros(chunks[1] + 100), false),
        (footer, bytes[..footer].to_vec(), true),
        (footer + 3, bytes[..footer + 3].to_vec(), true),
    ] {
        std::fs::write(&dst, &file).unwrap();
        assert!(refused(&dst).contains("--recover"), "{cut}: the refusal names the way to read it");
        let rec = Recording::open_cut_short(&dst).unwrap_or_else(|e| panic!("{cut}: {e}"));
        let info = rec.cut_short.clone().expect("said to be cut short");
        assert_eq!(info.file_bytes, cut as u64);
        assert!(info.at_byte <= cut as u64);
        let (first, last) = rec.span().expect("cycles kept");
        assert_eq!(first, 1);
        assert_eq!(Some(last), info.last_cycle);
        if whole_data {
            // The data section whole: every cycle.
            assert_eq!((last, info.cycles_dropped), (CYCLES, 0), "{info:?}");
            assert_eq!(rec.events.len(), whole.events.len());
        } else {
            assert!(last < CYCLES - 1 && last > 100, "{cut}: {last}");
        }
        // The cycles kept are the recording's, fingerprints and values.
        for (c, cycle) in &rec.cycles {
            let w = &whole.cycles[c];
            assert_eq!((cycle.hash, &cycle.leaves), (w.hash, &w.leaves), "cycle {c}");
        }
        assert!(rec.events.iter().all(|(_, e)| e["cycle"].as_u64().is_some_and(|c| c <= last)));
        assert!(rec.keyframes.keys().all(|&k| k <= last));
        assert_eq!(rec.metadata, whole.metadata, "the metadata is at the file's start");
    }
    // Cut inside the metadata record at the file's start: nothing to read, and said so.
    let mut pos = 8;
    while bytes[pos] != 0x0C {
        pos += 9 + u64::from_le_bytes(bytes[pos + 1..pos + 9].try_into().unwrap()) as usize;
    }
    std::fs::write(&dst, &bytes[..pos + 40]).unwrap();
    match Recording::open_cut_short(&dst) {
        Err(ReadError::Bad { message, .. }) => {
            assert!(message.contains("before its `situate` metadata record was whole"), "{message}")
        }
        other => panic!("a file cut in its metadata read: {:?}", other.map(|r| r.span())),
    }
    // Damage that is not a cut is refused as before.
    let mut flipped = bytes[..chunks[1] + 100].to_vec();
    flipped[chunks[0] + 9 + 60] ^= 0x55;
    std::fs::write(&dst, &flipped).unwrap();
    let text = match Recording::open_cut_short(&dst) {
        Err(ReadError::Bad { message, .. }) => message,
        other => panic!("a damaged chunk read: {:?}", other.map(|r| r.span())),
    };
    assert!(text.contains(&format!("at byte {} (chunk)", chunks[0])), "{text}");
    let _ = std::fs::remove_file(&dst);
    let _ = std::fs::remove_file(&src);
}
