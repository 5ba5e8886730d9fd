//! An action's motion simulated in rapier: the moving link (the robot's base with its gripper
//! and what it holds, or a door or drawer with what stands on it) is a kinematic body driven
//! along its path, step by step, among the rest test's bodies on the scene's own entities (a
//! `RapierSession`, which leaves them where they were: the check comes before the action is
//! made), and the objects near its path are free to be pushed, tipped or knocked down. A motion
//! that starts from a state the scene is not in yet runs in a scratch world of the tree. The grid search and the joint sweeps plan
//! motions that touch nothing; this is the check that the physics agrees, and it catches what
//! they cannot see (a chair nudged by the base's corner falls against the table).

use std::time::Instant;

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use glam::Affine3A;
use serde::Serialize;

use crate::geometry::mesh::box_corners;
use crate::kinematics::contact_pieces::contact_pieces;
use crate::kinematics::rest_test::{
    MAX_START_PENETRATION_M, REST_STEP_S, rest_bodies, start_penetrations,
};
use crate::kinematics::tree::KinematicTree;
use crate::sim::motion_path::LinkMotion;
use crate::systems::physics_validation::{attach_bodies, scratch_world};
use crate::systems::rapier_session::RapierSession;

/// An object moved farther than this (metres) or turned more than `KNOCK_TURN_DEG` was knocked.
pub const KNOCK_DISTANCE_M: f32 = 0.01;
pub const KNOCK_TURN_DEG: f32 = 5.0;
/// After the motion the world runs on this long (seconds), so what was knocked has fallen.
const AFTERMATH_S: f32 = 0.5;
/// Objects within this distance (metres) of where the moving links pass are simulated, with
/// what stands on them; the others hold still.
const NEAR_M: f32 = 0.05;
/// The swept volume is sampled at this many poses along the path (and its end).
const SWEEP_SAMPLES: usize = 24;

/// The moving links' collision group, and that of the rest of their own object (a door turns
/// about hinges flush with its cabinet: the joint, not contact, holds them together).
const MOVER_GROUP: Group = Group::GROUP_2;
const OWNER_GROUP: Group = Group::GROUP_3;

/// An object the motion moved.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Knocked {
    pub object: String,
    pub moved_m: f32,
    pub turned_deg: f32,
}

/// What one motion did to the objects around it.
#[derive(Clone, Debug, Serialize)]
pub struct MotionCheck {
    /// The moving link.
    pub link: String,
    /// Simulated seconds: the motion and its aftermath.
    pub simulated_s: f32,
    /// The objects near its path, simulated as it passed.
    pub near: Vec<String>,
    /// Those it moved more than 1 cm or turned more than 5 degrees.
    pub knocked: Vec<Knocked>,
    pub wall_ms: f64,
}

/// Drives `motion.link` (with everything under it in `tree`) along `motion` in rapier, the
/// objects near its path free, and reports what it moved, in a scratch world of `tree`'s links:
/// for a tree that is not the scene as it stands (a motion after another of the same action).
/// `motion.step_s` must be the rest test's step.
pub fn simulate_motion(tree: &KinematicTree, motion: &LinkMotion) -> MotionCheck {
    let (mut world, entities) = scratch_world(tree);
    simulate_motion_on(&mut world, tree, &entities, motion)
}

