//! The live simulation: a robot entity in the scene, robot actions as ECS messages, and one
//! system that performs them. Each action is checked against the kinematic tree as it stands
//! (`sim::actions`), its changes are applied to the transform hierarchy (pick re-parents to the
//! gripper, place to the new support, open sets the joint value), and the rest test confirms
//! the world still stands. Before any of that, its motions (the drive, the door's swing, the
//! arm's reach and retreat) are simulated in rapier; one that would knock an object, or take the
//! arm into the scene, refuses the action. A refused action changes nothing. A robot with an arm
//! has an entity per link of the arm, posed for the arm's configuration.

use std::time::Instant;

use bevy::prelude::*;
use serde::Serialize;

use crate::arm::rig::{ArmRig, MAST_RADIUS_M};
use crate::components::{Joint, LinkBody, Panoptic, RobotArmLink};
use crate::kinematics::JointSpec;
use crate::kinematics::link::LinkGeometry;
use crate::kinematics::rest_test::{ObjectVerdict, REST_STEP_S, Verdict};
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::{Action, Change, attempt_then, robot_in_tree};
use crate::sim::arm_phases::arm_phases;
use crate::sim::motion_check::{MotionCheck, Movers};
use crate::sim::motion_path::{LinkMotion, apply_motion, link_motion};
use crate::sim::robot::{BasePose, GRIPPER_LINK, ROBOT_LINK, RobotSpec};
use crate::systems::kinematic_tree::{
    ReadTreeError, read_kinematic_tree, read_kinematic_tree_entities,
};
use crate::systems::motion_physics::simulate_movers_on;
use crate::systems::physics_validation::{PhysicsReport, scene_rest_physics, scratch_world};
use crate::systems::scene_graph::{SceneRoot, transform_of};

/// The robot's base entity: its figures and the place it last navigated to (for the planner).
#[derive(Component, Clone, Debug)]
pub struct Robot {
    pub spec: RobotSpec,
    pub place: String,
}

/// The robot's gripper entity (a child of the base); a held object is its child.
#[derive(Component, Clone, Copy, Debug)]
pub struct Gripper;

/// The objects the last rest test found falling on their own (unstable at rest, not for starting
/// inside something): the motion checks hold them still rather than blame their fall on the
/// robot. The rest tests before and after each action report them.
#[derive(Resource, Clone, Debug, Default)]
pub struct FallsAtRest(pub Vec<String>);

/// The rest test of the scene in `world` as it stands, its falling objects recorded in
/// [`FallsAtRest`] for the next motions' checks.
pub fn rest_physics(world: &mut World) -> Result<PhysicsReport, ReadTreeError> {
    let report = scene_rest_physics(world)?;
    let falling = report
        .objects
        .iter()
        .filter(|o| o.verdict == Verdict::Unstable)
        .map(|o| o.object.clone())
        .collect();
    world.insert_resource(FallsAtRest(falling));
    Ok(report)
}

/// Asks the robot to perform an action; the actions that follow it (a task's next steps) let
/// a pick look ahead to its place.
#[derive(Message, Clone, Debug)]
pub struct ActionRequest(pub Action, pub Vec<Action>);

/// The physics check after an action: the rest test of the whole scene.
#[derive(Clone, Debug, Serialize)]
pub struct StepPhysics {
    /// The objects simulated and judged.
    pub checked: Vec<String>,
    /// Share of them judged stable.
    pub stable_fraction: f32,
    /// Objects judged unstable or penetrating, with the reason.
    pub not_stable: Vec<ObjectVerdict>,
}

