//! A steady cycle allocates nothing: counted by a global allocator (a count
//! of this thread's allocations, not a time, so it cannot flake), for
//! derived skills (`#[derive(Skill)]` with `[f32; 24]` and `f64` ports),
//! hand-written Rust skills (`FnSkill`, the path bindings use) and C skills
//! through the C ABI; with a tap whose reader gives its frames back; and on a
//! spawned manager (its own cycle thread, the path a running robot takes),
//! counted over every thread.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::process::Command;

use situate::manager::{ClockKind, ExecutorKind, Manager, Registry, RobotSpec, SkillSpec};
use situate::manager::{Reply, Request};
use situate::prelude::*;
use situate::{FnSkill, Io, PortSpec, SignalType, SkillDecl, SkillType, ValueRef};
use situate_bench::skills::{self, Flavor};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

/// Allocations on every thread.
static ALL_ALLOCATIONS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

// SAFETY: every call is passed on to the system allocator unchanged; the
// count is a thread-local `Cell` without a destructor, which never allocates.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        ALL_ALLOCATIONS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: the caller's contract is the system allocator's.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: as above.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|n| n.set(n.get() + 1));
        ALL_ALLOCATIONS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        // SAFETY: as above.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// The tests of this file run one at a time: the spawned manager's test
/// counts every thread's allocations, and a test building its robot beside it
/// allocated into its count (5 failures in 30 runs of this file).
fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    static LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    LOCK.lock().unwrap_or_else(|p| p.into_inner())
}

fn allocations() -> u64 {
    ALLOCATIONS.with(Cell::get)
}

/// Allocations on this thread during `cycles` cycles, after a warm-up
/// (the first cycles compile the plan and size the buffers; the first is
/// sampled, and the next ones, run back to back, are not). The count spans
/// sampled cycles, which run every body the usual way
/// ([`cycle_spanning_samples`]).
fn allocations_per_steady_cycles(m: &mut Manager, cycles: u64) -> u64 {
    for _ in 0..200 {
        m.cycle();
    }
    let before = allocations();
    // The build allocated: the counter counts.
    assert!(before > 0);
    for k in 0..cycles {
        cycle_spanning_samples(m, k);
    }
    allocations() - before
}

/// Cycle `k` of a count: before every 32nd, a pause of two ticks of the
/// kernel's coarse clock (at most 4 ms each), so that the next cycle due to
/// be sampled is (at most one a tick is: `TIMING_SAMPLE`), however fast
/// the cycles run. A sampled cycle runs every body the usual way, the others
/// run the common step the short way: a count must see both.
fn cycle_spanning_samples(m: &mut Manager, k: u64) {
    if k.is_multiple_of(32) {
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    m.cycle();
}

#[test]
fn a_steady_cycle_of_a_spawned_manager_allocates_nothing() {
    let _serial = one_at_a_time();
    let mut spec = robot();
    spec.skills.extend(skills::chain("c", 50, Flavor::Derive, true));
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "c", 50);
    assert_eq!(spawned_steady_allocations(m), Some(0), "500 steady cycles of a spawned manager allocated");
}

/// What 500 steady cycles of `m`, spawned, allocate on any thread (the
/// manager is stopped and joined after).
fn spawned_steady_allocations(m: Manager) -> Option<u64> {
    use situate::manager::control::Control;
    let (mut handle, joiner) = m.spawn(false);
    let mut step = |cycles: u64| {
        let before = ALL_ALLOCATIONS.load(std::sync::atomic::Ordering::Relaxed);
        if let Err(e) = handle.request(Request::Step { cycles }) {
            panic!("step refused: {e}");
        }
        ALL_ALLOCATIONS.load(std::sync::atomic::Ordering::Relaxed) - before
    };
    step(200);
    // A step request of 1 cycle and one of 501 cost the same to ask and
    // answer: the difference is what 500 cycles allocate, on any thread.
    // Another thread of the process allocating at the same time can only
    // add to one of them: the least of a few tries is the cycles' own. (With
    // 5 tries, one fresh-clone `make test` beside another saw 1 allocation in
    // each; what allocated was not found. A cycle that allocates does in
    // every try, so more tries lose nothing.)
    let extra = (0..20).map(|_| step(501).saturating_sub(step(1))).min();
    drop(handle);
    assert!(joiner.join_timeout(std::time::Duration::from_secs(60)).is_ok(), "the manager did not end");
    extra
}

#[derive(Skill, Default)]
#[skill(name = "alloc.scale")]
struct Scale {
    #[input]
    x: f64,
    #[output]
    y: f64,
}

impl Body for Scale {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        self.y = 2.0 * self.x;
        Ok(())
    }
}

