//! Loading C and C++ skill libraries: the entry symbol, the ABI version, the
//! manifests and the layout check, then one [`SkillType`] per skill type.
//!
//! Each instance owns C-layout buffers for its inputs, outputs and
//! parameters (computed from the manifest, see [`crate::layout`]) and a
//! host-allocated state. Before a step the runtime fills the inputs buffer
//! from the port values (scalars and fixed arrays copied inline, variable
//! arrays, strings and bytes as pointer + length into the values themselves,
//! no copy) and zeroes the outputs buffer; after it, every output whose
//! `has_` flag is set becomes a value. The library stays loaded as long as a
//! skill type or an instance from it lives.

use std::alloc::Layout;
use std::ffi::{c_char, c_void, CStr};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::ptr::NonNull;
use std::sync::Arc;

use situate_core::{Context, ElemType, Io, ParamType, Resources, Skill, SkillDecl, SkillError, SkillType, Value};

use crate::abi::{
    situate_activate_fn, situate_context, situate_deactivate_fn, situate_entry_fn, situate_error, situate_field,
    situate_fini_fn, situate_host, situate_init_fn, situate_init_with_fn, situate_library, situate_resources,
    situate_set_param_fn, situate_skill_type, SITUATE_ABI_VERSION, SITUATE_ENTRY_SYMBOL, SITUATE_ERROR_CAPACITY,
    SITUATE_OK,
};
use crate::entry::{read_entry, SKILL_TYPE_BASE_SIZE};
use crate::layout::{code_c, flag_name, Field, FieldKind, SkillLayout, StructLayout};
use crate::manifest::{parse_manifest, ManifestError};
use crate::resource::resource_for_c;

/// Why a library was not loaded. Every message names the library's path.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{path}: no such file")]
    Missing { path: PathBuf },
    #[error("{path}: not a loadable shared library: {message}")]
    NotALibrary { path: PathBuf, message: String },
    #[error("{path}: not a situate skill library: it does not export `{symbol}` (build it with SITUATE_LIBRARY or SITUATE_CPP_LIBRARY)")]
    MissingSymbol { path: PathBuf, symbol: String },
    #[error("{path}: built for ABI v{found}, this situate speaks v{expected}: rebuild the library against this situate's headers")]
    AbiVersion { path: PathBuf, found: u32, expected: u32 },
    #[error("{path}: {message}")]
    Malformed { path: PathBuf, message: String },
    #[error("{path}: skill type #{index} ({skill}): manifest {source}")]
    Manifest { path: PathBuf, index: usize, skill: String, source: ManifestError },
    #[error("{path}: skill `{skill}`: {message}")]
    Layout { path: PathBuf, skill: String, message: String },
}

/// The functions of one skill type, copied out of the library's table.
struct Vtable {
    init: situate_init_fn,
    init_with: situate_init_with_fn,
    fini: situate_fini_fn,
    step: unsafe extern "C" fn(*mut c_void, *const c_void, *mut c_void, *const c_void, *mut situate_context) -> i32,
    set_param: situate_set_param_fn,
    activate: situate_activate_fn,
    deactivate: situate_deactivate_fn,
}

/// One loaded skill type: what every instance shares.
struct CType {
    decl: Arc<SkillDecl>,
    layout: SkillLayout,
    /// Per input port: its flag offset (optional inputs) and its field.
    inputs: Vec<(Option<usize>, Field)>,
    /// Per output port: its flag offset and its field.
    outputs: Vec<(usize, Field)>,
    block: BlockLayout,
    vt: Vtable,
    /// Keeps the code alive while any type or instance uses it.
    _lib: Arc<libloading::Library>,
}