/// What one action did.
#[derive(Clone, Debug, Serialize)]
pub struct StepRecord {
    pub step: usize,
    pub action: Action,
    pub success: bool,
    /// Why the action was refused (nothing changed).
    pub failed_precondition: Option<String>,
    /// The kinematic-tree changes it made.
    pub changes: Vec<Change>,
    /// Its motions simulated in rapier, in order (a refused action's up to the one that knocked
    /// something).
    pub motion: Vec<MotionCheck>,
    /// The rest test after it (absent when refused).
    pub physics: Option<StepPhysics>,
    /// Wall-clock milliseconds for the action, its motions' simulation and its physics check.
    pub wall_ms: f64,
    /// Of `wall_ms`, the milliseconds of the physics check.
    pub physics_ms: f64,
    /// The action moved its door or drawer part of the way (no one place of the base follows
    /// its handle all the way); the next step goes on with the same action.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub part_way: bool,
}

impl StepRecord {
    /// Milliseconds its motions took to simulate.
    pub fn motion_ms(&self) -> f64 {
        self.motion
            .iter()
            .map(|m| m.wall_ms)
            .fold(0.0, |a, b| a + b)
    }
}

/// Every action performed so far, in order.
#[derive(Resource, Clone, Debug, Default)]
pub struct SimulationTrace(pub Vec<StepRecord>);

/// Spawns the robot under the scene root at `pose`: a base link on a fixed joint (the mobile
/// base is placed, not simulated) and a gripper link fixed on it at `base_from_gripper` (its
/// mesh `gripper_mesh`): the plate on the base's column, or an arm's stowed hand.
pub fn spawn_robot(
    world: &mut World,
    spec: RobotSpec,
    pose: BasePose,
    (base_from_gripper, gripper_mesh): (glam::Affine3A, crate::geometry::TriMesh),
    arm: Option<&ArmRig>,
) -> Result<Entity, ReadTreeError> {
    let root = world
        .query_filtered::<Entity, With<SceneRoot>>()
        .iter(world)
        .next()
        .ok_or(ReadTreeError::NoSceneRoot)?;
    let fixed = Joint {
        spec: JointSpec::FIXED,
        value: 0.0,
    };
    let base = world
        .spawn((
            Name::new(ROBOT_LINK),
            Robot {
                spec,
                place: crate::sim::symbolic::START_PLACE.into(),
            },
            LinkBody(std::sync::Arc::new(LinkGeometry::new(
                spec.base_mesh(),
                [0.2, 0.3, 0.6],
                ROBOT_LINK,
            ))),
            fixed,
            transform_of(pose.world_from_base()),
            ChildOf(root),
        ))
        .id();
    world.spawn((
        Name::new(GRIPPER_LINK),
        Gripper,
        LinkBody(std::sync::Arc::new(LinkGeometry::new(
            gripper_mesh,
            [0.1, 0.1, 0.1],
            ROBOT_LINK,
        ))),
        fixed,
        transform_of(base_from_gripper),
        ChildOf(base),
    ));
    if let Some(rig) = arm {
        let stowed = rig.stowed_link_poses();
        for (l, (link, pose)) in rig.arm.links.iter().zip(stowed).enumerate() {
            let mut entity = world.spawn((
                Name::new(link.name.clone()),
                RobotArmLink(l),
                transform_of(pose),
                ChildOf(base),
            ));
            // The viewer draws link bodies: its visual meshes (the rapier checks collide the
            // rig's pieces); a lift's mast, which touches nothing, is seen too.
            let mast = rig
                .mast()
                .filter(|(mast, _)| *mast == l)
                .map(|(_, length)| {
                    crate::geometry::TriMesh::cylinder(
                        Vec3::NEG_Z * length,
                        MAST_RADIUS_M,
                        length,
                        16,
                    )
                });
            if !link.look.positions.is_empty() || mast.is_some() {
                let mut pieces = link.pieces.clone();
                let mut look = (*link.look).clone();
                if let Some(mast) = mast {
                    look.append(&mast);
                    pieces.push(mast);
                }
                entity.insert(LinkBody(std::sync::Arc::new(LinkGeometry::of_look(
                    look, pieces, ARM_COLOR, ROBOT_LINK,
                ))));
            }
        }
    }
    Ok(base)
}

