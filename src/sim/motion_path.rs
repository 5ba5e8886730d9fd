//! How an action's motion unfolds in time: the base drives along its A* path while it turns to
//! its new heading, a door or drawer moves from its old value to its new. The rapier motion
//! check (systems/motion_physics.rs) simulates these paths, and the viewer shows them.

use glam::{Affine3A, Quat, Vec2};

use crate::kinematics::tree::KinematicTree;
use crate::kinematics::{JointKind, JointSpec};
use crate::sim::actions::Change;
use crate::sim::robot::{BasePose, GRIPPER_LINK, ROBOT_LINK};

/// The base drives at this speed (m/s) and turns at this rate (rad/s), whichever takes longer.
pub const DRIVE_SPEED_M_S: f32 = 1.2;
pub const TURN_RATE_RAD_S: f32 = 1.5;
/// A door turns at this rate (rad/s), a drawer slides at this speed (m/s).
pub const DOOR_RATE_RAD_S: f32 = 1.2;
pub const DRAWER_SPEED_M_S: f32 = 0.3;
/// No motion takes less than this (seconds): a small correction still moves visibly.
pub const MIN_MOTION_S: f32 = 0.3;

/// The turn from yaw `from` to yaw `to` the short way round, radians.
pub fn shortest_turn(from: f32, to: f32) -> f32 {
    use std::f32::consts::{PI, TAU};
    (to - from + PI).rem_euclid(TAU) - PI
}

/// The point a fraction `t` of the way along the polyline `path`, by length.
pub fn along(path: &[Vec2], t: f32) -> Vec2 {
    let length: f32 = path.windows(2).map(|w| w[0].distance(w[1])).sum();
    let mut left = t.clamp(0.0, 1.0) * length;
    for w in path.windows(2) {
        let leg = w[0].distance(w[1]);
        if left <= leg && leg > 0.0 {
            return w[0].lerp(w[1], left / leg);
        }
        left -= leg;
    }
    path.last().copied().unwrap_or_default()
}

/// A drive's polyline: from its start through the A* waypoints to its end.
pub fn drive_path(change: &Change) -> Option<Vec<Vec2>> {
    let Change::MoveBase { from, to, path, .. } = change else {
        return None;
    };
    let mut points = vec![from.position];
    points.extend(path.iter().copied());
    points.push(to.position);
    points.dedup();
    Some(points)
}

/// Seconds a drive from `from` to `to` along `path_length_m` takes.
pub fn drive_seconds(from: &BasePose, to: &BasePose, path_length_m: f32) -> f32 {
    (path_length_m / DRIVE_SPEED_M_S)
        .max(shortest_turn(from.yaw, to.yaw).abs() / TURN_RATE_RAD_S)
        .max(MIN_MOTION_S)
}

/// Seconds a joint of `kind` takes from `from` to `to`.
pub fn joint_seconds(kind: JointKind, from: f32, to: f32) -> f32 {
    let rate = match kind {
        JointKind::Prismatic => DRAWER_SPEED_M_S,
        _ => DOOR_RATE_RAD_S,
    };
    ((to - from).abs() / rate).max(MIN_MOTION_S)
}

/// Seconds a change's motion takes at the robot's speeds (`None` for one without motion: an
/// attachment happens at once; an arm's motion is timed by `sim::arm_phases`).
pub fn motion_seconds(tree: &KinematicTree, change: &Change) -> Option<f32> {
    match change {
        Change::MoveBase {
            from,
            to,
            path_length_m,
            ..
        } => Some(drive_seconds(from, to, *path_length_m)),
        Change::SetJoint { link, from, to } => {
            let joint = tree.links.iter().find(|l| &l.name == link)?.joint;
            Some(joint_seconds(joint.kind, *from, *to))
        }
        Change::Attach { .. } | Change::ArmMotion { .. } => None,
    }
}

/// A link of the tree moving: its world pose at times `step_s` apart, from the start of the
/// motion to its end. What the link carries moves with it.
#[derive(Clone, Debug)]
pub struct LinkMotion {
    pub link: usize,
    pub world_from_link: Vec<Affine3A>,
    pub step_s: f32,
}

