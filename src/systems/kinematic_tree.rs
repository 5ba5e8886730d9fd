//! The KinematicTree stage: every scene entity becomes a link (its `LinkBody`: mesh, collision
//! pieces, mass properties, the colour the camera saw on it), every moving part of its CAD model
//! a child entity with its own joint and its `ListedPart` (the part as contact_graph.json lists
//! it, with the handle perceived on its front or its model's),
//! and the whole transform hierarchy is read off as the `SceneKinematicTree` the exports and the
//! physics check use. Reading the tree from the ECS (not from the contact graph) means it can be
//! read again after any simulated action.

use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::Arc;

use bevy::ecs::system::SystemState;
use bevy::prelude::*;
use bevy::transform::helper::TransformHelper;
use glam::{Affine3A, Mat4};
use rayon::prelude::*;

use crate::cad::db::database::CadDatabase;
use crate::cad::model_parts::{attach_handles, model_parts};
use crate::components::{
    CadModel, Joint, LinkBody, ListedPart, ModelPart, Panoptic, PerceivedFront, RobotArmLink,
    SceneEntity, SegmentMesh,
};
use crate::error::IsceneError;
use crate::geometry::TriMesh;
use crate::graph::ContactGraph;
use crate::graph::parts::PartJson;
use crate::kinematics::JointSpec;
use crate::kinematics::link::{NodeLink, node_links};
use crate::kinematics::observed::{SeenShape, seen_shape};
use crate::kinematics::tree::{KinematicTree, TreeError, TreeLink};
use crate::perception::open_doors::door_openings;
use crate::perception::open_drawers::drawer_openings;
use crate::systems::cad_replacement::SceneModels;
use crate::systems::contact_graph::SceneGravity;
use crate::systems::link_colors::paint_links_as_seen;
use crate::systems::scene_graph::{SceneRoot, transform_of};
use crate::systems::scene_nodes::read_contact_graph;
use crate::systems::stages::record_failure;

