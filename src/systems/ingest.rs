//! Ingest stage: read every selected frame's depth and check its colour and label headers, in
//! parallel, so that bad input fails before any work is done, and record what the sequence holds.

use bevy::prelude::*;
use rayon::prelude::*;
use serde::Serialize;

use crate::error::{InputError, IsceneError};
use crate::io::Sequence;
use crate::io::sequence::DepthStats;
use crate::systems::stages::record_failure;

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

impl IngestReport {
    /// The report of `sequence`'s frames, whose depth measured `depth`.
    pub fn new(sequence: &Sequence, depth: &DepthStats) -> Self {
        Self {
            frames: sequence.frames.len(),
            width: sequence.camera.width,
            height: sequence.camera.height,
            valid_depth_fraction: depth.valid_fraction(),
            min_depth_m: depth.min_m,
            max_depth_m: depth.max_m,
            trajectory_length_m: sequence.trajectory_length_m(),
            has_gravity: sequence.gravity.is_some(),
            has_ground_truth_labels: sequence.labels.is_some(),
        }
    }
}

/// Reads and checks all frames; pure function behind the system.
pub fn ingest(sequence: &Sequence) -> Result<IngestReport, InputError> {
    let per_frame = (0..sequence.frames.len())
        .into_par_iter()
        .map(|i| sequence.check_frame(i).map(|depth| DepthStats::of(&depth)))
        .collect::<Vec<Result<_, InputError>>>()
        // The first bad frame in order, not whichever thread failed first: errors are reproducible.
        .into_iter()
        .collect::<Result<Vec<_>, InputError>>()?;
    let mut depth = DepthStats::default();
    for stats in &per_frame {
        depth.add(stats);
    }
    Ok(IngestReport::new(sequence, &depth))
}

pub fn ingest_system(
    mut commands: Commands,
    sequence: Res<InputSequence>,
) -> Result<(), IsceneError> {
    commands.insert_resource(ingest(&sequence.0)?);
    Ok(())
}

/// Adds the ingest system to its stage.
pub struct IngestPlugin;

impl Plugin for IngestPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            crate::systems::Reconstruct,
            // A live session reports what it integrated itself.
            ingest_system
                .pipe(record_failure)
                .run_if(not(resource_exists::<IngestReport>))
                .in_set(crate::systems::ReconstructionStage::Ingest),
        );
    }
}
