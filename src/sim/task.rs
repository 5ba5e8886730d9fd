//! Task files (JSON in scenes/tasks): the robot, where it starts, and either a script of actions
//! or goals for the planner.

use std::path::Path;

use serde::Deserialize;

use crate::base::InvalidValue;
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
/// closed`, `fridge_1 freezer open`, ...) to plan for and then run, and `then` further goals
/// in turn.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// The base (default: [`RobotSpec::default`], or [`RobotSpec::ARM_BASE`] under an arm).
    #[serde(default)]
    pub robot: Option<RobotSpec>,
    /// Default: the most open spot of the floor.
    #[serde(default)]
    pub start: Option<Start>,
    #[serde(default)]
    pub steps: Vec<Action>,
    #[serde(default)]
    pub goals: Vec<String>,
    /// Further goals reached in turn once `goals` hold, each set planned from where the one
    /// before leaves the scene: `"then": [["fridge_1 freezer closed"]]` after `"goals":
    /// ["fridge_1 freezer open"]` opens the drawer and shuts it again.
    #[serde(default)]
    pub then: Vec<Vec<String>>,
    /// Objects the camera could not see (a box inside a closed fridge), put into the scene before
    /// the task starts.
    #[serde(default)]
    pub add: Vec<AddedObject>,
}

/// An object a task adds: a model of the scene's CAD models (its folder's, or the built-in
/// library's) put in a container or on a surface, at the first free spot the simulator's own
/// placing finds there.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AddedObject {
    pub id: String,
    pub class: String,
    pub model: String,
    #[serde(default, rename = "in")]
    pub inside: Option<String>,
    #[serde(default)]
    pub on: Option<String>,
}