/// Why the transform hierarchy could not be read as a kinematic tree.
#[derive(Debug, thiserror::Error)]
pub enum ReadTreeError {
    #[error("no scene root")]
    NoSceneRoot,
    #[error(transparent)]
    Malformed(#[from] TreeError),
}

impl From<ReadTreeError> for IsceneError {
    fn from(e: ReadTreeError) -> Self {
        IsceneError::Internal(e.to_string())
    }
}

/// The kinematic tree as the ECS held it at the end of the KinematicTree stage.
#[derive(Resource, Clone, Debug)]
pub struct SceneKinematicTree(pub KinematicTree);

fn kinematic_tree_stage(world: &mut World) -> Result<(), IsceneError> {
    if !world.contains_resource::<SceneGravity>() {
        return Ok(());
    }
    let graph = read_contact_graph(world);
    let db = world.get_resource::<SceneModels>().map(|l| l.0.clone());
    spawn_node_links(world, &graph, db.as_deref());
    let (mut tree, entities) = read_kinematic_tree_entities(world)
        .map_err(|problem| IsceneError::Internal(format!("kinematic tree: {problem}")))?;
    paint_links_as_seen(world, &mut tree, &entities);
    world.insert_resource(SceneKinematicTree(tree));
    Ok(())
}

/// Gives the scene entities named in `seen` their segment meshes (in the world frame), of which
/// [`spawn_node_links`] builds the objects no model replaced: a world read back from a
/// reconstruction's folder gets the objects the reconstruction checked.
pub fn attach_segment_meshes(world: &mut World, seen: &HashMap<String, TriMesh>) {
    let entities: Vec<(Entity, String)> = world
        .query::<(Entity, &SceneEntity)>()
        .iter(world)
        .filter(|(_, id)| seen.contains_key(&id.0))
        .map(|(e, id)| (e, id.0.clone()))
        .collect();
    for (entity, id) in entities {
        world
            .entity_mut(entity)
            .insert(SegmentMesh(seen[&id].clone()));
    }
}

/// Gives every scene entity the links of its contact-graph node in `graph` (its own link's body
/// and the moving parts of its CAD model from `db`, spawned below it, each listed with its
/// handle: the one perceived on its front, else its model's).
pub fn spawn_node_links(world: &mut World, graph: &ContactGraph, db: Option<&CadDatabase>) {
    let mut entities: Vec<(Entity, String)> = world
        .query::<(Entity, &SceneEntity)>()
        .iter(world)
        .map(|(e, id)| (e, id.0.clone()))
        .collect();
    entities.sort_by(|a, b| a.1.cmp(&b.1));
    // Poses composed along the `ChildOf` chains now: the reconstruction runs its schedule once,
    // without the transform propagation systems.
    let mut helper = SystemState::<TransformHelper>::new(world);
    let helper = helper.get(world).expect("queries are always valid");
    let poses: Vec<Affine3A> = entities
        .iter()
        .map(|(e, _)| {
            helper
                .compute_global_transform(*e)
                .map_or(Affine3A::IDENTITY, |g| g.affine())
        })
        .collect();
    let perceived: Vec<Option<PerceivedFront>> = entities
        .iter()
        .map(|(e, _)| world.get::<PerceivedFront>(*e).cloned())
        .collect();
    // What the map saw of each object no model replaced: its link is made of it.
    let seen: Vec<Option<SeenShape>> = entities
        .iter()
        .map(|(e, id)| seen_shape(graph, id, &world.get::<SegmentMesh>(*e)?.0, db))
        .collect();
    let floor = graph.nodes.iter().find(|n| n.class == "floor");
    let links: Vec<(Vec<NodeLink>, Vec<PartJson>)> = entities
        .par_iter()
        .zip(poses.par_iter())
        .zip(perceived.par_iter())
        .zip(seen.par_iter())
        .map(|((((_, id), pose), perceived), seen)| {
            let Some(node) = graph.node(id) else {
                return (Vec::new(), Vec::new());
            };
            let placed = node.cad.as_ref().zip(db).and_then(|(c, db)| {
                let frame = Affine3A::from_mat4(Mat4::from_cols_array(&c.world_from_model));
                Some((db.get(&c.model)?, frame))
            });
            let handles = perceived.as_ref().map_or(&[][..], |f| &f.0.handles[..]);
            let parts = placed.map_or_else(Vec::new, |(model, frame)| {
                let mut parts = model_parts(&model.model, &frame);
                attach_handles(&mut parts, handles, &model.placed_handles(&frame));
                parts
            });
            // A drawer or door seen standing open stands open in the tree as far as it was
            // pulled out or turned, unless the graph says where it is.
            let opened: Vec<(String, f32)> = perceived
                .as_ref()
                .map_or_else(Vec::new, |f| {
                    let mut opened = drawer_openings(&f.0.front, &f.0.open_drawers, &parts);
                    opened.extend(door_openings(&f.0.front, &f.0.open_doors, &parts));
                    opened
                })
                .into_iter()
                .filter(|(name, _)| !node.joints.contains_key(name))
                .collect();
            let node = if opened.is_empty() {
                Cow::Borrowed(node)
            } else {
                let mut node = node.clone();
                node.joints.extend(opened);
                Cow::Owned(node)
            };
            let links = node_links(
                &node,
                placed.map(|(m, _)| &m.model),
                seen.as_ref(),
                *pose,
                floor,
            );
            (links, parts)
        })
        .collect();
    for ((entity, id), (links, parts)) in entities.iter().zip(links) {
        spawn_links(world, *entity, id, links, parts);
    }
}

/// Gives `entity` its own link's body and spawns the moving parts below it, each with the
/// listing of `parts` of its name.
fn spawn_links(
    world: &mut World,
    entity: Entity,
    id: &str,
    links: Vec<NodeLink>,
    mut parts: Vec<PartJson>,
) {
    let mut part_entities: Vec<Entity> = Vec::with_capacity(links.len());
    for link in links {
        let body = LinkBody(Arc::new(link.geometry));
        let (Some(part), Some(parent)) = (link.part, link.parent) else {
            world.entity_mut(entity).insert(body);
            part_entities.push(entity);
            continue;
        };
        let local = link.parent_from_link * link.joint.motion(link.value);
        let listing = parts
            .iter()
            .position(|p| p.name == part)
            .map(|k| ListedPart(parts.swap_remove(k)));
        let mut e = world.spawn((
            Name::new(format!("{id}_{part}")),
            ModelPart {
                object: entity,
                part,
            },
            body,
            Joint {
                spec: link.joint,
                value: link.value,
            },
            transform_of(local),
            ChildOf(part_entities[parent]),
        ));
        if let Some(listing) = listing {
            e.insert(listing);
        }
        part_entities.push(e.id());
    }
}

/// The transform hierarchy under the `SceneRoot` as a kinematic tree, depth first, children in
/// name order (so the same scene always gives the same files).
pub fn read_kinematic_tree(world: &mut World) -> Result<KinematicTree, ReadTreeError> {
    read_kinematic_tree_entities(world).map(|(tree, _)| tree)
}

/// The kinematic tree as `read_kinematic_tree` reads it, with the entity of each link.
pub fn read_kinematic_tree_entities(
    world: &mut World,
) -> Result<(KinematicTree, Vec<Entity>), ReadTreeError> {
    let root = world
        .query_filtered::<Entity, With<SceneRoot>>()
        .iter(world)
        .next()
        .ok_or(ReadTreeError::NoSceneRoot)?;
    let mut children_of: HashMap<Entity, Vec<(String, Entity)>> = HashMap::new();
    // The arm's links are the robot's, not the scene's: the trace has their motions.
    for (e, parent, name) in world
        .query_filtered::<(Entity, &ChildOf, &Name), Without<RobotArmLink>>()
        .iter(world)
    {
        children_of
            .entry(parent.parent())
            .or_default()
            .push((name.as_str().to_string(), e));
    }
    let mut tree = KinematicTree {
        links: vec![TreeLink::root()],
    };
    let mut entities = vec![root];
    let mut stack: Vec<(Entity, usize)> = vec![(root, 0)];
    while let Some((entity, index)) = stack.pop() {
        let mut children = children_of.remove(&entity).unwrap_or_default();
        children.sort_by(|a, b| a.0.cmp(&b.0));
        let mut pushed = Vec::with_capacity(children.len());
        for (name, child) in children {
            let e = world.entity(child);
            let joint = e.get::<Joint>().copied().unwrap_or(Joint {
                spec: JointSpec::FIXED,
                value: 0.0,
            });
            let local = e
                .get::<Transform>()
                .map_or(Affine3A::IDENTITY, Transform::compute_affine);
            // A part's class is its object's.
            let (node, class) = match (e.get::<SceneEntity>(), e.get::<ModelPart>()) {
                (Some(id), _) => (
                    Some(id.0.clone()),
                    e.get::<Panoptic>().map(|p| p.class.to_string()),
                ),
                (None, Some(part)) => (
                    world.get::<SceneEntity>(part.object).map(|id| id.0.clone()),
                    tree.links[index].class.clone(),
                ),
                (None, None) => (None, None),
            };
            tree.links.push(TreeLink {
                name,
                node,
                class,
                parent: Some(index),
                joint: joint.spec,
                value: joint.value,
                parent_from_link: local * joint.spec.motion(joint.value).inverse(),
                geometry: e.get::<LinkBody>().map(|b| b.0.clone()),
                modelled: e.contains::<CadModel>() || e.contains::<ModelPart>(),
            });
            entities.push(child);
            pushed.push((child, tree.links.len() - 1));
        }
        // Depth first: the stack pops from the back, so the first child goes on last.
        stack.extend(pushed.into_iter().rev());
    }
    tree.check()?;
    Ok((tree, entities))
}

/// Adds the KinematicTree stage.
pub struct KinematicTreePlugin;

impl Plugin for KinematicTreePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(
            crate::systems::Reconstruct,
            kinematic_tree_stage
                .pipe(record_failure)
                .in_set(crate::systems::ReconstructionStage::KinematicTree),
        );
    }
}
