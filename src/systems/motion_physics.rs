//! An action's motion simulated in rapier: the moving links are kinematic bodies driven along
//! their paths, step by step, among the rest test's bodies on the scene's own entities (a
//! `RapierSession`, which leaves them where they were: the check comes before the action is
//! made), and the objects near the paths are free to be pushed, tipped or knocked down. A motion
//! that starts from a state the scene is not in yet runs in a scratch world of the tree. The
//! grid search and the joint sweeps plan motions that touch nothing; this is the check that the
//! physics agrees, and it catches what they cannot see (a chair nudged by the base's corner falls
//! against the table). Which bodies take part and the verdicts: `sim::motion_check`.

use std::time::Instant;

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use glam::Affine3A;

use crate::arm::rig::ArmRig;
use crate::kinematics::motion_bounds::EMPTY_BOX;
use crate::kinematics::rest_test::REST_STEP_S;
use crate::kinematics::tree::KinematicTree;
use crate::sim::motion_check::{
    AFTERMATH_S, ArmDepth, MotionBodies, MotionCheck, Movers, knocked, robot_link,
};
use crate::sim::motion_path::LinkMotion;
use crate::systems::arm_bodies::{ArmBody, arm_colliders, arm_entities, arm_swept_bounds};
use crate::systems::physics_validation::{BodyMaking, attach_bodies, convex_pieces, scratch_world};
use crate::systems::rapier_session::RapierSession;

/// The moving links' collision group, and that of the rest of their own object (a door turns
/// about hinges flush with its cabinet: the joint, not contact, holds them together).
const MOVER_GROUP: Group = Group::GROUP_2;
const OWNER_GROUP: Group = Group::GROUP_3;

/// The arm's links' collision group: they touch everything but each other.
const ARM_GROUP: Group = Group::GROUP_4;

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
    debug_assert!((motion.step_s - REST_STEP_S).abs() < 1e-6);
    let links = [(motion.link, motion.world_from_link.clone())];
    let movers = Movers {
        links: &links,
        ..Movers::named(tree.links[motion.link].name.clone())
    };
    simulate_movers_on(world, tree, entities, &movers)
}

/// `movers` driven in rapier among the bodies of `tree` (on `entities` of `world`), the objects
/// near their paths free; what they moved, and how deep the arm went into the scene. The arm's
/// links are the world's `RobotArmLink` entities (spawned for the check when the world has
/// none: a scratch world). The world is left as it was.
pub fn simulate_movers_on(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    movers: &Movers,
) -> MotionCheck {
    let started = Instant::now();
    let arm_bodies = movers
        .arm
        .map(|(rig, _)| arm_colliders(rig))
        .unwrap_or_default();
    let arm_swept = movers
        .arm
        .map_or(EMPTY_BOX, |(_, path)| arm_swept_bounds(&arm_bodies, path));
    let taking_part = MotionBodies::new(tree, movers, arm_swept);
    let mut session = RapierSession::begin(world);
    let on_world = OnWorld { tree, entities };
    let (starts, on) = attach_scene(&mut session, world, &on_world, movers, &taking_part);
    let driven = attach_driven(&mut session, world, &on_world, movers, &taking_part);
    let (arm_entities, spawned) = arm_entities(world, &arm_bodies);
    let arm = movers.arm.map(|(rig, path)| {
        attach_arm(&mut session, world, &arm_bodies, &arm_entities, path);
        ArmInWorld {
            rig,
            path,
            bodies: &arm_bodies,
            entities: &arm_entities,
        }
    });
    let depth = drive(
        &mut session,
        world,
        &on_world,
        &driven,
        arm.as_ref(),
        movers.instants(),
    );
    let aftermath = (AFTERMATH_S / REST_STEP_S).round() as usize;
    for _ in 0..aftermath {
        session.step(world);
    }
    let mut knocked: Vec<_> = on
        .iter()
        .enumerate()
        .filter(|(b, _)| !taking_part.frozen[*b])
        .filter_map(|(b, entity)| {
            let end = session.pose(world, (*entity)?)?;
            knocked(&taking_part.bodies[b].name, starts[b], end)
        })
        .collect();
    session.end(world);
    if spawned {
        for entity in arm_entities {
            world.despawn(entity);
        }
    }
    knocked.sort_by(|a, b| a.object.cmp(&b.object));
    let MotionBodies { near, falling, .. } = &taking_part;
    MotionCheck {
        link: movers.name.clone(),
        simulated_s: (movers.instants().saturating_sub(1) + aftermath) as f32 * REST_STEP_S,
        near: taking_part.names(|b| near[b]),
        knocked,
        arm_depth: movers.arm.is_some().then_some(depth),
        falls_at_rest: taking_part.names(|b| near[b] && falling[b]),
        wall_ms: started.elapsed().as_secs_f64() * 1e3,
    }
}

