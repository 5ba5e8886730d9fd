//! The PhysicsValidation stage: the scene's own entities as rapier bodies (bevy_rapier3d),
//! simulated at rest for `REST_SECONDS` at a fixed step, each object judged stable, unstable or
//! penetrating with the reason; and every door and drawer swept across its range for
//! collisions. The same rest test checks the scene after each simulated action; a tree that is
//! no scene's state (a pose being tried) is simulated in a scratch world of its own.

use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::prelude::MassProperties as ParryMassProperties;
use glam::Affine3A;
use serde::Serialize;

use crate::error::IsceneError;
use crate::geometry::TriMesh;
use crate::kinematics::contact_pieces::contact_pieces;
use crate::kinematics::joint_sweep::{JointSweep, sweep_joints};
use crate::kinematics::rest_test::{
    MAX_START_PENETRATION_M, ObjectVerdict, REST_SECONDS, REST_STEP_S, RestBody, Verdict, judge,
    rest_bodies, start_penetrations,
};
use crate::kinematics::tree::KinematicTree;
use crate::systems::kinematic_tree::{
    ReadTreeError, SceneKinematicTree, read_kinematic_tree_entities,
};
use crate::systems::rapier_session::RapierSession;
use crate::systems::stages::record_failure;

/// What physics validation found, for report.json.
#[derive(Resource, Clone, Debug, Serialize)]
pub struct PhysicsReport {
    pub simulated_s: f32,
    pub step_s: f32,
    pub objects: Vec<ObjectVerdict>,
    /// Share of objects judged stable.
    pub stable_fraction: f32,
    pub joints: Vec<JointSweep>,
    /// Wall-clock seconds of the rest simulation.
    pub rest_wall_s: f64,
}

/// How a check's bodies are made: which are fixed where they stand (`frozen`: they start inside
/// another body, already judged penetrating, and their overlap must not throw their neighbours
/// about), a body's collision groups where it has its own, and the bodies whose shape is their
/// collision pieces, hollows decomposed (`hollow`, bodies of these links: what the arm's hand
/// goes into, a bowl it takes by the rim, the microwave it places into), instead of the hulls
/// of their components (resting and being knocked depend on the outside only, and the hulls
/// simulate several times faster).
pub(crate) struct BodyMaking<'a> {
    pub frozen: &'a [bool],
    pub groups: &'a dyn Fn(usize) -> Option<CollisionGroups>,
    pub hollow: &'a [usize],
    /// Links of fixed bodies whose contacts with kinematic bodies rapier computes (the fixed
    /// scene the arm passes near, an object held still while the hand comes to it): rapier
    /// skips those pairs by default.
    pub touchable: &'a [usize],
}

/// The contact pieces of `shape` (a link's hulls or its collision pieces) as convex colliders,
/// each placed in a compound's frame by `compound_from_link`.
pub(crate) fn convex_pieces(
    shape: &[TriMesh],
    compound_from_link: Affine3A,
) -> impl Iterator<Item = (Vec3, Quat, Collider)> + '_ {
    let (_, rotation, translation) = compound_from_link.to_scale_rotation_translation();
    let rotation = rotation.normalize();
    shape
        .iter()
        .flat_map(|piece| contact_pieces(&piece.positions))
        .filter_map(|points| Collider::convex_hull(&points))
        .map(move |c| (translation, rotation, c))
}

