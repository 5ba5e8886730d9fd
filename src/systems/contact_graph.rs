//! The ContactGraph stage: gravity, then the contact graph of the extracted entities in the
//! aligned world, hung into the ECS as the support tree.

use std::collections::HashMap;

use bevy::prelude::*;
use glam::Affine3A;

use crate::components::{ObservedSurface, Panoptic, SceneEntity, SegmentMesh};
use crate::graph::ContactGraph;
use crate::graph::build::{ContactGraphParams, GraphEntity, build_contact_graph_with_surfaces};
use crate::graph::gravity::{GravityReport, camera_up_hint, resolve_gravity};
use crate::map::extract_mesh;
use crate::systems::ingest::{InputSequence, StageError};
use crate::systems::panoptic_mapping::PanopticMap;
use crate::systems::scene_graph::attach_contact_graph;

/// How the stage finds gravity.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct GravityConfig {
    /// Ignore the sequence's gravity file and estimate from the map (the file, when there is one,
    /// is then only compared with).
    pub estimate: bool,
}

/// The stage's result: the graph in the aligned world, and the gravity that aligned it.
#[derive(Resource, Clone, Debug)]
pub struct SceneContactGraph {
    pub graph: ContactGraph,
    pub gravity: GravityReport,
}

fn contact_graph_stage(world: &mut World) {
    if world.resource::<StageError>().0.is_some() {
        return;
    }
    let mut query = world.query::<(Entity, &SceneEntity, &Panoptic, &SegmentMesh)>();
    let entities: Vec<(Entity, String, Panoptic, crate::geometry::TriMesh)> = query
        .iter(world)
        .map(|(e, id, p, m)| (e, id.0.clone(), p.clone(), m.0.clone()))
        .collect();
    let Some(map) = world.get_resource::<PanopticMap>() else {
        return;
    };
    let sequence = &world.resource::<InputSequence>().0;
    let estimate = world
        .get_resource::<GravityConfig>()
        .is_some_and(|c| c.estimate);
    let floor_points: Vec<glam::Vec3> = entities
        .iter()
        .filter(|(_, _, p, _)| p.class == "floor")
        .flat_map(|(_, _, _, m)| m.positions.iter().copied())
        .collect();
    let gravity = resolve_gravity(
        sequence.gravity,
        estimate,
        camera_up_hint(sequence.frames.iter().map(|f| f.world_from_camera)),
        || extract_mesh(&map.0.tsdf, 1.0).mesh,
        &floor_points,
    );
    let aligned_from_world =
        Affine3A::from_mat4(glam::Mat4::from_cols_array(&gravity.aligned_from_world));
    let aligned: Vec<crate::geometry::TriMesh> = entities
        .iter()
        .map(|(_, _, _, m)| m.transformed(&aligned_from_world))
        .collect();
    let graph_entities: Vec<GraphEntity> = entities
        .iter()
        .zip(&aligned)
        .map(|((_, id, p, _), mesh)| GraphEntity {
            id,
            class: &p.class,
            kind: p.kind,
            mesh,
        })
        .collect();
    let built = build_contact_graph_with_surfaces(
        &graph_entities,
        &ContactGraphParams::for_voxel(map.0.tsdf.voxel_size),
    );
    let graph = built.graph;
    let by_id: HashMap<String, Entity> = entities
        .iter()
        .map(|(e, id, _, _)| (id.clone(), *e))
        .collect();
    // The entities' meshes join the aligned world with their boxes.
    for ((e, _, _, _), mesh) in entities.iter().zip(aligned) {
        world.entity_mut(*e).insert(SegmentMesh(mesh));
    }
    for (node, surface) in graph.nodes.iter().zip(built.surfaces) {
        world
            .entity_mut(by_id[&node.id])
            .insert(ObservedSurface(surface));
    }
    if let Err(problem) = attach_contact_graph(world, &graph, &by_id) {
        world.resource_mut::<StageError>().0 = Some(crate::error::IsceneError::Internal(format!(
            "contact graph: {problem}"
        )));
        return;
    }
    world.insert_resource(SceneContactGraph { graph, gravity });
}

/// Adds the ContactGraph stage.
pub struct ContactGraphPlugin;

impl Plugin for ContactGraphPlugin {
    fn build(&self, app: &mut App) {
        use crate::systems::ReconstructionStage as Stage;
        app.add_systems(
            crate::systems::Reconstruct,
            contact_graph_stage.in_set(Stage::ContactGraph),
        );
    }
}
