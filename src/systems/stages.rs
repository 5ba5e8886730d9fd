//! The one ordering of the reconstruction: a schedule run once per reconstruction, and a chained
//! `SystemSet` per stage. Later stages add their systems to their set; the order lives here only.

use bevy::ecs::schedule::{LogLevel, ScheduleBuildSettings, ScheduleLabel};
use std::time::Instant;

use bevy::prelude::*;

use crate::error::IsceneError;

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
        // One failure stops the stages after it: every set runs only while none is recorded.
        for stage in Self::STAGES {
            schedule.configure_sets(stage.run_if(no_stage_failed));
        }
        app.add_schedule(schedule);
        app.init_resource::<StageError>();
        // A clock mark before the first stage, between every two stages, and after the last:
        // exclusive systems ordered around the sets, so they never race a stage's systems.
        app.init_resource::<StageMarks>();
        for k in 0..=Self::STAGES.len() {
            let mark = move |world: &mut World| {
                world
                    .resource_mut::<StageMarks>()
                    .0
                    .push((k, Instant::now()))
            };
            let config = match (
                k.checked_sub(1).map(|p| Self::STAGES[p]),
                Self::STAGES.get(k),
            ) {
                (None, Some(next)) => mark.before(*next),
                (Some(prev), Some(next)) => mark.after(prev).before(*next),
                (Some(prev), None) => mark.after(prev),
                (None, None) => continue,
            };
            app.add_systems(Reconstruct, config);
        }
    }
}

impl StagesPlugin {
    const STAGES: [ReconstructionStage; 11] = ReconstructionStage::ALL;
}

/// The first failure of a stage, for the caller to report (bad input: exit code 2). The stages
/// after it do not run.
#[derive(Resource, Default)]
pub struct StageError(pub Option<IsceneError>);

/// The run condition of every stage set.
pub fn no_stage_failed(error: Res<StageError>) -> bool {
    error.0.is_none()
}

/// Piped after every stage system that can fail (`system.pipe(record_failure)`): its error
/// becomes the `StageError`.
pub fn record_failure(In(result): In<Result<(), IsceneError>>, mut error: ResMut<StageError>) {
    if let Err(e) = result {
        error.0.get_or_insert(e);
    }
}

/// Clock readings between stages, taken by the `StagesPlugin`'s mark systems.
#[derive(Resource, Default)]
pub struct StageMarks(pub Vec<(usize, Instant)>);

impl StageMarks {
    /// Wall-clock seconds each stage took in the last run of the schedule.
    pub fn seconds(&self) -> Vec<(ReconstructionStage, f64)> {
        let at = |k: usize| self.0.iter().rev().find(|(i, _)| *i == k).map(|(_, t)| *t);
        ReconstructionStage::ALL
            .iter()
            .enumerate()
            .filter_map(|(k, stage)| {
                Some((*stage, at(k + 1)?.duration_since(at(k)?).as_secs_f64()))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Resource, Default)]
    struct Counter(u32);

    #[test]
    #[should_panic(expected = "conflicting data access have indeterminate execution order")]
    fn two_unordered_writers_in_one_stage_are_an_error() {
        let mut app = App::new();
        app.add_plugins(StagesPlugin).init_resource::<Counter>();
        let bump = |mut c: ResMut<Counter>| c.0 += 1;
        app.add_systems(
            Reconstruct,
            (
                bump.in_set(ReconstructionStage::Extract),
                bump.in_set(ReconstructionStage::Extract),
            ),
        );
        app.world_mut().run_schedule(Reconstruct);
    }

    #[test]
    fn a_failed_stage_stops_the_stages_after_it() {
        let mut app = App::new();
        app.add_plugins(StagesPlugin).init_resource::<Counter>();
        let fail = || -> Result<(), IsceneError> { Err(IsceneError::Internal("broken".into())) };
        app.add_systems(
            Reconstruct,
            (
                (|mut c: ResMut<Counter>| c.0 += 1).in_set(ReconstructionStage::Ingest),
                fail.pipe(record_failure)
                    .in_set(ReconstructionStage::Extract),
                (|mut c: ResMut<Counter>| c.0 += 10).in_set(ReconstructionStage::ContactGraph),
                (|mut c: ResMut<Counter>| c.0 += 100).in_set(ReconstructionStage::Export),
            ),
        );
        app.world_mut().run_schedule(Reconstruct);
        assert_eq!(app.world().resource::<Counter>().0, 1, "only ingest ran");
        let error = app.world_mut().resource_mut::<StageError>().0.take();
        assert!(
            matches!(error, Some(IsceneError::Internal(ref m)) if m == "broken"),
            "the failure is kept for the caller"
        );
    }

    #[test]
    fn writers_in_different_stages_are_ordered_by_the_chain() {
        let mut app = App::new();
        app.add_plugins(StagesPlugin).init_resource::<Counter>();
        app.add_systems(
            Reconstruct,
            (
                (|mut c: ResMut<Counter>| c.0 = c.0 * 10 + 2).in_set(ReconstructionStage::Export),
                (|mut c: ResMut<Counter>| c.0 = c.0 * 10 + 1).in_set(ReconstructionStage::Ingest),
            ),
        );
        app.world_mut().run_schedule(Reconstruct);
        assert_eq!(
            app.world().resource::<Counter>().0,
            12,
            "ingest runs before export"
        );
    }
}
