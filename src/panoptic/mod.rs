//! Volumetric panoptic mapping (Han et al., Sect. 3, on the Voxblox++ architecture): geometric
//! segmentation fused with panoptic masks, association to global segment labels, joint
//! instance fusion Phi(l, c, p), regularisation, and extraction of scene entities.

pub mod carve;
pub mod entities;
pub mod face_pieces;
pub mod fusion;
mod instance_groups;
pub mod instances;
pub mod live;
pub mod mapper;
pub mod panoptic_dir;
pub mod run;
pub mod sighted;

pub use carve::carve_objects;
pub use entities::{ClassIds, ExtractionParams, PanopticEntity, PanopticScene, extract_entities};
pub use instances::InstanceFusion;
pub use mapper::{MapperFrame, MapperParams, PanopticMapper, SegmentedFrame, segment_frame};
pub use run::map_sequence;
