//! Motion in the task player. The simulation applies an action's changes at once (the kinematic
//! tree is right the moment the action succeeds); the viewer then shows them happening, one after
//! another: the base drives along its A* path, turning from its old heading to its new, and a
//! door or drawer turns or slides from its old value to its new. Only transforms are animated:
//! the joints keep their new values, and when the motion ends every transform is the tree's.
//! Attachments (a pick, a place) happen at once, and what the gripper holds rides along. An
//! arm's motion moves its links along its configurations, the part its hand follows with it,
//! and the object it takes or sets down from the instant the hand has it or to the instant it
//! lets go. An object dropped by dragging follows the path rapier let it fall and settle along.

use bevy::prelude::*;
use glam::Affine3A;

use crate::components::Joint;
use crate::components::RobotArmLink;
use crate::kinematics::JointSpec;
use crate::sim::actions::Change;
use crate::sim::arm_phases::{ArmInstant, arm_timeline};
use crate::sim::motion_path::{along, drive_path, drive_seconds, joint_seconds, shortest_turn};
use crate::sim::robot::{GRIPPER_LINK, ROBOT_LINK};
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::scene_graph::{SceneRoot, transform_of};
use crate::systems::simulation::RobotArm;

/// The viewer shows no drive longer than this (seconds); longer ones play faster.
const MAX_DRIVE_S: f32 = 2.5;
/// A fall is over once every later pose is within this distance (metres) and turn (radians) of
/// where the object came to rest: what is left is too small to see.
const REST_STILL_M: f32 = 0.0005;
const REST_STILL_RAD: f32 = 0.005;

/// How one change moves its entity, at `t` in [0, 1].
#[derive(Clone, Debug)]
enum Tween {
    /// The base along `path` (world xy, start to end), its heading from `from_yaw` to `to_yaw`.
    Drive {
        path: Vec<Vec2>,
        from_yaw: f32,
        to_yaw: f32,
    },
    /// A joint from `from` to `to`; `end` is the link's transform at `to`.
    Joint {
        spec: JointSpec,
        from: f32,
        to: f32,
        end: Affine3A,
    },
    /// A link through `poses` (its local transforms, evenly spaced in time).
    Path { poses: Vec<Transform> },
}

impl Tween {
    fn at(&self, t: f32) -> Transform {
        match self {
            Tween::Drive {
                path,
                from_yaw,
                to_yaw,
            } => {
                let turn = shortest_turn(*from_yaw, *to_yaw);
                Transform::from_translation(along(path, t).extend(0.0))
                    .with_rotation(Quat::from_rotation_z(from_yaw + turn * t))
            }
            Tween::Joint {
                spec,
                from,
                to,
                end,
            } => transform_of(
                *end * spec.motion(*to).inverse() * spec.motion(from + (to - from) * t),
            ),
            Tween::Path { poses } => {
                let at = t.clamp(0.0, 1.0) * poses.len().saturating_sub(1) as f32;
                let (i, f) = (at.floor() as usize, at.fract());
                match (poses.get(i), poses.get(i + 1)) {
                    (Some(a), Some(b)) => {
                        Transform::from_translation(a.translation.lerp(b.translation, f))
                            .with_rotation(a.rotation.slerp(b.rotation, f))
                    }
                    (Some(a), None) => *a,
                    _ => Transform::IDENTITY,
                }
            }
        }
    }
}

/// The part of a fall worth showing: `path` up to the last pose that is visibly away from the
/// last one.
fn visible_fall(path: &[Affine3A]) -> &[Affine3A] {
    let Some(rest) = path.last() else {
        return path;
    };
    let away = |p: &Affine3A| {
        p.translation.distance(rest.translation) > REST_STILL_M
            || p.matrix3.z_axis.angle_between(rest.matrix3.z_axis) > REST_STILL_RAD
            || p.matrix3.x_axis.angle_between(rest.matrix3.x_axis) > REST_STILL_RAD
    };
    let last_away = path.iter().rposition(away).map_or(0, |i| i + 1);
    &path[..=last_away.min(path.len() - 1)]
}