/// The collider of a dynamic body: a compound of the convex pieces of all its links (their
/// hulls, or with `hollow` their collision pieces), with the links' own mass properties summed
/// in the body's frame.
pub(crate) fn dynamic_collider(
    tree: &KinematicTree,
    body: &RestBody,
    body_from_links: &[Affine3A],
    hollow: bool,
) -> Option<(Collider, ColliderMassProperties, f32)> {
    let mut pieces: Vec<(Vec3, Quat, Collider)> = Vec::new();
    let mut mass: Option<ParryMassProperties> = None;
    let mut friction = 0.5;
    for (&l, body_from_link) in body.links.iter().zip(body_from_links) {
        let Some(g) = tree.links[l].geometry.as_ref() else {
            continue;
        };
        let (_, rotation, translation) = body_from_link.to_scale_rotation_translation();
        let rotation = rotation.normalize();
        let shape = if hollow { &g.collision } else { &g.hulls };
        pieces.extend(convex_pieces(shape, *body_from_link));
        let link_mass = ParryMassProperties::with_inertia_matrix(
            g.inertial.center_of_mass,
            g.inertial.mass,
            g.inertial.inertia,
        )
        .transform_by(&bevy_rapier3d::rapier::math::Pose::from_parts(
            translation,
            rotation,
        ));
        mass = Some(mass.map_or(link_mass, |m| m + link_mass));
        if l == body.links[0] {
            friction = g.friction;
        }
    }
    let mass = mass?;
    (!pieces.is_empty()).then(|| {
        (
            Collider::compound(pieces),
            ColliderMassProperties::MassProperties(MassProperties::from_rapier(mass)),
            friction,
        )
    })
}

/// The rest test's bodies on the entities of their links (`entities[l]` is link `l`'s): a
/// dynamic body on the entity of its own link, carrying the pieces of every link locked to it; a
/// fixed body with its exact triangle mesh on each link of the static body; made as `making`
/// says. Returns each body's world pose at the start; the entity each dynamic body went on,
/// `None` for the rest.
pub(crate) fn attach_bodies(
    session: &mut RapierSession,
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    bodies: &[RestBody],
    making: &BodyMaking,
) -> (Vec<Affine3A>, Vec<Option<Entity>>) {
    let BodyMaking {
        frozen,
        groups,
        hollow,
        touchable,
    } = *making;
    let poses = tree.world_from_links();
    let mut starts = Vec::with_capacity(bodies.len());
    let mut on = vec![None; bodies.len()];
    for (b, body) in bodies.iter().enumerate() {
        let world_from_body = body.links.first().map_or(Affine3A::IDENTITY, |&l| poses[l]);
        starts.push(world_from_body);
        if body.dynamic {
            let body_from_world = world_from_body.inverse();
            let body_from_links: Vec<Affine3A> = body
                .links
                .iter()
                .map(|&l| body_from_world * poses[l])
                .collect();
            let Some((collider, mass, friction)) = dynamic_collider(
                tree,
                body,
                &body_from_links,
                body.links.iter().any(|l| hollow.contains(l)),
            ) else {
                continue;
            };
            let kind = if frozen[b] {
                RigidBody::Fixed
            } else {
                RigidBody::Dynamic
            };
            let entity = entities[body.links[0]];
            let kinds = if frozen[b] && body.links.iter().any(|l| touchable.contains(l)) {
                ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_STATIC
            } else {
                ActiveCollisionTypes::default()
            };
            let rapier_body = (kind, collider, mass, Friction::coefficient(friction), kinds);
            match groups(b) {
                Some(g) => session.attach(world, entity, world_from_body, (rapier_body, g)),
                None => session.attach(world, entity, world_from_body, rapier_body),
            }
            on[b] = Some(entity);
            continue;
        }
        for &l in &body.links {
            let Some(g) = tree.links[l].geometry.as_ref() else {
                continue;
            };
            let Ok(collider) =
                Collider::trimesh(g.surface.positions.clone(), g.surface.triangles.clone())
            else {
                continue;
            };
            let fixed = (
                RigidBody::Fixed,
                collider,
                Friction::coefficient(g.friction),
            );
            if touchable.contains(&l) {
                let kinds =
                    ActiveCollisionTypes::default() | ActiveCollisionTypes::KINEMATIC_STATIC;
                session.attach(world, entities[l], poses[l], (fixed, kinds));
            } else {
                session.attach(world, entities[l], poses[l], fixed);
            }
        }
    }
    (starts, on)
}

