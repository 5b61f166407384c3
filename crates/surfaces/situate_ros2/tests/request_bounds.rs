//! A request (or a message) can make the bridge allocate no more than a small multiple of its
//! own bytes, whatever lengths it declares: thousands of generated, truncated and corrupted
//! payloads of every service request type (and every message type) decoded under a global
//! allocator that counts this thread's live bytes; and the tester's 12-byte request declaring a
//! 4 GiB string, sent to a running robot, which answers with an error and runs on.
//!
//! The allocator refuses any single allocation above 256 MiB, as a robot with its memory limited
//! would: a decoder that allocates what a length declares aborts this test (`memory allocation
//! of 4294967295 bytes failed`) instead of taking the machine's memory.

mod support;

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use serde::de::DeserializeOwned;
use serde::Serialize;
use situate::manager::{Reply, Request};
use situate_ros2::msgs::{self, Bool, Float64, Header, Int64, LaserScan, Odometry, Time, Twist, Vector3};
use situate_ros2::services::{
    ListParametersRequest, ListParametersResponse, Names, Parameter, ParameterValue, SetBoolRequest, SetBoolResponse,
    SetParametersRequest, SetParametersResponse,
};
use situate_ros2::Bridge;
use support::{call, call_until_answered, config, observer, service_key, toy_robot};

/// No single allocation above this: a robot whose memory is limited.
const REFUSED_ABOVE: usize = 256 << 20;

struct Bounded;

thread_local! {
    /// This thread's live bytes (frees of another thread's allocations make it drift, which a
    /// measurement taken around one call on one thread does not see).
    static LIVE: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn grew(by: isize) {
    let _ = LIVE.try_with(|live| {
        live.set(live.get() + by);
        let _ = PEAK.try_with(|peak| peak.set(peak.get().max(live.get())));
    });
}

// SAFETY: every call is passed on to the system allocator unchanged, except that a request above
// REFUSED_ABOVE gets null (allowed: "out of memory"); the counts are thread-local `Cell`s without
// destructors, which never allocate.
unsafe impl GlobalAlloc for Bounded {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if layout.size() > REFUSED_ABOVE {
            return std::ptr::null_mut();
        }
        // SAFETY: the caller's contract is the system allocator's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            grew(layout.size() as isize);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        if layout.size() > REFUSED_ABOVE {
            return std::ptr::null_mut();
        }
        // SAFETY: as above.
        let p = unsafe { System.alloc_zeroed(layout) };
        if !p.is_null() {
            grew(layout.size() as isize);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        grew(-(layout.size() as isize));
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if new_size > REFUSED_ABOVE {
            return std::ptr::null_mut();
        }
        // SAFETY: as above.
        let p = unsafe { System.realloc(ptr, layout, new_size) };
        if !p.is_null() {
            grew(new_size as isize - layout.size() as isize);
        }
        p
    }
}

#[global_allocator]
static GLOBAL: Bounded = Bounded;

/// The most bytes live on this thread during `f`, above what was live before it (what `f`
/// returns still counts).
fn peak_during<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let before = LIVE.with(Cell::get);
    PEAK.with(|p| p.set(before));
    let r = f();
    let peak = PEAK.with(Cell::get) - before;
    (r, peak.max(0) as usize)
}

thread_local! {
    /// The largest ratio of peak bytes to payload bytes seen (payloads of 100 bytes or more),
    /// and the largest peak.
    static WORST: Cell<(f64, usize)> = const { Cell::new((0.0, 0)) };
}

/// What a payload of `len` bytes may cost to decode: a vector grows by doubling from 4 elements,
/// and an element in memory (a `String`: 24 bytes) is a few times its smallest encoding (a
/// string's length: 4 bytes), so a small multiple plus a little for the first elements. The
/// decoder before the fix allocated what a length declared: 4 GiB for a 12-byte request.
fn allowed(len: usize) -> usize {
    16 * len + 2048
}

/// A small deterministic generator (xorshift64*), so a failure replays.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn string(&mut self) -> String {
        const PIECES: [&str; 6] = ["a", "wander.speed", "é", "", "_", "日本"];
        (0..self.below(6)).map(|_| PIECES[self.below(PIECES.len() as u64) as usize]).collect()
    }
    fn strings(&mut self) -> Vec<String> {
        (0..self.below(5)).map(|_| self.string()).collect()
    }
    fn value(&mut self) -> ParameterValue {
        let n = self.below(4) as usize;
        ParameterValue {
            ty: self.below(10) as u8,
            bool_value: self.below(2) == 1,
            integer_value: self.next() as i64,
            double_value: self.below(1000) as f64 / 7.0,
            string_value: self.string(),
            byte_array_value: (0..n).map(|_| self.next() as u8).collect(),
            bool_array_value: (0..n).map(|_| self.below(2) == 1).collect(),
            integer_array_value: (0..n).map(|_| self.next() as i64).collect(),
            double_array_value: (0..n).map(|i| i as f64).collect(),
            string_array_value: self.strings(),
        }
    }
}