/// The arm's links' colour: the Panda's white.
const ARM_COLOR: [f32; 3] = [0.85, 0.85, 0.82];

/// Puts the arm's link entities where configuration `q` holds them, the fingers a gap of
/// `grip_m` apart (open when `None`).
fn pose_arm_links(world: &mut World, q: &[f32], grip_m: Option<f32>) {
    let Some(rig) = world.get_resource::<RobotArm>().map(|a| a.0.clone()) else {
        return;
    };
    let opening = grip_m.map_or(1.0, |g| rig.finger_opening(g));
    let poses = rig.arm.link_poses(&rig.base_from_root, q, opening);
    for (link, mut transform) in world
        .query::<(&RobotArmLink, &mut Transform)>()
        .iter_mut(world)
    {
        if let Some(pose) = poses.get(link.0) {
            *transform = transform_of(*pose);
        }
    }
}

/// An action that leaves its part part of the way goes on at most this many steps more.
const MAX_PART_WAY_STEPS: usize = 3;
/// How many times a pick or place whose arm motion rapier refused is planned again without it.
const MAX_REFUSED_REPLANS: usize = 3;

/// Performs `action` on the world: checks it, applies its changes, checks the physics; records
/// and returns what happened. A door or drawer moved part of the way is moved on in further
/// steps of the same action (each recorded), and the last step is returned.
pub fn perform(world: &mut World, action: &Action, then: &[Action]) -> StepRecord {
    let mut record = perform_step(world, action, then);
    for _ in 0..MAX_PART_WAY_STEPS {
        if !record.part_way {
            return record;
        }
        record = perform_step(world, action, then);
    }
    if !record.part_way {
        return record;
    }
    // Still short after its steps: the action fails there (the steps it made stay made).
    let short = StepRecord {
        step: record.step + 1,
        action: action.clone(),
        success: false,
        failed_precondition: Some(format!(
            "{} took {} steps, each part of the way, and is still short of where it goes",
            action.in_words(),
            MAX_PART_WAY_STEPS + 1
        )),
        changes: Vec::new(),
        motion: Vec::new(),
        physics: None,
        wall_ms: 0.0,
        physics_ms: 0.0,
        part_way: false,
    };
    world
        .get_resource_or_insert_with(SimulationTrace::default)
        .0
        .push(short.clone());
    short
}

/// One step of [`perform`].
fn perform_step(world: &mut World, action: &Action, then: &[Action]) -> StepRecord {
    let started = Instant::now();
    let step = world
        .get_resource::<SimulationTrace>()
        .map_or(0, |t| t.0.len());
    let mut motion = Vec::new();
    let outcome = read_kinematic_tree_entities(world)
        .map_err(|e| e.to_string())
        .and_then(|(tree, entities)| {
            let spec = robot_spec(world).ok_or("the scene has no robot")?;
            let arm = world.get_resource::<RobotArm>().map(|a| a.0.clone());
            let scene = (&tree, &entities[..]);
            planned_and_checked(
                world,
                scene,
                &spec,
                arm.as_deref(),
                (action, then),
                &mut motion,
            )
        });
    let record = match outcome {
        Err(reason) => StepRecord {
            step,
            action: action.clone(),
            success: false,
            failed_precondition: Some(reason),
            changes: Vec::new(),
            motion,
            physics: None,
            wall_ms: started.elapsed().as_secs_f64() * 1e3,
            physics_ms: 0.0,
            part_way: false,
        },
        Ok(changes) => {
            for change in &changes {
                apply_change(world, change);
            }
            // A pick's fingers stay closed on what it took while the hand carries it.
            for pair in changes.windows(2) {
                if let [
                    Change::ArmMotion {
                        reach,
                        retreat,
                        grip_m,
                        ..
                    },
                    Change::Attach { to, .. },
                ] = pair
                    && to == GRIPPER_LINK
                    && let Some(q) = retreat.last().or(reach.last())
                {
                    pose_arm_links(world, q, *grip_m);
                }
            }
            if let Action::Navigate { to } = action {
                for mut robot in world.query::<&mut Robot>().iter_mut(world) {
                    robot.place = to.clone();
                }
            }
            let physics_started = Instant::now();
            let physics = rest_physics(world)
                .inspect_err(|e| tracing::warn!("no rest test after step {step}: {e}"))
                .ok()
                .map(step_physics);
            let physics_ms = physics_started.elapsed().as_secs_f64() * 1e3;
            // Only a door or drawer can be left part of the way: no other step reads the tree.
            let part_way = matches!(action, Action::Open { .. } | Action::Close { .. })
                && read_kinematic_tree(world)
                    .is_ok_and(|tree| crate::sim::actions::left_part_way(&tree, action));
            StepRecord {
                step,
                action: action.clone(),
                success: true,
                failed_precondition: None,
                changes,
                motion,
                physics,
                wall_ms: started.elapsed().as_secs_f64() * 1e3,
                physics_ms,
                part_way,
            }
        }
    };
    world
        .get_resource_or_insert_with(SimulationTrace::default)
        .0
        .push(record.clone());
    record
}