/// A world of its own for a tree that is no scene's state (a pose the viewer is trying, a
/// motion not yet made): one entity per link. Returns it with the entity of each link.
pub(crate) fn scratch_world(tree: &KinematicTree) -> (World, Vec<Entity>) {
    let mut world = World::new();
    let entities = tree
        .links
        .iter()
        .map(|link| world.spawn(Name::new(link.name.clone())).id())
        .collect();
    (world, entities)
}

/// Simulates `tree` at rest and judges every object; sweeps its joints.
pub fn validate_physics(tree: &KinematicTree) -> PhysicsReport {
    PhysicsReport {
        joints: sweep_joints(tree),
        ..rest_physics(tree)
    }
}

/// Simulates `tree` at rest and judges every object, in a world of its own (no joint sweeps).
pub fn rest_physics(tree: &KinematicTree) -> PhysicsReport {
    let (mut world, entities) = scratch_world(tree);
    rest_report(&mut world, tree, &entities)
}

/// The rest test of the scene in `world` as it stands, on the scene's own entities: the check
/// after each simulated action. The world is left as it was.
pub fn scene_rest_physics(world: &mut World) -> Result<PhysicsReport, ReadTreeError> {
    let (tree, entities) = read_kinematic_tree_entities(world)?;
    Ok(rest_report(world, &tree, &entities))
}

/// Simulates at rest the bodies of `tree`, whose links are `entities` of `world`, and judges
/// every object.
fn rest_report(world: &mut World, tree: &KinematicTree, entities: &[Entity]) -> PhysicsReport {
    let bodies = rest_bodies(tree);
    let penetrations = start_penetrations(tree, &bodies);
    let frozen: Vec<bool> = penetrations
        .iter()
        .map(|(depth, _)| *depth > MAX_START_PENETRATION_M)
        .collect();
    let run = simulate(world, tree, entities, &bodies, &frozen, REST_SECONDS, None);
    let objects: Vec<ObjectVerdict> = bodies
        .iter()
        .enumerate()
        .filter(|(_, b)| b.dynamic)
        .map(|(i, b)| judge(tree, b, run.starts[i], run.ends[i], penetrations[i]))
        .collect();
    let stable = objects
        .iter()
        .filter(|o| o.verdict == Verdict::Stable)
        .count();
    PhysicsReport {
        simulated_s: run.simulated_s,
        step_s: REST_STEP_S,
        stable_fraction: if objects.is_empty() {
            1.0
        } else {
            stable as f32 / objects.len() as f32
        },
        objects,
        joints: Vec::new(),
        rest_wall_s: run.wall_s,
    }
}

/// Lets the object whose own link is `link` fall and come to rest under gravity, everything
/// else held where it stands, for `seconds`; returns its world pose at the start and after every
/// step of `REST_STEP_S`, the last where it came to rest (`None` when the link is no object of
/// its own, such as the layout or a door). A dragged object dropped a little above a surface
/// lands on it, and one dropped over an edge tips off it; the viewer plays the path back.
pub fn settle_object(tree: &KinematicTree, link: usize, seconds: f32) -> Option<Vec<Affine3A>> {
    let bodies = rest_bodies(tree);
    let body = bodies
        .iter()
        .position(|b| b.dynamic && b.links.first() == Some(&link))?;
    let frozen: Vec<bool> = (0..bodies.len()).map(|b| b != body).collect();
    let (mut world, entities) = scratch_world(tree);
    Some(
        simulate(
            &mut world,
            tree,
            &entities,
            &bodies,
            &frozen,
            seconds,
            Some(body),
        )
        .path,
    )
}

/// Where the bodies started and ended, and what simulating them cost.
struct Simulated {
    starts: Vec<Affine3A>,
    ends: Vec<Affine3A>,
    simulated_s: f32,
    wall_s: f64,
    /// The pose of the body asked to be followed, at the start and after every step.
    path: Vec<Affine3A>,
}