/// One animated change: its entity, when it starts and how long it takes.
#[derive(Clone, Debug)]
struct Leg {
    entity: Entity,
    tween: Tween,
    start_s: f32,
    duration_s: f32,
}

/// The motion being shown; empty when none.
#[derive(Resource, Clone, Debug, Default)]
pub struct Motion {
    legs: Vec<Leg>,
    elapsed_s: f32,
    /// Entities shown under another parent while the motion runs (an object an arm hands over
    /// moves in a frame of its own until the hand has it or lets go of it), with the parent
    /// and transform they go back to when it ends.
    parents: Vec<(Entity, Entity, Transform)>,
}

impl Motion {
    pub fn is_running(&self) -> bool {
        !self.legs.is_empty()
    }

    fn total_s(&self) -> f32 {
        self.legs
            .iter()
            .map(|l| l.start_s + l.duration_s)
            .fold(0.0, f32::max)
    }
}

/// The motion of `changes`, already applied to the world: each leg from the change's start to the
/// entity's transform now.
fn motion_of(world: &mut World, changes: &[Change]) -> Motion {
    let mut named = world.query::<(Entity, &Name, &Transform, Option<&Joint>)>();
    let mut find = |world: &World, name: &str| {
        named
            .iter(world)
            .find(|(_, n, _, _)| n.as_str() == name)
            .map(|(e, _, t, j)| (e, *t, j.map(|j| j.spec)))
    };
    let mut legs = Vec::new();
    let mut start_s = 0.0;
    // (entity, parent while shown, parent and transform at the end)
    let mut parents: Vec<(Entity, Entity, Entity, Transform)> = Vec::new();
    // A part the arm's hand moved is shown moving with the hand, not again after it.
    let followed: Vec<&str> = changes
        .iter()
        .filter_map(|c| match c {
            Change::ArmMotion { part: Some(p), .. } => Some(p.link.as_str()),
            _ => None,
        })
        .collect();
    for (k, change) in changes.iter().enumerate() {
        if let Change::ArmMotion { .. } = change {
            let (arm, duration_s) = arm_legs(world, changes, k, start_s, &mut parents);
            legs.extend(arm);
            start_s += duration_s;
            continue;
        }
        if let Change::SetJoint { link, .. } = change
            && followed.contains(&link.as_str())
        {
            continue;
        }
        let leg = match change {
            Change::MoveBase {
                from,
                to,
                path_length_m,
                ..
            } => find(world, ROBOT_LINK).map(|(entity, _, _)| {
                let tween = Tween::Drive {
                    path: drive_path(change).unwrap_or_default(),
                    from_yaw: from.yaw,
                    to_yaw: to.yaw,
                };
                let seconds = drive_seconds(from, to, *path_length_m).min(MAX_DRIVE_S);
                (entity, tween, seconds)
            }),
            Change::SetJoint { link, from, to } => {
                find(world, link).and_then(|(entity, end, spec)| {
                    let end = Affine3A::from_scale_rotation_translation(
                        end.scale,
                        end.rotation,
                        end.translation,
                    );
                    let spec = spec?;
                    let seconds = joint_seconds(spec.kind, *from, *to);
                    let tween = Tween::Joint {
                        spec,
                        from: *from,
                        to: *to,
                        end,
                    };
                    Some((entity, tween, seconds))
                })
            }
            Change::Attach { .. } | Change::ArmMotion { .. } => None,
        };
        if let Some((entity, tween, duration_s)) = leg {
            legs.push(Leg {
                entity,
                tween,
                start_s,
                duration_s,
            });
            start_s += duration_s;
        }
    }
    for &(entity, shown_under, ..) in &parents {
        world.entity_mut(entity).insert(ChildOf(shown_under));
    }
    Motion {
        legs,
        elapsed_s: 0.0,
        parents: parents
            .into_iter()
            .map(|(e, _, end, transform)| (e, end, transform))
            .collect(),
    }
}