/// The tree a check simulates and the entity of each of its links (`entities[l]`).
struct OnWorld<'a> {
    tree: &'a KinematicTree,
    entities: &'a [Entity],
}

/// The arm of a check: its rig, its links' poses at each instant, their bodies and entities.
struct ArmInWorld<'a> {
    rig: &'a ArmRig,
    path: &'a [Vec<Affine3A>],
    bodies: &'a [ArmBody],
    entities: &'a [Entity],
}

/// The rest test's bodies that take part, as `taking_part` says (owners kept off the driven
/// links); each body's start pose and the entity of each dynamic one.
fn attach_scene(
    session: &mut RapierSession,
    world: &mut World,
    on_world: &OnWorld,
    movers: &Movers,
    taking_part: &MotionBodies,
) -> (Vec<Affine3A>, Vec<Option<Entity>>) {
    let owner_groups = |b: usize| {
        taking_part
            .owners
            .contains(&b)
            .then(|| CollisionGroups::new(OWNER_GROUP, Group::ALL ^ MOVER_GROUP))
    };
    let making = BodyMaking {
        frozen: &taking_part.frozen,
        groups: &owner_groups,
        hollow: movers.hollow,
        touchable: &taking_part.touchable,
    };
    let OnWorld { tree, entities } = *on_world;
    attach_bodies(session, world, tree, entities, &taking_part.bodies, &making)
}

/// Each driven link as a kinematic body carrying its subtree, at its path's start; the driven
/// entities with their paths.
fn attach_driven<'m>(
    session: &mut RapierSession,
    world: &mut World,
    on_world: &OnWorld,
    movers: &'m Movers,
    taking_part: &MotionBodies,
) -> Vec<(Entity, &'m [Affine3A])> {
    let OnWorld { tree, entities } = *on_world;
    let mut driven = Vec::new();
    for ((l, path), under) in movers.links.iter().zip(&taking_part.carried) {
        if let Some(collider) = mover_collider(tree, under, &taking_part.poses, path[0]) {
            session.attach(
                world,
                entities[*l],
                path[0],
                (
                    RigidBody::KinematicPositionBased,
                    collider,
                    CollisionGroups::new(MOVER_GROUP, Group::ALL ^ OWNER_GROUP),
                ),
            );
            driven.push((entities[*l], &path[..]));
        }
    }
    driven
}

/// The arm's links as kinematic bodies at the path's start.
fn attach_arm(
    session: &mut RapierSession,
    world: &mut World,
    bodies: &[ArmBody],
    entities: &[Entity],
    path: &[Vec<Affine3A>],
) {
    for (body, &entity) in bodies.iter().zip(entities) {
        session.attach(
            world,
            entity,
            path[0][body.link],
            (
                RigidBody::KinematicPositionBased,
                body.collider.clone(),
                CollisionGroups::new(ARM_GROUP, Group::ALL ^ ARM_GROUP),
            ),
        );
    }
}

