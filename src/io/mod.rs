//! Reading and writing files: RGB-D sequences in their several layouts, meshes, glTF, staged outputs.

pub mod atomic;
pub mod gltf_write;
pub mod images;
pub mod intrinsics;
pub mod labels;
pub mod native;
pub mod open3d_log;
pub mod output_folder;
pub mod ply;
pub mod pose;
pub mod sequence;
pub mod tum;
pub mod write_sequence;

pub use sequence::{Frame, FrameRecord, Sequence};
