//! The bottom layer: types and functions that every stage shares and that depend on nothing else
//! of the crate (class ids, joint kinds and limits, walks up parent chains, the stable hash, the process's memory, refused values, sRGB to linear light). Modules above may use it; it uses none
//! of them.

pub mod class_id;
pub mod hash;
pub mod invalid_value;
pub mod joint;
pub mod parent_chain;
pub mod process;
pub mod srgb;

pub use class_id::ClassId;
pub use hash::stable_hash;
pub use invalid_value::InvalidValue;
pub use joint::{JointKind, JointSpec};
