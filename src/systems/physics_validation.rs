//! The PhysicsValidation stage: the kinematic tree as rapier bodies in an ECS world of its own
//! (bevy_rapier3d), simulated at rest for `REST_SECONDS` at a fixed step, each object judged
//! stable, unstable or penetrating with the reason; and every door and drawer swept across its
//! range for collisions.

use bevy::ecs::schedule::SingleThreadedExecutor;
use bevy::prelude::*;
use bevy_rapier3d::prelude::*;
use bevy_rapier3d::rapier::prelude::{
    IntegrationParameters, MassProperties as ParryMassProperties,
};
use glam::Affine3A;
use serde::Serialize;

use crate::kinematics::contact_pieces::contact_pieces;
use crate::kinematics::joint_sweep::{JointSweep, sweep_joints};
use crate::kinematics::rest_test::{
    MAX_START_PENETRATION_M, ObjectVerdict, REST_SECONDS, REST_STEP_S, REST_SUBSTEPS, RestBody,
    Verdict, judge, rest_bodies, start_penetrations,
};
use crate::kinematics::tree::KinematicTree;
use crate::systems::kinematic_tree::SceneKinematicTree;

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

/// The pose of a simulated body.
pub(crate) fn pose_of(transform: &Transform) -> Affine3A {
    Affine3A::from_rotation_translation(transform.rotation, transform.translation)
}

/// A rapier pose is rigid: drop the rounding-level scale a composed affine carries.
pub(crate) fn rigid(a: &Affine3A) -> Transform {
    let (_, rotation, translation) = a.to_scale_rotation_translation();
    Transform::from_translation(translation).with_rotation(rotation.normalize())
}

/// Marks a simulated body with its index among the rest test's bodies.
#[derive(Component)]
pub(crate) struct RestBodyIndex(pub usize);

/// The collider of a dynamic body: a compound of the convex pieces of all its links, with the
/// links' own mass properties summed in the body's frame.
pub(crate) fn dynamic_collider(
    tree: &KinematicTree,
    body: &RestBody,
    body_from_links: &[Affine3A],
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
        pieces.extend(
            g.collision
                .iter()
                .flat_map(|piece| contact_pieces(&piece.positions))
                .filter_map(|points| Collider::convex_hull(&points))
                .map(|c| (translation, rotation, c)),
        );
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

/// Spawns the bodies; those in `frozen` (they start inside another body, already judged
/// penetrating) stay where they are, so their overlap does not throw their neighbours about.
pub(crate) fn spawn_bodies(
    world: &mut World,
    tree: &KinematicTree,
    bodies: &[RestBody],
    frozen: &[bool],
) -> Vec<Affine3A> {
    let poses = tree.world_from_links();
    let mut starts = Vec::with_capacity(bodies.len());
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
            let Some((collider, mass, friction)) = dynamic_collider(tree, body, &body_from_links)
            else {
                continue;
            };
            let kind = if frozen[b] {
                RigidBody::Fixed
            } else {
                RigidBody::Dynamic
            };
            world.spawn((
                kind,
                collider,
                mass,
                Friction::coefficient(friction),
                rigid(&world_from_body),
                RestBodyIndex(b),
            ));
            continue;
        }
        // The static body: each link's exact triangle mesh where it stands.
        for &l in &body.links {
            let Some(g) = tree.links[l].geometry.as_ref() else {
                continue;
            };
            let Ok(collider) =
                Collider::trimesh(g.surface.positions.clone(), g.surface.triangles.clone())
            else {
                continue;
            };
            world.spawn((
                RigidBody::Fixed,
                collider,
                Friction::coefficient(g.friction),
                rigid(&poses[l]),
            ));
        }
    }
    starts
}

/// The rapier world of the rest test: z up, and contacts recomputed every step. Rapier's
/// default recycles a pair's contact points until the bodies have drifted 5 cm apart, which
/// is a whole bottle's width: small objects on furniture then rested on stale points, drifted
/// about a centimetre and tipped up to 19 degrees (MuJoCo rests the same files to 0.1 mm);
/// recomputed, the rendered scenes' small objects stay within 3 mm and 0.3 degrees.
fn rest_test_context() -> RapierContextInitialization {
    RapierContextInitialization::InitializeDefaultRapierContext {
        integration_parameters: IntegrationParameters {
            contact_recycling: false,
            ..default()
        },
        rapier_configuration: RapierConfiguration {
            gravity: Vec3::new(0.0, 0.0, -9.81),
            ..RapierConfiguration::new(1.0)
        },
    }
}

