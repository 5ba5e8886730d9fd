//! Pipeline stages as ECS systems: thin wrappers that read components, call a bevy-free
//! algorithm, and write components. `stages` fixes their order.

pub mod arm_bodies;
pub mod cad_replacement;
pub mod contact_graph;
pub mod export;
pub mod ingest;
pub mod kinematic_tree;
pub mod link_colors;
pub mod motion_physics;
pub mod panoptic_mapping;
pub mod physics_validation;
pub mod rapier_session;
pub mod scene_graph;
pub mod scene_nodes;
pub mod simulation;
pub mod stages;

pub use cad_replacement::CadReplacementPlugin;
pub use contact_graph::ContactGraphPlugin;
pub use export::ExportPlugin;
pub use ingest::IngestPlugin;
pub use kinematic_tree::KinematicTreePlugin;
pub use panoptic_mapping::PanopticMappingPlugin;
pub use physics_validation::PhysicsValidationPlugin;
pub use stages::{Reconstruct, ReconstructionStage, StagesPlugin};