impl AddedObject {
    /// The node it goes into or onto, and whether into.
    pub fn host(&self) -> Result<(&str, bool), InvalidValue> {
        match (&self.inside, &self.on) {
            (Some(c), None) => Ok((c, true)),
            (None, Some(s)) => Ok((s, false)),
            _ => Err(InvalidValue::whole(format!(
                "add {:?}: give exactly one of \"in\" and \"on\"",
                self.id
            ))),
        }
    }
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
        if !task.then.is_empty() && task.goals.is_empty() {
            return Err(InputError::invalid(
                path,
                "\"then\" follows \"goals\": a task with \"then\" needs \"goals\"",
            ));
        }
        if let Some(i) = task.then.iter().position(Vec::is_empty) {
            return Err(InputError::invalid(
                path,
                format!("then[{i}]: an empty set of goals"),
            ));
        }
        task.check_limits()
            .map_err(|p| InputError::invalid(path, p))?;
        Ok(task)
    }

    /// The base the task runs: its own, else the default one for a robot with or without an
    /// arm.
    pub fn robot_spec(&self, arm: bool) -> RobotSpec {
        self.robot.unwrap_or(if arm {
            RobotSpec::ARM_BASE
        } else {
            RobotSpec::default()
        })
    }

    /// Every number a task sets, within what a room and a mobile manipulator can mean: a
    /// robot of 1e20 m or a push of 1e30 m is a broken file, not a long job.
    fn check_limits(&self) -> Result<(), InvalidValue> {
        let r = self.robot.unwrap_or_default();
        for (key, value, max) in [
            ("robot.radius", r.radius, MAX_ROBOT_RADIUS_M),
            ("robot.height", r.height, MAX_ROBOT_HEIGHT_M),
            ("robot.reach", r.reach, MAX_ROBOT_HEIGHT_M),
            (
                "robot.max_reach_height",
                r.max_reach_height,
                MAX_ROBOT_HEIGHT_M,
            ),
        ] {
            if !(value.is_finite() && value > 0.0 && value <= max) {
                return Err(InvalidValue::at(
                    key,
                    format!("{value} m is outside (0, {max}] m"),
                ));
            }
        }
        if let Some([lo, hi]) = r.lift
            && !(lo.is_finite()
                && hi.is_finite()
                && 0.0 < lo
                && lo <= r.height
                && r.height <= hi
                && hi <= MAX_ROBOT_HEIGHT_M)
        {
            return Err(InvalidValue::at(
                "robot.lift",
                format!(
                    "[{lo}, {hi}] m must hold robot.height ({} m), from above 0 to at most {MAX_ROBOT_HEIGHT_M} m",
                    r.height
                ),
            ));
        }
        if let Some(s) = self.start
            && !(s
                .position
                .iter()
                .all(|x| x.is_finite() && x.abs() <= MAX_COORDINATE_M)
                && s.yaw_deg.is_finite())
        {
            return Err(InvalidValue::at(
                "start",
                format!(
                    "position and yaw_deg must be finite numbers, the position within {MAX_COORDINATE_M} m"
                ),
            ));
        }
        if self.steps.len() > MAX_STEPS {
            return Err(InvalidValue::at(
                "steps",
                format!("{} steps, more than {MAX_STEPS}", self.steps.len()),
            ));
        }
        let goals = self.goals.len() + self.then.iter().map(Vec::len).sum::<usize>();
        if goals > MAX_GOALS {
            return Err(InvalidValue::at(
                "goals",
                format!("{goals} goals (with \"then\"), more than {MAX_GOALS}"),
            ));
        }
        if self.add.len() > MAX_ADDED {
            return Err(InvalidValue::at(
                "add",
                format!("{} objects, more than {MAX_ADDED}", self.add.len()),
            ));
        }
        for (i, added) in self.add.iter().enumerate() {
            for id in [&added.id, &added.model] {
                crate::file_name::check_file_name(id)
                    .map_err(|e| InvalidValue::at(format!("add[{i}]"), e.to_string()))?;
            }
            let (host, _) = added.host().map_err(|e| e.under(&format!("add[{i}]")))?;
            crate::file_name::check_file_name(host)
                .map_err(|e| InvalidValue::at(format!("add[{i}]"), e.to_string()))?;
        }
        for (i, step) in self.steps.iter().enumerate() {
            let key = format!("steps[{i}]");
            for id in step.node_ids() {
                crate::file_name::check_file_name(id)
                    .map_err(|e| InvalidValue::at(&key, e.to_string()))?;
            }
            match step {
                Action::Open { value: Some(v), .. }
                    if !(v.is_finite() && v.abs() <= MAX_JOINT_VALUE) =>
                {
                    return Err(InvalidValue::at(
                        format!("{key}.value"),
                        format!(
                            "{v} is not a joint value within {MAX_JOINT_VALUE} (radians or metres)"
                        ),
                    ));
                }
                Action::Push {
                    direction,
                    distance,
                    ..
                } => {
                    if !(distance.is_finite() && *distance > 0.0 && *distance <= MAX_PUSH_M) {
                        return Err(InvalidValue::at(
                            format!("{key}.distance"),
                            format!("{distance} m is outside (0, {MAX_PUSH_M}] m"),
                        ));
                    }
                    let length = (direction[0] * direction[0] + direction[1] * direction[1]).sqrt();
                    if !(length.is_finite() && length > 1e-6) {
                        return Err(InvalidValue::at(
                            format!("{key}.direction"),
                            format!("{direction:?} is not a direction"),
                        ));
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }
}

/// The largest robot base radius a task may set, metres.
pub const MAX_ROBOT_RADIUS_M: f32 = 2.0;
/// The largest robot height, reach or reach height, metres.
pub const MAX_ROBOT_HEIGHT_M: f32 = 5.0;
/// How far from the origin a start may lie, metres.
pub const MAX_COORDINATE_M: f32 = 1000.0;
/// The longest push, metres.
pub const MAX_PUSH_M: f32 = 20.0;
/// The largest joint value an `open` may ask for (radians or metres).
pub const MAX_JOINT_VALUE: f32 = 10.0;
/// Steps of a scripted task.
pub const MAX_STEPS: usize = 1000;
/// Goals of a planned task.
pub const MAX_GOALS: usize = 32;
/// The most objects a task may add.
pub const MAX_ADDED: usize = 64;