/// A hand-written skill: `y = x + 1` over the raw ports.
fn plus_one() -> SkillType {
    let mut decl = SkillDecl::new("alloc.plus_one", SkillKind::Sync);
    decl.inputs.push(PortSpec::new("x", SignalType::F64));
    decl.outputs.push(PortSpec::new("y", SignalType::F64));
    let d = decl.clone();
    SkillType::new(decl, move || {
        Ok(Box::new(FnSkill::new(&d, |io: &mut Io<'_>, _: &[Value]| {
            let x = io.inputs[0].as_ref().and_then(Value::as_f64).ok_or("no x")?;
            io.outputs[0] = Some(Value::F64(x + 1.0));
            Ok(())
        })) as _)
    })
}

/// Whether `signal` holds a value.
fn written(m: &mut Manager, signal: &str) -> bool {
    matches!(m.request(Request::QuerySignal { signal: signal.into() }), Ok(Reply::Signal(r)) if r.value.is_some())
}

fn robot() -> RobotSpec {
    RobotSpec::new("allocations").clock(ClockKind::Simulated).period_s(0.01).executor(ExecutorKind::Serial, None)
}

#[test]
fn a_steady_cycle_of_derived_array_skills_allocates_nothing() {
    let _serial = one_at_a_time();
    // Of 50 steps; and of more than a sampled cycle times, whose windows
    // run every step the usual way in turn.
    for n in [50, 3 * situate::manager::manager::SAMPLED_STEPS] {
        let mut spec = robot();
        spec.skills.extend(skills::chain("c", n, Flavor::Derive, true));
        let mut m = skills::build(&spec);
        skills::check_chain(&mut m, "c", n);
        assert_eq!(allocations_per_steady_cycles(&mut m, 1000), 0, "a chain of {n}");
    }
}

#[test]
fn a_tapped_cycle_whose_reader_gives_frames_back_allocates_nothing() {
    let _serial = one_at_a_time();
    // A recording or the GUI's history taps every cycle. The frame copies
    // the arrays' numbers: it must not hold the skills' own buffers, or each
    // skill would allocate a new array every cycle while a frame is out.
    let mut spec = robot();
    spec.skills.extend(skills::chain("c", 50, Flavor::Derive, true));
    let mut m = skills::build(&spec);
    skills::check_chain(&mut m, "c", 50);
    let tap = m.tap(16);
    let cycle_and_read = |m: &mut Manager, k: u64| {
        cycle_spanning_samples(m, k);
        let frame = tap.frames.try_recv().unwrap_or_else(|e| panic!("no frame: {e}"));
        assert!(frame.values.iter().any(|(_, v)| matches!(v, ValueRef::F32s(a) if a.len() == 24)));
        tap.give_back(frame);
    };
    for k in 1..=200 {
        cycle_and_read(&mut m, k);
    }
    let before = allocations();
    for k in 0..1000 {
        cycle_and_read(&mut m, k);
    }
    assert_eq!(allocations() - before, 0, "1000 tapped cycles allocated");
    assert_eq!(tap.dropped(), 0);
}

#[test]
fn a_steady_cycle_of_derived_and_hand_written_scalar_skills_allocates_nothing() {
    let _serial = one_at_a_time();
    let mut registry = skills::registry();
    registry.register::<Scale>().register::<Source>();
    registry.add(plus_one());
    let mut spec = robot();
    spec.skills.extend(skills::chain("c", 3, Flavor::Derive, true));
    spec.skills.push(SkillSpec::new("src", "alloc.source").remap("y", "s0"));
    for j in 0..20 {
        let ty = if j % 2 == 0 { "alloc.plus_one" } else { "alloc.scale" };
        spec.skills
            .push(SkillSpec::new(&format!("k{j}"), ty).remap("x", &format!("s{j}")).remap("y", &format!("s{}", j + 1)));
    }
    let mut m = match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    };
    m.cycle();
    assert!(written(&mut m, "s20"), "the scalar chain did not run");
    assert_eq!(allocations_per_steady_cycles(&mut m, 1000), 0);
}

#[derive(Skill, Default)]
#[skill(name = "alloc.source")]
struct Source {
    #[output]
    y: f64,
}

impl Body for Source {
    fn step(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.y = cx.cycle() as f64;
        Ok(())
    }
}

const MANIFEST: &str = "name: c.plus_one\ninputs: {x: f64}\noutputs: {y: f64}\n";

const C_SOURCE: &str = r#"#include "c_plus_one.h"
struct c_plus_one_state { char unused; };
situate_status c_plus_one_step(c_plus_one_state* s, const c_plus_one_inputs* in, c_plus_one_outputs* out,
                               const c_plus_one_params* p, situate_context* cx) {
    (void)s; (void)p; (void)cx;
    out->y = in->x + 1.0;
    out->has_y = true;
    return SITUATE_OK;
}
SITUATE_LIBRARY(SITUATE_SKILL(c_plus_one))
"#;

