//! Opening and closing doors and drawers: which joint, how far it may go (its sweep checked),
//! where the base stands for it, and whether a container's doors still close over something
//! set inside.

use glam::{Affine3A, Vec2};

use crate::arm::rig::ArmRig;
use crate::kinematics::JointSpec;
use crate::kinematics::joint_sweep::{LinkSolids, SWEEP_TOLERANCE_M, SweepPose};
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::error::ArmTries;
use crate::sim::actions::reach::{APPROACH_M, drive, nav_goal};
use crate::sim::actions::{ActionError, Change, RobotInTree, arm_bases, part_motion};
use crate::sim::robot::{GRIPPER_LINK, ROBOT_LINK, RobotSpec};
use crate::sim::scene_view::{SceneView, TOUCH_M, closed_value, open_value};

/// A door turns at most this far (radians), a drawer slides this far (metres), between the
/// poses where its path is checked.
const SWEEP_STEP: f32 = 0.05;
/// A door opened as far as it goes must be at least this fraction open.
const MIN_OPEN_FRACTION: f32 = 0.6;
/// A door opened as far as it goes that stopped short of this fraction of the way is tried from
/// places where the arm follows it all the way, and taken from there when it opens at least
/// `FARTHER` (radians, or metres for a drawer) farther.
const WIDE_OPEN_FRACTION: f32 = 0.9;
const FARTHER: f32 = 0.1;
/// The base stands within this distance (metres) of a place chosen to work a part from.
const PLACE_TO_STAND_M: f32 = 0.08;
/// A part no one place follows all the way goes these fractions of the way from one place (the
/// largest first), each at least `MIN_PART_WAY_FRACTION` of its range.
const PART_WAY_FRACTIONS: [f32; 2] = [0.5, 0.25];
const MIN_PART_WAY_FRACTION: f32 = 0.1;
/// A part within this (radians or metres) of where an action moves it is there.
const THERE: f32 = 0.02;

/// Whether `action` (an open or a close), performed on the scene that is now `tree`, left its
/// part short of where it goes: it moved part of the way from one place, and goes on from
/// another.
pub fn left_part_way(tree: &KinematicTree, action: &super::Action) -> bool {
    use super::Action;
    let (object, part) = match action {
        Action::Open { object, part, .. } | Action::Close { object, part } => (object, part),
        _ => return false,
    };
    let view = SceneView::new(tree);
    let Ok(joint) = joint_of(&view, object, part.as_deref()) else {
        return false;
    };
    let link = &tree.links[joint];
    match action {
        Action::Open { value: None, .. } => {
            let open = open_value(tree, joint);
            (link.value - MIN_OPEN_FRACTION * open) * open.signum() < -THERE
        }
        Action::Open { value: Some(v), .. } => (link.value - link.joint.clamp(*v)).abs() > THERE,
        _ => (link.value - closed_value(tree, joint)).abs() > THERE,
    }
}

