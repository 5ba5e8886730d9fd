//! Rapier on a world's own entities. A `RapierSession` gives entities of the world (the scene's
//! objects, or the links of a tree spawned for a scratch check) rapier bodies, steps them in
//! the world's physics schedule at the rest test's fixed step, reads their poses back from
//! rapier, and takes every component it added away again when it ends: a check leaves the world
//! as it found it.
//!
//! A body starts at the world pose the check gives it (the kinematic tree's pose of its link),
//! set as the entity's `GlobalTransform` for the session; bevy_rapier's copy of transform
//! propagation is off, because a scene whose transforms changed since they were last propagated
//! (an action just moved the robot) would otherwise put bodies where the scene no longer is.
//! Nothing is written back to `Transform`s either: the objects of a scene are nested (a cup is a
//! child of its table), and bevy_rapier's writeback turns a child's new world pose into a local
//! one against its parent's pose of the step before, which drifts whenever both move. The poses
//! a check judges are rapier's own; kinematic bodies are driven with `drive`.

use std::collections::HashSet;

use bevy::ecs::component::ComponentId;
use bevy::ecs::schedule::{ScheduleLabel, SingleThreadedExecutor};
use bevy::prelude::*;
use bevy_rapier3d::plugin::{
    NoUserData, PhysicsSet, RapierBevyComponentApply, RapierConfiguration, RapierContextEntityLink,
    RapierPhysicsPlugin, RapierTransformPropagateSet, TimestepMode,
};
use bevy_rapier3d::prelude::{
    CollisionEvent, ContactForceEvent, MassModifiedEvent, RapierColliderHandle,
    RapierContextColliders, RapierContextSimulation, RapierRigidBodyHandle, RapierRigidBodySet,
};
use bevy_rapier3d::rapier::prelude::ColliderHandle;
use bevy_rapier3d::rapier::prelude::IntegrationParameters;
use glam::Affine3A;

use crate::kinematics::rest_test::{REST_STEP_S, REST_SUBSTEPS};

/// A rapier pose is rigid: drop the rounding-level scale a composed affine carries.
fn rigid_transform(a: &Affine3A) -> Transform {
    let (_, rotation, translation) = a.to_scale_rotation_translation();
    Transform::from_translation(translation).with_rotation(rotation.normalize())
}

/// Brings newly attached bodies into rapier without stepping.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
struct RegisterBodies;

/// One fixed step of `REST_STEP_S`: what changed is brought into rapier, then it steps.
#[derive(ScheduleLabel, Clone, Debug, PartialEq, Eq, Hash)]
struct PhysicsStep;

/// Adds the two physics schedules and what bevy_rapier's systems read, once per world.
fn install_physics(world: &mut World) {
    if world
        .get_resource::<Schedules>()
        .is_some_and(|s| s.contains(PhysicsStep))
    {
        return;
    }
    world.init_resource::<Messages<CollisionEvent>>();
    world.init_resource::<Messages<ContactForceEvent>>();
    world.init_resource::<Messages<MassModifiedEvent>>();
    // A fixed step reads no clock, but the stepping system asks for one.
    world.init_resource::<Time>();
    world.insert_resource(TimestepMode::Fixed {
        dt: REST_STEP_S,
        substeps: REST_SUBSTEPS,
    });
    for (schedule, steps) in [
        (Schedule::new(RegisterBodies), false),
        (Schedule::new(PhysicsStep), true),
    ] {
        let mut schedule = schedule;
        // A scene's worth of bodies steps in well under a millisecond: handing each system to
        // a thread pool and back cost more than that (the kitchen's rest test took 120 ms on
        // the pool, 32 ms on one thread).
        schedule.set_executor(SingleThreadedExecutor::new());
        schedule.configure_sets((PhysicsSet::SyncBackend, PhysicsSet::StepSimulation).chain());
        schedule.configure_sets(
            RapierTransformPropagateSet
                .in_set(PhysicsSet::SyncBackend)
                .run_if(|| false),
        );
        schedule.configure_sets(RapierBevyComponentApply.in_set(PhysicsSet::SyncBackend));
        schedule.add_systems(RapierPhysicsPlugin::<NoUserData>::get_systems(
            PhysicsSet::SyncBackend,
        ));
        if steps {
            schedule.add_systems(RapierPhysicsPlugin::<NoUserData>::get_systems(
                PhysicsSet::StepSimulation,
            ));
        }
        world.add_schedule(schedule);
    }
}

