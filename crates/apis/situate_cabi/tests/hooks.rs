//! The lifecycle hooks of C and C++ skills inside a real manager: `activate`
//! (`on_activate`) before the first step after a switch on, `deactivate`
//! (`on_deactivate`) after the last step before a switch off, a failing
//! activation faults the skill with its message, a failing deactivation is a
//! print. And a library built before the hooks were appended to
//! `situate_skill_type` (shorter entries) still loads, its hooks NULL.

mod common;

use std::process::Command;
use std::time::{Duration, Instant};

use common::*;
use situate_cabi::{load_library, LoadError};
use situate_core::Value;
use situate_manager::{ClockKind, Control, Registry, RobotSpec, SkillSpec};

/// How long a threaded body is waited for (the machine may be loaded).
const BOUND: Duration = Duration::from_secs(60);

/// Prints `activate #N at CYCLE` (refused when the parameter `refuse` is set),
/// `first step at CYCLE` (the first run after an activation only, so that a
/// threaded body's history keeps the hooks' lines) and
/// `deactivate at CYCLE after RUNS runs` (refused when `refuse_off` is set);
/// writes the number of activations to `y` every run.
const MANIFEST: &str = "outputs: {y: i64}\nparams:\n  refuse: false\n  refuse_off: false\n";

const C_SOURCE: &str = r#"
#include "c_hooked.h"
#include "c_hooked_async.h"

typedef struct hooks {
    int64_t activations;
    int64_t runs;
    int initialised;
} hooks;

static situate_status hooks_activate(hooks* h, bool refuse, situate_context* cx) {
    if (!h->initialised) {
        return situate_fail(cx, "activated before init");
    }
    h->activations++;
    h->runs = 0;
    if (refuse) {
        return situate_fail(cx, "activation #%lld refused at cycle %llu", (long long)h->activations,
                            (unsigned long long)cx->cycle);
    }
    situate_print(cx, "activate #%lld at %llu", (long long)h->activations, (unsigned long long)cx->cycle);
    return SITUATE_OK;
}

static situate_status hooks_deactivate(hooks* h, bool refuse, situate_context* cx) {
    if (refuse) {
        return situate_fail(cx, "deactivation refused at cycle %llu", (unsigned long long)cx->cycle);
    }
    situate_print(cx, "deactivate at %llu after %lld runs", (unsigned long long)cx->cycle, (long long)h->runs);
    return SITUATE_OK;
}

static void hooks_step(hooks* h, situate_context* cx, int64_t* y) {
    if (h->runs == 0) {
        situate_print(cx, "first step at %llu", (unsigned long long)cx->cycle);
    }
    h->runs++;
    *y = h->activations;
}

/* c.hooked: step, activate and deactivate only (no init: the zeroed state is ready). */
struct c_hooked_state { hooks h; };
situate_status c_hooked_activate(c_hooked_state* s, const c_hooked_params* p, situate_context* cx) {
    s->h.initialised = 1;
    return hooks_activate(&s->h, p->refuse, cx);
}
situate_status c_hooked_deactivate(c_hooked_state* s, const c_hooked_params* p, situate_context* cx) {
    return hooks_deactivate(&s->h, p->refuse_off, cx);
}
situate_status c_hooked_step(c_hooked_state* s, const c_hooked_inputs* in, c_hooked_outputs* out,
                             const c_hooked_params* p, situate_context* cx) {
    (void)in; (void)p;
    hooks_step(&s->h, cx, &out->y);
    out->has_y = true;
    return SITUATE_OK;
}

