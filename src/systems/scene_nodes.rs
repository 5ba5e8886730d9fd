//! The contact graph as the scene's entities hold it. The world is the truth: each node is an
//! entity's components (`SceneEntity`, `Panoptic`, `OrientedBox`, `SurfacePlanes`, its
//! `CadModel` once replaced, the values of its moving parts' `Joint`s), support is its `ChildOf`
//! and the proximal pairs are pair entities (`ProximalEndA`, `ProximalEndB`). `ContactGraph` is
//! what this reads off it: the export format (contact_graph.json), and the view the Bevy-free
//! algorithms of the CAD stages take, as `read_kinematic_tree` reads the kinematic tree off the
//! transform hierarchy.

use std::collections::{BTreeMap, HashMap};

use bevy::ecs::system::{SystemParam, SystemState};
use bevy::prelude::*;

use crate::components::{
    CadModel, Joint, ListedPart, ModelPart, OrientedBox, Panoptic, ProximalPairQuery, SceneEntity,
    SurfacePlanes,
};
use crate::geometry::Plane;
use crate::graph::parts::PartJson;
use crate::graph::{CadPlacement, ContactGraph, GraphEdge, GraphNode};

/// Where an entity's node stands in the contact graph: the order the entities were spawned in,
/// which is the panoptic map's extraction order with the counters the ContactGraph stage found
/// after it, the order that stage builds the graph in. In a reconstruction entity indices follow
/// spawn order: no node is spawned after an entity was despawned (only a proximal pair that a
/// later attachment of the graph drops is ever despawned, and every node exists by then), so no
/// index is reused. `Entity`'s own ordering compares opaque bits and does not follow it.
pub fn graph_order(entity: Entity) -> u32 {
    entity.index_u32()
}

type NodeComponents = (
    Entity,
    &'static SceneEntity,
    &'static Panoptic,
    &'static OrientedBox,
    &'static SurfacePlanes,
    Option<&'static CadModel>,
    Option<&'static ChildOf>,
);

/// The scene entities that are contact-graph nodes (those the ContactGraph stage gave a box and
/// planes), for systems that read the graph.
#[derive(SystemParam)]
pub struct SceneNodes<'w, 's> {
    nodes: Query<'w, 's, NodeComponents>,
    parts: Query<
        'w,
        's,
        (
            &'static ModelPart,
            &'static Joint,
            Option<&'static ListedPart>,
        ),
    >,
    pairs: Query<'w, 's, ProximalPairQuery>,
}

impl SceneNodes<'_, '_> {
    /// The nodes' entities in the graph's order ([`graph_order`]).
    pub fn entities(&self) -> Vec<Entity> {
        let mut entities: Vec<Entity> = self.nodes.iter().map(|n| n.0).collect();
        entities.sort_by_key(|e| graph_order(*e));
        entities
    }

    /// Each node's entity by its id.
    pub fn entities_by_id(&self) -> HashMap<String, Entity> {
        self.nodes.iter().map(|n| (n.1.0.clone(), n.0)).collect()
    }

    /// The node's id, if `entity` is a node.
    pub fn id(&self, entity: Entity) -> Option<&str> {
        self.nodes.get(entity).ok().map(|n| n.1.0.as_str())
    }

    /// The contact graph the entities hold. A joint value is listed where a part stands away
    /// from its rest (a reconstruction's parts all rest, as its graph has them); the parts
    /// listed are their entities' `ListedPart`s, by name.
    pub fn contact_graph(&self) -> ContactGraph {
        let order = self.entities();
        let position: HashMap<Entity, usize> =
            order.iter().enumerate().map(|(k, e)| (*e, k)).collect();
        let mut joints: HashMap<Entity, BTreeMap<String, f32>> = HashMap::new();
        let mut listed: HashMap<Entity, Vec<PartJson>> = HashMap::new();
        for (part, joint, listing) in &self.parts {
            if joint.value != 0.0 {
                joints
                    .entry(part.object)
                    .or_default()
                    .insert(part.part.clone(), joint.value);
            }
            if let Some(listing) = listing {
                listed
                    .entry(part.object)
                    .or_default()
                    .push(listing.0.clone());
            }
        }
        for parts in listed.values_mut() {
            parts.sort_by(|a, b| a.name.cmp(&b.name));
        }
        let rows: Vec<_> = order
            .iter()
            .filter_map(|e| self.nodes.get(*e).ok())
            .collect();
        let nodes = rows
            .iter()
            .map(|(e, id, panoptic, bbox, planes, cad, ..)| GraphNode {
                id: id.0.clone(),
                class: panoptic.class.to_string(),
                kind: panoptic.kind,
                bbox: bbox.0.into(),
                planes: planes.0.iter().map(Plane::to_array).collect(),
                cad: cad.map(CadPlacement::from),
                joints: joints.remove(e).unwrap_or_default(),
                parts: listed.remove(e).unwrap_or_default(),
            })
            .collect();
        // Support edges in the order of their children, then each proximal pair once, in the
        // order of its first and then its second end (the order the ContactGraph stage found them).
        let mut edges: Vec<GraphEdge> = rows
            .iter()
            .filter_map(|(_, id, _, _, _, _, parent)| {
                let parent = self.id(parent.as_ref()?.parent())?;
                Some(GraphEdge::Support {
                    parent: parent.to_string(),
                    child: id.0.clone(),
                })
            })
            .collect();
        let mut pairs: Vec<(usize, usize)> = self
            .pairs
            .iter()
            .filter_map(|(a, b)| Some((*position.get(&a.0)?, *position.get(&b.0)?)))
            .map(|(k, j)| (k.min(j), k.max(j)))
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        edges.extend(pairs.into_iter().map(|(k, j)| GraphEdge::Proximal {
            a: rows[k].1.0.clone(),
            b: rows[j].1.0.clone(),
        }));
        ContactGraph { nodes, edges }
    }
}

/// The contact graph `world`'s scene entities hold (`SceneNodes::contact_graph`).
pub fn read_contact_graph(world: &mut World) -> ContactGraph {
    let mut state = SystemState::<SceneNodes>::new(world);
    state
        .get(world)
        .expect("queries are always valid")
        .contact_graph()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::db::database::CadDatabase;
    use crate::systems::kinematic_tree::spawn_node_links;
    use crate::systems::scene_graph::spawn_contact_graph;

    #[test]
    fn the_graph_read_off_the_world_is_the_graph_spawned_into_it() {
        let graph = crate::scene::kitchen_contact_graph();
        let mut world = World::new();
        spawn_contact_graph(&mut world, &graph).expect("spawn");
        spawn_node_links(&mut world, &graph, Some(&CadDatabase::parametric()));
        let mut read = read_contact_graph(&mut world);
        // The world lists the models' parts as the ground truth does, each with its model's
        // handle, which the ground truth leaves out.
        let mut expected = graph.clone();
        for node in &mut expected.nodes {
            node.joints.retain(|_, v| *v != 0.0);
            node.parts.sort_by(|a, b| a.name.cmp(&b.name));
        }
        let parts: usize = read.nodes.iter().map(|n| n.parts.len()).sum();
        assert!(parts >= 5, "{parts} parts");
        for node in &mut read.nodes {
            for part in &mut node.parts {
                // Doors and drawers have handles; a dishwasher's rack has none.
                let opened_by_hand = ["door", "drawer", "freezer"]
                    .iter()
                    .any(|p| part.name.starts_with(p));
                assert_eq!(
                    part.handle.is_some(),
                    opened_by_hand,
                    "{}/{}",
                    node.id,
                    part.name
                );
                part.handle = None;
            }
        }
        assert_eq!(read, expected);
    }
}
