//! Skills in C and C++ through a small, versioned C ABI (`include/situate.h`).
//!
//! - [`abi`]: the ABI's `#[repr(C)]` definitions (the header is generated
//!   from them by cbindgen);
//! - [`manifest`]: a foreign skill's declaration (YAML, with its `name`);
//! - [`layout`]: the C layout of a skill's inputs, outputs and parameters,
//!   computed from its declaration;
//! - [`gen`]: `situate gen c|cpp`, the typed structs for an author;
//! - [`loader`]: [`load_library`], a shared library's skill types.
//!
//! A C body that returns an error status faults its skill (deactivated, an
//! event with the message; the cycle goes on). A C or C++ skill that crashes
//! the process (a bad pointer, `abort`) cannot be contained in-process: run
//! such a skill out of process as an async cskill over the link.

pub mod abi;
mod entry;
pub mod gen;
pub mod layout;
pub mod loader;
pub mod manifest;
mod resource;

pub use gen::{generate, generate_text, write_generated, GenError, GeneratedFile, Lang};
pub use layout::{Field, FieldKind, SkillLayout, StructLayout};
pub use loader::{load_library, LoadError};
pub use manifest::{parse_manifest, ManifestError, ManifestProblem};
pub use resource::CResource;