/* c.hooked_async: every hook. */
struct c_hooked_async_state { hooks h; };
situate_status c_hooked_async_init(c_hooked_async_state* s, const c_hooked_async_params* p, situate_error* e) {
    (void)p; (void)e;
    s->h.initialised = 1;
    return SITUATE_OK;
}
void c_hooked_async_fini(c_hooked_async_state* s) { s->h.initialised = 0; }
situate_status c_hooked_async_set_param(c_hooked_async_state* s, uint32_t i, const c_hooked_async_params* p,
                                        situate_error* e) {
    (void)s; (void)i; (void)p; (void)e;
    return SITUATE_OK;
}
situate_status c_hooked_async_activate(c_hooked_async_state* s, const c_hooked_async_params* p,
                                       situate_context* cx) {
    return hooks_activate(&s->h, p->refuse, cx);
}
situate_status c_hooked_async_deactivate(c_hooked_async_state* s, const c_hooked_async_params* p,
                                         situate_context* cx) {
    return hooks_deactivate(&s->h, p->refuse_off, cx);
}
situate_status c_hooked_async_step(c_hooked_async_state* s, const c_hooked_async_inputs* in,
                                   c_hooked_async_outputs* out, const c_hooked_async_params* p,
                                   situate_context* cx) {
    (void)in; (void)p;
    hooks_step(&s->h, cx, &out->y);
    out->has_y = true;
    return SITUATE_OK;
}

SITUATE_LIBRARY(SITUATE_SKILL_WITH(c_hooked, NULL, NULL, NULL, c_hooked__activate, c_hooked__deactivate),
                SITUATE_SKILL_ALL_HOOKS(c_hooked_async))
"#;

const CPP_SOURCE: &str = r#"
#include <stdexcept>
#include <string>
#include "cpp_hooked.hpp"
// Both forms of the hooks: with the parameters and the context, or the context only.
class Hooked : public cpp_hooked::Skill {
 public:
  void on_activate(const Params& p, situate::Context& cx) {
    ++activations_;
    runs_ = 0;
    if (p.refuse) {
      throw std::runtime_error("activation #" + std::to_string(activations_) + " refused at cycle " +
                               std::to_string(cx.cycle()));
    }
    cx.print("activate #" + std::to_string(activations_) + " at " + std::to_string(cx.cycle()));
  }
  void on_deactivate(situate::Context& cx) {
    if (refuse_off_) throw std::runtime_error("deactivation refused at cycle " + std::to_string(cx.cycle()));
    cx.print("deactivate at " + std::to_string(cx.cycle()) + " after " + std::to_string(runs_) + " runs");
  }
  void step(const Inputs&, Outputs& out, const Params& p, situate::Context& cx) {
    refuse_off_ = p.refuse_off;
    if (runs_ == 0) cx.print("first step at " + std::to_string(cx.cycle()));
    ++runs_;
    out.y = activations_;
    out.has_y = true;
  }

 private:
  int64_t activations_ = 0;
  int64_t runs_ = 0;
  bool refuse_off_ = false;
};
SITUATE_CPP_LIBRARY(Hooked)
"#;

fn registry(test: &str) -> Registry {
    let async_manifest = format!("kind: async\n{MANIFEST}");
    registry_of(
        test,
        &[("c_hooked", MANIFEST, "c"), ("c_hooked_async", &async_manifest, "c"), ("cpp_hooked", MANIFEST, "cpp")],
        &[("c_hooked", "c_hooked.c", C_SOURCE, false), ("cpp_hooked", "cpp_hooked.cpp", CPP_SOURCE, true)],
    )
}

fn prints(m: &mut impl Control, skill: &str) -> Vec<String> {
    m.skill(skill).expect("the skill").prints.into_iter().map(|(_, line)| line).collect()
}

fn y(m: &mut impl Control) -> (Option<Value>, u64) {
    let r = m.query("y").expect("y");
    (r.value, r.cycle)
}