/// One type's payloads: valid ones read back unchanged; every truncation of them, every
/// 4-aligned word of them replaced by an oversized length, random corruptions and random bodies
/// are read without a panic; none costs more than `allowed`. Returns how many were decoded.
fn fuzz<T>(rng: &mut Rng, make: impl Fn(&mut Rng) -> T) -> usize
where
    T: Serialize + DeserializeOwned + PartialEq + std::fmt::Debug,
{
    let mut decoded = 0;
    let mut check = |payload: &[u8]| {
        let (result, peak) = peak_during(|| msgs::decode::<T>(payload));
        assert!(
            peak <= allowed(payload.len()),
            "{}: {peak} bytes allocated for a payload of {} ({payload:02x?}); {result:?}",
            std::any::type_name::<T>(),
            payload.len()
        );
        decoded += 1;
        WORST.with(|w| {
            let (ratio, most) = w.get();
            let r = if payload.len() >= 100 { peak as f64 / payload.len() as f64 } else { 0.0 };
            w.set((ratio.max(r), most.max(peak)));
        });
        result
    };
    for _ in 0..60 {
        let value = make(rng);
        let mut bytes = if rng.below(4) == 0 {
            cdr::serialize::<_, _, cdr::CdrBe>(&value, cdr::Infinite).expect("encodes")
        } else {
            msgs::encode(&value).expect("encodes")
        };
        assert_eq!(check(&bytes).expect("a valid payload reads back"), value);
        for cut in 0..bytes.len() {
            // A cut inside the message fails; a cut in trailing padding may not.
            let _ = check(&bytes[..cut]);
        }
        let big_endian = bytes[1] == 0;
        for at in (4..bytes.len().saturating_sub(3)).step_by(4) {
            let left = (bytes.len() - at) as u32;
            for declared in [u32::MAX, 0x8000_0000, 0x7fff_ffff, 0x0100_0000, left, left + 1, left * 2] {
                let mut bad = bytes.clone();
                let word = if big_endian { declared.to_be_bytes() } else { declared.to_le_bytes() };
                bad[at..at + 4].copy_from_slice(&word);
                let _ = check(&bad);
            }
        }
        for _ in 0..20 {
            let at = 4 + rng.below((bytes.len() - 4).max(1) as u64) as usize;
            if at < bytes.len() {
                let keep = bytes[at];
                bytes[at] = rng.next() as u8;
                let _ = check(&bytes);
                bytes[at] = keep;
            }
        }
    }
    for _ in 0..500 {
        let mut payload = vec![0, 1, 0, 0];
        for _ in 0..rng.below(48) {
            // Mostly small numbers, as lengths and counts are, and some anything.
            payload.push(if rng.below(3) == 0 { rng.next() as u8 } else { rng.below(4) as u8 });
        }
        let _ = check(&payload);
    }
    decoded
}

#[test]
fn every_length_in_a_request_or_message_is_bounded_by_the_bytes_present() {
    let mut rng = Rng(0x5eed_1234_abcd_0001);
    let mut total = 0;
    // The service requests.
    total += fuzz(&mut rng, |r| SetBoolRequest { data: r.below(2) == 1 });
    total += fuzz(&mut rng, |r| Names { names: r.strings() });
    total += fuzz(&mut rng, |r| ListParametersRequest { prefixes: r.strings(), depth: r.below(4) });
    total += fuzz(&mut rng, |r| SetParametersRequest {
        parameters: (0..r.below(4)).map(|_| Parameter { name: r.string(), value: r.value() }).collect(),
    });
    // The messages, which a subscription would read.
    total += fuzz(&mut rng, |r| Twist {
        linear: Vector3 { x: r.below(9) as f64, ..Vector3::default() },
        angular: Vector3::default(),
    });
    total += fuzz(&mut rng, |r| Odometry {
        header: Header { stamp: Time { sec: r.below(100) as i32, nanosec: 5 }, frame_id: r.string() },
        child_frame_id: r.string(),
        ..Odometry::default()
    });
    total += fuzz(&mut rng, |r| LaserScan {
        header: Header { stamp: Time::default(), frame_id: r.string() },
        ranges: (0..r.below(30)).map(|i| i as f32).collect(),
        intensities: (0..r.below(3)).map(|i| i as f32).collect(),
        ..LaserScan::default()
    });
    total += fuzz(&mut rng, |r| Float64 { data: r.below(100) as f64 });
    total += fuzz(&mut rng, |r| Int64 { data: r.next() as i64 });
    total += fuzz(&mut rng, |r| Bool { data: r.below(2) == 1 });
    assert!(total > 20_000, "{total} payloads");
    let (ratio, most) = WORST.with(Cell::get);
    println!("{total} payloads decoded; at most {most} bytes allocated, {ratio:.1} times the payload's bytes from 100 bytes on");
}

