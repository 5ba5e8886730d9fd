//! The volumetric map: a hashed TSDF of voxel blocks (first part of the panoptic mapping, issue 3).

pub mod tsdf;

pub use tsdf::{BLOCK_SIDE, TsdfMap, Voxel};