/// `action`'s changes on the scene `(tree, entities)` as it stands, planned (looking ahead to
/// `then`) and their motions simulated in rapier (the checks into `motion`), or why not. A pick
/// or place whose arm motion rapier refuses is planned again without it (another grasp, spot
/// or base pose), up to [`MAX_REFUSED_REPLANS`] times; the reason lists every refusal.
fn planned_and_checked(
    world: &mut World,
    (tree, entities): (&KinematicTree, &[Entity]),
    spec: &RobotSpec,
    arm: Option<&ArmRig>,
    (action, then): (&Action, &[Action]),
    motion: &mut Vec<MotionCheck>,
) -> Result<Vec<Change>, String> {
    let (mut refused, mut refusals) = (Vec::new(), Vec::new());
    loop {
        let changes = attempt_then(tree, spec, arm, action, then, &refused).map_err(|e| {
            refusals.push(e.to_string());
            refusals.join("; then ")
        })?;
        let arm_from;
        (*motion, arm_from) = simulate_motions(world, tree, entities, &changes, arm);
        let Some((k, why)) = motion
            .iter()
            .enumerate()
            .find_map(|(k, m)| Some((k, m.refusal()?)))
        else {
            return Ok(changes);
        };
        // Only the arm's own motion (not the base's drive) is another grasp's to mend.
        let by_the_arm = arm_from.is_some_and(|from| k >= from);
        let arm_motion = changes.iter().find_map(|c| match c {
            Change::ArmMotion {
                what, part: None, ..
            } if by_the_arm => Some(what.clone()),
            _ => None,
        });
        refusals.push(why);
        match arm_motion {
            Some(what) if refused.len() < MAX_REFUSED_REPLANS => {
                tracing::debug!("{}: {what} refused in rapier", action.in_words());
                refused.push(what);
            }
            _ => return Err(refusals.join("; then ")),
        }
    }
}