/// Loads a C or C++ skill library and returns its skill types, ready to be
/// registered by name (`Registry::add`).
pub fn load_library(path: &Path) -> Result<Vec<SkillType>, LoadError> {
    let malformed = |message: String| LoadError::Malformed { path: path.to_path_buf(), message };
    if !path.exists() {
        return Err(LoadError::Missing { path: path.to_path_buf() });
    }
    // SAFETY: loading runs the library's initialisers; naming a library to
    // load is trusting its code, as for any plugin.
    let lib = unsafe { libloading::Library::new(path) }
        .map_err(|e| LoadError::NotALibrary { path: path.to_path_buf(), message: e.to_string() })?;
    let lib = Arc::new(lib);
    let symbol = format!("{SITUATE_ENTRY_SYMBOL}\0");
    // SAFETY: the symbol is declared by situate.h with exactly this type.
    let entry: situate_entry_fn = unsafe { lib.get::<situate_entry_fn>(symbol.as_bytes()) }
        .map(|s| *s)
        .map_err(|_| LoadError::MissingSymbol { path: path.to_path_buf(), symbol: SITUATE_ENTRY_SYMBOL.into() })?;
    // SAFETY: calling the library's entry, as the ABI defines it.
    let table = unsafe { entry() };
    if table.is_null() {
        return Err(malformed(format!("`{SITUATE_ENTRY_SYMBOL}` returned NULL")));
    }
    // SAFETY: `abi_version` is the first field in every ABI version.
    let found = unsafe { *table.cast::<u32>() };
    if found != SITUATE_ABI_VERSION {
        return Err(LoadError::AbiVersion { path: path.to_path_buf(), found, expected: SITUATE_ABI_VERSION });
    }
    // SAFETY: same version, so the same layout.
    let table: &situate_library = unsafe { &*table };
    // Entries may be shorter than this host's: built before optional fields were appended (see
    // SITUATE_ABI_VERSION). Longer ones come from newer headers, with hooks this host would
    // never call.
    let entry_size = table.skill_type_size as usize;
    let ours = std::mem::size_of::<situate_skill_type>();
    if entry_size > ours {
        return Err(malformed(format!(
            "its skill type table entries are {entry_size} bytes, this situate's are {ours}: it was built against \
             newer situate headers; rebuild it against this situate's headers"
        )));
    }
    if entry_size < SKILL_TYPE_BASE_SIZE {
        return Err(malformed(format!(
            "its skill type table entries are {entry_size} bytes, fewer than the {SKILL_TYPE_BASE_SIZE} every \
             ABI v{SITUATE_ABI_VERSION} entry has"
        )));
    }
    if table.skill_count > 0 && table.skills.is_null() {
        return Err(malformed(format!("it declares {} skill types but no table", table.skill_count)));
    }
    let mut types: Vec<SkillType> = Vec::new();
    for index in 0..table.skill_count as usize {
        // SAFETY: `skills` holds `skill_count` entries of `entry_size` bytes, checked above.
        let raw = unsafe { read_entry(table.skills, entry_size, index) };
        let ty = load_type(path, index, &raw, &lib)?;
        if types.iter().any(|t| t.decl.type_name == ty.decl.type_name) {
            return Err(malformed(format!("skill type `{}` is declared twice", ty.decl.type_name)));
        }
        let ty = Arc::new(ty);
        let decl = (*ty.decl).clone();
        types.push(SkillType::with_resources(decl, move |resources| {
            CSkill::new(Arc::clone(&ty), resources).map(|s| Box::new(s) as Box<dyn Skill>)
        }));
    }
    tracing::debug!(path = %path.display(), types = types.len(), "loaded skill library");
    Ok(types)
}