#[test]
fn the_tester_s_12_byte_request_costs_nothing() {
    // GetParameters: one name, declaring 4 GiB - 1 bytes, none of them present.
    let payload = [0, 1, 0, 0, 1, 0, 0, 0, 0xff, 0xff, 0xff, 0xff];
    let (result, peak) = peak_during(|| msgs::decode::<Names>(&payload));
    let e = result.expect_err("refused");
    assert!(e.to_string().contains("declares 4294967295 bytes, 0 left"), "{e}");
    assert!(peak <= allowed(payload.len()), "{peak} bytes");
}

#[test]
fn requests_declaring_more_than_they_carry_get_an_error_reply_and_the_robot_runs_on() {
    let robot = toy_robot("boundbot");
    let bridge = Bridge::start("boundbot", robot.handle.clone(), robot.session(), &config("ros2:\n  services: true\n"))
        .expect("starts");
    let observer = observer(&robot.endpoint);
    let list = service_key(&bridge, "/boundbot/list_parameters");
    let valid = msgs::encode(&ListParametersRequest { prefixes: vec![], depth: 0 }).expect("encode");
    call_until_answered(&observer, &list, &valid);

    // One string (or sequence) declared 4 GiB - 1 long, in 12 bytes.
    let huge = [0, 1, 0, 0, 1, 0, 0, 0, 0xff, 0xff, 0xff, 0xff];
    // Services whose response cannot say so: a Zenoh error reply naming the type and the problem.
    for (name, ty) in [
        ("get_parameters", "rcl_interfaces/srv/GetParameters"),
        ("describe_parameters", "rcl_interfaces/srv/DescribeParameters"),
        ("get_parameter_types", "rcl_interfaces/srv/GetParameterTypes"),
    ] {
        let key = service_key(&bridge, &format!("/boundbot/{name}"));
        let err = call(&observer, &key, &huge, 1).expect_err("an error reply");
        assert!(err.contains(ty) && err.contains("`names[0]`") && err.contains("declares 4294967295 bytes"), "{err}");
    }
    let err = call(&observer, &list, &[0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff], 1).expect_err("an error reply");
    assert!(err.contains("`prefixes`") && err.contains("declares 4294967295 elements"), "{err}");

    // SetParameters says so in its one result, SetBool in its message: a ROS 2 client shows it.
    let key = service_key(&bridge, "/boundbot/set_parameters");
    let (payload, seq, _) = call(&observer, &key, &huge, 7).expect("a response");
    assert_eq!(seq, 7, "the response answers the call");
    let r: SetParametersResponse = msgs::decode(&payload).expect("a SetParameters response");
    assert_eq!(r.results.len(), 1, "{r:?}");
    assert!(!r.results[0].successful, "{r:?}");
    let reason = &r.results[0].reason;
    assert!(reason.contains("rcl_interfaces/srv/SetParameters") && reason.contains("`parameters[0].name`"), "{reason}");
    let key = service_key(&bridge, "/boundbot/wander/set_active");
    let (payload, _, _) = call(&observer, &key, &[0, 1, 0, 0], 8).expect("a response");
    let r: SetBoolResponse = msgs::decode(&payload).expect("a SetBool response");
    assert!(!r.success && r.message.contains("std_srvs/srv/SetBool") && r.message.contains("`data`"), "{r:?}");

    // A request past the limit is not read at all.
    let mut big = vec![0, 1, 0, 0];
    big.resize(situate_ros2::services::MAX_REQUEST_BYTES + 1, 0);
    let err = call(&observer, &list, &big, 9).expect_err("an error reply");
    assert!(err.contains("limited to 1048576 bytes"), "{err}");

    // The robot runs on and the bridge still answers.
    let (payload, _, _) = call(&observer, &list, &valid, 10).expect("answered");
    let listed: ListParametersResponse = msgs::decode(&payload).expect("a ListParameters response");
    assert!(listed.result.names.contains(&"wander.speed".to_string()), "{listed:?}");
    assert!(matches!(robot.handle.request_timeout(Request::QueryStats, support::WAIT), Ok(Reply::Stats(_))));
    assert_eq!(bridge.service_stats().malformed, 7, "every refused request counted");
}
