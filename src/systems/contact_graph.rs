//! The ContactGraph stage: gravity, then the contact graph of the extracted entities in the
//! aligned world, hung into the ECS as the support tree.

use std::collections::HashMap;

use bevy::prelude::*;
use glam::Affine3A;

use crate::components::{ObservedSurface, Panoptic, SceneEntity, SegmentMesh, SightedOutline};
use crate::error::IsceneError;
use crate::graph::build::{
    COUNTER_CLASS, ContactGraphParams, GraphEntity, build_contact_graph_with_surfaces,
};
use crate::graph::counters::{CounterParams, find_counter_tops};
use crate::graph::gravity::{GravityReport, camera_up_hint, resolve_gravity};
use crate::map::extract_mesh;
use crate::systems::ingest::InputSequence;
use crate::systems::panoptic_mapping::{PanopticMap, PanopticSurface};
use crate::systems::scene_graph::attach_contact_graph;
use crate::systems::scene_nodes::graph_order;
use crate::systems::stages::record_failure;

/// How the stage finds gravity.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct GravityConfig {
    /// Ignore the sequence's gravity file and estimate from the map (the file, when there is one,
    /// is then only compared with).
    pub estimate: bool,
}

/// The gravity that aligned the world (the stage's other result, the graph, is the scene
/// entities' components: `scene_nodes` reads it off them).
#[derive(Resource, Clone, Debug)]
pub struct SceneGravity(pub GravityReport);

fn contact_graph_stage(world: &mut World) -> Result<(), IsceneError> {
    let mut query = world.query::<(Entity, &SceneEntity, &Panoptic, &SegmentMesh)>();
    let mut entities: Vec<(Entity, String, Panoptic, crate::geometry::TriMesh)> = query
        .iter(world)
        .map(|(e, id, p, m)| (e, id.0.clone(), p.clone(), m.0.clone()))
        .collect();
    entities.sort_by_key(|(e, ..)| graph_order(*e));
    let outlines: Vec<Vec<Vec<glam::Vec3>>> = entities
        .iter()
        .map(|(e, ..)| {
            world
                .get::<SightedOutline>(*e)
                .map(|o| o.0.clone())
                .unwrap_or_default()
        })
        .collect();
    let Some(map) = world.get_resource::<PanopticMap>() else {
        return Ok(());
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
    let voxel_size = map.0.tsdf.voxel_size;
    let precise_depth = world
        .get_resource::<PanopticSurface>()
        .is_some_and(|s| s.precise_depth.is_some());
    entities.extend(spawn_counters(world, aligned_from_world, &entities));
    let aligned: Vec<crate::geometry::TriMesh> = entities
        .iter()
        .map(|(_, _, _, m)| m.transformed(&aligned_from_world))
        .collect();
    // Counters spawned above have no outline.
    let aligned_outlines: Vec<Vec<Vec<glam::Vec3>>> = outlines
        .iter()
        .map(|frames| {
            frames
                .iter()
                .map(|points| {
                    points
                        .iter()
                        .map(|&p| aligned_from_world.transform_point3(p))
                        .collect()
                })
                .collect()
        })
        .collect();
    let no_outline = Vec::new();
    let graph_entities: Vec<GraphEntity> = entities
        .iter()
        .zip(&aligned)
        .enumerate()
        .map(|(k, ((_, id, p, _), mesh))| GraphEntity {
            id,
            class: &p.class,
            kind: p.kind,
            mesh,
            sighted: aligned_outlines.get(k).unwrap_or(&no_outline),
        })
        .collect();
    let built = build_contact_graph_with_surfaces(
        &graph_entities,
        &ContactGraphParams::for_voxel(voxel_size, precise_depth),
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
    attach_contact_graph(world, &graph, &by_id)
        .map_err(|problem| IsceneError::Internal(format!("contact graph: {problem}")))?;
    world.insert_resource(SceneGravity(gravity));
    Ok(())
}

/// Finds the counter tops among the map's surface no entity claims (graph/counters.rs) and
/// spawns a `counter` entity for each, its mesh the top's points (world frame, no triangles: the
/// map saw a surface, not a solid; the contact graph stretches its box down to the floor).
fn spawn_counters(
    world: &mut World,
    aligned_from_world: Affine3A,
    entities: &[(Entity, String, Panoptic, crate::geometry::TriMesh)],
) -> Vec<(Entity, String, Panoptic, crate::geometry::TriMesh)> {
    let Some(surface) = world.get_resource::<PanopticSurface>() else {
        return Vec::new();
    };
    let unclaimed: Vec<glam::Vec3> = surface
        .voxels
        .iter()
        .filter(|(_, entity)| *entity == 0)
        .map(|(p, _)| aligned_from_world.transform_point3(*p))
        .collect();
    let world_from_aligned = aligned_from_world.inverse();
    let tops = find_counter_tops(&unclaimed, &CounterParams::default());
    let mut spawned = Vec::new();
    let mut k = 0;
    for top in tops {
        // The next free id (a segmenter never names a counter, but stay safe).
        let id = loop {
            k += 1;
            let id = format!("counter_{k}");
            if !entities.iter().any(|(_, other, _, _)| *other == id) {
                break id;
            }
        };
        let panoptic = Panoptic {
            instance: COUNTER_INSTANCE_BASE + k,
            class: COUNTER_CLASS.into(),
            kind: crate::classes::EntityKind::Rigid,
        };
        let mesh = crate::geometry::TriMesh {
            positions: top
                .iter()
                .map(|p| world_from_aligned.transform_point3(*p))
                .collect(),
            triangles: Vec::new(),
        };
        let entity = world
            .spawn((
                SceneEntity(id.clone()),
                panoptic.clone(),
                SegmentMesh(mesh.clone()),
            ))
            .id();
        spawned.push((entity, id, panoptic, mesh));
    }
    spawned
}

/// Counters' instance numbers start here, clear of the map's instances.
const COUNTER_INSTANCE_BASE: u32 = 100_000;

/// Adds the ContactGraph stage.
pub struct ContactGraphPlugin;

impl Plugin for ContactGraphPlugin {
    fn build(&self, app: &mut App) {
        use crate::systems::ReconstructionStage as Stage;
        app.add_systems(
            crate::systems::Reconstruct,
            contact_graph_stage
                .pipe(record_failure)
                .in_set(Stage::ContactGraph),
        );
    }
}