fn load_type(
    path: &Path,
    index: usize,
    raw: &situate_skill_type,
    lib: &Arc<libloading::Library>,
) -> Result<CType, LoadError> {
    let malformed = |message: String| LoadError::Malformed { path: path.to_path_buf(), message };
    if raw.manifest.is_null() {
        return Err(malformed(format!("skill type #{index} has no manifest")));
    }
    // SAFETY: the ABI says `manifest` is NUL-terminated.
    let text = unsafe { CStr::from_ptr(raw.manifest) }
        .to_str()
        .map_err(|e| malformed(format!("skill type #{index}: the manifest is not UTF-8 ({e})")))?;
    let decl = parse_manifest(text).map_err(|source| LoadError::Manifest {
        path: path.to_path_buf(),
        index,
        skill: name_hint(text),
        source,
    })?;
    let skill = decl.type_name.clone();
    let layout_err = |message: String| LoadError::Layout { path: path.to_path_buf(), skill: skill.clone(), message };
    let layout = SkillLayout::of(&decl).map_err(layout_err)?;
    for (what, theirs, ours) in [
        ("inputs", raw.inputs_size, layout.inputs.size),
        ("outputs", raw.outputs_size, layout.outputs.size),
        ("params", raw.params_size, layout.params.size),
    ] {
        if theirs != ours {
            return Err(layout_err(format!(
                "layout mismatch: sizeof({}_{what}) is {theirs} in the library, {ours} from its manifest \
                 (regenerate its header with `situate gen` and rebuild)",
                layout.prefix
            )));
        }
    }
    // Field by field: a struct of the right size can still hold a `double` where the manifest
    // says `i64`, or its fields in another order (a hand-edited or hand-written struct).
    for (what, ptr, count, ours) in [
        ("inputs", raw.inputs_fields, raw.inputs_field_count, &layout.inputs),
        ("outputs", raw.outputs_fields, raw.outputs_field_count, &layout.outputs),
        ("params", raw.params_fields, raw.params_field_count, &layout.params),
    ] {
        check_fields(&format!("{}_{what}", layout.prefix), ptr, count, ours).map_err(layout_err)?;
    }
    let Some(step) = raw.step else {
        return Err(layout_err("the skill type has no step function".into()));
    };
    let block = BlockLayout::new(&layout, raw.state_size, raw.state_align).ok_or_else(|| {
        layout_err(format!("bad state layout: size {}, alignment {}", raw.state_size, raw.state_align))
    })?;
    let field = |s: &StructLayout, name: &str| s.fields.iter().find(|f| &*f.name == name).cloned();
    let mut inputs = Vec::new();
    for p in &decl.inputs {
        let flag = if p.optional { field(&layout.inputs, &flag_name(&p.name)).map(|f| f.offset) } else { None };
        let f = field(&layout.inputs, &p.name).ok_or_else(|| layout_err(format!("no field for input `{}`", p.name)))?;
        inputs.push((flag, f));
    }
    let mut outputs = Vec::new();
    for p in &decl.outputs {
        let flag = field(&layout.outputs, &flag_name(&p.name)).map(|f| f.offset).unwrap_or(0);
        let f =
            field(&layout.outputs, &p.name).ok_or_else(|| layout_err(format!("no field for output `{}`", p.name)))?;
        outputs.push((flag, f));
    }
    Ok(CType {
        decl: Arc::new(decl),
        layout,
        inputs,
        outputs,
        block,
        vt: Vtable {
            init: raw.init,
            init_with: raw.init_with,
            fini: raw.fini,
            step,
            set_param: raw.set_param,
            activate: raw.activate,
            deactivate: raw.deactivate,
        },
        _lib: Arc::clone(lib),
    })
}

/// Compares a library's field table of struct `ty` with the layout computed
/// from the manifest: the same fields, in order, each of the same type,
/// element count, offset and size.
fn check_fields(ty: &str, ptr: *const situate_field, count: u32, ours: &StructLayout) -> Result<(), String> {
    let rebuild = "(regenerate its header with `situate gen` and rebuild)";
    if ptr.is_null() {
        return Err(format!("the library gives no field table for `{ty}` {rebuild}"));
    }
    let expected = ours.flat();
    if count as usize > 4 * expected.len() + 64 {
        return Err(format!("the field table of `{ty}` claims {count} fields; the manifest has {}", expected.len()));
    }
    // SAFETY: the ABI says `ptr` holds `count` entries; the count is bounded above.
    let theirs = unsafe { std::slice::from_raw_parts(ptr, count as usize) };
    let show = |code: u32, count: u32, fixed: bool| {
        if fixed || count != 1 {
            format!("{}[{count}]", code_c(code))
        } else {
            code_c(code).to_string()
        }
    };
    for (i, want) in expected.iter().enumerate() {
        let Some(got) = theirs.get(i) else {
            return Err(format!(
                "layout mismatch: `{ty}` has {count} fields in the library, {} from its manifest (the first missing is \
                 `{}`) {rebuild}",
                expected.len(),
                want.name
            ));
        };
        let name = if got.name.is_null() {
            String::from("(no name)")
        } else {
            // SAFETY: the ABI says names are NUL-terminated.
            unsafe { CStr::from_ptr(got.name) }.to_string_lossy().into_owned()
        };
        if name != want.name
            || got.code != want.code
            || got.count != want.count
            || got.offset != want.offset
            || got.size != want.size
        {
            return Err(format!(
                "layout mismatch: `{ty}` field #{i}: the manifest says `{}` {} at offset {} ({} bytes), \
                 the library has `{name}` {} at offset {} ({} bytes) {rebuild}",
                want.name,
                show(want.code, want.count, want.fixed),
                want.offset,
                want.size,
                show(got.code, got.count, want.fixed),
                got.offset,
                got.size,
            ));
        }
    }
    if theirs.len() > expected.len() {
        return Err(format!(
            "layout mismatch: `{ty}` has {count} fields in the library, {} from its manifest {rebuild}",
            expected.len()
        ));
    }
    Ok(())
}

