//! The C ABI, as `#[repr(C)]` definitions. `include/situate.h` is generated
//! from this file by cbindgen (a test fails when the committed header is
//! stale); keep every item here plain C.
//!
//! A library exports one function, [`SITUATE_ENTRY_SYMBOL`], returning a
//! [`situate_library`]: the ABI version it was built for and its skill types.
//! Values cross as C-layout structs (see `layout`): scalars and fixed arrays
//! inline, variable arrays, strings and bytes as pointer + length into buffers
//! that stay valid during the call only.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_void};

/// The version of this ABI. A library built for another version is refused
/// at load time with a clear error.
///
/// Optional fields appended at the end of `situate_skill_type` do not change
/// it: a library says how large its entries are (`skill_type_size`), the host
/// reads a field only when that size covers it (else the field is NULL), and
/// a host older than the library refuses its longer entries by their size.
/// The lifecycle hooks (`activate`, `deactivate`) were appended so, in v2,
/// and then `init_with` (resources handed in at construction).
pub const SITUATE_ABI_VERSION: u32 = 2;

/// A call succeeded.
pub const SITUATE_OK: i32 = 0;

/// A call failed; the error's message says why.
pub const SITUATE_ERROR: i32 = 1;

/// The capacity of an error's message, NUL included.
pub const SITUATE_ERROR_CAPACITY: usize = 512;

/// What every call returns: `SITUATE_OK` or an error (any other value).
pub type situate_status = i32;

/// Why a call failed: a NUL-terminated UTF-8 message (truncated to fit).
#[repr(C)]
pub struct situate_error {
    pub message: [c_char; SITUATE_ERROR_CAPACITY],
}

/// A read-only UTF-8 string (not NUL-terminated), or bytes.
#[repr(C)]
pub struct situate_str {
    pub ptr: *const c_char,
    pub len: usize,
}

/// Bytes: pointer and length.
#[repr(C)]
pub struct situate_bytes {
    pub ptr: *const u8,
    pub len: usize,
}

/// A variable-length `f32[]` array: pointer and number of elements.
#[repr(C)]
pub struct situate_f32_slice {
    pub ptr: *const f32,
    pub len: usize,
}

/// A variable-length `f64[]` array: pointer and number of elements.
#[repr(C)]
pub struct situate_f64_slice {
    pub ptr: *const f64,
    pub len: usize,
}

/// A variable-length `i64[]` array: pointer and number of elements.
#[repr(C)]
pub struct situate_i64_slice {
    pub ptr: *const i64,
    pub len: usize,
}

/// The host's services, valid during the call.
#[repr(C)]
pub struct situate_host {
    /// Adds a line (UTF-8, `len` bytes) to the skill's own prints.
    pub print: Option<unsafe extern "C" fn(host_data: *mut c_void, line: *const c_char, len: usize)>,
}

/// What a body sees besides its ports; valid during the call only.
#[repr(C)]
pub struct situate_context {
    /// The cycle this body runs in.
    pub cycle: u64,
    /// Seconds since the manager started, on its clock.
    pub time_s: f64,
    /// Where a failing body writes its message (never NULL from the host).
    pub error: *mut situate_error,
    /// The host's services.
    pub host: *const situate_host,
    /// Passed back to the host's services.
    pub host_data: *mut c_void,
}

/// The resources the program running the skill provides to it, by name (a
/// bus handle, a device's driver, a model loaded once); valid during the
/// call to `init_with` only. Keep a resource's pointer, not this struct.
#[repr(C)]
pub struct situate_resources {
    /// The resource `name` (UTF-8, `len` bytes): the pointer the program
    /// provided under that name, or NULL when it provides none of that name
    /// for C (`situate_resource` calls it).
    pub get: Option<unsafe extern "C" fn(host_data: *const c_void, name: *const c_char, len: usize) -> *mut c_void>,
    /// Passed back to `get`.
    pub host_data: *const c_void,
}

/// Constructs a skill instance in `state` (host-allocated, zeroed,
/// `state_size` bytes aligned to `state_align`) from its initial parameters.
pub type situate_init_fn = Option<
    unsafe extern "C" fn(state: *mut c_void, params: *const c_void, error: *mut situate_error) -> situate_status,
>;

/// Constructs a skill instance as `situate_init_fn` does, with the
/// resources it needs (`situate_resource(resources, "bus")`): a missing one is
/// an error status (`situate_missing_resource(error, "bus")`), and the robot
/// is not built. Used instead of `init` when set.
pub type situate_init_with_fn = Option<
    unsafe extern "C" fn(
        state: *mut c_void,
        params: *const c_void,
        resources: *const situate_resources,
        error: *mut situate_error,
    ) -> situate_status,
>;

/// Destroys the instance in `state` (the host frees the memory).
pub type situate_fini_fn = Option<unsafe extern "C" fn(state: *mut c_void)>;

/// Runs the body once: reads `inputs`, writes `outputs` (zeroed by the host;
/// set each produced output's `has_` flag).
pub type situate_step_fn = Option<
    unsafe extern "C" fn(
        state: *mut c_void,
        inputs: *const c_void,
        outputs: *mut c_void,
        params: *const c_void,
        cx: *mut situate_context,
    ) -> situate_status,
>;

/// Parameter `index` changed; `params` holds the new values.
pub type situate_set_param_fn = Option<
    unsafe extern "C" fn(
        state: *mut c_void,
        index: u32,
        params: *const c_void,
        error: *mut situate_error,
    ) -> situate_status,