#[test]
fn c_and_cpp_hooks_are_called_around_the_runs_and_a_failing_activation_faults() {
    let r = registry("hooks_sync");
    for ty in ["c.hooked", "cpp.hooked"] {
        let mut m = build(&simulated("hooks").skill(SkillSpec::new("h", ty)), &r);
        let events = m.events();
        m.step(2).unwrap();
        assert_eq!(prints(&mut m, "h"), ["activate #1 at 1", "first step at 1"], "{ty}");
        assert_eq!(y(&mut m), (Some(Value::I64(1)), 2), "{ty}");

        m.deactivate(&["h"]).unwrap();
        m.step(2).unwrap();
        assert_eq!(prints(&mut m, "h")[2..], ["deactivate at 3 after 2 runs"], "{ty}");
        let info = m.skill("h").unwrap();
        assert!(!info.active && info.faulted.is_none(), "{ty}: {info:?}");

        m.activate(&["h"]).unwrap();
        m.step(1).unwrap();
        assert_eq!(prints(&mut m, "h")[3..], ["activate #2 at 5", "first step at 5"], "{ty}");
        assert_eq!(y(&mut m), (Some(Value::I64(2)), 5), "{ty}");

        // Off and on again between two cycles: deactivated, then activated.
        m.deactivate(&["h"]).unwrap();
        m.activate(&["h"]).unwrap();
        m.step(1).unwrap();
        assert_eq!(
            prints(&mut m, "h")[5..],
            ["deactivate at 6 after 1 runs", "activate #3 at 6", "first step at 6"],
            "{ty}"
        );

        // The parameters the activation sees are the current ones: it refuses.
        m.set_param("h", "refuse", Value::Bool(true)).unwrap();
        m.deactivate(&["h"]).unwrap();
        m.activate(&["h"]).unwrap();
        m.step(2).unwrap();
        assert_eq!(prints(&mut m, "h")[8..], ["deactivate at 7 after 1 runs"], "{ty}: no run once faulted");
        let cause = "`activate` failed: activation #4 refused at cycle 7";
        let f = faults(&events);
        assert_eq!(f.len(), 1, "{ty}: {f:?}");
        assert_eq!((f[0].0.as_str(), f[0].2), ("h", 7), "{ty}");
        assert!(f[0].1.contains(cause), "{ty}: {f:?}");
        let info = m.skill("h").unwrap();
        assert!(!info.active, "{ty}: {info:?}");
        assert!(info.faulted.as_deref().is_some_and(|c| c.contains(cause)), "{ty}: {info:?}");
        assert_eq!(y(&mut m).1, 6, "{ty}: nothing written once faulted");
    }
}

#[test]
fn a_failing_deactivation_is_a_print_and_the_skill_is_off_unfaulted() {
    let r = registry("hooks_deactivate");
    for ty in ["c.hooked", "cpp.hooked"] {
        let mut m = build(&simulated("hooks").skill(SkillSpec::new("h", ty)), &r);
        let events = m.events();
        m.set_param("h", "refuse_off", Value::Bool(true)).unwrap();
        m.step(1).unwrap();
        m.deactivate(&["h"]).unwrap();
        m.step(1).unwrap();
        let info = m.skill("h").unwrap();
        assert!(!info.active && info.faulted.is_none(), "{ty}: {info:?}");
        let seen = prints(&mut m, "h");
        assert!(
            seen.iter().any(|p| p.contains("`deactivate` failed: deactivation refused at cycle 2")),
            "{ty}: {seen:?}"
        );
        assert!(faults(&events).is_empty(), "{ty}");
    }
}

/// Waits, with a generous bound, until the prints of `skill` satisfy `ok`.
fn until_printed(m: &mut impl Control, skill: &str, what_for: &str, ok: impl Fn(&[String]) -> bool) -> Vec<String> {
    let deadline = Instant::now() + BOUND;
    loop {
        let seen = prints(m, skill);
        if ok(&seen) {
            return seen;
        }
        assert!(Instant::now() < deadline, "never {what_for}: {seen:?}");
        std::thread::sleep(Duration::from_millis(5));
    }
}

