//! The robot arm's links as rapier bodies for a motion check: one compound collider per link
//! with collision pieces, on the world's `RobotArmLink` entities (or entities spawned for the
//! check in a scratch world), and the box the links sweep along a path.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use glam::Affine3A;

use crate::arm::rig::ArmRig;
use crate::components::RobotArmLink;
use crate::kinematics::joint_sweep::world_bounds;
use crate::kinematics::motion_bounds::sampled;

/// One of the arm's links as a body: its pieces as one collider in its frame, and their box.
pub(crate) struct ArmBody {
    pub link: usize,
    pub collider: Collider,
    pub bounds: (Vec3, Vec3),
}

/// The arm's links that have collision pieces, as bodies.
pub(crate) fn arm_colliders(rig: &ArmRig) -> Vec<ArmBody> {
    rig.arm
        .links
        .iter()
        .enumerate()
        .filter_map(|(link, l)| {
            let pieces: Vec<(Vec3, Quat, Collider)> = l
                .pieces
                .iter()
                .filter_map(|piece| Collider::convex_hull(&piece.positions))
                .map(|c| (Vec3::ZERO, Quat::IDENTITY, c))
                .collect();
            let bounds = l
                .pieces
                .iter()
                .flat_map(|piece| piece.positions.iter())
                .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
            (!pieces.is_empty()).then(|| ArmBody {
                link,
                collider: Collider::compound(pieces),
                bounds,
            })
        })
        .collect()
}

/// The world's entities of the arm's links `bodies` (their `RobotArmLink`s), or new ones when
/// the world has not got them all (a scratch world); whether they were spawned.
pub(crate) fn arm_entities(world: &mut World, bodies: &[ArmBody]) -> (Vec<Entity>, bool) {
    let own: Vec<(Entity, usize)> = world
        .query::<(Entity, &RobotArmLink)>()
        .iter(world)
        .map(|(e, l)| (e, l.0))
        .collect();
    let found: Option<Vec<Entity>> = bodies
        .iter()
        .map(|b| own.iter().find(|(_, o)| *o == b.link).map(|(e, _)| *e))
        .collect();
    match found {
        Some(entities) => (entities, false),
        None => (
            bodies
                .iter()
                .map(|b| world.spawn(RobotArmLink(b.link)).id())
                .collect(),
            true,
        ),
    }
}

/// The world box the arm's links `bodies` pass through along `path` (`path[k][l]`).
pub(crate) fn arm_swept_bounds(bodies: &[ArmBody], path: &[Vec<Affine3A>]) -> (Vec3, Vec3) {
    sampled(path.len())
        .flat_map(|k| {
            bodies
                .iter()
                .map(move |b| world_bounds(&path[k][b.link], b.bounds.0, b.bounds.1))
        })
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), (lo, hi)| {
            (a.min(lo), b.max(hi))
        })
}
