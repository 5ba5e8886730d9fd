//! `iscene simulate DIR --task TASK.json --out DIR2`: loads a scene folder (a reconstruction's
//! output, or a rendered sequence's `gt/`) into a live ECS world with a robot, runs the task's
//! actions (or plans them for its goals first), and writes the trace, the PDDL of the task and
//! the scene's exports after the last step.

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy::prelude::*;
use glam::Affine3A;
use serde::Serialize;

use crate::arm::Arm;
use crate::arm::reach::ArmRig;
use crate::base::InvalidValue;
use crate::cad::db::database::CadDatabase;
use crate::error::{InputError, IsceneError};
use crate::export::write_tree_exports;
use crate::graph::ContactGraph;
use crate::graph::GraphEdge;
use crate::io::atomic::StagedDir;
use crate::io::output_folder::{OutputCommand, OutputTarget};
use crate::io::write_sequence::write_text;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::Change;
use crate::sim::actions::nav_grid;
use crate::sim::graph_sync::graph_after;
use crate::sim::planner::{ground, plan};
use crate::sim::replay::replay_files;
use crate::sim::robot::{BasePose, ROBOT_LINK};
use crate::sim::scene_view::SceneView;
use crate::sim::symbolic::{Fact, SymbolicScene, parse_goal, symbolic_scene};
use crate::sim::task::{AddedObject, Task};
use crate::sim::trajectory::trajectory;
use crate::sim::{actions::Action, pddl};
use crate::systems::kinematic_tree::{read_kinematic_tree, spawn_node_links};
use crate::systems::physics_validation::scene_rest_physics;
use crate::systems::scene_graph::spawn_contact_graph;
use crate::systems::simulation::{
    ActionRequest, RobotArm, SimulationPlugin, SimulationTrace, StepPhysics, StepRecord,
    robot_state, spawn_robot, step_physics,
};

/// States the planner may expand before it gives up: 6 s and 130 MB to prove 7 kitchen goals
/// unreachable (test build, 2026-11-26; 2 million took 42 s and 900 MB). The kitchen's
/// demonstration goals need 15 to 702 (an 8-step plan).
const MAX_EXPANDED: usize = 250_000;

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

/// The live world of `graph`: its entities, their links (CAD models from `db`, usually
/// `CadDatabase::for_scene` of the scene's folder) and the robot at `start` (default: the most
/// open spot of the floor).
pub fn simulation_app(
    graph: &ContactGraph,
    task: &Task,
    db: &CadDatabase,
    arm: Option<&Arm>,
) -> Result<App, IsceneError> {
    let mut app = App::new();
    app.add_plugins(SimulationPlugin);
    let world = app.world_mut();
    spawn_contact_graph(world, graph)?;
    spawn_node_links(world, graph, Some(db));
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
    let rig = arm.map(|arm| ArmRig::new(arm.clone(), spec.height));
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

/// A task ready to run: the scene's graph, its symbolic start state, the goals and the actions
/// (the task's own steps, or the planner's plan for its goals).
struct PreparedTask {
    graph: ContactGraph,
    task: Task,
    scene: SymbolicScene,
    goals: Vec<Fact>,
    plan: Option<Vec<String>>,
    /// States the planner expanded to find `plan`.
    planner_expanded: Option<usize>,
    actions: Vec<Action>,
    /// The models the scene's links come from.
    db: CadDatabase,
}

/// The task on the scene in `dir`, and the world built to read its start state (ready to run).
fn prepare(
    dir: &Path,
    task_path: &Path,
    arm: Option<&Arm>,
) -> Result<(PreparedTask, App), IsceneError> {
    let graph = ContactGraph::load(&dir.join("contact_graph.json"))?;
    let task = Task::load(task_path)?;
    let db = CadDatabase::for_scene(dir)?;
    let graph =
        add_unseen_objects(graph, &task.add, &db).map_err(|p| InputError::invalid(task_path, p))?;
    check_steps_name_movable_nodes(&task, &graph).map_err(|p| InputError::invalid(task_path, p))?;
    let mut app = simulation_app(&graph, &task, &db, arm)?;
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
        db,
    };
    Ok((prepared, app))
}

