//! Robot actions on the kinematic tree: each checks its preconditions against the scene as it
//! stands and either refuses with the reason or returns the changes to the tree it makes
//! (the base moves, a joint turns, a link hangs from a new parent). Nothing here changes the
//! tree; the simulation system applies the changes to the ECS.

use glam::{Affine3A, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::arm::rig::ArmRig;
use crate::kinematics::tree::KinematicTree;
use crate::sim::robot::{BasePose, GRIPPER_LINK, ROBOT_LINK, RobotSpec};
use crate::sim::scene_view::{SceneView, TOUCH_M};

mod arm_bases;
mod arm_motion;
mod arm_scene;
mod error;
mod joints;
mod look_ahead;
mod part_motion;
mod place_in;
mod reach;

pub use arm_scene::scene_obstacles;
pub use error::ActionError;
pub use joints::left_part_way;
use joints::{closes_with, move_joint};
use look_ahead::{MAX_LOOKS_AHEAD, pick_ahead, plans_after};
pub use reach::nav_grid;
use reach::{approach, approach_point, navigate, within_reach};

/// One robot action, as task scripts write it (`{"action": "open", "object": "fridge_1"}`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "action", rename_all = "snake_case", deny_unknown_fields)]
pub enum Action {
    /// Drive the base to where it reaches the node `to` (in front of it when it has doors).
    Navigate { to: String },
    /// Turn or slide a door or drawer (`part`, default the main one) to `value` (default: as
    /// far open as it goes without hitting anything).
    Open {
        object: String,
        #[serde(default)]
        part: Option<String>,
        #[serde(default)]
        value: Option<f32>,
    },
    /// Close a door or drawer (`part`, default the main one).
    Close {
        object: String,
        #[serde(default)]
        part: Option<String>,
    },
    /// Take a movable object into the gripper.
    Pick { object: String },
    /// Set the held object down on top of `surface`.
    PlaceOn { object: String, surface: String },
    /// Set the held object down inside the open container.
    PlaceIn { object: String, container: String },
    /// Slide an object over its support by `distance` metres along `direction` (x, y).
    Push {
        object: String,
        direction: [f32; 2],
        distance: f32,
    },
}

impl Action {
    /// The action in words (a trace's reasons, the viewer's panel).
    pub fn in_words(&self) -> String {
        match self {
            Action::Navigate { to } => format!("navigate to {to}"),
            Action::Open { object, part, .. } => match part {
                Some(part) => format!("open {object} ({part})"),
                None => format!("open {object}"),
            },
            Action::Close { object, part } => match part {
                Some(part) => format!("close {object} ({part})"),
                None => format!("close {object}"),
            },
            Action::Pick { object } => format!("pick {object}"),
            Action::PlaceOn { object, surface } => format!("place {object} on {surface}"),
            Action::PlaceIn { object, container } => format!("place {object} in {container}"),
            Action::Push {
                object,
                direction,
                distance,
            } => format!(
                "push {object} {distance:.2} m along ({:.2}, {:.2})",
                direction[0], direction[1]
            ),
        }
    }

    /// The scene nodes the action names.
    pub fn node_ids(&self) -> Vec<&str> {
        match self {
            Action::Navigate { to } => vec![to],
            Action::Open { object, .. }
            | Action::Close { object, .. }
            | Action::Pick { object } => {
                vec![object]
            }
            Action::PlaceOn { object, surface } => vec![object, surface],
            Action::PlaceIn { object, container } => vec![object, container],
            Action::Push { object, .. } => vec![object],
        }
    }

    /// The node the action picks up or moves, if any.
    pub fn moved_object(&self) -> Option<&str> {
        match self {
            Action::Pick { object }
            | Action::PlaceOn { object, .. }
            | Action::PlaceIn { object, .. }
            | Action::Push { object, .. } => Some(object),
            _ => None,
        }
    }

    /// A short text for traces: `open fridge_1`.
    pub fn label(&self) -> String {
        match self {
            Action::Navigate { to } => format!("navigate {to}"),
            Action::Open { object, part, .. } | Action::Close { object, part } => {
                let verb = if matches!(self, Action::Open { .. }) {
                    "open"
                } else {
                    "close"
                };
                match part {
                    Some(part) => format!("{verb} {object} {part}"),
                    None => format!("{verb} {object}"),
                }
            }
            Action::Pick { object } => format!("pick {object}"),
            Action::PlaceOn { object, surface } => format!("place {object} on {surface}"),
            Action::PlaceIn { object, container } => format!("place {object} in {container}"),
            Action::Push {
                object, distance, ..
            } => format!("push {object} {distance} m"),
        }
    }
}

/// One change an action makes to the kinematic tree.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "change", rename_all = "snake_case")]
pub enum Change {
    /// The base drove along `path` (its length, metres) to `to`.
    MoveBase {
        from: BasePose,
        to: BasePose,
        path_length_m: f32,
        #[serde(skip)]
        path: Vec<Vec2>,
    },
    /// A joint moved.
    SetJoint { link: String, from: f32, to: f32 },
    /// A link now hangs from `to` (the same parent for a push), at `parent_from_link`.
    Attach {
        link: String,
        from: String,
        to: String,
        #[serde(skip)]
        parent_from_link: Affine3A,
    },
    /// The arm moved from its stowed configuration to a grasp or release along `reach`
    /// (configurations of its chain's joints, radians or metres, root to tool), closed or opened
    /// the hand, and went back along `retreat`.
    ArmMotion {
        what: String,
        reach: Vec<Vec<f32>>,
        retreat: Vec<Vec<f32>>,
        /// Between the reach and the retreat, the hand on a door's or drawer's handle.
        #[serde(skip_serializing_if = "Option::is_none")]
        part: Option<PartFollow>,
        /// The fingers' gap, metres, while they hold what the hand takes, carries or works
        /// (`arm::grasp::finger_gap`): closed on a pick's object from the end of the reach, on
        /// a place's until its end, on a handle while the part follows. Open otherwise, and
        /// throughout when `None` (nothing between them).
        #[serde(skip_serializing_if = "Option::is_none")]
        grip_m: Option<f32>,
    },
}

/// The hand following a part's handle: the joint of link `link` at `values[k]` while the arm
/// is at `along[k]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartFollow {
    pub link: String,
    pub values: Vec<f32>,
    pub along: Vec<Vec<f32>>,
}