/// The motions of `changes` (a drive, a door, the arm's reach, follow and retreat) simulated in
/// rapier one after another from `tree`, the scene in `world` as it stands (`entities[l]` is
/// link `l`'s entity), up to the first attachment (which happens at once), the arm's motion (the
/// last the action makes) or the first that knocks something or takes the arm into the scene.
/// The first motion runs on the scene's own entities (the arm's on its link entities); those
/// after it start from a state the scene is not in yet, and run in a scratch world of the tree
/// as the motions before left it. With the checks, the index of the first of the arm's own
/// motion (its reach, follow and retreat), if it ran.
fn simulate_motions(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    changes: &[Change],
    arm: Option<&ArmRig>,
) -> (Vec<MotionCheck>, Option<usize>) {
    let mut tree = tree.clone();
    let (mut checks, mut arm_from) = (Vec::new(), None);
    let mut as_the_scene_stands = true;
    let falling: Vec<usize> = world
        .get_resource::<FallsAtRest>()
        .map_or(&[][..], |f| &f.0)
        .iter()
        .filter_map(|id| tree.links.iter().position(|l| l.name == *id))
        .collect();
    for (k, change) in changes.iter().enumerate() {
        if let (Change::ArmMotion { .. }, Some(rig)) = (change, arm) {
            arm_from = Some(checks.len());
            let handover = changes.get(k + 1);
            for phase in arm_phases(&tree, rig, change, handover, REST_STEP_S) {
                let movers = Movers {
                    links: &phase.links,
                    hidden: &phase.hidden,
                    hollow: &phase.hollow,
                    still: &phase.still,
                    set_on: &phase.set_on,
                    falling: &falling,
                    arm: Some((rig, &phase.arm)),
                    ..Movers::named(format!("{ROBOT_LINK} ({})", phase.what))
                };
                let check =
                    check_movers(world, &phase.tree, entities, &movers, as_the_scene_stands);
                let refused = check.refusal().is_some();
                checks.push(check);
                if refused {
                    break;
                }
                as_the_scene_stands = false;
            }
            break;
        }
        if let Some(motion) = link_motion(&tree, change, REST_STEP_S) {
            let check = match (change, arm) {
                (Change::MoveBase { .. }, Some(rig)) => check_drive_with_arm(
                    world,
                    &tree,
                    entities,
                    (&motion, &falling),
                    rig,
                    as_the_scene_stands,
                ),
                _ => {
                    let links = [(motion.link, motion.world_from_link.clone())];
                    let movers = Movers {
                        links: &links,
                        falling: &falling,
                        ..Movers::named(tree.links[motion.link].name.clone())
                    };
                    check_movers(world, &tree, entities, &movers, as_the_scene_stands)
                }
            };
            let refused = check.refusal().is_some();
            checks.push(check);
            if refused {
                break;
            }
        }
        if !apply_motion(&mut tree, change) {
            break;
        }
        as_the_scene_stands = false;
    }
    (checks, arm_from)
}

/// `movers` checked in rapier on the scene's own entities when `tree` is the scene as it stands
/// (`on_world`), else in a scratch world of `tree`.
fn check_movers(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    movers: &Movers,
    on_world: bool,
) -> MotionCheck {
    if on_world {
        simulate_movers_on(world, tree, entities, movers)
    } else {
        let (mut scratch, own) = scratch_world(tree);
        simulate_movers_on(&mut scratch, tree, &own, movers)
    }
}

/// The base's drive `motion` checked with the stowed arm of `rig` riding on it: the arm must
/// not knock what the base passes, nor go into it (`falling` held still).
fn check_drive_with_arm(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    (motion, falling): (&LinkMotion, &[usize]),
    rig: &ArmRig,
    on_world: bool,
) -> MotionCheck {
    let stowed = rig.stowed_link_poses();
    let arm_path: Vec<Vec<glam::Affine3A>> = motion
        .world_from_link
        .iter()
        .map(|base| stowed.iter().map(|p| *base * *p).collect())
        .collect();
    let links = [(motion.link, motion.world_from_link.clone())];
    // The gripper link stands for the stowed hand, which the arm's own hand is here.
    let hidden: Vec<usize> = tree
        .links
        .iter()
        .position(|l| l.name == GRIPPER_LINK)
        .into_iter()
        .collect();
    let movers = Movers {
        links: &links,
        hidden: &hidden,
        falling,
        arm: Some((rig, &arm_path)),
        ..Movers::named(ROBOT_LINK)
    };
    check_movers(world, tree, entities, &movers, on_world)
}

fn robot_spec(world: &mut World) -> Option<RobotSpec> {
    world.query::<&Robot>().iter(world).next().map(|r| r.spec)
}

