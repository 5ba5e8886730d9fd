//! `iscene bench simulation`: a task's steps timed over fresh runs, with their physics checks.

use std::path::Path;

use bevy::prelude::*;
use serde::Serialize;

use super::prepare::prepare;
use super::{read_arm, run_actions, simulation_app};
use crate::error::IsceneError;
use crate::systems::simulation::{SimulationTrace, StepRecord};

/// Figures of `iscene bench simulation`.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationBenchReport {
    pub task: String,
    pub runs: usize,
    pub threads: usize,
    pub steps: Vec<StepTiming>,
    /// The slowest step's median, milliseconds (issue 7's bar: under 200 ms).
    pub slowest_median_ms: f64,
}

/// One step's time over the runs: the action with its physics check (inside the system) and
/// the whole ECS update that performed it.
#[derive(Clone, Debug, Serialize)]
pub struct StepTiming {
    pub action: String,
    pub median_ms: f64,
    pub max_ms: f64,
    pub median_physics_ms: f64,
    /// Of `median_ms`, the rapier simulation of its motions.
    pub median_motion_ms: f64,
    pub median_update_ms: f64,
    /// Objects the physics check simulated.
    pub checked: usize,
    /// Steps the action took (more than one for a door moved part of the way from each of
    /// several places); the times are the action's, its steps together.
    pub steps: usize,
}

/// The records of `steps` grouped by the action they performed: a door moved part of the way
/// takes steps of the same action until the last, which is not part-way.
fn per_action(steps: &[StepRecord]) -> Vec<Vec<&StepRecord>> {
    let mut actions: Vec<Vec<&StepRecord>> = Vec::new();
    let mut open = false;
    for step in steps {
        if !open {
            actions.push(Vec::new());
        }
        actions.last_mut().expect("pushed").push(step);
        open = step.part_way;
    }
    actions
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Runs the task `runs` times in fresh worlds and reports each step's time. Every run must
/// succeed: a failing task is not a benchmark.
pub fn bench_simulation(
    dir: &Path,
    task: &Path,
    robot: Option<&Path>,
    runs: usize,
) -> Result<SimulationBenchReport, IsceneError> {
    let arm = robot.map(read_arm).transpose()?;
    let (prepared, first) = prepare(dir, task, arm.as_ref())?;
    let mut first = Some(first);
    let mut per_run: Vec<(Vec<StepRecord>, Vec<f64>)> = Vec::with_capacity(runs);
    for _ in 0..runs {
        let mut app = match first.take() {
            Some(app) => app,
            None => simulation_app(
                &prepared.graph,
                &prepared.task,
                &prepared.shapes,
                arm.as_ref(),
            )?,
        };
        let update_ms = run_actions(&mut app, &prepared.actions);
        let steps = app.world().resource::<SimulationTrace>().0.clone();
        if let Some(failed) = steps.iter().find(|s| !s.success) {
            return Err(IsceneError::Internal(format!(
                "step {} ({}) failed: {}",
                failed.step,
                failed.action.label(),
                failed.failed_precondition.as_deref().unwrap_or("?")
            )));
        }
        per_run.push((steps, update_ms));
    }
    let grouped: Vec<Vec<Vec<&StepRecord>>> = per_run.iter().map(|(s, _)| per_action(s)).collect();
    // Each run's figure for action `i`: `of` summed over its steps.
    let each_run = |i: usize, of: &dyn Fn(&StepRecord) -> f64| -> Vec<f64> {
        grouped
            .iter()
            .map(|run| run[i].iter().map(|s| of(s)).sum())
            .collect()
    };
    let steps: Vec<StepTiming> = prepared
        .actions
        .iter()
        .enumerate()
        .map(|(i, action)| StepTiming {
            action: action.label(),
            median_ms: median(each_run(i, &|s| s.wall_ms)),
            max_ms: each_run(i, &|s| s.wall_ms).into_iter().fold(0.0, f64::max),
            median_physics_ms: median(each_run(i, &|s| s.physics_ms)),
            median_motion_ms: median(each_run(i, &|s| s.motion_ms())),
            median_update_ms: median(per_run.iter().map(|(_, u)| u[i]).collect()),
            checked: grouped[0][i]
                .last()
                .and_then(|s| s.physics.as_ref())
                .map_or(0, |p| p.checked.len()),
            steps: grouped[0][i].len(),
        })
        .collect();
    Ok(SimulationBenchReport {
        task: task.display().to_string(),
        runs,
        threads: rayon::current_num_threads(),
        slowest_median_ms: steps.iter().map(|s| s.median_ms).fold(0.0, f64::max),
        steps,
    })
}
