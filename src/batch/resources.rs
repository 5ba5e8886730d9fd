//! What one input costs, for sizing cluster requests: time and peak memory per input, from the
//! batch folder's own finished inputs when it has some, otherwise from the figures measured on
//! this project's reference machine (README, "Batches and clusters"), scaled by frames and voxel size.

use super::manifest::{BatchInput, InputSource};
use super::summary::InputCost;

/// Memory one input may take while it runs, GB, when choosing how many run at once on this
/// machine (a 2 cm map of a generated room, the rendering and the CAD stage, with margin).
pub const INPUT_MEMORY_BUDGET_GB: f64 = 3.0;

/// Measured with `iscene batch` on the reference machine (2 cores, one input at a time, 2 cm
/// voxels, the oracle segmentation, seeds 0-7 of 300 frames; 2026-11-27): seconds per frame of
/// an input, everything included (generate, render, reconstruct, eval): 24.2 s per room.
pub const SECONDS_PER_FRAME: f64 = 0.081;
/// The largest peak resident memory of one such input, MB (533 MB measured, rounded up).
pub const PEAK_MEMORY_MB: f64 = 550.0;
/// How time and memory grow with the resolution: cost x (0.02 m / voxel)^exponent, from seeds
/// 0-3 at 2 cm and at 1 cm (22 s and 48 s per room; 533 MB and 3014 MB at most). Memory grows
/// faster than the surface's square because the CAD and physics stages keep the finer meshes.
const TIME_EXPONENT: f64 = 1.1;
const MEMORY_EXPONENT: f64 = 2.5;
/// Frames assumed for a sequence input without `"frames"` (7-Scenes sequences hold 1000).
const SEQUENCE_FRAMES_ASSUMED: usize = 1000;
/// Frames of a specification rendered without `"frames"` (the renderer's default).
const SPEC_FRAMES_DEFAULT: usize = 300;

/// The expected cost of one input: seconds and peak memory, MB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cost {
    pub seconds: f64,
    pub memory_mb: f64,
}

/// The expected cost of `input`: the batch's own measured figures when there are any (`measured`,
/// the slowest and largest finished input), the reference figures otherwise.
pub fn input_cost(input: &BatchInput, measured: Option<&InputCost>) -> Cost {
    if let Some(m) = measured {
        return Cost {
            seconds: m.seconds_max,
            memory_mb: m.peak_memory_mb_max,
        };
    }
    let frames = input.frames.unwrap_or(match input.source {
        InputSource::Sequence { .. } => SEQUENCE_FRAMES_ASSUMED,
        _ => SPEC_FRAMES_DEFAULT,
    });
    let resolution = 0.02 / f64::from(input.voxel);
    Cost {
        seconds: SECONDS_PER_FRAME * frames as f64 * resolution.powf(TIME_EXPONENT),
        memory_mb: PEAK_MEMORY_MB * resolution.powf(MEMORY_EXPONENT),
    }
}

/// What one array task asks a cluster for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TaskRequest {
    pub cpus: usize,
    /// Inputs the task runs at once.
    pub jobs: usize,
    pub memory_mb: u64,
    pub minutes: u64,
}

/// The request of a task that runs `costs` (its share), `jobs` at a time on `cpus` cores: twice
/// the expected time plus ten minutes (a shared node is slower than the reference machine, and a
/// task killed at its limit loses its running inputs), and the largest input's memory per job
/// with a third more.
pub fn task_request(costs: &[Cost], cpus: usize, jobs: usize) -> TaskRequest {
    let seconds: f64 = costs.iter().map(|c| c.seconds).sum::<f64>() / jobs as f64;
    let memory = costs.iter().map(|c| c.memory_mb).fold(0.0, f64::max);
    TaskRequest {
        cpus,
        jobs,
        // Rounded up to 100 MB (less a hair, so that 1600.0000001 stays 1600).
        memory_mb: ((memory * jobs as f64 * 4.0 / 3.0 / 100.0 - 1e-6).ceil() as u64).max(1) * 100,
        minutes: (2.0 * seconds / 60.0).ceil() as u64 + 10,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::manifest::Manifest;
    use std::path::Path;

    fn input(extra: serde_json::Value) -> BatchInput {
        let mut entry = serde_json::json!({"seed": 1});
        if let (Some(e), Some(x)) = (entry.as_object_mut(), extra.as_object()) {
            e.extend(x.clone());
        }
        let value = serde_json::json!({ "inputs": [entry] });
        Manifest::from_value(&value, Path::new("."))
            .expect("manifest")
            .inputs
            .remove(0)
    }

    #[test]
    fn the_reference_figures_scale_with_frames_and_resolution() {
        let base = input_cost(&input(serde_json::json!({})), None);
        let long = input_cost(&input(serde_json::json!({"frames": 600})), None);
        assert!((long.seconds - 2.0 * base.seconds).abs() < 1e-9);
        let fine = input_cost(&input(serde_json::json!({"voxel": 0.01})), None);
        assert!((fine.memory_mb / base.memory_mb - 2f64.powf(MEMORY_EXPONENT)).abs() < 1e-9);
        assert!((fine.seconds / base.seconds - 2f64.powf(TIME_EXPONENT)).abs() < 1e-9);
        let coarse = input_cost(&input(serde_json::json!({"voxel": 0.04})), None);
        assert!(coarse.memory_mb < base.memory_mb && coarse.seconds < base.seconds);
    }

    #[test]
    fn measured_figures_replace_the_reference_ones() {
        let measured = InputCost {
            inputs: 3,
            seconds_mean: 10.0,
            seconds_max: 20.0,
            peak_memory_mb_mean: 300.0,
            peak_memory_mb_max: 400.0,
        };
        let cost = input_cost(&input(serde_json::json!({})), Some(&measured));
        assert_eq!(
            cost,
            Cost {
                seconds: 20.0,
                memory_mb: 400.0
            }
        );
    }

    #[test]
    fn a_task_asks_for_its_share_with_margin() {
        let costs = [Cost {
            seconds: 600.0,
            memory_mb: 1000.0,
        }; 3];
        let one = task_request(&costs, 2, 1);
        assert_eq!(one.minutes, 60 + 10);
        assert_eq!(one.memory_mb, 1400);
        let two = task_request(&costs, 4, 2);
        assert_eq!(two.minutes, 30 + 10);
        assert_eq!(two.memory_mb, 2700);
    }
}
