//! Ingest stage: read every selected frame's depth and check its colour and label headers, in
//! parallel, so that bad input fails before any work is done, and record what the sequence holds.

use bevy::prelude::*;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::InputError;
use crate::io::Sequence;
use glam::Vec3;

/// The input sequence of this reconstruction.
#[derive(Resource)]
pub struct InputSequence(pub Sequence);

/// What the ingest stage found.
#[derive(Resource, Clone, Debug, Default, Serialize)]
pub struct IngestReport {
    pub frames: usize,
    pub width: u32,
    pub height: u32,
    /// Fraction of pixels with a depth measurement, over all frames.
    pub valid_depth_fraction: f64,
    pub min_depth_m: f32,
    pub max_depth_m: f32,
    /// Path length of the camera trajectory, metres.
    pub trajectory_length_m: f32,
    pub has_gravity: bool,
    pub has_ground_truth_labels: bool,
}

/// The first error of a stage, for the caller to report (bad input: exit code 2); later stages
/// do nothing once it is set.
#[derive(Resource, Default)]
pub struct StageError(pub Option<crate::error::IsceneError>);

/// Reads and checks all frames; pure function behind the system.
pub fn ingest(sequence: &Sequence) -> Result<IngestReport, InputError> {
    let stats = (0..sequence.frames.len())
        .into_par_iter()
        .map(|i| {
            let depth = sequence.check_frame(i)?;
            let (mut valid, mut lo, mut hi) = (0usize, f32::INFINITY, 0.0f32);
            for &d in depth.iter().filter(|&&d| d > 0.0) {
                valid += 1;
                lo = lo.min(d);
                hi = hi.max(d);
            }
            Ok((valid, depth.len(), lo, hi))
        })
        .collect::<Vec<Result<_, InputError>>>()
        // The first bad frame in order, not whichever thread failed first: errors are reproducible.
        .into_iter()
        .collect::<Result<Vec<_>, InputError>>()?;
    let (valid, total) = stats
        .iter()
        .fold((0usize, 0usize), |(v, t), s| (v + s.0, t + s.1));
    let trajectory_length_m = sequence
        .frames
        .windows(2)
        .map(|w| {
            Vec3::from(w[1].world_from_camera.translation)
                .distance(w[0].world_from_camera.translation.into())
        })
        .sum();
    Ok(IngestReport {
        frames: sequence.frames.len(),
        width: sequence.camera.width,
        height: sequence.camera.height,
        valid_depth_fraction: if total > 0 {
            valid as f64 / total as f64
        } else {
            0.0
        },
        min_depth_m: stats.iter().map(|s| s.2).fold(f32::INFINITY, f32::min),
        max_depth_m: stats.iter().map(|s| s.3).fold(0.0, f32::max),
        trajectory_length_m,
        has_gravity: sequence.gravity.is_some(),
        has_ground_truth_labels: sequence.labels.is_some(),
    })
}

pub fn ingest_system(
    mut commands: Commands,
    sequence: Res<InputSequence>,
    mut error: ResMut<StageError>,
) {
    match ingest(&sequence.0) {
        Ok(report) => commands.insert_resource(report),
        Err(e) => error.0 = Some(e.into()),
    }
}

/// Adds the ingest system to its stage.
pub struct IngestPlugin;

impl Plugin for IngestPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StageError>().add_systems(
            crate::systems::Reconstruct,
            // A live session reports what it integrated itself.
            ingest_system
                .run_if(not(resource_exists::<IngestReport>))
                .in_set(crate::systems::ReconstructionStage::Ingest),
        );
    }
}
