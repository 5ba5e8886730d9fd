//! The volumetric map: a hashed TSDF of voxel blocks with a segment label per voxel, and the
//! labelled marching cubes that turns it into meshes, and the colours it saw on a surface.

pub mod agreement;
pub mod block;
pub mod depth_precision;
pub mod frame_labels;
pub mod free_space;
mod integrator;
pub mod memory_budget;
pub mod mesh;
pub mod seen_color;
pub mod tsdf;
mod voxel;

pub use frame_labels::{FrameLabelStore, FrameLabels};
pub use mesh::{LabelledMesh, extract_mesh};
pub use tsdf::{BLOCK_SIDE, SegmentLabel, TsdfFrame, TsdfMap, Voxel};

/// Median of `values` (reordered in place); 0 when empty.
pub fn median(values: &mut [f32]) -> f32 {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, f32::total_cmp).1
}
