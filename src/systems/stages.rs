//! The one ordering of the reconstruction: a schedule run once per reconstruction, and a chained
//! `SystemSet` per stage. Later stages add their systems to their set; the order lives here only.

use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel};
use bevy::prelude::*;

/// The schedule a reconstruction runs once, stage after stage.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
pub struct Reconstruct;

/// Stages of the reconstruction, in the order they run.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ReconstructionStage {
    /// Read and check every frame of the input sequence (images, poses, gravity).
    Ingest,
    /// Per-frame panoptic segmentation (oracle or onnx) beside geometric depth segmentation.
    Segment,
    /// Fuse frames into the hashed TSDF with segment labels and the Phi(l, c, p) counts.
    Integrate,
    /// Regularise labels and extract one scene entity (mesh, class, instance) per object and layout piece.
    Extract,
    /// Gravity alignment, boxes, planes, support and proximal relations.
    ContactGraph,
    /// Rank CAD candidates of each object's class.
    CadMatch,
    /// Align the best candidates (Levenberg-Marquardt or ICP) and keep the best alignment error.
    CadAlign,
    /// Global physical check: support areas, penetration, min-conflict choice, snapping.
    PhysicalCheck,
    /// Kinematic tree: links, joints, masses, inertias, collision shapes.
    KinematicTree,
    /// Physics validation with rapier: does the scene stand, do the joints move freely.
    PhysicsValidation,
    /// Write the output folder.
    Export,
}

impl ReconstructionStage {
    pub const ALL: [ReconstructionStage; 11] = [
        Self::Ingest,
        Self::Segment,
        Self::Integrate,
        Self::Extract,
        Self::ContactGraph,
        Self::CadMatch,
        Self::CadAlign,
        Self::PhysicalCheck,
        Self::KinematicTree,
        Self::PhysicsValidation,
        Self::Export,
    ];

    /// The stage's name in report.json.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ingest => "ingest",
            Self::Segment => "segment",
            Self::Integrate => "integrate",
            Self::Extract => "extract",
            Self::ContactGraph => "contact_graph",
            Self::CadMatch => "cad_match",
            Self::CadAlign => "cad_align",
            Self::PhysicalCheck => "physical_check",
            Self::KinematicTree => "kinematic_tree",
            Self::PhysicsValidation => "physics_validation",
            Self::Export => "export",
        }
    }
}

/// Creates the `Reconstruct` schedule with its stages chained, system-order ambiguities as errors.
pub struct StagesPlugin;

impl Plugin for StagesPlugin {
    fn build(&self, app: &mut App) {
        let mut schedule = Schedule::new(Reconstruct);
        schedule.set_build_settings(ScheduleBuildSettings {
            ambiguity_detection: LogLevel::Error,
            ..default()
        });
        schedule.configure_sets(
            (
                ReconstructionStage::Ingest,
                ReconstructionStage::Segment,
                ReconstructionStage::Integrate,
                ReconstructionStage::Extract,
                ReconstructionStage::ContactGraph,
                ReconstructionStage::CadMatch,
                ReconstructionStage::CadAlign,
                ReconstructionStage::PhysicalCheck,
                ReconstructionStage::KinematicTree,
                ReconstructionStage::PhysicsValidation,
                ReconstructionStage::Export,
            )
                .chain(),
        );
        app.add_schedule(schedule);
    }
}