/// The rapier context of a check: z up, and contacts recomputed every step. Rapier's default
/// recycles a pair's contact points until the bodies have drifted 5 cm apart, which is a whole
/// bottle's width: small objects on furniture then rested on stale points, drifted about a
/// centimetre and tipped up to 19 degrees (MuJoCo rests the same files to 0.1 mm); recomputed,
/// the rendered scenes' small objects stay within 3 mm and 0.3 degrees. No continuous collision
/// detection: the checks move nothing fast (objects at rest, a door's swing, a push at a walk),
/// and rapier 0.35 sweeps every body that moves a tenth of its thinnest convex piece in a step
/// (a cup's wall is millimetres thin), recomputing each piece's mass properties per sweep: a
/// quarter of the rest test's time on the Sweet Home 3D kitchen, for displacements equal to
/// the micrometre without it.
fn check_context() -> (RapierContextSimulation, RapierConfiguration) {
    let mut simulation = RapierContextSimulation::default();
    simulation.integration_parameters = IntegrationParameters {
        contact_recycling: false,
        max_ccd_substeps: 0,
        ..default()
    };
    (
        simulation,
        RapierConfiguration {
            gravity: Vec3::new(0.0, 0.0, -9.81),
            ..RapierConfiguration::new(1.0)
        },
    )
}

/// Rapier bodies on entities of a world for the length of one check.
pub struct RapierSession {
    context: Entity,
    /// Each entity given a body, with the components and the world pose it had before.
    had: Vec<(Entity, HashSet<ComponentId>, Option<GlobalTransform>)>,
}

impl RapierSession {
    /// A fresh rapier context in `world`, every check starting from the same state.
    pub fn begin(world: &mut World) -> Self {
        install_physics(world);
        let context = world
            .spawn((Name::new("rapier context of a check"), check_context()))
            .id();
        Self {
            context,
            had: Vec::new(),
        }
    }

    /// Gives `entity` a body (`RigidBody`, `Collider` and what goes with them) at `world_pose`
    /// and brings it into rapier at once, so bodies enter rapier in the order they are attached:
    /// the solver's results depend on that order, and the same scene must give the same verdicts.
    pub fn attach(
        &mut self,
        world: &mut World,
        entity: Entity,
        world_pose: Affine3A,
        body: impl Bundle,
    ) {
        let had: HashSet<ComponentId> = world
            .entity(entity)
            .archetype()
            .components()
            .iter()
            .copied()
            .collect();
        let pose = world.get::<GlobalTransform>(entity).copied();
        self.had.push((entity, had, pose));
        world.entity_mut(entity).insert((
            body,
            RapierContextEntityLink(self.context),
            GlobalTransform::from(rigid_transform(&world_pose)),
        ));
        world.run_schedule(RegisterBodies);
    }

    /// Moves the kinematic body of `entity` to `world_pose` by the next step.
    pub fn drive(&self, world: &mut World, entity: Entity, world_pose: Affine3A) {
        world
            .entity_mut(entity)
            .insert(GlobalTransform::from(rigid_transform(&world_pose)));
    }

    /// Simulates one fixed step.
    pub fn step(&self, world: &mut World) {
        world.run_schedule(PhysicsStep);
    }

    /// The world pose of `entity`'s body as rapier has it now.
    pub fn pose(&self, world: &World, entity: Entity) -> Option<Affine3A> {
        let handle = world.get::<RapierRigidBodyHandle>(entity)?;
        let body = world
            .get::<RapierRigidBodySet>(self.context)?
            .bodies
            .get(handle.0)?;
        let t = bevy_rapier3d::utils::iso_to_transform(body.position());
        Some(Affine3A::from_rotation_translation(
            t.rotation,
            t.translation,
        ))
    }