/// Simulates the bodies in rapier on their links' entities for `seconds` at the rest test's
/// fixed step; those in `frozen` are fixed where they stand. The body `follow` has its pose
/// recorded after every step. The entities are left as they were.
fn simulate(
    world: &mut World,
    tree: &KinematicTree,
    entities: &[Entity],
    bodies: &[RestBody],
    frozen: &[bool],
    seconds: f32,
    follow: Option<usize>,
) -> Simulated {
    let mut session = RapierSession::begin(world);
    let making = BodyMaking {
        frozen,
        groups: &|_| None,
        hollow: &[],
        touchable: &[],
    };
    let (starts, on) = attach_bodies(&mut session, world, tree, entities, bodies, &making);
    let started = std::time::Instant::now();
    let steps = (seconds / REST_STEP_S).round() as usize;
    let followed = follow.and_then(|b| on[b]);
    let mut path = follow.map(|b| vec![starts[b]]).unwrap_or_default();
    for _ in 0..steps {
        session.step(world);
        if let Some(pose) = followed.and_then(|e| session.pose(world, e)) {
            path.push(pose);
        }
    }
    let wall_s = started.elapsed().as_secs_f64();
    let ends = on
        .iter()
        .zip(&starts)
        .map(|(e, start)| e.and_then(|e| session.pose(world, e)).unwrap_or(*start))
        .collect();
    session.end(world);
    Simulated {
        starts,
        ends,
        simulated_s: steps as f32 * REST_STEP_S,
        wall_s,
        path,
    }
}

/// The rest test on the scene's own entities, then the joint sweeps.
fn physics_validation_stage(world: &mut World) -> Result<(), IsceneError> {
    if !world.contains_resource::<SceneKinematicTree>() {
        return Ok(());
    }
    let (tree, entities) = read_kinematic_tree_entities(world)?;
    let report = PhysicsReport {
        joints: sweep_joints(&tree),
        ..rest_report(world, &tree, &entities)
    };
    narrow_blocked_joints(world, &report.joints);
    world.insert_resource(report);
    Ok(())
}

/// Narrows each joint whose sweep met something near its limit to the range it moves freely
/// in, in the ECS and in the tree the exports write: a door that meets the wall at 90 degrees of
/// 100 opens to 90. A joint stopped sooner is a conflict (report.json) and keeps its range: it is
/// never shrunk to whatever is left to make it pass.
fn narrow_blocked_joints(world: &mut World, sweeps: &[JointSweep]) {
    let blocked: Vec<(&str, (f32, f32))> = sweeps
        .iter()
        .filter(|s| !s.conflict)
        .filter_map(|s| s.reachable.map(|r| (s.link.as_str(), r)))
        .collect();
    if blocked.is_empty() {
        return;
    }
    for (name, mut joint) in world
        .query::<(&Name, &mut crate::components::Joint)>()
        .iter_mut(world)
    {
        if let Some((_, range)) = blocked.iter().find(|(link, _)| *link == name.as_str()) {
            joint.spec.limits = Some(*range);
        }
    }
    if let Some(mut tree) = world.get_resource_mut::<SceneKinematicTree>() {
        for link in &mut tree.0.links {
            if let Some((_, range)) = blocked.iter().find(|(l, _)| *l == link.name) {
                link.joint.limits = Some(*range);
            }
        }
    }
}

/// Adds the PhysicsValidation stage.
pub struct PhysicsValidationPlugin;