/// `graph` with the task's added objects, each put where the simulator's own placing puts a held
/// object: the first free spot inside the container (`"in"`, its lowest level with room, centred,
/// then towards the front) or on the surface (`"on"`), supported by it. One at a time, so each
/// sees the ones before it.
fn add_unseen_objects(
    mut graph: ContactGraph,
    adds: &[AddedObject],
    db: &CadDatabase,
) -> Result<ContactGraph, InvalidValue> {
    for (i, added) in adds.iter().enumerate() {
        let at = |problem: String| InvalidValue::at(format!("add[{i}] ({})", added.id), problem);
        let (host, inside) = added.host().map_err(|e| at(e.to_string()))?;
        if graph.node(&added.id).is_some() {
            return Err(at("the scene already has a node of this id".into()));
        }
        let class = crate::classes::ClassTable::builtin()
            .get(&added.class)
            .ok_or_else(|| at(format!("unknown class {:?}", added.class)))?;
        if !class.movable {
            return Err(at(format!(
                "{} objects do not move; add a movable one",
                added.class
            )));
        }
        let model = db.get(&added.model).ok_or_else(|| {
            at(format!(
                "no model {:?} in the scene's models or the library",
                added.model
            ))
        })?;
        let Some(parent) = graph.node(host) else {
            return Err(at(format!("the scene has no node {host:?}")));
        };
        // Provisionally at the top centre of the host's box; the placing moves it.
        let parent_box = crate::geometry::GravityBox::from(&parent.bbox);
        let top = parent_box.center + Vec3::Z * parent_box.size.z / 2.0;
        let world_from_model =
            Affine3A::from_rotation_translation(Quat::from_rotation_z(parent_box.yaw), top);
        graph.nodes.push(node_of_model(
            &added.id,
            &added.class,
            class.kind,
            &model.model,
            world_from_model,
        ));
        graph.edges.push(GraphEdge::Support {
            parent: host.to_string(),
            child: added.id.clone(),
        });
        let mut app = App::new();
        app.add_plugins(SimulationPlugin);
        spawn_contact_graph(app.world_mut(), &graph).map_err(|e| at(e.to_string()))?;
        spawn_node_links(app.world_mut(), &graph, Some(db));
        let tree = read_kinematic_tree(app.world_mut()).map_err(|e| at(e.to_string()))?;
        let view = SceneView::new(&tree);
        let link = view
            .node_link(&added.id)
            .ok_or_else(|| at("its model built no link".into()))?;
        let spot = if inside {
            if !view.is_container(host) {
                return Err(at(format!("{host} is not a container")));
            }
            view.spot_in(link, host, &[])
                .ok_or_else(|| at(format!("{} does not fit in {host}", added.model)))?
        } else {
            if view.is_layout(host) && !matches!(host_class(&graph, host), Some("floor")) {
                return Err(at(format!("{host} is not a surface to put things on")));
            }
            let centre = top.truncate();
            view.spot_on(link, host, centre, &[])
                .ok_or_else(|| at(format!("no free spot on {host} for {}", added.model)))?
        };
        // The link's frame need not be the model's: move the model as the link moves.
        let link_from_model = view.poses[link].inverse() * world_from_model;
        let placed = spot * link_from_model;
        let node = graph.nodes.last_mut().expect("just added");
        *node = node_of_model(&added.id, &added.class, class.kind, &model.model, placed);
    }
    Ok(graph)
}

fn host_class<'a>(graph: &'a ContactGraph, id: &str) -> Option<&'a str> {
    graph.node(id).map(|n| n.class.as_str())
}