    /// For each pair in contact (or about to be) of a collider on one of `entities` with
    /// another collider, the other collider's entity and the least signed distance between
    /// them: negative when they overlap. Rapier computes contacts only for the pairs of body
    /// kinds their `ActiveCollisionTypes` allow.
    pub fn contacts(&self, world: &World, entities: &[Entity]) -> Vec<(Entity, Entity, f32)> {
        let (Some(simulation), Some(colliders)) = (
            world.get::<RapierContextSimulation>(self.context),
            world.get::<RapierContextColliders>(self.context),
        ) else {
            return Vec::new();
        };
        let handles: Vec<(Entity, ColliderHandle)> = entities
            .iter()
            .filter_map(|&e| Some((e, world.get::<RapierColliderHandle>(e)?.0)))
            .collect();
        let mut found = Vec::new();
        for &(entity, handle) in &handles {
            for pair in simulation.narrow_phase.contact_pairs_with(handle) {
                let other = if pair.collider1 == handle {
                    pair.collider2
                } else {
                    pair.collider1
                };
                let least = pair
                    .manifolds
                    .iter()
                    .flat_map(|m| m.points.iter().map(|p| p.dist))
                    .fold(f32::INFINITY, f32::min);
                if let (true, Some(other)) = (least.is_finite(), colliders.collider_entity(other)) {
                    found.push((entity, other, least));
                }
            }
        }
        found
    }

    /// Takes every component the session added away from its entities (bevy_rapier's handles
    /// and links included) and puts their world poses back, lets rapier forget them, and drops
    /// the context.
    pub fn end(self, world: &mut World) {
        for (entity, had, pose) in &self.had {
            let Ok(mut e) = world.get_entity_mut(*entity) else {
                continue;
            };
            if let Some(pose) = pose {
                e.insert(*pose);
            }
            let added: Vec<ComponentId> = e
                .archetype()
                .components()
                .iter()
                .copied()
                .filter(|c| !had.contains(c))
                .collect();
            e.remove_by_ids(&added);
        }
        world.run_schedule(RegisterBodies);
        world.despawn(self.context);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy_rapier3d::prelude::{Collider, RigidBody};

    /// Drops `ball` from 50 cm onto `floor` for one simulated second; returns where it landed.
    fn drop_ball(world: &mut World, floor: Entity, ball: Entity) -> Affine3A {
        let at = |z: f32| Affine3A::from_translation(Vec3::Z * z);
        let mut session = RapierSession::begin(world);
        session.attach(
            world,
            floor,
            at(-0.05),
            (RigidBody::Fixed, Collider::cuboid(2.0, 2.0, 0.05)),
        );
        session.attach(
            world,
            ball,
            at(0.5),
            (RigidBody::Dynamic, Collider::ball(0.1)),
        );
        for _ in 0..120 {
            session.step(world);
        }
        let landed = session.pose(world, ball).expect("a body");
        session.end(world);
        landed
    }

    #[test]
    fn a_session_simulates_the_entities_and_leaves_them_as_they_were() {
        let mut world = World::new();
        let floor = world.spawn(Name::new("floor")).id();
        let start = Transform::from_xyz(0.0, 0.0, 0.5);
        let ball = world.spawn((Name::new("ball"), start)).id();
        let components = |world: &World| -> Vec<usize> {
            [floor, ball]
                .iter()
                .map(|&e| world.entity(e).archetype().components().len())
                .collect()
        };
        let before = components(&world);

        let landed = drop_ball(&mut world, floor, ball);
        assert!(
            (landed.translation.z - 0.1).abs() < 0.01,
            "it fell onto the floor: {landed:?}"
        );

        // The transforms were never written; the components are the ones it had.
        assert_eq!(*world.get::<Transform>(ball).expect("kept"), start);
        assert_eq!(
            *world.get::<GlobalTransform>(ball).expect("kept"),
            GlobalTransform::IDENTITY
        );
        assert_eq!(components(&world), before);
        assert!(
            world
                .query::<&RapierContextSimulation>()
                .iter(&world)
                .next()
                .is_none()
        );

        // A second session on the same world starts afresh and gives the same fall.
        assert_eq!(drop_ball(&mut world, floor, ball), landed);
    }
}