/// The `name:` of a manifest that does not parse, for the message.
fn name_hint(text: &str) -> String {
    text.lines()
        .find_map(|l| l.strip_prefix("name:"))
        .map(|n| n.trim().trim_matches('"').to_string())
        .unwrap_or_else(|| "unnamed".into())
}

/// An 8-byte-aligned zeroed buffer of `size` bytes (every field's alignment
/// divides 8).
#[cfg(test)]
fn buffer(size: usize) -> Vec<u64> {
    vec![0u64; size.div_ceil(8).max(1)]
}

/// Where an instance's buffers sit in its one allocation: inputs, outputs,
/// params, state, error (one allocation keeps a call's data in one or two
/// cache lines).
struct BlockLayout {
    layout: Layout,
    outputs: usize,
    params: usize,
    state: usize,
    error: usize,
}

impl BlockLayout {
    fn new(l: &SkillLayout, state_size: usize, state_align: usize) -> Option<BlockLayout> {
        let up = |x: usize, a: usize| x.checked_next_multiple_of(a);
        let state_align = state_align.max(1);
        if !state_align.is_power_of_two() {
            return None;
        }
        let outputs = up(l.inputs.size, 8)?;
        let params = up(outputs.checked_add(l.outputs.size)?, 8)?;
        let state = up(params.checked_add(l.params.size)?, state_align.max(8))?;
        let error = up(state.checked_add(state_size)?, 8)?;
        let size = error.checked_add(std::mem::size_of::<situate_error>())?;
        let layout = Layout::from_size_align(size, state_align.max(8)).ok()?;
        Some(BlockLayout { layout, outputs, params, state, error })
    }
}

/// One instance of a C or C++ skill.
struct CSkill {
    ty: Arc<CType>,
    /// Inputs, outputs, params, state and error (see [`BlockLayout`]).
    block: NonNull<u8>,
    /// Whether the state was initialised (and needs `fini`).
    live: bool,
    /// Keeps string parameters alive while the params buffer points at them.
    param_strs: Vec<Option<Arc<str>>>,
    /// A failed `set_param` hook, reported by the next step.
    pending: Option<String>,
}

// SAFETY: an instance is used by one thread at a time (`&mut self`); the ABI
// requires a skill's functions not to depend on the calling thread.
unsafe impl Send for CSkill {}

static HOST: situate_host = situate_host { print: Some(host_print) };

/// The host's `print`: never unwinds into C.
unsafe extern "C" fn host_print(data: *mut c_void, line: *const c_char, len: usize) {
    let _ = catch_unwind(AssertUnwindSafe(|| {
        if data.is_null() || (line.is_null() && len > 0) {
            return;
        }
        let bytes = if len == 0 {
            &[][..]
        } else {
            // SAFETY: the caller passes `len` readable bytes.
            unsafe { std::slice::from_raw_parts(line.cast::<u8>(), len) }
        };
        // SAFETY: `data` is the `Context` the host put in the call's context.
        let cx = unsafe { &mut *data.cast::<Context>() };
        cx.print(String::from_utf8_lossy(bytes).into_owned());
    }));
}