/// Seconds between the poses of an arm motion's legs.
const ARM_FRAME_S: f32 = 1.0 / 30.0;

/// The legs of the arm motion `changes[k]`, already applied, all from `start_s`: the arm's
/// links along its configurations, the gripper (what it holds rides with it) along the tool,
/// the part the hand follows, and the object handed over by the attachment after it (a pick's
/// stays where it stood until the hand has it, a place's rides in the hand until it is set
/// down); and how long it takes.
fn arm_legs(
    world: &mut World,
    changes: &[Change],
    k: usize,
    start_s: f32,
    parents: &mut Vec<(Entity, Entity, Entity, Transform)>,
) -> (Vec<Leg>, f32) {
    let Some(rig) = world.get_resource::<RobotArm>().map(|a| a.0.clone()) else {
        return (Vec::new(), 0.0);
    };
    let change = &changes[k];
    let part = match change {
        Change::ArmMotion { part: Some(p), .. } => Some(p.link.as_str()),
        _ => None,
    };
    let part_from = changes
        .iter()
        .find_map(|c| match c {
            Change::SetJoint { link, from, .. } if Some(link.as_str()) == part => Some(*from),
            _ => None,
        })
        .unwrap_or(0.0);
    // A place's hand comes holding what it sets down.
    let holding =
        matches!(changes.get(k + 1), Some(Change::Attach { to, .. }) if to != GRIPPER_LINK);
    let instants = arm_timeline(&rig, change, part_from, holding, ARM_FRAME_S);
    if instants.len() < 2 {
        return (Vec::new(), 0.0);
    }
    let duration_s = (instants.len() - 1) as f32 * ARM_FRAME_S;
    let leg = |entity: Entity, poses: Vec<Transform>| Leg {
        entity,
        tween: Tween::Path { poses },
        start_s,
        duration_s,
    };
    let link_poses: Vec<Vec<Affine3A>> = instants
        .iter()
        .map(|i| rig.arm.link_poses(&rig.base_from_root, &i.q, i.opening))
        .collect();
    let tool: Vec<Affine3A> = instants
        .iter()
        .map(|i| rig.arm.tool_pose(&rig.base_from_root, &i.q))
        .collect();
    let mut legs: Vec<Leg> = world
        .query::<(Entity, &RobotArmLink)>()
        .iter(world)
        .map(|(e, l)| (e, l.0))
        .collect::<Vec<_>>()
        .into_iter()
        .map(|(e, l)| leg(e, link_poses.iter().map(|p| transform_of(p[l])).collect()))
        .collect();
    if let Some(gripper) = entity_named(world, GRIPPER_LINK) {
        legs.push(leg(
            gripper.0,
            tool.iter().map(|p| transform_of(*p)).collect(),
        ));
    }
    if let Some((entity, now)) = part.and_then(|p| entity_named(world, p))
        && let Some(joint) = world.get::<Joint>(entity).copied()
    {
        // The link's transform at a value: its transform now, turned back from the value now.
        let at = |v: f32| {
            transform_of(now * joint.spec.motion(joint.value).inverse() * joint.spec.motion(v))
        };
        legs.push(leg(
            entity,
            instants
                .iter()
                .map(|i| at(i.part.unwrap_or(joint.value)))
                .collect(),
        ));
    }
    if let Some(Change::Attach { link, to, .. }) = changes.get(k + 1)
        && let Some((object, now)) = entity_named(world, link)
        && let Some(shown) = handed_over(world, &instants, &tool, to, now)
    {
        legs.push(leg(object, shown.poses));
        parents.push((object, shown.parent, shown.end_parent, transform_of(now)));
    }
    (legs, duration_s)
}

/// An object handed over during an arm motion, as shown: the parent it moves under while the
/// motion runs, its transforms there, and the parent it ends under.
struct HandedOver {
    parent: Entity,
    poses: Vec<Transform>,
    end_parent: Entity,
}

