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

/// A task ready to run: the scene's graph, its symbolic start state, its sets of goals and the
/// actions (the task's own steps, or the planner's plans for its goals in turn).
pub(super) struct PreparedTask {
    pub(super) graph: ContactGraph,
    pub(super) task: Task,
    pub(super) scene: SymbolicScene,
    /// `goals`, then each of `then`; none for a task of steps.
    pub(super) stages: Vec<GoalStage>,
    pub(super) plan: Option<Vec<String>>,
    /// States the planner expanded to find `plan`.
    pub(super) planner_expanded: Option<usize>,
    pub(super) actions: Vec<Action>,
    /// What the scene's links are built of.
    pub(super) shapes: SceneShapes,
}

/// One set of a task's goals: the symbolic state it is planned from (where the set before
/// leaves the scene), the goals, and where its actions end among the task's.
pub(super) struct GoalStage {
    pub(super) from: SymbolicScene,
    pub(super) goals: Vec<Fact>,
    pub(super) until: usize,
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
    let (stages, plan, actions) = if task.goals.is_empty() {
        (Vec::new(), None, task.steps.clone())
    } else {
        let (stages, names, actions, expanded) = plan_in_turn(&task, &scene, task_path)?;
        (stages, Some((names, expanded)), actions)
    };
    let prepared = PreparedTask {
        graph,
        task,
        scene,
        stages,
        planner_expanded: plan.as_ref().map(|(_, e)| *e),
        plan: plan.map(|(names, _)| names),
        actions,
        shapes,
    };
    Ok((prepared, app))
}

/// The task's sets of goals (`goals`, then each of `then`) planned in turn from `scene`, each
/// from where the plan before leaves it: the stages, the plans' operators and actions one
/// after the other, and the states the planner expanded in all.
#[allow(clippy::type_complexity, reason = "the four parts of one result")]
fn plan_in_turn(
    task: &Task,
    scene: &SymbolicScene,
    task_path: &Path,
) -> Result<(Vec<GoalStage>, Vec<String>, Vec<Action>, usize), InputError> {
    let sets = std::iter::once(("goals".to_string(), &task.goals)).chain(
        task.then
            .iter()
            .enumerate()
            .map(|(i, set)| (format!("then[{i}]"), set)),
    );
    let (mut stages, mut names, mut actions, mut expanded) =
        (Vec::new(), Vec::new(), Vec::new(), 0);
    let mut from = scene.clone();
    for (key, set) in sets {
        let goals: Vec<Fact> = set
            .iter()
            .map(|g| {
                parse_goal(g, &from)
                    .map_err(|p| InputError::invalid(task_path, format!("{key}: {p}")))
            })
            .collect::<Result<_, _>>()?;
        let found = plan(&ground(&from, &goals), MAX_EXPANDED).ok_or_else(|| {
            InputError::invalid(
                task_path,
                format!(
                    "{key}: no plan reaches the goals {set:?} (searched up to {MAX_EXPANDED} \
                     states{})",
                    if key == "goals" {
                        ""
                    } else {
                        " from where the goals before leave the scene"
                    }
                ),
            )
        })?;
        expanded += found.expanded;
        let next = SymbolicScene {
            facts: found.end.iter().cloned().collect(),
            ..from.clone()
        };
        for (name, action) in found.steps {
            names.push(name);
            actions.push(action);
        }
        stages.push(GoalStage {
            from,
            goals,
            until: actions.len(),
        });
        from = next;
    }
    Ok((stages, names, actions, expanded))
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