/// The robot as the tree holds it: its base pose and what hangs from its gripper.
#[derive(Clone, Debug)]
pub struct RobotInTree {
    pub base: BasePose,
    pub holding: Option<String>,
    /// Arm motions (by what they do, `ArmMotion::what`) the simulation in rapier refused for
    /// the action being planned: its grasps are not tried again.
    pub refused: Vec<String>,
}

/// Reads the robot's pose and load off the tree (`None` when it has no robot).
pub fn robot_in_tree(tree: &KinematicTree) -> Option<RobotInTree> {
    let view = SceneView::new(tree);
    let base = view.link(ROBOT_LINK)?;
    let gripper = view.link(GRIPPER_LINK)?;
    let pose = view.poses[base];
    let holding = tree
        .links
        .iter()
        .find(|l| l.parent == Some(gripper))
        .map(|l| l.name.clone());
    Some(RobotInTree {
        base: BasePose {
            position: pose.translation.truncate(),
            yaw: crate::sim::scene_view::yaw_of(&pose),
        },
        holding,
        refused: Vec::new(),
    })
}

/// Checks `action` against `tree` and returns what it changes, or the precondition that fails.
/// With an `arm`, picks and places are the arm's planned motions (and fail when it finds none);
/// without one the gripper takes and sets down what the base reaches.
pub fn attempt(
    tree: &KinematicTree,
    robot: &RobotSpec,
    arm: Option<&ArmRig>,
    action: &Action,
) -> Result<Vec<Change>, ActionError> {
    attempt_then(tree, robot, arm, action, &[], &[])
}

