//! `iscene simulate DIR --task TASK.json --out DIR2`: loads a scene folder (a reconstruction's
//! output, or a rendered sequence's `gt/`) into a live ECS world with a robot, runs the task's
//! actions (or plans them for its goals first), and writes the trace, the PDDL of the task and
//! the scene's exports after the last step.

use std::path::{Path, PathBuf};

use bevy::prelude::*;
use serde::Serialize;

use crate::cad::database::CadDatabase;
use crate::error::{InputError, IsceneError};
use crate::export::write_tree_exports;
use crate::graph::ContactGraph;
use crate::io::atomic::StagedDir;
use crate::io::write_sequence::write_text;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::nav_grid;
use crate::sim::graph_sync::graph_after;
use crate::sim::planner::{ground, plan};
use crate::sim::robot::BasePose;
use crate::sim::scene_view::SceneView;
use crate::sim::symbolic::{Fact, parse_goal, symbolic_scene};
use crate::sim::task::Task;
use crate::sim::{actions::Action, pddl};
use crate::systems::kinematic_tree::{read_kinematic_tree, spawn_node_links};
use crate::systems::scene_graph::spawn_contact_graph;
use crate::systems::simulation::{
    ActionRequest, SimulationPlugin, SimulationTrace, StepRecord, robot_state, spawn_robot,
};

/// States the planner may expand before it gives up.
const MAX_EXPANDED: usize = 2_000_000;

pub struct SimulateOptions {
    /// A folder with contact_graph.json.
    pub dir: PathBuf,
    pub task: PathBuf,
    pub out: PathBuf,
}

/// What `simulate` did, as trace.json holds it.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationSummary {
    pub task: String,
    pub goals: Vec<String>,
    /// The planner's plan (PDDL operator names), when the task has goals.
    pub plan: Option<Vec<String>>,
    pub steps: Vec<StepRecord>,
    /// Every step succeeded (and the goals hold at the end).
    pub success: bool,
    pub output: PathBuf,
}

/// The live world of `graph`: its entities, their links (CAD models from the parametric
/// library) and the robot at `start` (default: the most open spot of the floor).
pub fn simulation_app(graph: &ContactGraph, task: &Task) -> Result<App, String> {
    let mut app = App::new();
    app.add_plugins(SimulationPlugin);
    let world = app.world_mut();
    spawn_contact_graph(world, graph)?;
    spawn_node_links(world, graph, Some(&CadDatabase::parametric()));
    let pose = match task.start {
        Some(s) => BasePose {
            position: Vec2::from(s.position),
            yaw: s.yaw_deg.to_radians(),
        },
        None => {
            let tree = read_kinematic_tree(world)?;
            default_start(&tree).ok_or("the scene has no floor to put the robot on")?
        }
    };
    spawn_robot(world, task.robot, pose)?;
    Ok(app)
}

/// The most open spot of the floor, facing +x.
fn default_start(tree: &KinematicTree) -> Option<BasePose> {
    let grid = nav_grid(&SceneView::new(tree)).ok()?;
    Some(BasePose {
        position: grid.most_open()?,
        yaw: 0.0,
    })
}

/// Runs `options.task` on the scene in `options.dir` and writes `options.out`.
pub fn simulate(options: &SimulateOptions) -> Result<SimulationSummary, IsceneError> {
    let graph_path = options.dir.join("contact_graph.json");
    let graph = ContactGraph::load(&graph_path)?;
    let task = Task::load(&options.task)?;
    let mut app = simulation_app(&graph, &task).map_err(IsceneError::Internal)?;
    let before = read_kinematic_tree(app.world_mut()).map_err(IsceneError::Internal)?;

    // The symbolic start state, the goals and the plan.
    let (place, holding) = robot_state(app.world_mut()).unwrap_or_default();
    let view = SceneView::new(&before);
    let scene = symbolic_scene(&view, &place, holding.as_deref());
    let goals: Vec<Fact> = task
        .goals
        .iter()
        .map(|g| parse_goal(g, &scene).map_err(|p| InputError::invalid(&options.task, p)))
        .collect::<Result<_, _>>()?;
    let (plan_names, actions): (Option<Vec<String>>, Vec<Action>) = if goals.is_empty() {
        (None, task.steps.clone())
    } else {
        let found = plan(&ground(&scene, &goals), MAX_EXPANDED).ok_or_else(|| {
            InputError::invalid(
                &options.task,
                format!("no plan reaches the goals {:?}", task.goals),
            )
        })?;
        let (names, actions) = found.steps.into_iter().unzip();
        (Some(names), actions)
    };

    for action in actions {
        app.world_mut()
            .resource_mut::<Messages<ActionRequest>>()
            .write(ActionRequest(action));
        app.update();
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
    let steps = app.world().resource::<SimulationTrace>().0.clone();
    let after = read_kinematic_tree(app.world_mut()).map_err(IsceneError::Internal)?;
    let (place, holding) = robot_state(app.world_mut()).unwrap_or_default();
    let end = symbolic_scene(&SceneView::new(&after), &place, holding.as_deref());
    let goals_hold = goals.iter().all(|g| end.facts.contains(g));
    let all_ran = plan_names.as_ref().map_or(task.steps.len(), Vec::len) == steps.len();
    let summary = SimulationSummary {
        task: options.task.display().to_string(),
        goals: task.goals.clone(),
        plan: plan_names,
        success: all_ran && steps.iter().all(|s| s.success) && goals_hold,
        steps,
        output: options.out.clone(),
    };
    write_outputs(
        &options.out,
        &graph,
        &before,
        &after,
        &scene,
        &goals,
        &summary,
    )?;
    Ok(summary)
}

fn write_outputs(
    out: &Path,
    graph: &ContactGraph,
    before: &KinematicTree,
    after: &KinematicTree,
    scene: &crate::sim::symbolic::SymbolicScene,
    goals: &[Fact],
    summary: &SimulationSummary,
) -> Result<(), IsceneError> {
    let staged = StagedDir::new(out)?;
    let dir = staged.path();
    write_text(
        &dir.join("trace.json"),
        &serde_json::to_string_pretty(summary)
            .map_err(|e| IsceneError::Internal(format!("trace.json: {e}")))?,
    )?;
    write_text(&dir.join("domain.pddl"), &pddl::domain())?;
    write_text(
        &dir.join("problem.pddl"),
        &pddl::problem("task", scene, goals),
    )?;
    write_text(
        &dir.join("contact_graph.json"),
        &graph_after(graph, before, after).to_json(),
    )?;
    write_tree_exports(dir, after, "scene")?;
    staged.commit()?;
    Ok(())
}