/// `simulate_motion` on the entities of `world` whose links `tree` holds (`entities[l]` is link
/// `l`'s): the scene's own entities when `tree` is the scene as it stands. The moving link's
/// entity carries the kinematic body. The world is left as it was.
pub fn simulate_motion_on(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    motion: &LinkMotion,
) -> MotionCheck {
    let started = Instant::now();
    debug_assert!((motion.step_s - REST_STEP_S).abs() < 1e-6);
    let n = tree.links.len();
    // Links come after their parents: one pass marks the moving subtree.
    let mut moving = vec![false; n];
    for i in 0..n {
        moving[i] = i == motion.link || tree.links[i].parent.is_some_and(|p| moving[p]);
    }
    let mut bodies = rest_bodies(tree);
    let owner = bodies
        .iter()
        .position(|b| b.dynamic && b.links.contains(&motion.link))
        .filter(|&b| !moving[bodies[b].links[0]]);
    for body in &mut bodies {
        body.links.retain(|&l| !moving[l]);
    }
    let poses = tree.world_from_links();
    let swept = swept_bounds(tree, &moving, &poses, motion);
    let mut body_of = vec![0; n];
    for (b, body) in bodies.iter().enumerate() {
        for &l in &body.links {
            body_of[l] = b;
        }
    }
    // Near the path, or standing on something that is (bodies come after their supports).
    let mut near = vec![false; bodies.len()];
    for (b, body) in bodies.iter().enumerate() {
        let Some(&first) = body.links.first() else {
            continue;
        };
        let on_near = tree.links[first]
            .parent
            .is_some_and(|p| !moving[p] && near[body_of[p]]);
        near[b] = body.dynamic
            && (on_near
                || body_bounds(tree, &body.links, &poses)
                    .is_some_and(|(lo, hi)| overlaps((lo, hi), swept, NEAR_M)));
    }
    let penetrations = start_penetrations(tree, &bodies);
    let frozen: Vec<bool> = (0..bodies.len())
        .map(|b| !near[b] || penetrations[b].0 > MAX_START_PENETRATION_M)
        .collect();

    let mut session = RapierSession::begin(world);
    let owner_groups = |b: usize| {
        (Some(b) == owner).then(|| CollisionGroups::new(OWNER_GROUP, Group::ALL ^ MOVER_GROUP))
    };
    let (starts, on) = attach_bodies(
        &mut session,
        world,
        tree,
        entities,
        &bodies,
        &frozen,
        &owner_groups,
    );
    let start = motion.world_from_link[0];
    let mover = mover_collider(tree, &moving, &poses, start).map(|collider| {
        let mover = entities[motion.link];
        session.attach(
            world,
            mover,
            start,
            (
                RigidBody::KinematicPositionBased,
                collider,
                CollisionGroups::new(MOVER_GROUP, Group::ALL ^ OWNER_GROUP),
            ),
        );
        mover
    });
    for pose in &motion.world_from_link[1..] {
        if let Some(mover) = mover {
            session.drive(world, mover, *pose);
        }
        session.step(world);
    }
    let aftermath = (AFTERMATH_S / REST_STEP_S).round() as usize;
    for _ in 0..aftermath {
        session.step(world);
    }
    let mut knocked = Vec::new();
    for (b, entity) in on.iter().enumerate() {
        let Some(end) = entity
            .filter(|_| !frozen[b])
            .and_then(|e| session.pose(world, e))
        else {
            continue;
        };
        let moved_m = end.translation.distance(starts[b].translation);
        let turned_deg = glam::Quat::from_mat3a(&end.matrix3)
            .angle_between(glam::Quat::from_mat3a(&starts[b].matrix3))
            .to_degrees();
        if moved_m > KNOCK_DISTANCE_M || turned_deg > KNOCK_TURN_DEG {
            knocked.push(Knocked {
                object: bodies[b].name.clone(),
                moved_m,
                turned_deg,
            });
        }
    }
    session.end(world);
    knocked.sort_by(|a, b| a.object.cmp(&b.object));
    MotionCheck {
        link: tree.links[motion.link].name.clone(),
        simulated_s: (motion.world_from_link.len() - 1 + aftermath) as f32 * REST_STEP_S,
        near: (0..bodies.len())
            .filter(|&b| near[b])
            .map(|b| bodies[b].name.clone())
            .collect(),
        knocked,
        wall_ms: started.elapsed().as_secs_f64() * 1e3,
    }
}

/// The moving links' convex collision pieces as one compound, in the frame of the moving link
/// at `world_from_mover`.
fn mover_collider(
    tree: &KinematicTree,
    moving: &[bool],
    poses: &[Affine3A],
    world_from_mover: Affine3A,
) -> Option<Collider> {
    let mover_from_world = world_from_mover.inverse();
    let mut pieces = Vec::new();
    for (l, link) in tree.links.iter().enumerate() {
        let (true, Some(g)) = (moving[l], link.geometry.as_ref()) else {
            continue;
        };
        let (_, rotation, translation) =
            (mover_from_world * poses[l]).to_scale_rotation_translation();
        pieces.extend(
            g.hulls
                .iter()
                .flat_map(|piece| contact_pieces(&piece.positions))
                .filter_map(|points| Collider::convex_hull(&points))
                .map(|c| (translation, rotation.normalize(), c)),
        );
    }
    (!pieces.is_empty()).then(|| Collider::compound(pieces))
}