/// How the object attached to `to` at `now` (its transform there) by an arm motion through
/// `instants` (the tool at `tool`, in the base's frame) is shown. Taken by the hand (`to` is
/// the gripper), it stands in the world where it stood until the hand has it; set down, it
/// rides in the hand (through the base's drive before) until the hand lets go of it.
fn handed_over(
    world: &mut World,
    instants: &[ArmInstant],
    tool: &[Affine3A],
    to: &str,
    now: Affine3A,
) -> Option<HandedOver> {
    let tree = read_kinematic_tree(world).ok()?;
    let poses = tree.world_from_links();
    let world_of = |name: &str| {
        let l = tree.links.iter().position(|l| l.name == name)?;
        Some(poses[l])
    };
    let base = world_of(ROBOT_LINK)?;
    let reached = instants.iter().position(|i| i.reached).unwrap_or(0);
    let hand_at_grip = base * tool[reached.saturating_sub(1)];
    let end_parent = entity_named(world, to)?.0;
    let gripper = entity_named(world, GRIPPER_LINK)?.0;
    let shown = |pose: Affine3A| transform_of(pose);
    if to == GRIPPER_LINK {
        let root = world
            .query_filtered::<Entity, With<SceneRoot>>()
            .iter(world)
            .next()?;
        let stood = hand_at_grip * now;
        let poses = instants
            .iter()
            .zip(tool)
            .map(|(i, t)| shown(if i.reached { base * *t * now } else { stood }))
            .collect();
        Some(HandedOver {
            parent: root,
            poses,
            end_parent,
        })
    } else {
        let set_down = world_of(to)? * now;
        let in_hand = hand_at_grip.inverse() * set_down;
        let poses = instants
            .iter()
            .zip(tool)
            .map(|(i, t)| {
                shown(if i.reached {
                    (base * *t).inverse() * set_down
                } else {
                    in_hand
                })
            })
            .collect();
        Some(HandedOver {
            parent: gripper,
            poses,
            end_parent,
        })
    }
}

/// The entity named `name` and its transform.
fn entity_named(world: &mut World, name: &str) -> Option<(Entity, Affine3A)> {
    world
        .query::<(Entity, &Name, &Transform)>()
        .iter(world)
        .find(|(_, n, _)| n.as_str() == name)
        .map(|(e, _, t)| (e, t.compute_affine()))
}

/// Ends the motion under way at once: every transform is the tree's again. Called before the
/// scene changes from a click or a drag, because a joint's change is applied to its transform
/// as it stands, which must not be a frame of a motion.
pub fn finish_motion(world: &mut World) {
    let running = std::mem::take(&mut *world.resource_mut::<Motion>());
    for leg in &running.legs {
        if let Some(mut transform) = world.get_mut::<Transform>(leg.entity) {
            *transform = leg.tween.at(1.0);
        }
    }
    for &(entity, parent, transform) in &running.parents {
        world
            .entity_mut(entity)
            .insert((ChildOf(parent), transform));
    }
}

/// Shows `changes`, already applied to the world (after `finish_motion`), happening.
pub fn show_motion(world: &mut World, changes: &[Change]) {
    let motion = motion_of(world, changes);
    world.insert_resource(motion);
}

/// Shows the link named `link`, already at rest where `path` (its world poses, `step_s` apart)
/// ends, falling along it. The transforms are the link's own, relative to its parent, which
/// holds still while it falls.
pub fn show_fall(world: &mut World, link: &str, path: &[Affine3A], step_s: f32) {
    let Some((entity, end)) = world
        .query::<(Entity, &Name, &Transform)>()
        .iter(world)
        .find(|(_, n, _)| n.as_str() == link)
        .map(|(e, _, t)| (e, *t))
    else {
        return;
    };
    let fall = visible_fall(path);
    let Some(rest) = fall.last() else {
        return;
    };
    let end = Affine3A::from_scale_rotation_translation(end.scale, end.rotation, end.translation);
    // parent_from_link at each pose: the end's, moved by the pose's offset from the rest pose.
    let poses = fall
        .iter()
        .map(|p| transform_of(end * rest.inverse() * *p))
        .collect::<Vec<_>>();
    let duration_s = (fall.len().saturating_sub(1) as f32 * step_s).max(step_s);
    world.insert_resource(Motion {
        legs: vec![Leg {
            entity,
            tween: Tween::Path { poses },
            start_s: 0.0,
            duration_s,
        }],
        elapsed_s: 0.0,
        parents: Vec::new(),
    });
}