fn error_text(e: &situate_error) -> String {
    let bytes: Vec<u8> = e.message.iter().take_while(|&&c| c != 0).map(|&c| c as u8).collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

impl CSkill {
    fn new(ty: Arc<CType>, resources: &Resources) -> Result<CSkill, String> {
        // SAFETY: the layout has a non-zero size (it holds the error).
        let block = NonNull::new(unsafe { std::alloc::alloc_zeroed(ty.block.layout) })
            .ok_or_else(|| format!("{}: cannot allocate the instance", ty.decl.type_name))?;
        let mut s = CSkill { param_strs: vec![None; ty.decl.params.len()], pending: None, block, live: false, ty };
        for i in 0..s.ty.decl.params.len() {
            let default = s.ty.decl.params[i].default.clone();
            s.write_param(i, &default);
        }
        let (state, params) = (s.at(s.ty.block.state).cast(), s.at(s.ty.block.params).cast());
        let status = if let Some(init_with) = s.ty.vt.init_with {
            let given = situate_resources {
                get: Some(resource_for_c),
                host_data: std::ptr::from_ref(resources).cast::<std::ffi::c_void>(),
            };
            // SAFETY: state, params, the resources and error are valid for the call; `given`
            // points at `resources`, which outlives it.
            Some(unsafe { init_with(state, params, &given, s.error()) })
        } else {
            // SAFETY: state, params and error are valid for the call.
            s.ty.vt.init.map(|init| unsafe { init(state, params, s.error()) })
        };
        if let Some(status) = status {
            if status != SITUATE_OK {
                let msg = s.take_error(status);
                return Err(format!("{}: init failed: {msg}", s.ty.decl.type_name));
            }
        }
        s.live = true;
        Ok(s)
    }

    /// The address `offset` bytes into the block.
    #[inline]
    fn at(&self, offset: usize) -> *mut u8 {
        // SAFETY: every offset used is inside the block.
        unsafe { self.block.as_ptr().add(offset) }
    }

    #[inline]
    fn error(&self) -> *mut situate_error {
        self.at(self.ty.block.error).cast()
    }

    /// Calls a lifecycle hook (`activate` or `deactivate`), if the library
    /// has it, with the context `cx`.
    fn hook(&mut self, hook: situate_activate_fn, cx: &mut Context) -> Result<(), SkillError> {
        let Some(hook) = hook else { return Ok(()) };
        let mut ccx = situate_context {
            cycle: cx.cycle(),
            time_s: cx.time_s(),
            error: self.error(),
            host: &HOST,
            host_data: (cx as *mut Context).cast(),
        };
        // SAFETY: state, params and the context are valid for the call.
        let status = unsafe {
            hook(self.at(self.ty.block.state).cast(), self.at(self.ty.block.params).cast_const().cast(), &mut ccx)
        };
        if status != SITUATE_OK {
            return Err(SkillError::new(self.take_error(status)));
        }
        Ok(())
    }

    fn take_error(&mut self, status: i32) -> String {
        // SAFETY: the error lies in the block, NUL-terminated by the host's
        // zeroing and kept so below (the last byte is never read).
        let error = unsafe { &mut *self.error() };
        error.message[SITUATE_ERROR_CAPACITY - 1] = 0;
        let msg = error_text(error);
        error.message[0] = 0;
        if msg.is_empty() {
            format!("returned status {status} with no message")
        } else {
            msg
        }
    }

    fn write_param(&mut self, index: usize, value: &Value) {
        let Some(spec) = self.ty.decl.params.get(index) else { return };
        let Some(f) = self.ty.layout.params.fields.iter().find(|f| *f.name == *spec.name) else { return };
        let base = self.at(self.ty.block.params);
        // SAFETY: the field lies inside the params buffer (layout computed
        // from the same declaration); the value was checked by the manager.
        unsafe {
            let dst = base.add(f.offset);
            match (spec.ty, value) {
                (ParamType::Bool, Value::Bool(b)) => dst.write(u8::from(*b)),
                (ParamType::I64, Value::I64(x)) => dst.cast::<i64>().write_unaligned(*x),
                (ParamType::F64, v) => dst.cast::<f64>().write_unaligned(v.as_f64().unwrap_or(0.0)),
                (ParamType::Str, Value::Str(s)) => {
                    write_ptr_len(dst, s.as_ptr(), s.len());
                    self.param_strs[index] = Some(Arc::clone(s));
                }
                _ => {
                    tracing::warn!(skill = %self.ty.decl.type_name, param = %spec.name, "parameter value of the wrong type ignored")
                }
            }
        }
    }

    fn fill_inputs(&mut self, inputs: &[Option<Value>]) -> Result<(), String> {
        let base = self.at(0);
        for ((flag, f), v) in self.ty.inputs.iter().zip(inputs) {
            // SAFETY: offsets lie inside the buffer; pointers written point
            // into `inputs`' values, alive during the step.
            unsafe {
                let dst = base.add(f.offset);
                match v {
                    Some(v) => {
                        if let Some(flag) = flag {
                            base.add(*flag).write(1);
                        }
                        match (&f.kind, v) {
                            (FieldKind::F64, Value::F64(x)) => dst.cast::<f64>().write_unaligned(*x),
                            _ => write_value(&f.kind, dst, v).map_err(|e| format!("input `{}`: {e}", f.name))?,
                        }
                    }
                    None => {
                        if let Some(flag) = flag {
                            base.add(*flag).write(0);
                        }
                        std::ptr::write_bytes(dst, 0, f.size);
                    }
                }
            }
        }
        Ok(())
    }

    fn read_outputs(&self, outputs: &mut [Option<Value>]) -> Result<(), String> {
        let base = self.at(self.ty.block.outputs).cast_const();
        for ((flag, f), slot) in self.ty.outputs.iter().zip(outputs.iter_mut()) {
            // SAFETY: offsets lie inside the buffer.
            unsafe {
                if base.add(*flag).read() != 0 {
                    let src = base.add(f.offset);
                    // Scalars directly (the common case, and no detour through a
                    // `Result` on the stack).
                    *slot = Some(match f.kind {
                        FieldKind::F64 => Value::F64(src.cast::<f64>().read_unaligned()),
                        FieldKind::I64 => Value::I64(src.cast::<i64>().read_unaligned()),
                        FieldKind::Bool => Value::Bool(src.read() != 0),
                        _ => read_value(&f.kind, src).map_err(|e| format!("output `{}`: {e}", f.name))?,
                    });
                }
            }
        }
        Ok(())
    }
}

impl Skill for CSkill {
    fn step(&mut self, io: &mut Io<'_>) -> Result<(), SkillError> {
        if let Some(msg) = self.pending.take() {
            return Err(SkillError::new(msg));
        }
        self.fill_inputs(io.inputs)?;
        let outputs = self.at(self.ty.block.outputs);
        for (flag, _) in &self.ty.outputs {
            // SAFETY: the flag lies in the outputs buffer. Only flags are
            // cleared: a value is read only when its flag is set.
            unsafe { outputs.add(*flag).write(0) };
        }
        let mut cx = situate_context {
            cycle: io.cx.cycle(),
            time_s: io.cx.time_s(),
            error: self.error(),
            host: &HOST,
            host_data: (io.cx as *mut Context).cast(),
        };
        // SAFETY: every pointer is valid for the call; the buffers have the
        // layout the library was built with (checked at load).
        let status = unsafe {
            (self.ty.vt.step)(
                self.at(self.ty.block.state).cast(),
                self.at(0).cast_const().cast(),
                outputs.cast(),
                self.at(self.ty.block.params).cast_const().cast(),
                &mut cx,
            )
        };
        if status != SITUATE_OK {
            return Err(SkillError::new(self.take_error(status)));
        }
        self.read_outputs(io.outputs).map_err(SkillError::new)
    }

    fn set_param(&mut self, index: usize, value: &Value) {
        self.write_param(index, value);
        if let Some(hook) = self.ty.vt.set_param {
            // SAFETY: valid pointers for the call.
            let status = unsafe {
                hook(
                    self.at(self.ty.block.state).cast(),
                    index as u32,
                    self.at(self.ty.block.params).cast(),
                    self.error(),
                )
            };
            if status != SITUATE_OK {
                let name = self.ty.decl.params.get(index).map_or("?", |p| p.name.as_str()).to_string();
                let msg = self.take_error(status);
                self.pending = Some(format!("refused parameter `{name}`: {msg}"));
            }
        }
    }

    fn activate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.hook(self.ty.vt.activate, cx)
    }

    fn deactivate(&mut self, cx: &mut Context) -> Result<(), SkillError> {
        self.hook(self.ty.vt.deactivate, cx)
    }
}