/// Opens (`open` is `Some(value)`; `Some(None)` as far as it goes) or closes (`None`) a door or
/// drawer of `object`. The base first steps to where it stands for the doors (in front, out of
/// their swing) when it is not there; the sweep is checked with the base where it ends. With an
/// arm, the base stands where the arm reaches the handle along its whole path (out of the
/// part's way: the sweep says), and the hand takes the handle and moves the part.
pub(super) fn move_joint(
    tree: &KinematicTree,
    robot: &RobotSpec,
    arm: Option<&ArmRig>,
    state: &RobotInTree,
    object: &str,
    part: Option<&str>,
    open: Option<Option<f32>>,
) -> Result<Vec<Change>, ActionError> {
    let view = SceneView::new(tree);
    let joint = joint_of(&view, object, part)?;
    let name = tree.links[joint].name.clone();
    let from = tree.links[joint].value;
    let Some(rig) = arm else {
        let own = view.node_link(object).unwrap_or(0);
        let goal = nav_goal(&view, robot, object, own);
        let (mut changes, moved, _) = stand_for_part(&view, robot, state, object, &goal)?;
        let (to, _) = part_target(&SceneView::new(&moved), joint, open, &[])?;
        changes.push(Change::SetJoint {
            link: name,
            from,
            to,
        });
        return Ok(changes);
    };
    if let Some(held) = &state.holding {
        return Err(ActionError::Holds(held.clone()));
    }
    let nominal = match open {
        Some(Some(v)) => tree.links[joint].joint.clamp(v),
        // Where it is open enough: the arm may not follow it farther from one place.
        Some(None) => MIN_OPEN_FRACTION * open_value(tree, joint),
        None => closed_value(tree, joint),
    };
    let farthest = match open {
        Some(None) => open_value(tree, joint),
        _ => nominal,
    };
    let places =
        part_motion::places_to_stand(&view, rig, robot, object, joint, (nominal, farthest))?;
    // The first of `places` the base gets to and the arm works the part from towards `open`
    // (none of those in `tried`, where the base stood already): the changes and the part's
    // value after them.
    let from_places = |places: Vec<Vec2>, open: Option<Option<f32>>, tried: &mut Vec<Vec2>| {
        if places.is_empty() {
            return Err(ActionError::ArmCannot {
                what: format!("work {name}"),
                attempts: vec![format!(
                    "no place to stand in front of {object} from which the arm reaches the \
                     handle along its path and the part misses the base"
                )],
            });
        }
        let mut tries = ArmTries::default();
        for place in places {
            let goal = crate::sim::navigation::NavGoal {
                target: place,
                reach: PLACE_TO_STAND_M,
                facing: None,
                keep_out: Vec::new(),
            };
            // The stowed hand is not where the hand is while it works the part: the arm's own
            // check keeps it clear of the part.
            let stowed_hand: Vec<usize> = view.link(GRIPPER_LINK).into_iter().collect();
            let stood = stand_for_part(&view, robot, state, object, &goal).and_then(|stood| {
                let target = part_target(&SceneView::new(&stood.1), joint, open, &stowed_hand)?;
                Ok((stood, target))
            });
            let ((mut changes, moved, after), (to, least)) = match stood {
                Ok(found) => found,
                Err(e) => {
                    tracing::debug!("{name} from ({:.2}, {:.2}): {e}", place.x, place.y);
                    tries.unreached(e);
                    continue;
                }
            };
            let p = after.base.position;
            if tried
                .iter()
                .any(|t| t.distance(p) <= arm_bases::SAME_BASE_M)
            {
                continue;
            }
            tried.push(p);
            let view = SceneView::new(&moved);
            match part_motion::work_part(&view, rig, &after, object, joint, to, least) {
                Ok(work) => {
                    changes.push(work.motion);
                    changes.push(Change::SetJoint {
                        link: name.clone(),
                        from,
                        to: work.reached,
                    });
                    return Ok((changes, work.reached));
                }
                Err(e) => tries.failed(&arm_bases::base_words(&after), e)?,
            }
        }
        Err(tries.error(Some(format!("work {name}"))))
    };
    let mut tried = Vec::new();
    let (changes, reached) = match from_places(places, open, &mut tried) {
        Ok(found) => found,
        // No one place follows the handle all the way (a fridge's door in a corner: the places
        // clear of its swing are out of the arm's reach of the handle while it is closed). The
        // part goes part of the way from one place, the step ends there, and the action goes on
        // from another (`left_part_way`).
        Err(whole) => {
            let range = (open_value(tree, joint) - closed_value(tree, joint)).abs();
            return PART_WAY_FRACTIONS
                .iter()
                .map(|f| from + f * (nominal - from))
                .filter(|to| (to - from).abs() >= MIN_PART_WAY_FRACTION * range)
                .find_map(|to| {
                    let places =
                        part_motion::places_to_stand(&view, rig, robot, object, joint, (to, to))
                            .ok()?;
                    tracing::debug!("{name}: part of the way, to {to:.2}");
                    from_places(places, Some(Some(to)), &mut Vec::new()).ok()
                })
                .map(|(changes, _)| changes)
                .ok_or(whole);
        }
    };
    // A door opened as far as it goes that stopped well short of it may go farther from a
    // place where the arm follows its handle all the way: a cabinet's door stopped at 65 % stood
    // in front of its own opening, between the base and the level behind it; at 73 % the hand
    // set a cup there. Taken only when it opens the door noticeably farther.
    if farthest != nominal && reached / farthest < WIDE_OPEN_FRACTION {
        let wide =
            part_motion::places_to_stand(&view, rig, robot, object, joint, (farthest, farthest))
                .unwrap_or_default();
        if let Ok((wider, wider_reached)) = from_places(wide, open, &mut tried)
            && (wider_reached - reached) * farthest.signum() >= FARTHER
        {
            return Ok(wider);
        }
    }
    Ok(changes)
}

/// Whether every open door and drawer of `container` still closes with the held `object` set at
/// `spot` (the world pose of its link): a spot near the front can be in a door's way.
pub(super) fn closes_with(
    view: &SceneView,
    object: usize,
    container: &str,
    spot: Affine3A,
) -> bool {
    let open: Vec<&str> = view
        .moving_parts(container)
        .into_iter()
        .filter(|&j| (view.tree.links[j].value - closed_value(view.tree, j)).abs() >= 1e-4)
        .map(|j| view.tree.links[j].name.as_str())
        .collect();
    let Some(own) = view.node_link(container).filter(|_| !open.is_empty()) else {
        return true;
    };
    let mut tree = view.tree.clone();
    tree.reparent(
        object,
        own,
        view.poses[own].inverse() * spot,
        JointSpec::FIXED,
    );
    let placed = SceneView::new(&tree);
    let robot: Vec<usize> = [ROBOT_LINK, GRIPPER_LINK]
        .iter()
        .filter_map(|name| placed.link(name))
        .collect();
    open.iter()
        .filter_map(|name| placed.link(name))
        .all(|joint| sweep(&placed, joint, closed_value(&tree, joint), &robot).is_ok())
}

