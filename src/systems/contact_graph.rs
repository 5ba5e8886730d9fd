//! The ContactGraph stage: gravity, then the contact graph of the extracted entities in the
//! aligned world, hung into the ECS as the support tree.

use std::collections::HashMap;

use bevy::prelude::*;
use glam::Vec3;

use crate::geometry::TriMesh;

use crate::components::{
    CounterBody, ObservedSurface, Panoptic, SceneEntity, SegmentMesh, SightedOutline,
};
use crate::error::IsceneError;
use crate::graph::build::{
    COUNTER_CLASS, ContactGraphParams, GraphEntity, build_contact_graph_with_surfaces,
};
use crate::graph::counters::{CounterParams, counter_body, find_counter_tops};
use crate::graph::gravity::{GravityReport, camera_up_hint, resolve_gravity};
use crate::map::extract_mesh;
use crate::systems::ingest::InputSequence;
use crate::systems::panoptic_mapping::{PanopticMap, PanopticSurface};
use crate::systems::scene_graph::attach_contact_graph;
use crate::systems::scene_nodes::graph_order;
use crate::systems::stages::StageError;

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

/// ContactGraph, first: gravity, from the sequence's file or estimated from the map and the floor
/// entities, which aligns the world. No map, no graph: the stage leaves nothing.
fn resolve_scene_gravity(
    mut commands: Commands,
    entities: Query<(Entity, &Panoptic, &SegmentMesh)>,
    map: Option<Res<PanopticMap>>,
    sequence: Res<InputSequence>,
    config: Option<Res<GravityConfig>>,
) {
    let Some(map) = map else {
        return;
    };
    let mut floors: Vec<(Entity, &SegmentMesh)> = entities
        .iter()
        .filter(|(_, p, _)| p.class == "floor")
        .map(|(e, _, m)| (e, m))
        .collect();
    floors.sort_by_key(|(e, _)| graph_order(*e));
    let floor_points: Vec<Vec3> = floors
        .iter()
        .flat_map(|(_, m)| m.0.positions.iter().copied())
        .collect();
    let gravity = resolve_gravity(
        sequence.0.gravity,
        config.is_some_and(|c| c.estimate),
        camera_up_hint(sequence.0.frames.iter().map(|f| f.world_from_camera)),
        || extract_mesh(&map.0.tsdf, 1.0).mesh,
        &floor_points,
    );
    commands.insert_resource(SceneGravity(gravity));
}

/// ContactGraph, second: a `counter` entity for each counter top among the map's surface that
/// no entity claims (graph/counters.rs), its mesh the top's points (world frame, no triangles:
/// the map saw a surface, not a solid; the contact graph stretches its box down to the floor),
/// with what the map saw under the top as its `CounterBody`.
fn spawn_counters(
    mut commands: Commands,
    ids: Query<&SceneEntity>,
    gravity: Option<Res<SceneGravity>>,
    surface: Option<Res<PanopticSurface>>,
) {
    let (Some(gravity), Some(surface)) = (gravity, surface) else {
        return;
    };
    let aligned_from_world = gravity.0.aligned_from_world();
    let unclaimed: Vec<Vec3> = surface
        .voxels
        .iter()
        .filter(|(_, entity)| *entity == 0)
        .map(|(p, _)| aligned_from_world.transform_point3(*p))
        .collect();
    // What a counter's body may hold: surface nothing claims or a layout entity does (its front
    // is a vertical plane a wall may take), never another object's.
    let layout_or_unclaimed: Vec<Vec3> = surface
        .voxels
        .iter()
        .filter(|(_, entity)| {
            *entity == 0
                || surface
                    .entities
                    .get(*entity as usize - 1)
                    .is_some_and(|e| e.kind == crate::classes::EntityKind::Layout)
        })
        .map(|(p, _)| aligned_from_world.transform_point3(*p))
        .collect();
    let world_from_aligned = aligned_from_world.inverse();
    let tops = find_counter_tops(&unclaimed, &CounterParams::default());
    let counter_kind = crate::classes::ClassTable::builtin()
        .get(COUNTER_CLASS)
        .map_or(crate::classes::EntityKind::Rigid, |c| c.kind);
    let mut k = 0;
    for top in tops {
        // The next free id (a segmenter never names a counter, but stay safe).
        let id = loop {
            k += 1;
            let id = format!("counter_{k}");
            if !ids.iter().any(|other| other.0 == id) {
                break id;
            }
        };
        let body = CounterBody(counter_body(&top, &layout_or_unclaimed));
        let mesh = TriMesh {
            positions: top
                .iter()
                .map(|p| world_from_aligned.transform_point3(*p))
                .collect(),
            triangles: Vec::new(),
        };
        commands.spawn((
            SceneEntity(id),
            Panoptic {
                instance: COUNTER_INSTANCE_BASE + k,
                class: COUNTER_CLASS.into(),
                kind: counter_kind,
            },
            SegmentMesh(mesh),
            body,
        ));
    }
}