impl Plugin for PhysicsValidationPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            crate::systems::Reconstruct,
            physics_validation_stage
                .pipe(record_failure)
                .in_set(crate::systems::ReconstructionStage::PhysicsValidation),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;

    fn link(
        name: &str,
        class: &str,
        parent: usize,
        joint: JointSpec,
        mesh: TriMesh,
        at: Vec3,
    ) -> TreeLink {
        TreeLink::body(
            name,
            class,
            parent,
            joint,
            Affine3A::from_translation(at),
            mesh,
        )
    }

    /// A floor, a box standing on it and a box `gap` above it.
    fn scene(gap: f32) -> KinematicTree {
        KinematicTree {
            links: vec![
                TreeLink::root(),
                link(
                    "floor",
                    "floor",
                    0,
                    JointSpec::FIXED,
                    TriMesh::cuboid(Vec3::new(-2.0, -2.0, -0.05), Vec3::new(2.0, 2.0, 0.0)),
                    Vec3::ZERO,
                ),
                link(
                    "box_1",
                    "box",
                    1,
                    JointSpec::FLOATING,
                    TriMesh::cuboid(Vec3::new(-0.2, -0.2, 0.0), Vec3::new(0.2, 0.2, 0.3)),
                    Vec3::new(0.5, 0.0, 0.0),
                ),
                link(
                    "box_2",
                    "box",
                    1,
                    JointSpec::FLOATING,
                    TriMesh::cuboid(Vec3::new(-0.2, -0.2, 0.0), Vec3::new(0.2, 0.2, 0.3)),
                    Vec3::new(-0.5, 0.0, gap),
                ),
            ],
        }
    }

    #[test]
    fn a_box_on_the_floor_stands_and_a_box_in_the_air_falls() {
        let report = validate_physics(&scene(0.2));
        let verdict = |name: &str| {
            report
                .objects
                .iter()
                .find(|o| o.object == name)
                .expect("judged")
                .clone()
        };
        let standing = verdict("box_1");
        assert_eq!(standing.verdict, Verdict::Stable, "{standing:?}");
        assert!(standing.displacement_m < 0.002, "{standing:?}");
        let falling = verdict("box_2");
        assert_eq!(falling.verdict, Verdict::Unstable, "{falling:?}");
        assert!(
            (falling.displacement_m - 0.2).abs() < 0.01,
            "lands on the floor: {falling:?}"
        );
    }

    #[test]
    fn a_settled_object_lands_straight_down_on_what_is_under_it() {
        let tree = scene(0.2);
        let path = settle_object(&tree, 3, 1.5).expect("box_2 is an object");
        // The start, then one pose per step, falling all the way.
        assert_eq!(path.len(), 1 + (1.5 / REST_STEP_S).round() as usize);
        assert!((path[0].translation.z - 0.2).abs() < 1e-5);
        assert!(
            path.windows(2)
                .all(|w| w[1].translation.z <= w[0].translation.z + 1e-3)
        );
        let landed = *path.last().expect("a path");
        let t = landed.translation;
        assert!(t.z.abs() < 0.003, "box_2 rests on the floor: {t}");
        assert!(
            (t.x + 0.5).abs() < 0.003 && t.y.abs() < 0.003,
            "straight down: {t}"
        );
        let tilt = landed
            .matrix3
            .z_axis
            .angle_between(glam::Vec3A::Z)
            .to_degrees();
        assert!(tilt < 1.0, "upright: {tilt} degrees");
        // The floor is no object of its own.
        assert!(settle_object(&tree, 1, 1.5).is_none());
    }

    #[test]
    fn an_object_dropped_over_an_edge_tips_off_it() {
        // box_2 let go with three quarters of its bottom over the side of box_1 (30 cm tall).
        let mut tree = scene(0.0);
        tree.links[3].parent_from_link = Affine3A::from_translation(Vec3::new(0.8, 0.0, 0.301));
        let path = settle_object(&tree, 3, 1.5).expect("box_2 is an object");
        let landed = *path.last().expect("a path");
        assert!(
            landed.translation.z < 0.2 || landed.matrix3.z_axis.z < 0.9,
            "it fell or tipped: {landed:?}"
        );
    }
}