/// Poses every animated entity for the time elapsed: a leg not started stands at its start, a
/// finished one at its end; once all have finished the motion is over.
pub(crate) fn animate(
    mut commands: Commands,
    time: Res<Time>,
    mut motion: ResMut<Motion>,
    mut transforms: Query<&mut Transform>,
) {
    if !motion.is_running() {
        return;
    }
    motion.elapsed_s += time.delta_secs();
    let over = motion.elapsed_s >= motion.total_s();
    // Latest leg last: an entity with two legs shows the one under way.
    for leg in &motion.legs {
        let t = if over {
            1.0
        } else {
            ((motion.elapsed_s - leg.start_s) / leg.duration_s).clamp(0.0, 1.0)
        };
        let earlier_leg = motion
            .legs
            .iter()
            .any(|l| l.entity == leg.entity && l.start_s < leg.start_s);
        if !over && t == 0.0 && earlier_leg {
            continue;
        }
        if let Ok(mut transform) = transforms.get_mut(leg.entity) {
            *transform = leg.tween.at(t);
        }
    }
    if over {
        motion.legs.clear();
        for (entity, parent, transform) in motion.parents.drain(..) {
            commands.entity(entity).insert((ChildOf(parent), transform));
        }
    }
}

pub struct MotionPlugin;

impl Plugin for MotionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Motion>().add_systems(
            PostUpdate,
            animate.before(bevy::transform::TransformSystems::Propagate),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drive_turns_the_short_way_and_a_joint_ends_where_the_tree_has_it() {
        let drive = Tween::Drive {
            path: vec![Vec2::ZERO, Vec2::X],
            from_yaw: 3.0,
            to_yaw: -3.0,
        };
        let half = drive.at(0.5).rotation.to_euler(EulerRot::ZYX).0;
        assert!((half.abs() - std::f32::consts::PI).abs() < 0.01, "{half}");

        let spec = JointSpec::revolute(Vec3::Z, 0.0, 1.5);
        let end = Affine3A::from_translation(Vec3::X) * spec.motion(1.2);
        let joint = Tween::Joint {
            spec,
            from: 0.0,
            to: 1.2,
            end,
        };
        let at_end = joint.at(1.0);
        assert!(at_end.translation.abs_diff_eq(Vec3::X, 1e-6));
        assert!(at_end.rotation.angle_between(Quat::from_rotation_z(1.2)) < 1e-5);
        let at_start = joint.at(0.0);
        assert!(at_start.rotation.angle_between(Quat::IDENTITY) < 1e-5);
    }

    #[test]
    fn a_fall_is_shown_until_it_stops_visibly_moving_and_passes_through_its_poses() {
        let fall: Vec<Affine3A> = [0.3, 0.2, 0.1, 0.0, 0.0001, 0.0, 0.0]
            .iter()
            .map(|&z| Affine3A::from_translation(Vec3::new(0.0, 0.0, z)))
            .collect();
        // The 0.1 mm bounce is no motion to show: the fall ends where it first reaches the floor.
        assert_eq!(visible_fall(&fall).len(), 4);
        let path = Tween::Path {
            poses: visible_fall(&fall)
                .iter()
                .map(|p| transform_of(*p))
                .collect(),
        };
        assert!((path.at(0.0).translation.z - 0.3).abs() < 1e-6);
        assert!((path.at(0.5).translation.z - 0.15).abs() < 1e-6);
        assert_eq!(path.at(1.0).translation.z, 0.0);
        // Nothing moved: one pose, shown as it is.
        assert_eq!(visible_fall(&fall[5..]).len(), 1);
    }
}