/// The world box of `links`' collision pieces at `poses`.
fn body_bounds(tree: &KinematicTree, links: &[usize], poses: &[Affine3A]) -> Option<(Vec3, Vec3)> {
    links
        .iter()
        .filter_map(|&l| {
            let (lo, hi) = link_bounds(tree, l)?;
            Some(world_box(poses[l], lo, hi))
        })
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The box, in the link's frame, of its collision pieces.
fn link_bounds(tree: &KinematicTree, link: usize) -> Option<(Vec3, Vec3)> {
    let g = tree.links[link].geometry.as_ref()?;
    g.collision
        .iter()
        .flat_map(|piece| piece.positions.iter())
        .fold(None, |acc: Option<(Vec3, Vec3)>, p| {
            Some(acc.map_or((*p, *p), |(lo, hi)| (lo.min(*p), hi.max(*p))))
        })
}

/// The world box of the local box `lo..hi` at `world_from_local`.
fn world_box(world_from_local: Affine3A, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    box_corners(lo, hi)
        .iter()
        .map(|c| world_from_local.transform_point3(*c))
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), c| (a.min(c), b.max(c)))
}

/// The world box the moving links pass through along `motion`.
fn swept_bounds(
    tree: &KinematicTree,
    moving: &[bool],
    poses: &[Affine3A],
    motion: &LinkMotion,
) -> (Vec3, Vec3) {
    let mover_from_world = poses[motion.link].inverse();
    let local: Vec<(Affine3A, Vec3, Vec3)> = (0..tree.links.len())
        .filter(|&l| moving[l])
        .filter_map(|l| {
            let (lo, hi) = link_bounds(tree, l)?;
            Some((mover_from_world * poses[l], lo, hi))
        })
        .collect();
    let last = motion.world_from_link.len() - 1;
    let stride = (last / SWEEP_SAMPLES).max(1);
    (0..=last)
        .step_by(stride)
        .chain(std::iter::once(last))
        .flat_map(|k| {
            let world_from_mover = motion.world_from_link[k];
            local.iter().map(move |(mover_from_link, lo, hi)| {
                world_box(world_from_mover * *mover_from_link, *lo, *hi)
            })
        })
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), (lo, hi)| {
            (a.min(lo), b.max(hi))
        })
}

