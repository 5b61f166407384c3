//! Reading a library's skill type entries: fields are only ever appended to
//! `situate_skill_type`, each optional, so a library built before one existed has
//! shorter entries, and the host reads each entry up to its last whole field
//! (the others NULL).

use crate::abi::{situate_activate_fn, situate_deactivate_fn, situate_init_with_fn, situate_skill_type};

/// The size of a skill type entry before the lifecycle hooks were appended
/// (the first ABI v2 libraries): the shortest entry a library may declare.
/// The old struct ended where `activate` starts: its last field was followed
/// by padding up to the alignment of a pointer, which is `activate`'s.
pub(crate) const SKILL_TYPE_BASE_SIZE: usize = std::mem::offset_of!(situate_skill_type, activate);

/// Where each field appended after [`SKILL_TYPE_BASE_SIZE`] ends, in order:
/// an entry of `skill_type_size` bytes has those that end within it.
const SKILL_TYPE_APPENDED_ENDS: [usize; 3] = [
    std::mem::offset_of!(situate_skill_type, activate) + std::mem::size_of::<situate_activate_fn>(),
    std::mem::offset_of!(situate_skill_type, deactivate) + std::mem::size_of::<situate_deactivate_fn>(),
    std::mem::offset_of!(situate_skill_type, init_with) + std::mem::size_of::<situate_init_with_fn>(),
];

/// How many bytes of an entry of `entry_size` bytes the host reads: up to the
/// end of the last appended field wholly inside it.
fn covered_len(entry_size: usize) -> usize {
    SKILL_TYPE_APPENDED_ENDS.iter().copied().filter(|&end| end <= entry_size).max().unwrap_or(SKILL_TYPE_BASE_SIZE)
}

/// Entry `index` of a table of `entry_size`-byte entries, as this host's
/// struct: the fields the entry covers copied, the others NULL.
///
/// # Safety
/// `skills` must hold `index + 1` entries of `entry_size` bytes, and
/// `entry_size` must be at least [`SKILL_TYPE_BASE_SIZE`].
pub(crate) unsafe fn read_entry(
    skills: *const situate_skill_type,
    entry_size: usize,
    index: usize,
) -> situate_skill_type {
    let mut entry = std::mem::MaybeUninit::<situate_skill_type>::zeroed();
    // SAFETY: per the contract, the bytes read lie in the library's entry; the
    // struct is valid zeroed (null pointers, `None` functions, zero sizes) and
    // the copied bytes are fields of the same types at the same offsets.
    unsafe {
        let src = skills.cast::<u8>().add(index * entry_size);
        std::ptr::copy_nonoverlapping(src, entry.as_mut_ptr().cast::<u8>(), covered_len(entry_size));
        entry.assume_init()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_entry_is_read_up_to_its_last_whole_field() {
        let ours = std::mem::size_of::<situate_skill_type>();
        let ptr = std::mem::size_of::<situate_activate_fn>();
        assert_eq!(ours, SKILL_TYPE_BASE_SIZE + 3 * ptr, "two hooks and `init_with` appended, no padding after them");
        assert_eq!(covered_len(SKILL_TYPE_BASE_SIZE), SKILL_TYPE_BASE_SIZE);
        assert_eq!(covered_len(SKILL_TYPE_BASE_SIZE + ptr / 2), SKILL_TYPE_BASE_SIZE, "never half a pointer");
        assert_eq!(covered_len(SKILL_TYPE_BASE_SIZE + ptr), SKILL_TYPE_BASE_SIZE + ptr);
        assert_eq!(covered_len(SKILL_TYPE_BASE_SIZE + 2 * ptr), SKILL_TYPE_BASE_SIZE + 2 * ptr, "the hooks only");
        assert_eq!(covered_len(ours), ours);
        // An old entry followed by bytes a longer read would take for hooks: they stay NULL.
        let mut bytes = vec![0xA5u8; 2 * ours];
        bytes[..SKILL_TYPE_BASE_SIZE].fill(0);
        let base = bytes.as_ptr().cast::<situate_skill_type>();
        // SAFETY: the buffer holds more than one old entry.
        let entry = unsafe { read_entry(base, SKILL_TYPE_BASE_SIZE, 0) };
        assert!(entry.activate.is_none() && entry.deactivate.is_none() && entry.step.is_none());
        // An entry with the hooks but not `init_with` (a library built before it): NULL.
        let mut bytes = vec![0xA5u8; 2 * ours];
        bytes[..SKILL_TYPE_BASE_SIZE + 2 * ptr].fill(0);
        // SAFETY: as above.
        let entry =
            unsafe { read_entry(bytes.as_ptr().cast::<situate_skill_type>(), SKILL_TYPE_BASE_SIZE + 2 * ptr, 0) };
        assert!(entry.init_with.is_none());
    }
}