/// Generates the header and compiles the C skill; `None` when there is no C
/// compiler on this machine.
fn compile_c(dir: &Path) -> Option<PathBuf> {
    let manifest = dir.join("c_plus_one.yaml");
    std::fs::write(&manifest, MANIFEST).expect("write the manifest");
    for f in situate_cabi::generate(situate_cabi::Lang::C, &manifest).expect("generate the header") {
        std::fs::write(dir.join(&f.path), f.contents).expect("write the header");
    }
    let src = dir.join("c_plus_one.c");
    std::fs::write(&src, C_SOURCE).expect("write the source");
    let lib = dir.join("libc_plus_one.so");
    let include = Path::new(env!("CARGO_MANIFEST_DIR")).join("../include");
    let out = Command::new("gcc")
        .args(["-std=c11", "-O2", "-shared", "-fPIC", "-fvisibility=hidden", "-I"])
        .arg(include)
        .arg("-I")
        .arg(dir)
        .arg(&src)
        .arg("-o")
        .arg(&lib)
        .output();
    match out {
        Err(e) => {
            eprintln!("no C compiler ({e}): the C skill is not counted");
            None
        }
        Ok(out) => {
            assert!(out.status.success(), "compiling {}: {}", src.display(), String::from_utf8_lossy(&out.stderr));
            Some(lib)
        }
    }
}

#[test]
fn a_steady_cycle_of_c_skills_allocates_nothing() {
    let _serial = one_at_a_time();
    // Per process: two runs of this file at once must not share its files.
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("allocations-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a scratch directory");
    let Some(lib) = compile_c(&dir) else { return };
    let mut registry = Registry::new();
    registry.register::<Source>();
    for t in situate_cabi::load_library(&lib).expect("load the C library") {
        registry.add(t);
    }
    let mut spec = robot();
    spec.skills.push(SkillSpec::new("src", "alloc.source").remap("y", "s0"));
    for j in 0..20 {
        spec.skills.push(
            SkillSpec::new(&format!("c{j}"), "c.plus_one")
                .remap("x", &format!("s{j}"))
                .remap("y", &format!("s{}", j + 1)),
        );
    }
    let mut m = match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    };
    m.cycle();
    assert!(written(&mut m, "s20"), "the C chain did not run");
    let allocated = allocations_per_steady_cycles(&mut m, 1000);
    drop(m);
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(allocated, 0);
}

/// Steers the toy wheel base from the sonar ring and the pose: an array
/// and a record in, a record out.
#[derive(Skill, Default)]
#[skill(name = "alloc.steer")]
struct Steer {
    #[input(signal = "sonar.range")]
    range: [f32; 24],
    #[input]
    odom: situate_toys::Pose,
    #[output]
    drive: situate_toys::Drive,
}

impl Body for Steer {
    fn step(&mut self, _: &mut Context) -> Result<(), SkillError> {
        let ahead = f64::from(self.range[0]);
        self.drive = situate_toys::Drive { v: 0.1 * ahead.min(1.0), w: 0.5 - 0.1 * self.odom.theta.sin() };
        Ok(())
    }
}

/// A robot with devices: the toy sonar ring (a `[f32; 24]` reading) and
/// wheel base (a record command in, a record pose out), and a skill that
/// steers it from both readings.
fn robot_with_devices(clock: ClockKind) -> Manager {
    let mut registry = Registry::new();
    situate_toys::register(&mut registry);
    registry.register::<Steer>();
    let spec = RobotSpec::new("devices")
        .clock(clock)
        .period_s(0.01)
        .executor(ExecutorKind::Serial, None)
        .skill(SkillSpec::new("sonar", "toy.sonar"))
        .skill(SkillSpec::new("wheels", "toy.wheels"))
        .skill(SkillSpec::new("steer", "alloc.steer"));
    match Manager::build(&spec, &registry) {
        Ok(m) => m,
        Err(e) => panic!("build failed:\n{e}"),
    }
}

#[test]
fn a_steady_cycle_of_a_robot_with_lockstep_devices_allocates_nothing() {
    let _serial = one_at_a_time();
    // The simulated clock: the devices' exchanges run in the cycle, on this thread.
    let mut m = robot_with_devices(ClockKind::Simulated);
    for _ in 0..3 {
        m.cycle();
    }
    for signal in ["sonar.range", "odom", "drive"] {
        assert!(written(&mut m, signal), "{signal} was not written");
    }
    assert_eq!(allocations_per_steady_cycles(&mut m, 1000), 0, "1000 cycles with lockstep devices allocated");
    // The robot moved: the cycles ran the devices and the skill.
    let Ok(Reply::Signal(odom)) = m.request(Request::QuerySignal { signal: "odom.x".into() }) else {
        panic!("no odom.x")
    };
    assert!(odom.value.as_ref().and_then(Value::as_f64).is_some_and(|x| x != 0.0), "the base did not move: {odom:?}");
}

#[test]
fn a_steady_cycle_of_a_spawned_robot_with_lockstep_devices_allocates_nothing() {
    let _serial = one_at_a_time();
    let m = robot_with_devices(ClockKind::Simulated);
    assert_eq!(spawned_steady_allocations(m), Some(0), "500 steady cycles of a spawned robot with devices allocated");
}