/// [`attempt`] for a task whose next actions are `then`: an arm's pick looks ahead to the place
/// of its object among them (`pick_ahead`). The arm motions `refused` (by what they do) are not
/// planned again.
pub fn attempt_then(
    tree: &KinematicTree,
    robot: &RobotSpec,
    arm: Option<&ArmRig>,
    action: &Action,
    then: &[Action],
    refused: &[String],
) -> Result<Vec<Change>, ActionError> {
    let view = SceneView::new(tree);
    let Some(mut state) = robot_in_tree(tree) else {
        return Err(ActionError::NoRobot);
    };
    state.refused = refused.to_vec();
    match action {
        Action::Navigate { to } => navigate(&view, robot, &state, to),
        Action::Open {
            object,
            part,
            value,
        } => move_joint(
            tree,
            robot,
            arm,
            &state,
            object,
            part.as_deref(),
            Some(*value),
        ),
        Action::Close { object, part } => {
            move_joint(tree, robot, arm, &state, object, part.as_deref(), None)
        }
        Action::Pick { object } => {
            let (changes, moved) = approach(&view, robot, &state, object)?;
            // The checks of a pick, and the gripper's taking of the object without an arm.
            let picked = pick(&view, robot, &moved, object)?;
            match (arm, view.node_link(object)) {
                (Some(rig), Some(link)) => {
                    let around = arm_scene::AroundObject::new(&view, link);
                    let target = view.poses[link].translation.truncate();
                    let ahead = pick_ahead(object, then);
                    // Into a container the hand carries the object in level through its front:
                    // held from the side, the forearm stays out of the level.
                    let level_first = matches!(ahead.last(), Some(Action::PlaceIn { .. }));
                    let looked = std::cell::Cell::new(0);
                    // Whether the place that follows plans after this pick (from the base
                    // `at`), within a budget of looks.
                    let place_follows = |at: &RobotInTree, picked: &[Change]| {
                        if ahead.is_empty() || looked.get() >= MAX_LOOKS_AHEAD {
                            return Ok(());
                        }
                        looked.set(looked.get() + 1);
                        plans_after(tree, robot, rig, (&state, at), picked, ahead)
                    };
                    arm_bases::from_some_base(
                        &view,
                        robot,
                        &state,
                        (changes, moved),
                        (target, None),
                        &|at| {
                            arm_motion::pick_motion(
                                &view,
                                rig,
                                at,
                                (object, link),
                                &around,
                                level_first,
                                &|c| place_follows(at, c),
                            )
                        },
                    )
                }
                _ => Ok(changes.into_iter().chain(picked).collect()),
            }
        }
        Action::PlaceOn { object, surface } => {
            let link = held(&view, &state, object)?;
            if !view.nodes().contains(&surface.as_str()) || view.is_layout(surface) {
                return Err(ActionError::NotASurface(surface.clone()));
            }
            let gripper = view.link(GRIPPER_LINK).unwrap_or(0);
            let base = view.link(ROBOT_LINK).unwrap_or(0);
            // The free spot nearest the robot (not under its own base), then a drive to it.
            let spot = view
                .spot_on(link, surface, state.base.position, &[gripper, base])
                .ok_or_else(|| ActionError::NoFreeSpot(surface.clone()))?;
            let Some(rig) = arm else {
                let target = spot.translation.truncate();
                let (mut changes, _) = approach_point(&view, robot, &state, target, surface)?;
                changes.extend(attach(&view, link, surface, spot)?);
                return Ok(changes);
            };
            arm_bases::place_on_some_spot(
                &view,
                robot,
                rig,
                &state,
                (object, link),
                surface,
                spot,
                &[gripper, base],
            )
        }
        Action::PlaceIn { object, container } => {
            let link = held(&view, &state, object)?;
            if !view.is_container(container) {
                return Err(ActionError::NotAContainer(container.clone()));
            }
            if !view.is_open(container) {
                return Err(ActionError::Closed(container.clone()));
            }
            let (mut changes, moved) = approach(&view, robot, &state, container)?;
            let gripper = view.link(GRIPPER_LINK).unwrap_or(0);
            // An arm reaches a spot near the front best; any spot must let the doors close.
            let near = arm.map(|_| moved.base.position);
            let held_by = [gripper];
            let mut spots = view
                .spots_in(link, container, &held_by, near)
                .filter(|spot| closes_with(&view, link, container, *spot));
            let spot = spots.next().ok_or_else(|| ActionError::DoesNotFit {
                object: object.clone(),
                container: container.clone(),
            })?;
            let Some(rig) = arm else {
                changes.extend(attach(&view, link, container, spot)?);
                return Ok(changes);
            };
            place_in::by_arm(
                &view,
                robot,
                rig,
                &state,
                (changes, moved),
                (object, link),
                container,
                spot,
                spots,
            )
        }
        Action::Push {
            object,
            direction,
            distance,
        } => push(
            &view,
            robot,
            &state,
            object,
            Vec2::from(*direction),
            *distance,
        ),
    }
}

/// The link of `object` if the robot holds it.
fn held(view: &SceneView, state: &RobotInTree, object: &str) -> Result<usize, ActionError> {
    if state.holding.as_deref() != Some(object) {
        return Err(match &state.holding {
            Some(h) => ActionError::HoldsAnother {
                held: h.clone(),
                object: object.to_string(),
            },
            None => ActionError::NotHolding(object.to_string()),
        });
    }
    view.node_link(object)
        .ok_or_else(|| ActionError::NotInScene(object.to_string()))
}