/// Steps the session through the motion's `instants`, the driven links and the arm at their
/// poses of each; how deep the arm went into the scene.
fn drive(
    session: &mut RapierSession,
    world: &mut World,
    on_world: &OnWorld,
    driven: &[(Entity, &[Affine3A])],
    arm: Option<&ArmInWorld>,
    instants: usize,
) -> ArmDepth {
    let OnWorld { tree, entities } = *on_world;
    // What the arm may touch without it counting: what the robot holds (it moves with the hand,
    // or stays in the stowed one).
    let not_scene: Vec<Entity> = (0..tree.links.len())
        .filter(|&l| tree.links[l].parent.is_some_and(|p| robot_link(tree, p)))
        .map(|l| entities[l])
        .collect();
    let mut depth = ArmDepth::default();
    for k in 1..instants {
        for (entity, path) in driven {
            session.drive(world, *entity, path[k]);
        }
        let Some(arm) = arm else {
            session.step(world);
            continue;
        };
        for (body, &entity) in arm.bodies.iter().zip(arm.entities) {
            session.drive(world, entity, arm.path[k][body.link]);
        }
        session.step(world);
        for (link, other, least) in session.contacts(world, arm.entities) {
            if -least <= depth.depth_m || not_scene.contains(&other) {
                continue;
            }
            let arm_link = arm
                .entities
                .iter()
                .position(|&e| e == link)
                .map(|b| arm.rig.arm.links[arm.bodies[b].link].name.clone());
            let into = entities
                .iter()
                .position(|&e| e == other)
                .map(|l| tree.links[l].name.clone());
            depth = ArmDepth {
                depth_m: -least,
                arm_link,
                into,
            };
        }
    }
    depth
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
        pieces.extend(convex_pieces(&g.hulls, mover_from_world * poses[l]));
    }
    (!pieces.is_empty()).then(|| Collider::compound(pieces))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::RobotArmLink;
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
    fn a_bottle_that_falls_on_its_own_is_held_still_and_not_blamed_on_the_motion() {
        // The bottle hangs 30 cm above the floor beside the pusher's path: it falls, pushed or
        // not.
        let mut hanging = scene(Vec3::new(-0.3, 0.21, 0.0));
        hanging.links[2].parent_from_link =
            Affine3A::from_translation(Vec3::Z * 0.3) * hanging.links[2].parent_from_link;
        let motion = slide(&hanging, Vec3::X * 1.2);
        let check = simulate_motion(&hanging, &motion);
        assert!(
            check.knocked.iter().any(|k| k.object == "bottle_1"),
            "{check:?}"
        );
        assert!(check.falls_at_rest.is_empty());
        // The last rest test found it falling: held still, and said so.
        let links = [(motion.link, motion.world_from_link.clone())];
        let movers = Movers {
            links: &links,
            falling: &[2],
            ..Movers::named("pusher")
        };
        let (mut world, entities) = scratch_world(&hanging);
        let check = simulate_movers_on(&mut world, &hanging, &entities, &movers);
        assert!(check.knocked.is_empty(), "{check:?}");
        assert_eq!(check.falls_at_rest, ["bottle_1"]);
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

    /// A two-link arm whose forearm is a 1 m bar 10 cm thick, and a path of that forearm
    /// (the other links have no pieces) from `from` to `to` in one second.
    fn bar_arm() -> ArmRig {
        let mut arm = crate::arm::tests::two_link_arm();
        arm.links[2].pieces = vec![TriMesh::cuboid(
            Vec3::new(0.0, -0.05, -0.05),
            Vec3::new(1.0, 0.05, 0.05),
        )];
        ArmRig::new(arm, 0.5)
    }

    fn bar_path(rig: &ArmRig, from: Vec3, to: Vec3) -> Vec<Vec<Affine3A>> {
        let steps = (1.0 / REST_STEP_S).round() as usize;
        (0..=steps)
            .map(|k| {
                let mut poses = vec![Affine3A::IDENTITY; rig.arm.links.len()];
                poses[2] = Affine3A::from_translation(from.lerp(to, k as f32 / steps as f32));
                poses
            })
            .collect()
    }

    fn arm_check(tree: &KinematicTree, rig: &ArmRig, path: &[Vec<Affine3A>]) -> MotionCheck {
        let (mut world, entities) = scratch_world(tree);
        let movers = Movers {
            arm: Some((rig, path)),
            ..Movers::named("arm")
        };
        let check = simulate_movers_on(&mut world, tree, &entities, &movers);
        // The arm's bodies were spawned for the check and are gone again.
        assert_eq!(world.query::<&RobotArmLink>().iter(&world).count(), 0);
        check
    }

    #[test]
    fn an_arm_link_lowered_into_the_floor_goes_in_as_deep_as_it_went_and_one_above_it_does_not() {
        let tree = scene(Vec3::new(1.5, 1.5, 0.0));
        let rig = bar_arm();
        // The bar's underside from 25 cm down to 1 cm into the floor, away from everything.
        let into = bar_path(&rig, Vec3::new(0.5, -2.0, 0.3), Vec3::new(0.5, -2.0, 0.04));
        let check = arm_check(&tree, &rig, &into);
        let depth = check
            .arm_depth
            .clone()
            .expect("an arm's check measures depth");
        assert!((depth.depth_m - 0.01).abs() < 0.002, "{check:?}");
        assert_eq!(depth.arm_link.as_deref(), Some("fore"));
        assert_eq!(depth.into.as_deref(), Some("floor"));
        assert!(check.knocked.is_empty(), "{check:?}");
        // Stopped 5 cm above it: no contact.
        let above = bar_path(&rig, Vec3::new(0.5, -2.0, 0.3), Vec3::new(0.5, -2.0, 0.1));
        let check = arm_check(&tree, &rig, &above);
        assert_eq!(check.arm_depth.map(|d| d.depth_m), Some(0.0));
    }

    #[test]
    fn an_arm_check_drives_the_worlds_own_arm_entities_and_leaves_them_as_they_were() {
        let tree = scene(Vec3::new(1.5, 1.5, 0.0));
        let rig = bar_arm();
        let (mut world, entities) = scratch_world(&tree);
        let fore = world
            .spawn((
                RobotArmLink(2),
                Transform::IDENTITY,
                GlobalTransform::IDENTITY,
            ))
            .id();
        let before = world.entity(fore).archetype().components().len();
        let into = bar_path(&rig, Vec3::new(0.5, -2.0, 0.3), Vec3::new(0.5, -2.0, 0.04));
        let movers = Movers {
            arm: Some((&rig, &into)),
            ..Movers::named("arm")
        };
        let check = simulate_movers_on(&mut world, &tree, &entities, &movers);
        assert!(check.arm_depth.is_some_and(|d| d.depth_m > 0.008));
        // The same entity, not a spawned one: it is still there, as it was.
        assert_eq!(world.query::<&RobotArmLink>().iter(&world).count(), 1);
        assert_eq!(world.entity(fore).archetype().components().len(), before);
        assert_eq!(
            world.get::<GlobalTransform>(fore),
            Some(&GlobalTransform::IDENTITY)
        );
    }

    #[test]
    fn an_arm_link_swept_through_a_bottle_knocks_it() {
        let tree = scene(Vec3::new(1.5, 1.5, 0.0));
        let rig = bar_arm();
        // Along y at 10 cm, its length over x = 0..1: through the bottle at (0.5, 0).
        let through = bar_path(&rig, Vec3::new(0.0, -0.5, 0.1), Vec3::new(0.0, 0.5, 0.1));
        let check = arm_check(&tree, &rig, &through);
        assert!(check.near.contains(&"bottle_1".to_string()), "{check:?}");
        assert!(
            check.knocked.iter().any(|k| k.object == "bottle_1"),
            "{check:?}"
        );
        // 30 cm above it: untouched.
        let over = bar_path(&rig, Vec3::new(0.0, -0.5, 0.6), Vec3::new(0.0, 0.5, 0.6));
        let check = arm_check(&tree, &rig, &over);
        assert!(check.knocked.is_empty(), "{check:?}");
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
