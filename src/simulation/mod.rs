//! `iscene simulate DIR --task TASK.json --out DIR2`: loads a scene folder (a reconstruction's
//! output, or a rendered sequence's `gt/`) into a live ECS world with a robot, runs the task's
//! actions (or plans them for its goals first), and writes the trace, the PDDL of the task and
//! the scene's exports after the last step.
//!
//! Preparing a task (its added objects, its plan) is in `prepare` and `added_objects`,
//! `iscene bench simulation` in `bench`, the benchmark's pick and place in `pick_place_trial`.

mod added_objects;
mod bench;
mod pick_place_trial;
mod prepare;
mod scene_shapes;

pub use bench::{SimulationBenchReport, StepTiming, bench_simulation};
pub use pick_place_trial::{PickPlaceTrial, pick_and_place_trial};
pub use prepare::task_world;
pub use scene_shapes::SceneShapes;

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy::prelude::*;
use serde::Serialize;

use crate::arm::Arm;
use crate::arm::rig::ArmRig;
use crate::error::{InputError, IsceneError};
use crate::export::write_tree_exports;
use crate::graph::ContactGraph;
use crate::io::atomic::StagedDir;
use crate::io::output_folder::{OutputCommand, OutputTarget};
use crate::io::write_sequence::write_text;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::Change;
use crate::sim::actions::nav_grid;
use crate::sim::graph_sync::graph_after;
use crate::sim::replay::replay_files;
use crate::sim::robot::{BasePose, ROBOT_LINK};
use crate::sim::scene_view::SceneView;
use crate::sim::symbolic::symbolic_scene;
use crate::sim::task::Task;
use crate::sim::trajectory::trajectory;
use crate::sim::{actions::Action, pddl};
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::scene_graph::spawn_contact_graph;
use crate::systems::simulation::{
    ActionRequest, RobotArm, SimulationPlugin, SimulationTrace, StepPhysics, StepRecord,
    rest_physics, robot_state, spawn_robot, step_physics,
};
use prepare::{PreparedTask, prepare};

pub struct SimulateOptions {
    /// A folder with contact_graph.json.
    pub dir: PathBuf,
    pub task: PathBuf,
    pub out: PathBuf,
    /// Replace an earlier output of another iscene command at `out` (`--force`).
    pub force: bool,
    /// The URDF of an arm on the base (`--robot`): picks and places become its planned
    /// motions. `None`: the base's gripper takes what it reaches.
    pub robot: Option<PathBuf>,
}

/// What `simulate` did, as trace.json holds it.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationSummary {
    pub task: String,
    pub goals: Vec<String>,
    /// The task's further goals, reached in turn after `goals`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub then: Vec<Vec<String>>,
    /// The planner's plan (PDDL operator names), when the task has goals.
    pub plan: Option<Vec<String>>,
    /// States the planner expanded to find the plan (it gives up past 250,000).
    pub planner_expanded: Option<usize>,
    /// The rest test of the whole scene before the first action.
    pub physics_before: StepPhysics,
    pub steps: Vec<StepRecord>,
    /// Every step succeeded (and the goals hold at the end).
    pub success: bool,
    pub output: PathBuf,
}

/// The live world of `graph`: its entities, their links (of `shapes`, usually
/// `SceneShapes::read` of the scene's folder) and the robot at `start` (default: the most open
/// spot of the floor).
pub fn simulation_app(
    graph: &ContactGraph,
    task: &Task,
    shapes: &SceneShapes,
    arm: Option<&Arm>,
) -> Result<App, IsceneError> {
    let mut app = App::new();
    app.add_plugins(SimulationPlugin);
    let world = app.world_mut();
    spawn_contact_graph(world, graph)?;
    shapes.spawn_links(world, graph);
    let pose = match task.start {
        Some(s) => BasePose {
            position: Vec2::from(s.position),
            yaw: s.yaw_deg.to_radians(),
        },
        None => {
            let tree = read_kinematic_tree(world)?;
            default_start(&tree).ok_or_else(|| {
                IsceneError::Internal("the scene has no floor to put the robot on".into())
            })?
        }
    };
    let spec = task.robot_spec(arm.is_some());
    let rig = arm.map(|arm| spec.mount(ArmRig::new(arm.clone(), spec.height)));
    // A held object rides in the arm's stowed hand, or on the plate of a base without one.
    let gripper = rig.as_ref().map_or_else(
        || (spec.base_from_gripper(), spec.gripper_mesh()),
        |rig| (rig.base_from_stowed_tool(), rig.arm.hand_mesh()),
    );
    spawn_robot(world, spec, pose, gripper, rig.as_ref())?;
    if let Some(rig) = rig {
        app.insert_resource(RobotArm(std::sync::Arc::new(rig)));
    }
    Ok(app)
}

