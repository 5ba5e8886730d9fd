//! `iscene`: an RGB-D stream of an indoor room to a functionally equivalent, interactive scene.
//!
//! Bevy-free cores (`geometry`, `cad`, `scene`, `render`, `io`, `segmentation`, `graph`,
//! `kinematics`) hold the algorithms as plain data and functions; `components` and `systems` make
//! them an ECS world whose transform hierarchy is the kinematic tree.

pub mod arm;
pub mod base;
pub mod batch;
pub mod bench;
pub mod benchmark;
pub mod cad;
pub mod classes;
pub mod components;
pub mod error;
pub mod eval;
pub mod export;
pub mod file_name;
pub mod fuzzing;
pub mod geometry;
pub mod graph;
pub mod io;
pub mod kinematics;
pub mod map;
pub mod panoptic;
pub mod perception;
pub mod pipeline;
pub mod progress;
pub mod render;
pub mod replay;
pub mod scene;
pub mod segmentation;
pub mod sim;
pub mod simulation;
pub mod systems;
#[cfg(feature = "viewer")]
pub mod viewer;

use bevy::app::PluginGroupBuilder;
use bevy::prelude::*;

/// Every reconstruction plugin. Each stage's plugin can be disabled or replaced on its own.
pub struct ReconstructionPlugins;

impl PluginGroup for ReconstructionPlugins {
    fn build(self) -> PluginGroupBuilder {
        PluginGroupBuilder::start::<Self>()
            .add(systems::StagesPlugin)
            .add(systems::IngestPlugin)
            .add(systems::PanopticMappingPlugin)
            .add(systems::ContactGraphPlugin)
            .add(systems::CadReplacementPlugin)
            .add(systems::KinematicTreePlugin)
            .add(systems::PhysicsValidationPlugin)
            .add(systems::ExportPlugin)
    }
}

pub mod prelude {
    pub use crate::ReconstructionPlugins;
    pub use crate::components::*;
    pub use crate::error::{InputError, IsceneError};
    pub use crate::systems::{Reconstruct, ReconstructionStage};
}

/// The built-in kitchen, compiled in so that `iscene` works from any folder.
pub const BUILTIN_KITCHEN: &str = include_str!("../scenes/kitchen.json");