>;

/// The skill was switched on (at start if it starts active, or by the
/// sequencer): called once before its first `step` after that, on the thread
/// that runs its body, with the current parameters. An error status
/// (`situate_fail(cx, ...)`) faults the skill with the message. Its prints
/// (`situate_print(cx, ...)`) are the skill's.
pub type situate_activate_fn =
    Option<unsafe extern "C" fn(state: *mut c_void, params: *const c_void, cx: *mut situate_context) -> situate_status>;

/// The skill was switched off (by the sequencer, or by a fault): called once
/// after its last `step`, on the thread that runs its body. The skill is off
/// whatever it returns: an error status is a warning and one of the skill's
/// prints, not a fault. Not called at shutdown (only `fini`).
pub type situate_deactivate_fn =
    Option<unsafe extern "C" fn(state: *mut c_void, params: *const c_void, cx: *mut situate_context) -> situate_status>;

/// A field's type in a [`situate_field`]: what the compiler saw, by
/// `SITUATE_FIELD_CODE` (C11 `_Generic`, C++ templates) in the generated
/// headers. `bool`.
pub const SITUATE_FIELD_BOOL: u32 = 1;
/// `int64_t`.
pub const SITUATE_FIELD_I64: u32 = 2;
/// `double`.
pub const SITUATE_FIELD_F64: u32 = 3;
/// `float` (the elements of an `f32[N]` array).
pub const SITUATE_FIELD_F32: u32 = 4;
/// `situate_str`.
pub const SITUATE_FIELD_STR: u32 = 5;
/// `situate_bytes`.
pub const SITUATE_FIELD_BYTES: u32 = 6;
/// `situate_f32_slice`.
pub const SITUATE_FIELD_F32_SLICE: u32 = 7;
/// `situate_f64_slice`.
pub const SITUATE_FIELD_F64_SLICE: u32 = 8;
/// `situate_i64_slice`.
pub const SITUATE_FIELD_I64_SLICE: u32 = 9;
/// `uint8_t` (the placeholder field of an empty struct).
pub const SITUATE_FIELD_U8: u32 = 10;

/// One field of a struct as the library was compiled: records are
/// flattened (`sonar.range`), a fixed array is one field of `count`
/// elements of type `code`. The host checks every one against the layout it
/// computes from the manifest, so a struct of the right size with a wrong
/// field (a `double` where the manifest says `i64`) is refused at load.
#[repr(C)]
pub struct situate_field {
    /// NUL-terminated; nested fields joined with `.`.
    pub name: *const c_char,
    /// `SITUATE_FIELD_*`, or 0 for a type the host does not know.
    pub code: u32,
    /// Elements of a fixed array, else 1.
    pub count: u32,
    /// `offsetof` the field in its top-level struct.
    pub offset: usize,
    /// `sizeof` the field.
    pub size: usize,
}

/// One skill type of a library.
///
/// Fields are only ever appended, each optional: a library built before a
/// field existed has shorter entries (`skill_type_size`) and the host takes
/// the field as NULL.
#[repr(C)]
pub struct situate_skill_type {
    /// The declaration: a NUL-terminated YAML manifest with a `name`.
    pub manifest: *const c_char,
    /// `sizeof` the generated inputs, outputs and params structs, checked
    /// against the layout the host computes from the manifest.
    pub inputs_size: usize,
    pub outputs_size: usize,
    pub params_size: usize,
    /// Size and alignment of an instance's state.
    pub state_size: usize,
    pub state_align: usize,
    /// Optional (NULL: the zeroed state is ready).
    pub init: situate_init_fn,
    /// Optional.
    pub fini: situate_fini_fn,
    /// Required.
    pub step: situate_step_fn,
    /// Optional.
    pub set_param: situate_set_param_fn,
    /// The fields of the inputs, outputs and params structs, as compiled
    /// (the generated headers write them); required.
    pub inputs_fields: *const situate_field,
    pub outputs_fields: *const situate_field,
    pub params_fields: *const situate_field,
    pub inputs_field_count: u32,
    pub outputs_field_count: u32,
    pub params_field_count: u32,
    /// Optional (appended in ABI v2: read only when `skill_type_size`
    /// covers it).
    pub activate: situate_activate_fn,
    /// Optional (appended in ABI v2, as `activate`).
    pub deactivate: situate_deactivate_fn,
    /// Optional, appended after the hooks: `init` given the program's
    /// resources; used instead of `init` when set.
    pub init_with: situate_init_with_fn,
}

/// What a library's entry function returns.
#[repr(C)]
pub struct situate_library {
    /// `SITUATE_ABI_VERSION` as the library was built. Always the first field.
    pub abi_version: u32,
    /// `sizeof(situate_skill_type)` as the library was built: the stride of
    /// `skills`, and which of the appended fields it has.
    pub skill_type_size: u32,
    /// The number of skill types in `skills`.
    pub skill_count: u32,
    pub skills: *const situate_skill_type,
}

/// The name of the function a library exports:
/// `const situate_library* situate_library_entry(void)` (in C, the
/// `SITUATE_ENTRY_SYMBOL` macro of the helpers).
pub const SITUATE_ENTRY_SYMBOL: &str = "situate_library_entry";

/// The entry function's type.
pub type situate_entry_fn = unsafe extern "C" fn() -> *const situate_library;