impl Drop for CSkill {
    fn drop(&mut self) {
        if let (true, Some(fini)) = (self.live, self.ty.vt.fini) {
            // SAFETY: the state was initialised.
            unsafe { fini(self.at(self.ty.block.state).cast()) };
        }
        // SAFETY: allocated in `new` with this layout.
        unsafe { std::alloc::dealloc(self.block.as_ptr(), self.ty.block.layout) };
    }
}

unsafe fn write_ptr_len<T>(dst: *mut u8, ptr: *const T, len: usize) {
    // SAFETY: the caller gives a field of pointer + length.
    unsafe {
        dst.cast::<*const T>().write_unaligned(ptr);
        dst.add(std::mem::size_of::<usize>()).cast::<usize>().write_unaligned(len);
    }
}

unsafe fn read_ptr_len<T>(src: *const u8) -> (*const T, usize) {
    // SAFETY: the caller gives a field of pointer + length.
    unsafe {
        (
            src.cast::<*const T>().read_unaligned(),
            src.add(std::mem::size_of::<usize>()).cast::<usize>().read_unaligned(),
        )
    }
}

fn mismatch(kind: &FieldKind, v: &Value) -> String {
    format!("expected {kind:?}, got {}", v.kind_name())
}

/// Writes `v` into a field of kind `kind` at `dst`.
///
/// # Safety
/// `dst` must hold a field of that kind.
#[inline]
unsafe fn write_value(kind: &FieldKind, dst: *mut u8, v: &Value) -> Result<(), String> {
    // SAFETY: per the contract.
    unsafe {
        match (kind, v) {
            (FieldKind::Bool | FieldKind::Flag, Value::Bool(b)) => dst.write(u8::from(*b)),
            (FieldKind::I64, Value::I64(x)) => dst.cast::<i64>().write_unaligned(*x),
            (FieldKind::F64, Value::F64(x)) => dst.cast::<f64>().write_unaligned(*x),
            (FieldKind::Str, Value::Str(s)) => write_ptr_len(dst, s.as_ptr(), s.len()),
            (FieldKind::Bytes, Value::Bytes(b)) => write_ptr_len(dst, b.as_ptr(), b.len()),
            (FieldKind::Fixed { elem: ElemType::F32, len }, Value::F32s(a)) if a.len() == *len => {
                std::ptr::copy_nonoverlapping(a.as_ptr(), dst.cast::<f32>(), *len)
            }
            (FieldKind::Fixed { elem: ElemType::F64, len }, Value::F64s(a)) if a.len() == *len => {
                std::ptr::copy_nonoverlapping(a.as_ptr(), dst.cast::<f64>(), *len)
            }
            (FieldKind::Fixed { elem: ElemType::I64, len }, Value::I64s(a)) if a.len() == *len => {
                std::ptr::copy_nonoverlapping(a.as_ptr(), dst.cast::<i64>(), *len)
            }
            (FieldKind::Var { elem: ElemType::F32 }, Value::F32s(a)) => write_ptr_len(dst, a.as_ptr(), a.len()),
            (FieldKind::Var { elem: ElemType::F64 }, Value::F64s(a)) => write_ptr_len(dst, a.as_ptr(), a.len()),
            (FieldKind::Var { elem: ElemType::I64 }, Value::I64s(a)) => write_ptr_len(dst, a.as_ptr(), a.len()),
            (FieldKind::Record { layout, .. }, Value::Record(r)) if r.fields.len() == layout.fields.len() => {
                for (f, (_, v)) in layout.fields.iter().zip(&r.fields) {
                    write_value(&f.kind, dst.add(f.offset), v).map_err(|e| format!("field `{}`: {e}", f.name))?;
                }
            }
            _ => return Err(mismatch(kind, v)),
        }
    }
    Ok(())
}