/// Whether two boxes come within `margin` of each other.
fn overlaps(a: (Vec3, Vec3), b: (Vec3, Vec3), margin: f32) -> bool {
    (a.0 - margin).cmple(b.1).all() && (b.0 - margin).cmple(a.1).all()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;
    use crate::sim::actions::Change;
    use crate::sim::motion_path::link_motion;

    fn cuboid(size: Vec3) -> TriMesh {
        TriMesh::cuboid(
            Vec3::new(-size.x, -size.y, 0.0) / 2.0,
            size.with_z(size.z * 2.0) / 2.0,
        )
    }

    /// A floor; a bottle standing at (0.5, 0); a 30 cm cube (`pusher`) at `pusher_at`; a
    /// cabinet at (-1, 1) whose door (hinged at its front left edge, flush with its front)
    /// opens towards -y.
    fn scene(pusher_at: Vec3) -> KinematicTree {
        let floor = TreeLink::body(
            "floor",
            "floor",
            0,
            JointSpec::FIXED,
            Affine3A::IDENTITY,
            TriMesh::cuboid(Vec3::new(-3.0, -3.0, -0.05), Vec3::new(3.0, 3.0, 0.0)),
        );
        let at = Affine3A::from_translation;
        let mut door = TreeLink::body(
            "cabinet_1_door",
            "cabinet",
            4,
            JointSpec::revolute(Vec3::NEG_Z, 0.0, 2.0),
            at(Vec3::new(-0.25, -0.25, 0.0)),
            TriMesh::cuboid(Vec3::new(0.0, -0.02, 0.0), Vec3::new(0.5, 0.0, 0.8)),
        );
        door.node = Some("cabinet_1".into());
        KinematicTree {
            links: vec![
                TreeLink::root(),
                floor,
                TreeLink::body(
                    "bottle_1",
                    "bottle",
                    1,
                    JointSpec::FLOATING,
                    at(Vec3::new(0.5, 0.0, 0.0)),
                    cuboid(Vec3::new(0.06, 0.06, 0.25)),
                ),
                TreeLink::body(
                    "pusher",
                    "box",
                    1,
                    JointSpec::FLOATING,
                    at(pusher_at),
                    cuboid(Vec3::splat(0.3)),
                ),
                TreeLink::body(
                    "cabinet_1",
                    "cabinet",
                    1,
                    JointSpec::FIXED,
                    at(Vec3::new(-1.0, 1.0, 0.0)),
                    cuboid(Vec3::new(0.5, 0.5, 0.8)),
                ),
                door,
            ],
        }
    }

    /// The pusher slid by `by`, at 1 m/s, sampled every rest-test step.
    fn slide(tree: &KinematicTree, by: Vec3) -> LinkMotion {
        let start = tree.world_from_links()[3];
        let steps = (by.length() / REST_STEP_S).ceil() as usize;
        LinkMotion {
            link: 3,
            world_from_link: (0..=steps)
                .map(|k| Affine3A::from_translation(by * k as f32 / steps as f32) * start)
                .collect(),
            step_s: REST_STEP_S,
        }
    }

    #[test]
    fn a_body_driven_through_a_bottle_knocks_it_and_one_driven_past_it_does_not() {
        let through = scene(Vec3::new(-0.3, 0.0, 0.0));
        let check = simulate_motion(&through, &slide(&through, Vec3::X * 1.2));
        assert_eq!(check.link, "pusher");
        assert!(check.near.contains(&"bottle_1".to_string()), "{check:?}");
        let knocked = check.knocked.iter().find(|k| k.object == "bottle_1");
        assert!(
            knocked.is_some_and(|k| k.moved_m > 0.1),
            "the bottle was in the way: {check:?}"
        );
        // 3 cm clear of it: near, simulated, untouched.
        let past = scene(Vec3::new(-0.3, 0.21, 0.0));
        let check = simulate_motion(&past, &slide(&past, Vec3::X * 1.2));
        assert!(check.near.contains(&"bottle_1".to_string()), "{check:?}");
        assert!(check.knocked.is_empty(), "{check:?}");
        // Far from it: not even simulated.
        let far = scene(Vec3::new(-0.3, -1.0, 0.0));
        let check = simulate_motion(&far, &slide(&far, Vec3::X * 1.2));
        assert!(!check.near.contains(&"bottle_1".to_string()), "{check:?}");
    }

    #[test]
    fn a_check_on_a_worlds_own_entities_finds_what_a_scratch_world_finds_and_changes_nothing() {
        let tree = scene(Vec3::new(-0.3, 0.0, 0.0));
        let motion = slide(&tree, Vec3::X * 1.2);
        let (mut world, entities) = scratch_world(&tree);
        let components = |world: &World| -> Vec<usize> {
            entities
                .iter()
                .map(|&e| world.entity(e).archetype().components().len())
                .collect()
        };
        let before = components(&world);
        let on_world = simulate_motion_on(&mut world, &tree, &entities, &motion);
        assert_eq!(components(&world), before);
        let scratch = simulate_motion(&tree, &motion);
        assert_eq!(on_world.knocked, scratch.knocked);
        assert_eq!(on_world.near, scratch.near);
        // And again on the same world: each check starts afresh.
        let again = simulate_motion_on(&mut world, &tree, &entities, &motion);
        assert_eq!(again.knocked, on_world.knocked);
    }

    #[test]
    fn a_door_swings_clear_of_its_own_cabinet_and_knocks_what_stands_in_its_way() {
        let tree = scene(Vec3::new(1.5, 1.5, 0.0));
        let open = Change::SetJoint {
            link: "cabinet_1_door".into(),
            from: 0.0,
            to: 1.5,
        };
        let motion = link_motion(&tree, &open, REST_STEP_S).expect("a joint motion");
        // Turning at 1.2 rad/s, sampled every step.
        assert_eq!(
            motion.world_from_link.len(),
            1 + (1.25 / REST_STEP_S).ceil() as usize
        );
        let check = simulate_motion(&tree, &motion);
        assert!(check.near.contains(&"cabinet_1".to_string()), "{check:?}");
        assert!(check.knocked.is_empty(), "{check:?}");

        // The bottle moved into the door's swing, in front of the cabinet.
        let mut blocked = tree.clone();
        blocked.links[2].parent_from_link = Affine3A::from_translation(Vec3::new(-1.1, 0.5, 0.0));
        let check = simulate_motion(&blocked, &motion);
        assert!(
            check.knocked.iter().any(|k| k.object == "bottle_1"),
            "the door hits the bottle: {check:?}"
        );
    }
}
