//! Resources a program provides to its C and C++ skills (`init_with`,
//! `situate_resources`): pointers, by name.

use std::ffi::{c_char, c_void};

use situate_core::Resources;

/// A pointer a program provides to its C and C++ skills as a resource, by
/// name: `registry.provide("bus", unsafe { CResource::new(bus) })`. A skill
/// gets it in `init_with` (`situate_resource(resources, "bus")`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CResource(*mut c_void);

// SAFETY: a `CResource` is only a pointer handed to C code; `CResource::new`'s caller promises
// that the skills may use what it points to from the threads that run them.
unsafe impl Send for CResource {}
// SAFETY: as for `Send`: the host never dereferences it.
unsafe impl Sync for CResource {}

impl CResource {
    /// # Safety
    /// `ptr` must stay valid as long as any skill made with it lives, and
    /// those skills must be allowed to use it from the threads that run
    /// them (the cycle's, or a threaded skill's own).
    pub unsafe fn new(ptr: *mut c_void) -> CResource {
        CResource(ptr)
    }

    pub fn as_ptr(self) -> *mut c_void {
        self.0
    }
}

/// `situate_resources.get`: the [`CResource`] named `name`, or NULL.
pub(crate) unsafe extern "C" fn resource_for_c(
    host_data: *const c_void,
    name: *const c_char,
    len: usize,
) -> *mut c_void {
    if host_data.is_null() || name.is_null() {
        return std::ptr::null_mut();
    }
    // SAFETY: `host_data` is the `Resources` `CSkill::new` passed, alive during `init_with`;
    // the ABI says `name` holds `len` bytes.
    let (resources, name) =
        unsafe { (&*host_data.cast::<Resources>(), std::slice::from_raw_parts(name.cast::<u8>(), len)) };
    let Ok(name) = std::str::from_utf8(name) else { return std::ptr::null_mut() };
    resources.get::<CResource>(name).map_or(std::ptr::null_mut(), |r| r.as_ptr())
}