#[test]
fn an_async_c_skill_is_told_on_its_thread_between_runs() {
    let r = registry("hooks_async");
    let spec =
        RobotSpec::new("hooks").clock(ClockKind::Wall).period_s(0.01).skill(SkillSpec::new("h", "c.hooked_async"));
    let (mut handle, join) = build(&spec, &r).spawn(true);
    let first = until_printed(&mut handle, "h", "a run", |p| p.iter().any(|l| l.starts_with("first step")));
    assert!(first[0].starts_with("activate #1 at "), "{first:?}");
    // A threaded body is told on its thread when it next waits; what it prints while its skill is
    // off reaches the skill's history when the cycle next takes its results (once on again), so
    // the order is checked after the second activation.
    handle.deactivate(&["h"]).unwrap();
    assert!(!handle.skill("h").unwrap().active);
    handle.activate(&["h"]).unwrap();
    let seen = until_printed(&mut handle, "h", "a run after a second activation", |p| {
        p.iter().skip_while(|l| !l.starts_with("activate #2")).any(|l| l.starts_with("first step"))
    });
    let phases: Vec<&str> = seen.iter().map(|l| l.split([' ', '#']).next().unwrap()).collect();
    assert_eq!(phases, ["activate", "first", "deactivate", "activate", "first"], "{seen:?}");
    let info = handle.skill("h").unwrap();
    assert!(info.active && info.faulted.is_none(), "{info:?}");
    handle.request(situate_manager::Request::Shutdown).unwrap();
    join.join_timeout(BOUND).ok().expect("the manager ended").unwrap();
}

#[test]
fn a_cpp_hook_of_another_signature_is_a_compile_error_not_a_silent_no_op() {
    let dir = scratch("hooks_cpp_signature");
    std::fs::write(dir.join("cpp_wrong.yaml"), "name: cpp.wrong\noutputs: {y: f64}\n").unwrap();
    gen("cpp", &dir.join("cpp_wrong.yaml"), &dir);
    let src = dir.join("wrong.cpp");
    std::fs::write(
        &src,
        "#include \"cpp_wrong.hpp\"\nclass Wrong : public cpp_wrong::Skill {\n public:\n  void on_activate() {}\n  \
         void step(const Inputs&, Outputs&, const Params&, situate::Context&) {}\n};\nSITUATE_CPP_LIBRARY(Wrong)\n",
    )
    .unwrap();
    let out = Command::new("g++")
        .args(["-std=c++17", "-fsyntax-only", "-I"])
        .arg(repo().join("include"))
        .arg("-I")
        .arg(&dir)
        .arg(&src)
        .output()
        .expect("g++");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "compiled");
    assert!(err.contains("on_activate must be callable as on_activate(const Params&, situate::Context&)"), "{err}");
}

/// A library whose skill type table has the entries of the headers before the hooks were
/// appended: two entries of the old, shorter layout, followed by what a host reading a longer
/// entry would take for its hooks (functions that fail, so a read past the entry faults).
const OLD_SOURCE: &str = r#"
#include "c_old.h"
#include "c_old2.h"

/* situate_skill_type before `activate` and `deactivate` were appended. */
typedef struct old_skill_type {
    const char* manifest;
    size_t inputs_size, outputs_size, params_size, state_size, state_align;
    situate_init_fn init;
    situate_fini_fn fini;
    situate_step_fn step;
    situate_set_param_fn set_param;
    const situate_field *inputs_fields, *outputs_fields, *params_fields;
    uint32_t inputs_field_count, outputs_field_count, params_field_count;
} old_skill_type;
_Static_assert(sizeof(old_skill_type) == offsetof(situate_skill_type, activate), "the old entry is a prefix");
_Static_assert(sizeof(old_skill_type) < sizeof(situate_skill_type), "the new entry is longer");

struct c_old_state { int64_t runs; };
situate_status c_old_step(c_old_state* s, const c_old_inputs* in, c_old_outputs* out, const c_old_params* p,
                          situate_context* cx) {
    (void)in; (void)p; (void)cx;
    out->y = ++s->runs;
    out->has_y = true;
    return SITUATE_OK;
}
struct c_old2_state { int64_t runs; };
situate_status c_old2_step(c_old2_state* s, const c_old2_inputs* in, c_old2_outputs* out, const c_old2_params* p,
                           situate_context* cx) {
    (void)in; (void)p; (void)cx;
    out->z = 10 * ++s->runs;
    out->has_z = true;
    return SITUATE_OK;
}

static situate_status trap(void* s, const void* p, situate_context* cx) {
    (void)s; (void)p;
    return situate_fail(cx, "the host read past the library's skill type entry");
}

