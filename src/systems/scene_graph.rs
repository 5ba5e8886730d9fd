//! Spawns a contact graph as ECS entities whose transform hierarchy is the kinematic tree: every
//! layout entity hangs from the scene root, every object from the entity that supports it.

use std::collections::{HashMap, HashSet};

use bevy::prelude::*;
use glam::{Affine3A, Mat4};

use crate::classes::EntityKind;
use crate::components::{
    CadModel, Joint, OrientedBox, Panoptic, ProximalEndA, ProximalEndB, SceneEntity, SurfacePlanes,
};
use crate::error::IsceneError;
use crate::geometry::{GravityBox, Plane};
use crate::graph::{ContactGraph, GraphEdge, GraphError};
use crate::kinematics::JointSpec;

/// Why a contact graph could not be hung into the ECS.
#[derive(Debug, thiserror::Error)]
pub enum SceneGraphError {
    #[error(transparent)]
    Malformed(#[from] GraphError),
    #[error("node {0:?} has no entity")]
    NoEntity(String),
}

impl From<SceneGraphError> for IsceneError {
    fn from(e: SceneGraphError) -> Self {
        IsceneError::Internal(e.to_string())
    }
}

/// Marks the root of the kinematic tree (the world frame).
#[derive(Component, Clone, Copy, Debug, Default)]
pub struct SceneRoot;

/// The pose of an entity's own frame: its CAD model's frame without the model's scale when it
/// has one (links of a kinematic tree are rigid frames; a per-axis scale in a parent's frame
/// would shear its children), else its box's.
fn world_from_entity(graph_box: &GravityBox, cad: Option<&CadModel>) -> Affine3A {
    match cad {
        Some(c) => {
            let (_, rotation, translation) =
                Mat4::from(c.world_from_model).to_scale_rotation_translation();
            Affine3A::from_rotation_translation(rotation.normalize(), translation)
        }
        None => graph_box.world_from_box(),
    }
}

/// The `Transform` of an affine pose (rotation normalised).
pub fn transform_of(a: Affine3A) -> Transform {
    let (scale, rotation, translation) = a.to_scale_rotation_translation();
    Transform {
        translation,
        rotation: rotation.normalize(),
        scale,
    }
}

/// Spawns `graph` under a new `SceneRoot`; returns the entity of each node id.
pub fn spawn_contact_graph(
    world: &mut World,
    graph: &ContactGraph,
) -> Result<HashMap<String, Entity>, SceneGraphError> {
    graph.check()?;
    let mut entities = HashMap::new();
    for node in &graph.nodes {
        let e = world.spawn((
            SceneEntity(node.id.clone()),
            Panoptic {
                instance: entities.len() as u32 + 1,
                class: crate::base::ClassId::new(&node.class),
                kind: node.kind,
            },
        ));
        entities.insert(node.id.clone(), e.id());
    }
    attach_contact_graph(world, graph, &entities)?;
    Ok(entities)
}

/// Gives the entities of `graph`'s nodes (`entities`: node id to entity) their boxes, planes and
/// CAD models, and hangs them under the `SceneRoot` (made when there is none) as the support
/// tree says: `ChildOf` the
/// supporting entity, a `Joint`, and a `Transform` relative to the parent; each proximal pair
/// becomes a pair entity related to both ends (attaching again keeps the pairs that stay).
pub fn attach_contact_graph(
    world: &mut World,
    graph: &ContactGraph,
    entities: &HashMap<String, Entity>,
) -> Result<Entity, SceneGraphError> {
    graph.check()?;
    if let Some(missing) = graph.nodes.iter().find(|n| !entities.contains_key(&n.id)) {
        return Err(SceneGraphError::NoEntity(missing.id.clone()));
    }
    // Attaching again (the CAD stage moves frames to the models) re-hangs under the same root.
    let existing = world
        .query_filtered::<Entity, With<SceneRoot>>()
        .iter(world)
        .next();
    let root = match existing {
        Some(root) => root,
        None => world
            .spawn((SceneRoot, Name::new("world"), Transform::IDENTITY))
            .id(),
    };
    for node in &graph.nodes {
        let mut e = world.entity_mut(entities[&node.id]);
        e.insert((
            Name::new(node.id.clone()),
            OrientedBox(GravityBox::from(&node.bbox)),
            SurfacePlanes(node.planes.iter().map(|p| Plane::from_array(*p)).collect()),
        ));
        match &node.cad {
            Some(c) => e.insert(CadModel::from(c)),
            None => e.remove::<CadModel>(),
        };
    }
    for node in &graph.nodes {
        let parent = graph.parent_of(&node.id).map_or(root, |p| entities[p]);
        world.entity_mut(entities[&node.id]).insert(ChildOf(parent));
    }
    hang_frames(world);
    attach_proximal_pairs(world, graph, entities);
    Ok(root)
}

/// Gives every node entity (a `SceneEntity` with a box) its frame and its joint to its support,
/// from its own components: its `Transform` relative to its parent (both entities' frames as
/// `world_from_entity` makes them; the `SceneRoot`'s is the world frame) and the joint
/// `kinematics::support_joint` gives its class (a layout entity under the root is fixed). The frames follow
/// the components, so a stage that changes a box or a model runs this again.
pub fn hang_frames(world: &mut World) {
    let mut nodes = world.query_filtered::<(
        Entity,
        &Panoptic,
        &OrientedBox,
        Option<&CadModel>,
        &ChildOf,
    ), With<SceneEntity>>();
    let poses: HashMap<Entity, Affine3A> = nodes
        .iter(world)
        .map(|(e, _, gbox, cad, _)| (e, world_from_entity(&gbox.0, cad)))
        .collect();
    let frames: Vec<(Entity, Transform, JointSpec)> = nodes
        .iter(world)
        .map(|(e, panoptic, _, cad, child_of)| {
            let parent_pose = poses.get(&child_of.parent()).copied();
            let joint = if parent_pose.is_none() && panoptic.kind == EntityKind::Layout {
                JointSpec::FIXED
            } else {
                crate::kinematics::support_joint(panoptic.class.as_str(), cad.is_some())
            };
            let local = parent_pose.unwrap_or(Affine3A::IDENTITY).inverse() * poses[&e];
            (e, transform_of(local), joint)
        })
        .collect();
    for (e, transform, spec) in frames {
        world
            .entity_mut(e)
            .insert((transform, Joint { spec, value: 0.0 }));
    }
}

/// Makes the proximal pair entities those of `graph`'s edges: pairs that stay are kept (so no
/// entity is despawned when nothing changed), stale ones despawned, new ones spawned in edge order.
fn attach_proximal_pairs(
    world: &mut World,
    graph: &ContactGraph,
    entities: &HashMap<String, Entity>,
) {
    let unordered = |a: Entity, b: Entity| {
        if a.index_u32() <= b.index_u32() {
            (a, b)
        } else {
            (b, a)
        }
    };
    let wanted: Vec<(Entity, Entity)> = graph
        .edges
        .iter()
        .filter_map(|edge| match edge {
            GraphEdge::Proximal { a, b } => Some((entities[a], entities[b])),
            GraphEdge::Support { .. } => None,
        })
        .collect();
    let wanted_set: HashSet<(Entity, Entity)> =
        wanted.iter().map(|&(a, b)| unordered(a, b)).collect();
    let existing: Vec<(Entity, (Entity, Entity))> = world
        .query::<(Entity, &ProximalEndA, &ProximalEndB)>()
        .iter(world)
        .map(|(pair, a, b)| (pair, unordered(a.0, b.0)))
        .collect();
    let mut kept = HashSet::new();
    for (pair, ends) in existing {
        if wanted_set.contains(&ends) && kept.insert(ends) {
            continue;
        }
        world.despawn(pair);
    }
    for (a, b) in wanted {
        if kept.insert(unordered(a, b)) {
            world.spawn((Name::new("proximal pair"), ProximalEndA(a), ProximalEndB(b)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::components::{ProximalPairQuery, proximal_partners};

    fn kitchen_graph() -> ContactGraph {
        crate::scene::kitchen_contact_graph()
    }

    fn kitchen_app() -> (App, HashMap<String, Entity>) {
        let graph = kitchen_graph();
        let mut app = App::new();
        app.add_plugins((MinimalPlugins, TransformPlugin));
        let entities = spawn_contact_graph(app.world_mut(), &graph).expect("spawn");
        app.update();
        (app, entities)
    }

    #[test]
    fn the_transform_hierarchy_is_the_support_tree() {
        let (mut app, entities) = kitchen_app();
        let world = app.world_mut();
        let cup = entities["cup_1"];
        let table = entities["table_1"];
        assert_eq!(
            world.get::<ChildOf>(cup).map(ChildOf::parent),
            Some(table),
            "the table supports the cup"
        );
        assert_eq!(
            world.get::<Joint>(cup).map(|j| j.spec.kind),
            Some(crate::kinematics::JointKind::Floating)
        );
        assert_eq!(
            world.get::<Joint>(table).map(|j| j.spec.kind),
            Some(crate::kinematics::JointKind::Fixed)
        );
        // The chair pulled up to the table touches it; the cup on the table is supported, so
        // not proximal.
        let chair = entities["chair_1"];
        let mut pairs = world.query::<ProximalPairQuery>();
        let mut near = |e: Entity| proximal_partners(pairs.iter(world), e);
        assert!(near(table).contains(&chair) && near(chair).contains(&table));
        assert!(!near(table).contains(&cup));
        // Attached again, the same pairs stay, once each.
        let graph = kitchen_graph();
        let before: Vec<Entity> = world
            .query_filtered::<Entity, With<ProximalEndA>>()
            .iter(world)
            .collect();
        attach_contact_graph(world, &graph, &entities).expect("attach again");
        let after: Vec<Entity> = world
            .query_filtered::<Entity, With<ProximalEndA>>()
            .iter(world)
            .collect();
        let proximal_edges = graph
            .edges
            .iter()
            .filter(|e| matches!(e, GraphEdge::Proximal { .. }))
            .count();
        assert!(proximal_edges > 0);
        assert_eq!((before.len(), &after), (proximal_edges, &before));
        let global = world.get::<GlobalTransform>(cup).expect("global transform");
        let cad = world.get::<CadModel>(cup).expect("cad");
        let expected = Vec3::from(cad.world_from_model.translation);
        assert!(
            global.translation().distance(expected) < 1e-4,
            "cup at {} instead of {expected}",
            global.translation()
        );
    }

    #[test]
    fn a_movable_object_no_model_replaced_is_fixed_where_it_was_seen() {
        let mut graph = kitchen_graph();
        graph
            .nodes
            .iter_mut()
            .find(|n| n.id == "cup_1")
            .expect("cup")
            .cad = None;
        let mut app = App::new();
        app.add_plugins((MinimalPlugins, TransformPlugin));
        let entities = spawn_contact_graph(app.world_mut(), &graph).expect("spawn");
        let world = app.world();
        let kind = |id: &str| world.get::<Joint>(entities[id]).map(|j| j.spec.kind);
        assert_eq!(kind("cup_1"), Some(crate::kinematics::JointKind::Fixed));
        assert_eq!(
            world.get::<ChildOf>(entities["cup_1"]).map(ChildOf::parent),
            Some(entities["table_1"]),
            "still on the table"
        );
        assert_eq!(
            kind("chair_1"),
            Some(crate::kinematics::JointKind::Floating)
        );
    }

    #[test]
    fn a_stretched_table_model_neither_moves_nor_shears_the_cup_on_it() {
        let mut graph = kitchen_graph();
        let table = graph
            .nodes
            .iter_mut()
            .find(|n| n.id == "table_1")
            .and_then(|n| n.cad.as_mut())
            .expect("table placement");
        let stretched = Mat4::from_cols_array(&table.world_from_model)
            * Mat4::from_scale(Vec3::new(1.2, 0.8, 1.05));
        table.world_from_model = stretched.to_cols_array();
        // Turned against the table, so a stretch in the table's frame would shear it.
        let cup = graph
            .nodes
            .iter_mut()
            .find(|n| n.id == "cup_1")
            .and_then(|n| n.cad.as_mut())
            .expect("cup placement");
        let turned = Mat4::from_cols_array(&cup.world_from_model) * Mat4::from_rotation_z(0.5);
        cup.world_from_model = turned.to_cols_array();
        let mut app = App::new();
        app.add_plugins((MinimalPlugins, TransformPlugin));
        let entities = spawn_contact_graph(app.world_mut(), &graph).expect("spawn");
        app.update();
        let world = app.world();
        let cup = world
            .get::<GlobalTransform>(entities["cup_1"])
            .expect("cup")
            .compute_transform();
        let cad = world.get::<CadModel>(entities["cup_1"]).expect("cad");
        let expected = Vec3::from(cad.world_from_model.translation);
        assert!(
            cup.translation.distance(expected) < 1e-4,
            "{}",
            cup.translation
        );
        assert!(
            (cup.scale - Vec3::ONE).abs().max_element() < 1e-4,
            "{}",
            cup.scale
        );
    }

    #[test]
    fn moving_a_table_moves_the_cup_on_it() {
        let (mut app, entities) = kitchen_app();
        let before = app
            .world()
            .get::<GlobalTransform>(entities["cup_1"])
            .expect("cup")
            .translation();
        app.world_mut()
            .get_mut::<Transform>(entities["table_1"])
            .expect("table")
            .translation += Vec3::new(0.5, 0.0, 0.0);
        app.update();
        let after = app
            .world()
            .get::<GlobalTransform>(entities["cup_1"])
            .expect("cup")
            .translation();
        assert!(
            (after - before - Vec3::new(0.5, 0.0, 0.0)).length() < 1e-4,
            "cup moved by {}",
            after - before
        );
    }
}