pub(super) fn attach(
    view: &SceneView,
    link: usize,
    to: &str,
    world_from_link: Affine3A,
) -> Result<Vec<Change>, ActionError> {
    let parent = view
        .node_link(to)
        .ok_or_else(|| ActionError::NotInScene(to.to_string()))?;
    let from = view.tree.links[link]
        .parent
        .map_or(String::new(), |p| view.tree.links[p].name.clone());
    Ok(vec![Change::Attach {
        link: view.tree.links[link].name.clone(),
        from,
        to: view.tree.links[parent].name.clone(),
        parent_from_link: view.poses[parent].inverse() * world_from_link,
    }])
}

fn pick(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    object: &str,
) -> Result<Vec<Change>, ActionError> {
    if let Some(h) = &state.holding {
        return Err(ActionError::AlreadyHolding(h.clone()));
    }
    let Some(link) = view.node_link(object) else {
        return Err(ActionError::NotInScene(object.to_string()));
    };
    if !view.is_movable(object) {
        return Err(ActionError::NotMovable(object.to_string()));
    }
    if let Some(on_top) = view
        .nodes()
        .into_iter()
        .find(|n| view.support_of(n) == Some(object))
    {
        return Err(ActionError::StandsOn {
            top: on_top.to_string(),
            object: object.to_string(),
        });
    }
    if let Some(container) = view.support_of(object)
        && view.is_inside(object, container)
        && !view.is_open(container)
    {
        return Err(ActionError::InsideClosed {
            object: object.to_string(),
            container: container.to_string(),
        });
    }
    within_reach(view, robot, state, object)?;
    let (lo, hi) = view
        .local_bounds(link)
        .ok_or_else(|| ActionError::NoGeometry(object.to_string()))?;
    // Carried on the gripper, the centre of its bottom on the gripper's origin.
    let bottom_centre = Vec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z);
    let gripper_from_link = Affine3A::from_translation(-bottom_centre);
    let from = view.support_of(object).map_or(String::new(), String::from);
    Ok(vec![Change::Attach {
        link: object.to_string(),
        from,
        to: GRIPPER_LINK.into(),
        parent_from_link: gripper_from_link,
    }])
}

fn push(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    object: &str,
    direction: Vec2,
    distance: f32,
) -> Result<Vec<Change>, ActionError> {
    let Some(link) = view.node_link(object) else {
        return Err(ActionError::NotInScene(object.to_string()));
    };
    if !view.is_movable(object) {
        return Err(ActionError::NotMovable(object.to_string()));
    }
    if state.holding.as_deref() == Some(object) {
        return Err(ActionError::Holds(object.to_string()));
    }
    let support = view
        .support_of(object)
        .ok_or_else(|| ActionError::StandsOnNothing(object.to_string()))?
        .to_string();
    within_reach(view, robot, state, object)?;
    let d = direction.normalize_or_zero();
    if d == Vec2::ZERO || !distance.is_finite() || distance <= 0.0 {
        return Err(ActionError::BadPush);
    }
    let ignore = view.body_links(&support);
    let steps = (distance / 0.02).ceil().max(1.0) as usize;
    let mut pose = view.poses[link];
    for k in 1..=steps {
        let shift = (d * distance * k as f32 / steps as f32).extend(0.0);
        pose = Affine3A::from_translation(shift) * view.poses[link];
        if view.overlap_at(link, pose, &ignore) > TOUCH_M {
            return Err(ActionError::WouldRunInto {
                object: object.to_string(),
                after_m: distance * (k - 1) as f32 / steps as f32,
            });
        }
    }
    // It must still stand on its support.
    let own = view.node_link(&support).unwrap_or(0);
    let (lo, hi) = view.local_bounds(link).unwrap_or_default();
    let bottom = pose.transform_point3(Vec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z));
    let in_support = view.poses[own].inverse().transform_point3(bottom);
    let top = crate::sim::scene_view::vertical_hits(
        &view.body_mesh_in_node(&support),
        in_support.truncate(),
    )
    .into_iter()
    .fold(f32::MIN, f32::max);
    if (top - in_support.z).abs() > 0.02 {
        return Err(ActionError::WouldSlideOff {
            object: object.to_string(),
            support,
        });
    }
    attach(view, link, &support, pose)
}
