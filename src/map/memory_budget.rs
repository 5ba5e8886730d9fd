//! The map's memory, estimated before mapping: a voxel size that would outgrow the memory budget
//! is refused at once instead of filling the machine frame by frame.
//!
//! The TSDF allocates whole blocks of [`BLOCK_VOXELS`] voxels along the surfaces it sees, so its
//! size is the surface area over the block's face, times the blocks a surface crosses per face
//! (it meets them at every angle, and the truncation band is a block thick). The surface area is
//! measured on a sample of the frames: their depth points, binned on a coarse grid, give the
//! area seen.

use std::collections::HashSet;

use glam::IVec3;

use crate::error::InputError;
use crate::io::Sequence;
use crate::map::tsdf::{BLOCK_SIDE, BLOCK_VOXELS, Voxel};

/// The finest and coarsest voxel sizes, metres.
pub const VOXEL_RANGE_M: (f32, f32) = (0.002, 0.2);
/// The default memory budget of a map, bytes (`--max-memory`).
pub const DEFAULT_MAX_MEMORY_GB: f64 = 8.0;
/// Frames sampled for the estimate, spread over the selection.
const SAMPLED_FRAMES: usize = 24;
/// Pixels sampled per frame: every this many in each direction.
const PIXEL_STRIDE: usize = 4;
/// The grid the sampled points are binned on, metres: fine enough to follow furniture, coarse
/// enough that a sample of frames covers its cells.
const AREA_CELL_M: f32 = 0.1;
/// Blocks a surface crosses per block face of its area (orientations and the band's thickness).
/// With it the estimate follows the whole reconstruction's peak memory (labels, free space and
/// meshes included) on 3 noise-free kitchen frames: 655 MB estimated, 531 MB peak at 5 mm;
/// 164 and 152 MB at 1 cm.
const BLOCKS_PER_FACE: f64 = 2.0;
/// Depth beyond this is not fused (the TSDF's ray length).
const MAX_DEPTH_M: f32 = 5.0;

/// Checks a voxel size given on the command line.
pub fn check_voxel_size(voxel: f32) -> Result<(), InputError> {
    let (lo, hi) = VOXEL_RANGE_M;
    if !(voxel.is_finite() && (lo..=hi).contains(&voxel)) {
        return Err(InputError::invalid(
            "--voxel",
            format!("{voxel} m is outside {lo}..{hi} m"),
        ));
    }
    Ok(())
}

/// Checks a memory budget given on the command line, in GB.
pub fn check_memory_budget(gb: f64) -> Result<(), InputError> {
    if !(gb.is_finite() && gb > 0.0) {
        return Err(InputError::invalid(
            "--max-memory",
            format!("{gb} GB is not a positive number of gigabytes"),
        ));
    }
    Ok(())
}

/// What the map of a sequence is expected to take.
#[derive(Clone, Copy, Debug)]
pub struct MapEstimate {
    /// Surface area the sampled frames see, square metres.
    pub surface_m2: f64,
    pub bytes: f64,
}

/// Estimates the map of the selected frames of `sequence` at `voxel` metres.
pub fn estimate_map(sequence: &Sequence, voxel: f32) -> Result<MapEstimate, InputError> {
    let n = sequence.frames.len();
    let samples = n.min(SAMPLED_FRAMES);
    let mut cells: HashSet<IVec3> = HashSet::new();
    for k in 0..samples {
        let frame = sequence.load_frame(k * n / samples.max(1))?;
        let camera = frame.camera;
        for v in (0..camera.height as usize).step_by(PIXEL_STRIDE) {
            for u in (0..camera.width as usize).step_by(PIXEL_STRIDE) {
                let d = frame.depth[v * camera.width as usize + u];
                if !(d > 0.0 && d <= MAX_DEPTH_M) {
                    continue;
                }
                let p = frame
                    .world_from_camera
                    .transform_point3(camera.unproject(u as f32, v as f32, d));
                if p.is_finite() {
                    cells.insert((p / AREA_CELL_M).floor().as_ivec3());
                }
            }
        }
    }
    let surface_m2 = cells.len() as f64 * f64::from(AREA_CELL_M * AREA_CELL_M);
    let block_face = f64::from(BLOCK_SIDE as f32 * voxel).powi(2);
    let blocks = surface_m2 / block_face * BLOCKS_PER_FACE;
    let block_bytes = (BLOCK_VOXELS * std::mem::size_of::<Voxel>() + 16) as f64;
    Ok(MapEstimate {
        surface_m2,
        bytes: blocks * block_bytes,
    })
}

/// Refuses a map expected to outgrow `max_gb`.
pub fn check_map_fits(sequence: &Sequence, voxel: f32, max_gb: f64) -> Result<(), InputError> {
    let estimate = estimate_map(sequence, voxel)?;
    let gb = estimate.bytes / 1e9;
    if gb > max_gb {
        return Err(InputError::invalid(
            "--voxel",
            format!(
                "{voxel} m voxels over the {:.0} m² of surface the frames see would take about \
                 {gb:.1} GB, over the --max-memory budget of {max_gb} GB: use a coarser --voxel \
                 or raise --max-memory",
                estimate.surface_m2
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_sizes_outside_the_range_and_nan_are_refused() {
        for bad in [f32::NAN, f32::INFINITY, 0.0, -0.02, 1e-5, 0.5] {
            assert!(check_voxel_size(bad).is_err(), "{bad}");
        }
        assert!(check_voxel_size(0.02).is_ok());
        assert!(check_memory_budget(f64::NAN).is_err() && check_memory_budget(0.5).is_ok());
    }
}