/// The motion of `change` in `tree` (as it stands before the change), sampled every `step_s`.
pub fn link_motion(tree: &KinematicTree, change: &Change, step_s: f32) -> Option<LinkMotion> {
    let seconds = motion_seconds(tree, change)?;
    let steps = (seconds / step_s).ceil().max(1.0) as usize;
    let fractions = (0..=steps).map(|k| k as f32 / steps as f32);
    let poses = tree.world_from_links();
    let (link, world_from_link) = match change {
        Change::MoveBase { from, to, .. } => {
            let link = tree.links.iter().position(|l| l.name == ROBOT_LINK)?;
            let path = drive_path(change)?;
            let turn = shortest_turn(from.yaw, to.yaw);
            let parent = tree.links[link]
                .parent
                .map_or(Affine3A::IDENTITY, |p| poses[p]);
            let moving = fractions
                .map(|t| {
                    parent
                        * Affine3A::from_rotation_translation(
                            Quat::from_rotation_z(from.yaw + turn * t),
                            along(&path, t).extend(0.0),
                        )
                })
                .collect();
            (link, moving)
        }
        Change::SetJoint { link, from, to } => {
            let link = tree.links.iter().position(|l| &l.name == link)?;
            let l = &tree.links[link];
            let parent = l.parent.map_or(Affine3A::IDENTITY, |p| poses[p]);
            let moving = fractions
                .map(|t| parent * l.parent_from_link * l.joint.motion(from + (to - from) * t))
                .collect();
            (link, moving)
        }
        Change::Attach { .. } | Change::ArmMotion { .. } => return None,
    };
    Some(LinkMotion {
        link,
        world_from_link,
        step_s,
    })
}

/// `tree` after a change that moves without re-parenting (a drive, a joint); `false` for an
/// attachment, which this leaves to the ECS.
pub fn apply_motion(tree: &mut KinematicTree, change: &Change) -> bool {
    match change {
        Change::MoveBase { to, .. } => {
            if let Some(robot) = tree.links.iter_mut().find(|l| l.name == ROBOT_LINK) {
                robot.parent_from_link = to.world_from_base();
            }
            true
        }
        Change::SetJoint { link, to, .. } => {
            if let Some(l) = tree.links.iter_mut().find(|l| &l.name == link) {
                l.value = *to;
            }
            true
        }
        Change::Attach { .. } | Change::ArmMotion { .. } => false,
    }
}

/// `tree` after `change` as the world makes it (`systems::simulation::apply_change`): a drive or
/// a joint moved, a link hung from another (held by the gripper on a fixed joint, else on the
/// joint its class and model give it); an arm's motion leaves the tree as it was. What a plan
/// looks ahead through.
pub fn apply_to_tree(tree: &mut KinematicTree, change: &Change) {
    if apply_motion(tree, change) {
        return;
    }
    if let Change::Attach {
        link,
        to,
        parent_from_link,
        ..
    } = change
    {
        let index = |name: &str| tree.links.iter().position(|l| l.name == name);
        let (Some(child), Some(parent)) = (index(link), index(to)) else {
            return;
        };
        let joint = if to == GRIPPER_LINK {
            JointSpec::FIXED
        } else {
            let l = &tree.links[child];
            crate::kinematics::support_joint(l.class.as_deref().unwrap_or(""), l.modelled)
        };
        tree.reparent(child, parent, *parent_from_link, joint);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn along_a_path_by_length() {
        let path = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(1.0, 3.0)];
        assert_eq!(along(&path, 0.0), Vec2::ZERO);
        assert!(along(&path, 0.25).abs_diff_eq(Vec2::new(1.0, 0.0), 1e-6));
        assert!(along(&path, 0.5).abs_diff_eq(Vec2::new(1.0, 1.0), 1e-6));
        assert_eq!(along(&path, 1.0), Vec2::new(1.0, 3.0));
        assert_eq!(along(&[Vec2::ONE], 0.5), Vec2::ONE);
    }

    #[test]
    fn turns_go_the_short_way() {
        assert!((shortest_turn(3.0, -3.0) - (std::f32::consts::TAU - 6.0)).abs() < 1e-5);
        assert!((shortest_turn(-1.0, 1.0) - 2.0).abs() < 1e-6);
    }
}
