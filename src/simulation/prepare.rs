//! A task made ready to run on a scene: its added objects placed, its steps checked against the
//! scene, and its goals planned into actions.

use std::path::Path;

use bevy::prelude::*;

use super::added_objects::add_unseen_objects;
use super::scene_shapes::SceneShapes;
use super::simulation_app;
use crate::arm::Arm;
use crate::base::InvalidValue;
use crate::error::{InputError, IsceneError};
use crate::graph::ContactGraph;
use crate::sim::actions::Action;
use crate::sim::planner::{ground, plan};
use crate::sim::scene_view::SceneView;
use crate::sim::symbolic::{Fact, SymbolicScene, parse_goal, symbolic_scene};
use crate::sim::task::Task;
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::simulation::robot_state;

/// States the planner may expand before it gives up: 6 s and 130 MB to prove 7 kitchen goals
/// unreachable (test build, 2026-11-26; 2 million took 42 s and 900 MB). The kitchen's
/// demonstration goals need 15 to 702 (an 8-step plan).
const MAX_EXPANDED: usize = 250_000;

/// A task ready to run: the scene's graph, its symbolic start state, the goals and the actions
/// (the task's own steps, or the planner's plan for its goals).
pub(super) struct PreparedTask {
    pub(super) graph: ContactGraph,
    pub(super) task: Task,
    pub(super) scene: SymbolicScene,
    pub(super) goals: Vec<Fact>,
    pub(super) plan: Option<Vec<String>>,
    /// States the planner expanded to find `plan`.
    pub(super) planner_expanded: Option<usize>,
    pub(super) actions: Vec<Action>,
    /// What the scene's links are built of.
    pub(super) shapes: SceneShapes,
}

/// The task on the scene in `dir`, and the world built to read its start state (ready to run).
pub(super) fn prepare(
    dir: &Path,
    task_path: &Path,
    arm: Option<&Arm>,
) -> Result<(PreparedTask, App), IsceneError> {
    let graph = ContactGraph::load(&dir.join("contact_graph.json"))?;
    let task = Task::load(task_path)?;
    let mut shapes = SceneShapes::read(dir, &graph)?;
    // An added object may be a library model built to a size of the task's choosing.
    shapes.models = shapes
        .models
        .with_sized_models(task.add.iter().map(|a| a.model.as_str()));
    let graph = add_unseen_objects(graph, &task.add, &shapes)
        .map_err(|p| InputError::invalid(task_path, p))?;
    check_steps_name_movable_nodes(&task, &graph).map_err(|p| InputError::invalid(task_path, p))?;
    let mut app = simulation_app(&graph, &task, &shapes, arm)?;
    let before = read_kinematic_tree(app.world_mut())?;
    let (place, holding) = robot_state(app.world_mut()).unwrap_or_default();
    let scene = SymbolicScene {
        hand_works_parts: arm.is_some(),
        ..symbolic_scene(&SceneView::new(&before), &place, holding.as_deref())
    };
    let goals: Vec<Fact> = task
        .goals
        .iter()
        .map(|g| parse_goal(g, &scene).map_err(|p| InputError::invalid(task_path, p)))
        .collect::<Result<_, _>>()?;
    let (plan, actions) = if goals.is_empty() {
        (None, task.steps.clone())
    } else {
        let found = plan(&ground(&scene, &goals), MAX_EXPANDED).ok_or_else(|| {
            InputError::invalid(
                task_path,
                format!(
                    "no plan reaches the goals {:?} (searched up to {MAX_EXPANDED} states)",
                    task.goals
                ),
            )
        })?;
        let expanded = found.expanded;
        let (names, actions) = found.steps.into_iter().unzip();
        (Some((names, expanded)), actions)
    };
    let prepared = PreparedTask {
        graph,
        task,
        scene,
        goals,
        planner_expanded: plan.as_ref().map(|(_, e)| *e),
        plan: plan.map(|(names, _)| names),
        actions,
        shapes,
    };
    Ok((prepared, app))
}

/// A step that names a node the scene lacks, or would pick up or push the room's layout, is a
/// wrong task file: refused before anything runs, not a step that fails.
fn check_steps_name_movable_nodes(task: &Task, graph: &ContactGraph) -> Result<(), InvalidValue> {
    for (i, step) in task.steps.iter().enumerate() {
        for id in step.node_ids() {
            if !graph.nodes.iter().any(|n| n.id == id) {
                return Err(InvalidValue::at(
                    format!("steps[{i}] ({})", step.label()),
                    format!("the scene has no node {id:?}"),
                ));
            }
        }
        if let Some(id) = step.moved_object()
            && crate::scene::spec::is_layout_id(id)
        {
            return Err(InvalidValue::at(
                format!("steps[{i}] ({})", step.label()),
                format!("{id} is part of the room's layout and cannot be moved"),
            ));
        }
    }
    Ok(())
}

/// The world of the scene in `dir` with the task's robot at its start (carrying `arm`, if
/// any), and the actions to run (the task's own steps, or the planner's plan for its goals):
/// what the viewer plays.
pub fn task_world(
    dir: &Path,
    task_path: &Path,
    arm: Option<&Arm>,
) -> Result<(Vec<Action>, App), IsceneError> {
    let (prepared, app) = prepare(dir, task_path, arm)?;
    Ok((prepared.actions, app))
}