#define OLD_ENTRY(prefix)                                                                          \
    { prefix##_manifest, sizeof(prefix##_inputs), sizeof(prefix##_outputs), sizeof(prefix##_params), \
      sizeof(prefix##_state), SITUATE_ALIGNOF(prefix##_state), NULL, NULL, prefix##__step, NULL,     \
      SITUATE__FIELDS(prefix) }

static const struct {
    old_skill_type types[2];
    situate_activate_fn after[4];
} table = {{OLD_ENTRY(c_old), OLD_ENTRY(c_old2)}, {trap, trap, trap, trap}};

static const situate_library lib = {SITUATE_ABI_VERSION, (uint32_t)sizeof(old_skill_type), 2,
                                    (const situate_skill_type*)(const void*)table.types};
SITUATE_EXPORT const situate_library* situate_library_entry(void);
const situate_library* situate_library_entry(void) { return &lib; }
"#;

#[test]
fn a_library_built_before_the_hooks_loads_and_runs_without_them() {
    let dir = scratch("hooks_old_layout");
    std::fs::write(dir.join("c_old.yaml"), "name: c.old\noutputs: {y: i64}\n").unwrap();
    std::fs::write(dir.join("c_old2.yaml"), "name: c.old2\noutputs: {z: i64}\n").unwrap();
    gen("c", &dir.join("c_old.yaml"), &dir);
    gen("c", &dir.join("c_old2.yaml"), &dir);
    let lib = shared_lib(&dir, "c_old", &[("c_old.c", OLD_SOURCE)], false);
    let types = load_library(&lib).expect("an old library loads");
    let names: Vec<&str> = types.iter().map(|t| t.decl.type_name.as_str()).collect();
    assert_eq!(names, ["c.old", "c.old2"], "entries read at the library's stride");
    let mut r = Registry::new();
    for t in types {
        r.add(t);
    }
    let spec = simulated("old").skill(SkillSpec::new("a", "c.old")).skill(SkillSpec::new("b", "c.old2"));
    let mut m = build(&spec, &r);
    let events = m.events();
    m.step(3).unwrap();
    assert!(faults(&events).is_empty(), "no hook read past the entries");
    assert_eq!(m.query("y").unwrap().value, Some(Value::I64(3)));
    assert_eq!(m.query("z").unwrap().value, Some(Value::I64(30)));
    m.deactivate(&["a", "b"]).unwrap();
    m.activate(&["a", "b"]).unwrap();
    m.step(1).unwrap();
    assert!(faults(&events).is_empty(), "no hook read past the entries");
    assert_eq!(m.query("z").unwrap().value, Some(Value::I64(40)));
}

/// A library whose table declares entries of `size` (a C expression) bytes and no skill types.
fn sized_lib(name: &str, size: &str) -> std::path::PathBuf {
    let dir = scratch(name);
    let body = format!(
        "#include <situate.h>\n\
         static const situate_library lib = {{ SITUATE_ABI_VERSION, (uint32_t)({size}), 0, NULL }};\n\
         SITUATE_EXPORT const situate_library* situate_library_entry(void);\n\
         const situate_library* situate_library_entry(void) {{ return &lib; }}\n"
    );
    shared_lib(&dir, name, &[(&format!("{name}.c"), &body)], false)
}

#[test]
fn entries_longer_than_this_hosts_or_shorter_than_the_first_are_refused() {
    let newer = sized_lib("entries_newer", "sizeof(situate_skill_type) + 8");
    let e = load_library(&newer).unwrap_err();
    assert!(matches!(e, LoadError::Malformed { .. }), "{e}");
    assert!(e.to_string().contains("it was built against newer situate headers"), "{e}");
    let shorter = sized_lib("entries_shorter", "offsetof(situate_skill_type, activate) - 8");
    let e = load_library(&shorter).unwrap_err();
    assert!(matches!(e, LoadError::Malformed { .. }), "{e}");
    assert!(e.to_string().contains("skill type table entries are"), "{e}");
    // Both sizes this host knows load (here with no skill types).
    for (name, size) in
        [("entries_old", "offsetof(situate_skill_type, activate)"), ("entries_now", "sizeof(situate_skill_type)")]
    {
        assert!(load_library(&sized_lib(name, size)).expect("loads").is_empty());
    }
}