/// What the contact graph reads of a scene entity.
type GraphEntityRow = (
    Entity,
    &'static SceneEntity,
    &'static Panoptic,
    &'static mut SegmentMesh,
    Option<&'static SightedOutline>,
    Option<&'static CounterBody>,
);

/// ContactGraph, last: the entities' meshes join the aligned world, and their contact graph
/// (`graph::build`) is hung into the ECS as the support tree, each node with the surface it was
/// built from.
fn build_contact_graph(
    mut commands: Commands,
    mut entities: Query<GraphEntityRow>,
    gravity: Option<Res<SceneGravity>>,
    map: Option<Res<PanopticMap>>,
    surface: Option<Res<PanopticSurface>>,
) {
    let (Some(gravity), Some(map)) = (gravity, map) else {
        return;
    };
    let aligned_from_world = gravity.0.aligned_from_world();
    for (_, _, _, mut mesh, ..) in &mut entities {
        mesh.0 = mesh.0.transformed(&aligned_from_world);
    }
    let mut rows: Vec<_> = entities.iter().collect();
    rows.sort_by_key(|(e, ..)| graph_order(*e));
    let aligned_outlines: Vec<Vec<Vec<Vec3>>> = rows
        .iter()
        .map(|(.., outline, _)| {
            outline.map_or_else(Vec::new, |o| {
                o.0.iter()
                    .map(|points| {
                        points
                            .iter()
                            .map(|&p| aligned_from_world.transform_point3(p))
                            .collect()
                    })
                    .collect()
            })
        })
        .collect();
    let graph_entities: Vec<GraphEntity> = rows
        .iter()
        .zip(&aligned_outlines)
        .map(|((_, id, p, mesh, ..), sighted)| GraphEntity {
            id: &id.0,
            class: &p.class,
            kind: p.kind,
            mesh: &mesh.0,
            sighted,
        })
        .collect();
    let precise_depth = surface.is_some_and(|s| s.precise_depth.is_some());
    let built = build_contact_graph_with_surfaces(
        &graph_entities,
        &ContactGraphParams::for_voxel(map.0.tsdf.voxel_size, precise_depth),
    );
    let by_id: HashMap<String, Entity> =
        rows.iter().map(|(e, id, ..)| (id.0.clone(), *e)).collect();
    let bodies: HashMap<&str, &CounterBody> = rows
        .iter()
        .filter_map(|(_, id, .., body)| Some((id.0.as_str(), (*body)?)))
        .collect();
    for (node, mut surface) in built.graph.nodes.iter().zip(built.surfaces) {
        if let Some(body) = bodies.get(node.id.as_str()) {
            surface.extend_from_slice(&body.0);
        }
        commands
            .entity(by_id[&node.id])
            .insert(ObservedSurface(surface));
    }
    let graph = built.graph;
    commands.queue(move |world: &mut World| {
        if let Err(problem) = attach_contact_graph(world, &graph, &by_id) {
            let error = IsceneError::Internal(format!("contact graph: {problem}"));
            world.resource_mut::<StageError>().0.get_or_insert(error);
        }
    });
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
            (resolve_scene_gravity, spawn_counters, build_contact_graph)
                .chain()
                .in_set(Stage::ContactGraph),
        );
    }
}
