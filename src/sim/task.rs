//! Task files (JSON in scenes/tasks): the robot, where it starts, and either a script of actions
//! or goals for the planner.

use std::path::Path;

use serde::Deserialize;

use crate::error::InputError;
use crate::sim::actions::Action;
use crate::sim::robot::RobotSpec;

/// Where the robot starts: a position on the floor (x, y) and a heading.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Start {
    pub position: [f32; 2],
    #[serde(default)]
    pub yaw_deg: f32,
}

/// A task: `steps` to run as written, or `goals` (`cup_1 in microwave_1`, `microwave_1
/// closed`, ...) to plan for and then run.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    #[serde(default)]
    pub robot: RobotSpec,
    /// Default: the most open spot of the floor.
    #[serde(default)]
    pub start: Option<Start>,
    #[serde(default)]
    pub steps: Vec<Action>,
    #[serde(default)]
    pub goals: Vec<String>,
}

impl Task {
    pub fn load(path: &Path) -> Result<Task, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
        let task: Task = serde_json::from_str(&text)
            .map_err(|e| InputError::invalid(path, format!("invalid task: {e}")))?;
        if task.steps.is_empty() == task.goals.is_empty() {
            return Err(InputError::invalid(
                path,
                "a task has either \"steps\" or \"goals\", not both and not neither",
            ));
        }
        let r = task.robot;
        if ![r.radius, r.height, r.reach, r.max_reach_height]
            .iter()
            .all(|x| x.is_finite() && *x > 0.0)
        {
            return Err(InputError::invalid(
                path,
                "robot figures must be positive numbers",
            ));
        }
        if let Some(s) = task.start
            && !(s.position.iter().all(|x| x.is_finite()) && s.yaw_deg.is_finite())
        {
            return Err(InputError::invalid(path, "start must be finite numbers"));
        }
        Ok(task)
    }
}