/// The most open spot of the floor, facing +x.
fn default_start(tree: &KinematicTree) -> Option<BasePose> {
    let grid = nav_grid(&SceneView::new(tree))
        .inspect_err(|e| tracing::warn!("no navigation grid for the robot's start: {e}"))
        .ok()?;
    Some(BasePose {
        position: grid.most_open()?,
        yaw: 0.0,
    })
}

/// Asks for each action in turn through the ECS, one update each, until one fails; returns
/// each update's wall-clock milliseconds.
pub(super) fn run_actions(app: &mut App, actions: &[Action]) -> Vec<f64> {
    run_actions_in(app, actions, 0..actions.len())
}

/// [`run_actions`] for the actions of `range` only, each looking ahead to all that follow it.
fn run_actions_in(app: &mut App, actions: &[Action], range: std::ops::Range<usize>) -> Vec<f64> {
    let mut update_ms = Vec::with_capacity(range.len());
    for (k, action) in actions.iter().enumerate().take(range.end).skip(range.start) {
        app.world_mut()
            .resource_mut::<Messages<ActionRequest>>()
            .write(ActionRequest(action.clone(), actions[k + 1..].to_vec()));
        let started = Instant::now();
        app.update();
        update_ms.push(started.elapsed().as_secs_f64() * 1e3);
        let failed = app
            .world()
            .resource::<SimulationTrace>()
            .0
            .last()
            .is_some_and(|s| !s.success);
        if failed {
            break;
        }
    }
    update_ms
}

/// Runs the prepared task's actions, each set of goals' in turn until one fails or its goals
/// do not hold after its actions (the next set was planned from where they hold); whether
/// every set's goals held after its actions (true for a task of steps).
fn run_stages(app: &mut App, prepared: &PreparedTask) -> Result<bool, IsceneError> {
    if prepared.stages.is_empty() {
        run_actions(app, &prepared.actions);
        return Ok(true);
    }
    let mut start = 0;
    for stage in &prepared.stages {
        run_actions_in(app, &prepared.actions, start..stage.until);
        let trace = &app.world().resource::<SimulationTrace>().0;
        if trace.last().is_some_and(|s| !s.success) {
            return Ok(false);
        }
        let now = read_kinematic_tree(app.world_mut())?;
        let (place, holding) = robot_state(app.world_mut()).unwrap_or_default();
        let facts = symbolic_scene(&SceneView::new(&now), &place, holding.as_deref()).facts;
        if !stage.goals.iter().all(|g| facts.contains(g)) {
            return Ok(false);
        }
        start = stage.until;
    }
    Ok(true)
}

/// Runs `options.task` on the scene in `options.dir` and writes `options.out`.
pub fn simulate(options: &SimulateOptions) -> Result<SimulationSummary, IsceneError> {
    // A robot file that is no arm is refused before anything is written.
    let arm = options.robot.as_deref().map(read_arm).transpose()?;
    let target = OutputTarget::claim(
        "--out",
        &options.out,
        OutputCommand::Simulate,
        &[&options.dir, &options.task],
        options.force,
    )?;
    let (prepared, mut app) = prepare(&options.dir, &options.task, arm.as_ref())?;
    let before = read_kinematic_tree(app.world_mut())?;
    let physics_before = step_physics(rest_physics(app.world_mut())?);
    let goals_hold = run_stages(&mut app, &prepared)?;
    let steps = app.world().resource::<SimulationTrace>().0.clone();
    let after = read_kinematic_tree(app.world_mut())?;
    // A door moved part of the way takes steps of its action beyond the plan's one.
    let all_ran = prepared.actions.len() == steps.iter().filter(|s| !s.part_way).count();
    let summary = SimulationSummary {
        task: options.task.display().to_string(),
        goals: prepared.task.goals.clone(),
        then: prepared.task.then.clone(),
        plan: prepared.plan.clone(),
        planner_expanded: prepared.planner_expanded,
        physics_before,
        success: all_ran && steps.iter().all(|s| s.success) && goals_hold,
        steps,
        output: options.out.clone(),
    };
    let rig = app.world().get_resource::<RobotArm>().map(|r| r.0.clone());
    write_outputs(
        &target,
        &prepared,
        (&before, &after),
        &summary,
        rig.as_deref(),
    )?;
    Ok(summary)
}