/// Copies `len` elements the library points at.
///
/// # Safety
/// `ptr` must point at `len` readable elements when `len > 0`.
unsafe fn copy_slice<T: Copy>(ptr: *const T, len: usize) -> Result<Arc<[T]>, String> {
    if len == 0 {
        return Ok(Arc::from(Vec::new()));
    }
    if ptr.is_null() {
        return Err(format!("NULL pointer with length {len}"));
    }
    // SAFETY: per the contract.
    Ok(Arc::from(unsafe { std::slice::from_raw_parts(ptr, len) }))
}

/// Reads a field of kind `kind` at `src` into a value (copying what the
/// library points at).
///
/// # Safety
/// `src` must hold a field of that kind, written by the library.
#[inline]
unsafe fn read_value(kind: &FieldKind, src: *const u8) -> Result<Value, String> {
    // SAFETY: per the contract.
    unsafe {
        Ok(match kind {
            FieldKind::Bool | FieldKind::Flag => Value::Bool(src.read() != 0),
            FieldKind::I64 => Value::I64(src.cast::<i64>().read_unaligned()),
            FieldKind::F64 => Value::F64(src.cast::<f64>().read_unaligned()),
            FieldKind::Str => {
                let (p, n) = read_ptr_len::<u8>(src);
                let bytes = copy_slice(p, n)?;
                let s = std::str::from_utf8(&bytes).map_err(|e| format!("the string is not UTF-8 ({e})"))?;
                Value::Str(Arc::from(s))
            }
            FieldKind::Bytes => {
                let (p, n) = read_ptr_len::<u8>(src);
                Value::Bytes(copy_slice(p, n)?)
            }
            FieldKind::Fixed { elem: ElemType::F32, len } => Value::F32s(copy_slice(src.cast::<f32>(), *len)?),
            FieldKind::Fixed { elem: ElemType::F64, len } => Value::F64s(copy_slice(src.cast::<f64>(), *len)?),
            FieldKind::Fixed { elem: ElemType::I64, len } => Value::I64s(copy_slice(src.cast::<i64>(), *len)?),
            FieldKind::Var { elem: ElemType::F32 } => {
                let (p, n) = read_ptr_len::<f32>(src);
                Value::F32s(copy_slice(p, n)?)
            }
            FieldKind::Var { elem: ElemType::F64 } => {
                let (p, n) = read_ptr_len::<f64>(src);
                Value::F64s(copy_slice(p, n)?)
            }
            FieldKind::Var { elem: ElemType::I64 } => {
                let (p, n) = read_ptr_len::<i64>(src);
                Value::I64s(copy_slice(p, n)?)
            }
            FieldKind::Record { layout, .. } => {
                let mut fields = Vec::with_capacity(layout.fields.len());
                for f in &layout.fields {
                    let v = read_value(&f.kind, src.add(f.offset)).map_err(|e| format!("field `{}`: {e}", f.name))?;
                    fields.push((Arc::clone(&f.name), v));
                }
                Value::Record(Arc::new(situate_core::RecordValue { fields }))
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use situate_core::record_value;

    #[test]
    fn values_round_trip_through_c_layout() {
        let t = situate_core::SignalType::parse("{a: bool, b: f32[3], c: string, d: f64[], e: i64}").unwrap();
        let mut d = SkillDecl::new("t", situate_core::SkillKind::Sync);
        d.outputs.push(situate_core::PortSpec::new("x", t));
        let l = SkillLayout::of(&d).unwrap();
        let f = &l.outputs.fields[1];
        let v = record_value(vec![
            ("a", Value::Bool(true)),
            ("b", Value::F32s(vec![1.0, 2.0, 3.0].into())),
            ("c", Value::Str("hé".into())),
            ("d", Value::F64s(vec![4.0].into())),
            ("e", Value::I64(-7)),
        ]);
        let mut buf = buffer(l.outputs.size);
        // SAFETY: the field lies in the buffer.
        let back = unsafe {
            let dst = buf.as_mut_ptr().cast::<u8>().add(f.offset);
            write_value(&f.kind, dst, &v).unwrap();
            read_value(&f.kind, dst).unwrap()
        };
        assert_eq!(back, v);
        let wrong = Value::F64(1.0);
        // SAFETY: as above.
        let e = unsafe { write_value(&f.kind, buf.as_mut_ptr().cast::<u8>().add(f.offset), &wrong) };
        assert!(e.is_err());
    }
}