/// The base's step to where it meets `goal` for working `object`'s parts, unless it is there:
/// the drive (if any), the tree with the base moved, and the robot after it.
fn stand_for_part(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    object: &str,
    goal: &crate::sim::navigation::NavGoal,
) -> Result<(Vec<Change>, KinematicTree, RobotInTree), ActionError> {
    let mut moved = view.tree.clone();
    if goal.is_met(state.base.position) {
        return Ok((Vec::new(), moved, state.clone()));
    }
    let (change, after) = drive(view, robot, state, goal, APPROACH_M)?
        .ok_or_else(|| ActionError::NoPlaceToWorkDoors(object.to_string()))?;
    if let Some(base) = view.link(ROBOT_LINK) {
        moved.links[base].parent_from_link = after.base.world_from_base();
    }
    Ok((vec![change], moved, after))
}

/// The value part `joint` moves to (`open` as for [`move_joint`]), its sweep checked in `view`,
/// and for a door opened as far as it goes, the least value that is open enough.
fn part_target(
    view: &SceneView,
    joint: usize,
    open: Option<Option<f32>>,
    ignore: &[usize],
) -> Result<(f32, Option<f32>), ActionError> {
    let tree = view.tree;
    let name = tree.links[joint].name.clone();
    let from = tree.links[joint].value;
    match open {
        None | Some(Some(_)) => {
            let target = match open {
                Some(Some(v)) => tree.links[joint].joint.clamp(v),
                _ => closed_value(tree, joint),
            };
            sweep(view, joint, target, ignore).map_err(|(hit, at)| ActionError::WouldHit {
                part: name.clone(),
                hit,
                at,
            })?;
            Ok((target, None))
        }
        Some(None) => {
            let target = open_value(tree, joint);
            let least = Some(MIN_OPEN_FRACTION * target);
            match sweep(view, joint, target, ignore) {
                Ok(()) => Ok((target, least)),
                Err((hit, at)) => {
                    // As far as it goes, if that is open enough to reach in.
                    let last = at - SWEEP_STEP * (target - from).signum();
                    if last / target < MIN_OPEN_FRACTION {
                        return Err(ActionError::HitsBeforeOpen {
                            part: name,
                            hit,
                            at,
                        });
                    }
                    Ok((last, least))
                }
            }
        }
    }
}

/// The moving part `part` of `object` (its main one when `None`).
fn joint_of(view: &SceneView, object: &str, part: Option<&str>) -> Result<usize, ActionError> {
    if view.node_link(object).is_none() {
        return Err(ActionError::NotInScene(object.to_string()));
    }
    let parts = view.moving_parts(object);
    match part {
        None => parts
            .first()
            .copied()
            .ok_or_else(|| ActionError::NotArticulated(object.to_string())),
        Some(p) => parts
            .into_iter()
            .find(|&j| view.tree.links[j].name == format!("{object}_{p}"))
            .ok_or_else(|| ActionError::NoSuchPart {
                object: object.to_string(),
                part: p.to_string(),
            }),
    }
}

/// Sweeps joint `joint` from its value to `target`, `ignore` left out; the first thing the
/// moving part (and what it carries) hits, with the value, or `Ok`.
fn sweep(
    view: &SceneView,
    joint: usize,
    target: f32,
    ignore: &[usize],
) -> Result<(), (String, f32)> {
    let tree = view.tree;
    let from = tree.links[joint].value;
    let steps = ((target - from).abs() / SWEEP_STEP).ceil().max(1.0) as usize;
    let solids: Vec<LinkSolids> = (0..tree.links.len())
        .map(|i| {
            if ignore.contains(&i) {
                LinkSolids::none()
            } else {
                LinkSolids::of(tree, i)
            }
        })
        .collect();
    let mut pose = SweepPose::new(tree, &solids, joint, &[]);
    // What already touches at the start (a door against its own frame) is contact.
    let at_start = pose.depths(from);
    for k in 1..=steps {
        let value = from + (target - from) * k as f32 / steps as f32;
        let depths = pose.depths(value);
        let hit = depths
            .iter()
            .zip(&at_start)
            .position(|(&depth, &before)| depth > SWEEP_TOLERANCE_M.max(before + TOUCH_M));
        if let Some(p) = hit {
            return Err((tree.links[pose.still_of(p)].name.clone(), value));
        }
    }
    Ok(())
}