/// The robot's place and what it holds (for the planner's start state).
pub fn robot_state(world: &mut World) -> Option<(String, Option<String>)> {
    let place = world.query::<&Robot>().iter(world).next()?.place.clone();
    let tree = read_kinematic_tree(world)
        .inspect_err(|e| tracing::warn!("the robot's state is unknown: {e}"))
        .ok()?;
    Some((place, robot_in_tree(&tree)?.holding))
}

fn entity_named(world: &mut World, name: &str) -> Option<Entity> {
    world
        .query::<(Entity, &Name)>()
        .iter(world)
        .find(|(_, n)| n.as_str() == name)
        .map(|(e, _)| e)
}

/// Applies one change to the transform hierarchy.
pub fn apply_change(world: &mut World, change: &Change) {
    match change {
        Change::MoveBase { to, .. } => {
            if let Some(base) = entity_named(world, ROBOT_LINK) {
                world
                    .entity_mut(base)
                    .insert(transform_of(to.world_from_base()));
            }
        }
        Change::SetJoint { link, to, .. } => {
            let Some(e) = entity_named(world, link) else {
                return;
            };
            let Some(mut joint) = world.get_mut::<Joint>(e) else {
                return;
            };
            let (spec, from) = (joint.spec, joint.value);
            joint.value = *to;
            // The part's transform is its joint frame moved by the joint's value.
            if let Some(mut t) = world.get_mut::<Transform>(e) {
                let now = glam::Affine3A::from_scale_rotation_translation(
                    t.scale,
                    t.rotation,
                    t.translation,
                );
                *t = transform_of(now * spec.motion(from).inverse() * spec.motion(*to));
            }
        }
        Change::Attach {
            link,
            to,
            parent_from_link,
            ..
        } => {
            let (Some(child), Some(parent)) = (entity_named(world, link), entity_named(world, to))
            else {
                return;
            };
            let held = to == GRIPPER_LINK;
            let joint = if held {
                JointSpec::FIXED
            } else {
                let class = world
                    .get::<Panoptic>(child)
                    .map_or("", |p| p.class.as_str());
                let has_model = world.get::<crate::components::CadModel>(child).is_some();
                crate::kinematics::support_joint(class, has_model)
            };
            world.entity_mut(child).insert((
                ChildOf(parent),
                transform_of(*parent_from_link),
                Joint {
                    spec: joint,
                    value: 0.0,
                },
            ));
        }
        // The arm ends where its last configuration holds it (stowed, after a whole action),
        // its fingers open; closed on what a pick took (`perform_step`).
        Change::ArmMotion { reach, retreat, .. } => {
            if let Some(q) = retreat.last().or(reach.last()) {
                pose_arm_links(world, q, None);
            }
        }
    }
}

/// A rest test reduced to what a step reports.
pub fn step_physics(report: PhysicsReport) -> StepPhysics {
    StepPhysics {
        checked: report.objects.iter().map(|o| o.object.clone()).collect(),
        stable_fraction: report.stable_fraction,
        not_stable: report
            .objects
            .into_iter()
            .filter(|o| o.verdict != Verdict::Stable)
            .collect(),
    }
}

/// Performs the actions asked for since the last update, in order.
fn perform_requested_actions(world: &mut World) {
    let requests: Vec<ActionRequest> = world
        .resource_mut::<Messages<ActionRequest>>()
        .drain()
        .collect();
    for ActionRequest(action, then) in requests {
        perform(world, &action, &then);
    }
}

/// The robot's arm, when it has one: picks and places are its planned motions.
#[derive(Resource, Clone)]
pub struct RobotArm(pub std::sync::Arc<crate::arm::rig::ArmRig>);

/// Adds the action messages, the trace and the system that performs actions.
pub struct SimulationPlugin;

impl Plugin for SimulationPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<ActionRequest>()
            .init_resource::<SimulationTrace>()
            .add_systems(Update, perform_requested_actions);
    }
}