/// A node for `model` standing at `world_from_model` (the model's origin is the bottom centre of
/// its box).
fn node_of_model(
    id: &str,
    class: &str,
    kind: crate::classes::EntityKind,
    model: &crate::cad::model::CadModel,
    world_from_model: Affine3A,
) -> crate::graph::GraphNode {
    let (_, rotation, _) = world_from_model.to_scale_rotation_translation();
    let centre = world_from_model.transform_point3(Vec3::Z * model.size.z / 2.0);
    crate::graph::GraphNode {
        id: id.to_string(),
        class: class.to_string(),
        kind,
        bbox: crate::graph::BoxJson {
            center: centre.to_array(),
            yaw: rotation.to_euler(EulerRot::ZYX).0,
            size: model.size.to_array(),
        },
        planes: Vec::new(),
        cad: Some(crate::graph::CadPlacement {
            model: model.id.clone(),
            world_from_model: Mat4::from(world_from_model).to_cols_array(),
            scale: 1.0,
            alignment_error: 0.0,
        }),
        joints: Default::default(),
        parts: Vec::new(),
    }
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

/// Asks for each action in turn through the ECS, one update each, until one fails; returns
/// each update's wall-clock milliseconds.
fn run_actions(app: &mut App, actions: &[Action]) -> Vec<f64> {
    let mut update_ms = Vec::with_capacity(actions.len());
    for action in actions {
        app.world_mut()
            .resource_mut::<Messages<ActionRequest>>()
            .write(ActionRequest(action.clone()));
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
    let physics_before = step_physics(scene_rest_physics(app.world_mut())?);
    run_actions(&mut app, &prepared.actions);
    let steps = app.world().resource::<SimulationTrace>().0.clone();
    let after = read_kinematic_tree(app.world_mut())?;
    let (place, holding) = robot_state(app.world_mut()).unwrap_or_default();
    let end = symbolic_scene(&SceneView::new(&after), &place, holding.as_deref());
    let goals_hold = prepared.goals.iter().all(|g| end.facts.contains(g));
    let all_ran = prepared.actions.len() == steps.len();
    let summary = SimulationSummary {
        task: options.task.display().to_string(),
        goals: prepared.task.goals.clone(),
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
            None => simulation_app(&prepared.graph, &prepared.task, &prepared.db, arm.as_ref())?,
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
    let steps: Vec<StepTiming> = prepared
        .actions
        .iter()
        .enumerate()
        .map(|(i, action)| StepTiming {
            action: action.label(),
            median_ms: median(per_run.iter().map(|(s, _)| s[i].wall_ms).collect()),
            max_ms: per_run
                .iter()
                .map(|(s, _)| s[i].wall_ms)
                .fold(0.0, f64::max),
            median_physics_ms: median(per_run.iter().map(|(s, _)| s[i].physics_ms).collect()),
            median_motion_ms: median(per_run.iter().map(|(s, _)| s[i].motion_ms()).collect()),
            median_update_ms: median(per_run.iter().map(|(_, u)| u[i]).collect()),
            checked: per_run[0].0[i]
                .physics
                .as_ref()
                .map_or(0, |p| p.checked.len()),
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
    write_text(
        &dir.join("problem.pddl"),
        &pddl::problem("task", &prepared.scene, &prepared.goals),
    )?;
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

/// A room's pick and place with the arm: what was moved where, whether it worked, and the
/// seconds its pick and place steps took (planning, motion checks and rest tests).
#[derive(Clone, Debug, Serialize)]
pub struct PickPlaceTrial {
    pub object: String,
    pub surface: String,
    pub success: bool,
    pub seconds: f64,
}

/// Classes whose open top holds things at a working height: the benchmark's pick and place
/// takes from and puts onto these first (a shelf's lower boards come after).
const TOP_CLASSES: [&str; 6] = [
    "table",
    "desk",
    "counter",
    "nightstand",
    "dresser",
    "sideboard",
];

/// Classes a parallel gripper is made for (a book lying flat offers it no side narrower than a
/// hand): the benchmark's pick and place takes one of these first.
const HANDY_CLASSES: [&str; 5] = ["cup", "mug", "bottle", "bowl", "can"];

/// The benchmark's task for a room: a movable object standing on something other than the
/// floor goes onto another surface, planned from the goal `"OBJECT on SURFACE"` with the arm of
/// `robot` on the scene in `dir`. Cups, mugs, bottles, bowls and cans on tables, desks and
/// counters come first, then other objects there, then the rest, each by id; the surface is
/// the first other one, tables, desks and counters first. The simulation's
/// output goes to `out`, its task beside it (`out` with `.task.json`). `None` when the room has
/// no such object and surface, or the planner finds no plan.
pub fn pick_and_place_trial(
    dir: &Path,
    robot: &Path,
    out: &Path,
) -> Result<Option<PickPlaceTrial>, IsceneError> {
    let graph = ContactGraph::load(&dir.join("contact_graph.json"))?;
    let classes = crate::classes::ClassTable::builtin();
    let is_layout = |id: &str| {
        graph
            .node(id)
            .is_none_or(|n| n.kind == crate::classes::EntityKind::Layout)
    };
    let supports: Vec<(&str, &str)> = graph
        .edges
        .iter()
        .filter_map(|e| match e {
            GraphEdge::Support { parent, child } => Some((parent.as_str(), child.as_str())),
            _ => None,
        })
        .collect();
    let on_top = |id: &str| {
        graph
            .node(id)
            .is_some_and(|n| TOP_CLASSES.contains(&n.class.as_str()))
    };
    let mut objects: Vec<(&str, &str)> = supports
        .iter()
        .filter(|(parent, child)| {
            !is_layout(parent)
                && graph
                    .node(child)
                    .and_then(|n| classes.get(&n.class))
                    .is_some_and(|c| c.movable)
        })
        .map(|&(parent, child)| (child, parent))
        .collect();
    let handy = |id: &str| {
        graph
            .node(id)
            .is_some_and(|n| HANDY_CLASSES.contains(&n.class.as_str()))
    };
    objects.sort_by_key(|&(object, support)| (!on_top(support), !handy(object), object));
    let mut surfaces: Vec<&str> = supports
        .iter()
        .map(|(parent, _)| *parent)
        .chain(
            graph
                .nodes
                .iter()
                .filter(|n| TOP_CLASSES.contains(&n.class.as_str()))
                .map(|n| n.id.as_str()),
        )
        .filter(|id| !is_layout(id))
        .collect();
    surfaces.sort_by_key(|&id| (!on_top(id), id));
    surfaces.dedup();
    let Some((object, surface)) = objects.iter().find_map(|&(object, support)| {
        let onto = surfaces
            .iter()
            .find(|s| **s != support && !objects.iter().any(|(o, _)| o == *s))?;
        Some((object.to_string(), onto.to_string()))
    }) else {
        return Ok(None);
    };
    let task = out.with_extension("task.json");
    write_text(
        &task,
        &serde_json::json!({ "goals": [format!("{object} on {surface}")] }).to_string(),
    )?;
    let summary = match simulate(&SimulateOptions {
        dir: dir.to_path_buf(),
        task,
        out: out.to_path_buf(),
        force: true,
        robot: Some(robot.to_path_buf()),
    }) {
        Ok(summary) => summary,
        Err(IsceneError::Input(e)) => {
            tracing::warn!("no pick and place in {}: {e}", dir.display());
            return Ok(None);
        }
        Err(other) => return Err(other),
    };
    let seconds = summary
        .steps
        .iter()
        .filter(|s| {
            matches!(
                s.action,
                Action::Pick { .. } | Action::PlaceOn { .. } | Action::PlaceIn { .. }
            )
        })
        .map(|s| s.wall_ms / 1e3)
        .sum();
    Ok(Some(PickPlaceTrial {
        object,
        surface,
        success: summary.success,
        seconds,
    }))
}