/// The arm of the URDF file `urdf`; a file that is no arm is bad input naming it.
pub fn read_arm(urdf: &Path) -> Result<Arm, IsceneError> {
    if !urdf.is_file() {
        return Err(InputError::missing(urdf, "the robot's URDF file").into());
    }
    Ok(Arm::read_urdf(urdf, None).map_err(|e| InputError::invalid(urdf, e))?)
}

/// Writes the trace, the task's PDDL, the contact graph and exports of the scene after the
/// task and, for a robot with an arm, the task's replay for MuJoCo.
fn write_outputs(
    out: &OutputTarget,
    prepared: &PreparedTask,
    (before, after): (&KinematicTree, &KinematicTree),
    summary: &SimulationSummary,
    rig: Option<&ArmRig>,
) -> Result<(), IsceneError> {
    let staged = StagedDir::new(out)?;
    let dir = staged.path();
    write_text(
        &dir.join("trace.json"),
        &serde_json::to_string_pretty(summary)
            .map_err(|e| IsceneError::Internal(format!("trace.json: {e}")))?,
    )?;
    write_text(
        &dir.join("domain.pddl"),
        &pddl::domain(prepared.scene.hand_works_parts),
    )?;
    // The goals' problem, and each of `then`'s from where the plan before leaves the scene.
    for (k, stage) in prepared.stages.iter().enumerate() {
        let name = match k {
            0 => "problem.pddl".to_string(),
            k => format!("problem_then_{}.pddl", k - 1),
        };
        write_text(
            &dir.join(name),
            &pddl::problem("task", &stage.from, &stage.goals),
        )?;
    }
    if prepared.stages.is_empty() {
        write_text(
            &dir.join("problem.pddl"),
            &pddl::problem("task", &prepared.scene, &[]),
        )?;
    }
    write_text(
        &dir.join("contact_graph.json"),
        &graph_after(&prepared.graph, before, after).to_json(),
    )?;
    write_tree_exports(dir, after, "scene")?;
    if let Some(rig) = rig {
        write_replay(dir, before, &prepared.task, summary, rig)?;
    }
    staged.commit()?;
    Ok(())
}

/// `replay.xml` (the scene as the task found it, with the robot and its arm), its arm's meshes
/// and `trajectory.csv` (the performed steps' joint values over time) into `dir`.
fn write_replay(
    dir: &Path,
    before: &KinematicTree,
    task: &Task,
    summary: &SimulationSummary,
    rig: &ArmRig,
) -> Result<(), IsceneError> {
    let steps: Vec<(usize, &[Change])> = summary
        .steps
        .iter()
        .filter(|s| s.success)
        .map(|s| (s.step, s.changes.as_slice()))
        .collect();
    let robot = before
        .links
        .iter()
        .position(|l| l.name == ROBOT_LINK)
        .ok_or_else(|| IsceneError::Internal("the scene has no robot to replay".into()))?;
    let trajectory = trajectory(before, rig, &steps)
        .ok_or_else(|| IsceneError::Internal("the scene has no robot to replay".into()))?;
    write_text(&dir.join("trajectory.csv"), &trajectory.csv())?;
    for file in replay_files(before, &[robot], &task.robot_spec(true), rig) {
        write_text(&dir.join(&file.path), &file.text)?;
    }
    Ok(())
}