/// Simulates `tree` at rest and judges every object; sweeps its joints.
pub fn validate_physics(tree: &KinematicTree) -> PhysicsReport {
    PhysicsReport {
        joints: sweep_joints(tree),
        ..rest_physics(tree)
    }
}

/// Simulates `tree` at rest and judges every object (no joint sweeps: the check after each
/// simulated action).
pub fn rest_physics(tree: &KinematicTree) -> PhysicsReport {
    let bodies = rest_bodies(tree);
    let penetrations = start_penetrations(tree, &bodies);
    let frozen: Vec<bool> = penetrations
        .iter()
        .map(|(depth, _)| *depth > MAX_START_PENETRATION_M)
        .collect();
    let run = simulate(tree, &bodies, &frozen, REST_SECONDS, None);
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
    Some(simulate(tree, &bodies, &frozen, seconds, Some(body)).path)
}

/// An empty rapier world as the rest test runs it: z up, gravity, a fixed step of
/// `REST_STEP_S` per update, contacts recomputed every step, on one thread.
pub(crate) fn rest_world() -> App {
    let mut app = App::new();
    app.add_plugins((
        // Transform propagation asks for the compute pool even on one thread.
        bevy::app::TaskPoolPlugin::default(),
        bevy::time::TimePlugin,
        bevy::transform::TransformPlugin,
        RapierPhysicsPlugin::<NoUserData>::default()
            .with_custom_initialization(rest_test_context()),
    ));
    app.insert_resource(TimestepMode::Fixed {
        dt: REST_STEP_S,
        substeps: REST_SUBSTEPS,
    });
    app.finish();
    app.cleanup();
    // A scene's worth of bodies steps in well under a millisecond; handing each system to a
    // thread pool and back cost more than that (three quarters of the kitchen's rest test went
    // to parking and waking threads: 120 ms, 32 ms on one thread).
    for (_, schedule) in app.world_mut().resource_mut::<Schedules>().iter_mut() {
        schedule.set_executor(SingleThreadedExecutor::new());
    }
    app.update();
    app
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

/// Simulates the bodies in rapier for `seconds` at the rest test's fixed step; those in `frozen`
/// are fixed where they stand. The body `follow` has its pose recorded after every step.
fn simulate(
    tree: &KinematicTree,
    bodies: &[RestBody],
    frozen: &[bool],
    seconds: f32,
    follow: Option<usize>,
) -> Simulated {
    let mut app = rest_world();
    let starts = spawn_bodies(app.world_mut(), tree, bodies, frozen);
    let started = std::time::Instant::now();
    let steps = (seconds / REST_STEP_S).round() as usize;
    let mut poses = app.world_mut().query::<(&RestBodyIndex, &Transform)>();
    let mut ends = starts.clone();
    let mut path = follow.map(|b| vec![starts[b]]).unwrap_or_default();
    // One update registers the new bodies (and steps once); the rest are the simulated time.
    for _ in 0..steps {
        app.update();
        if let Some(followed) = follow {
            for (index, transform) in poses.iter(app.world()) {
                if index.0 == followed {
                    path.push(pose_of(transform));
                }
            }
        }
    }
    let wall_s = started.elapsed().as_secs_f64();
    for (index, transform) in poses.iter(app.world()) {
        ends[index.0] = pose_of(transform);
    }
    Simulated {
        starts,
        ends,
        simulated_s: steps as f32 * REST_STEP_S,
        wall_s,
        path,
    }
}

fn physics_validation_stage(world: &mut World) {
    let Some(tree) = world.get_resource::<SceneKinematicTree>() else {
        return;
    };
    let report = validate_physics(&tree.0);
    narrow_blocked_joints(world, &report.joints);
    world.insert_resource(report);
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
            physics_validation_stage.in_set(crate::systems::ReconstructionStage::PhysicsValidation),
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
