//! The CadMatch, CadAlign and PhysicalCheck stages: rank the database's models for every object
//! of the contact graph, align the best candidates to the object's observed surface, choose
//! among them so the models neither interpenetrate nor overhang their supports, snap them on,
//! and let each chosen model's frame become its entity's frame in the transform tree.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::prelude::*;
use serde::Serialize;

use crate::cad::db::database::CadDatabase;
use crate::cad::replace::alignment::Alignment;
use crate::cad::replace::matching::Candidate;
use crate::cad::replace::replacement::{
    AlignMethod, ReplacementRecord, align_scene_reusing, check_and_place, observed_objects,
    rank_scene,
};
use crate::cad::replace::shape_filter::{Rejection, layout_planes, rejection};
use crate::components::{ObservedSurface, SceneEntity};
use crate::error::IsceneError;
use crate::graph::ContactGraph;
use crate::systems::contact_graph::SceneContactGraph;
use crate::systems::scene_graph::attach_contact_graph;
use crate::systems::stages::record_failure;

/// The database replacement chooses from (the parametric library unless one is given).
#[derive(Resource, Clone)]
pub struct CadLibrary(pub Arc<CadDatabase>);

/// The models the placements of the scene's contact graph refer to: the database replacement
/// chose from, and the library models the physical check built to an object's size.
#[derive(Resource, Clone)]
pub struct SceneModels(pub Arc<CadDatabase>);

/// How CadMatch and CadAlign choose and align candidates (Levenberg-Marquardt unless set).
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct CadAlignMethod(pub AlignMethod);

/// An object the shape filters kept from replacement, and why.
#[derive(Clone, Debug, Serialize)]
pub struct RejectedObject {
    pub id: String,
    #[serde(flatten)]
    pub rejection: Rejection,
}

/// CadMatch's result: the objects the shape filters rejected.
#[derive(Resource, Clone, Debug, Default)]
pub struct CadRejections(pub Vec<RejectedObject>);

/// CadMatch's result: the ranked candidates of each object id (none for a rejected object).
#[derive(Resource, Clone, Debug, Default)]
pub struct CadCandidates(pub Vec<(String, Vec<Candidate>)>);

/// CadAlign's result: each object id's aligned candidates, best first.
#[derive(Resource, Clone, Debug, Default)]
pub struct CadAlignments(pub Vec<(String, Vec<Alignment>)>);

/// What replacement did, for report.json.
/// The alignments of the last refresh of a live session, by object: an object whose class and box
/// have not changed (within 2 cm and 3 degrees) keeps them instead of being aligned again. Only a
/// live session's refreshes carry it; the final pass aligns everything.
#[derive(Resource, Clone, Debug, Default)]
pub struct CadAlignmentCache(
    pub HashMap<String, (String, crate::geometry::GravityBox, Vec<Alignment>)>,
);

impl CadAlignmentCache {
    const SAME_M: f32 = 0.02;
    const SAME_YAW: f32 = 0.05;

    fn reuse(&self, o: &crate::cad::replace::matching::ObservedObject) -> Option<Vec<Alignment>> {
        let (class, bbox, alignments) = self.0.get(o.id)?;
        let same = class == o.class
            && bbox.center.distance(o.bbox.center) <= Self::SAME_M
            && (bbox.size - o.bbox.size).abs().max_element() <= Self::SAME_M
            && half_turn_difference(bbox.yaw, o.bbox.yaw) <= Self::SAME_YAW;
        same.then(|| alignments.clone())
    }
}

/// `|a - b|` with yaws a half turn apart the same (a box turned by pi is the same box).
fn half_turn_difference(a: f32, b: f32) -> f32 {
    let d = (a - b).rem_euclid(std::f32::consts::PI);
    d.min(std::f32::consts::PI - d)
}

#[derive(Resource, Clone, Debug, Serialize)]
pub struct CadReport {
    pub align_method: AlignMethod,
    pub database_models: usize,
    /// Objects of the contact graph (layout excluded).
    pub objects: usize,
    /// Segments the shape filters found to be label bleeding or several objects: they keep
    /// their segment meshes.
    pub rejected: Vec<RejectedObject>,
    pub replaced: Vec<ReplacementRecord>,
    pub mean_alignment_error_m: Option<f32>,
    /// Objects the physical check moved off their best alignment.
    pub swapped: usize,
    /// Objects whose final placement still conflicts (penetration over 1 cm, layout
    /// penetration, support test, tipping over): they keep their segment meshes.
    pub conflicted: Vec<String>,
    /// Their placements as the check left them, with the conflicts.
    pub unplaced: Vec<ReplacementRecord>,
}

/// Each entity id's observed surface points.
fn observed_points(world: &mut World) -> HashMap<String, Vec<Vec3>> {
    world
        .query::<(&SceneEntity, &ObservedSurface)>()
        .iter(world)
        .map(|(id, surface)| (id.0.clone(), surface.0.clone()))
        .collect()
}

/// The contact graph and every entity's observed surface, once the contact graph is built.
fn observed_scene(world: &mut World) -> Option<(ContactGraph, HashMap<String, Vec<Vec3>>)> {
    let graph = world.get_resource::<SceneContactGraph>()?.graph.clone();
    Some((graph, observed_points(world)))
}

fn cad_match_stage(world: &mut World) {
    let Some((graph, points)) = observed_scene(world) else {
        return;
    };
    let db = world
        .get_resource_or_insert_with(|| CadLibrary(Arc::new(CadDatabase::parametric())))
        .0
        .clone();
    let method = world.get_resource_or_init::<CadAlignMethod>().0;
    let layout = layout_planes(&graph);
    let (mut objects, mut rejected) = (Vec::new(), Vec::new());
    for object in observed_objects(&graph, &points) {
        match rejection(&object, &layout) {
            Some(rejection) => rejected.push(RejectedObject {
                id: object.id.to_string(),
                rejection,
            }),
            None => objects.push(object),
        }
    }
    let ranked = rank_scene(&objects, &db, method);
    let candidates = objects
        .iter()
        .zip(ranked)
        .map(|(o, c)| (o.id.to_string(), c))
        .collect();
    world.insert_resource(CadCandidates(candidates));
    world.insert_resource(CadRejections(rejected));
}

fn cad_align_stage(world: &mut World) {
    let Some((graph, points)) = observed_scene(world) else {
        return;
    };
    let (Some(candidates), Some(db)) = (
        world.get_resource::<CadCandidates>(),
        world.get_resource::<CadLibrary>(),
    ) else {
        return;
    };
    let candidates = &candidates.0;
    let db = db.0.clone();
    let objects = observed_objects(&graph, &points);
    let ranked: Vec<Vec<Candidate>> = objects
        .iter()
        .map(|o| {
            candidates
                .iter()
                .find(|(id, _)| id == o.id)
                .map(|(_, c)| c.clone())
                .unwrap_or_default()
        })
        .collect();
    let method = world.get_resource_or_init::<CadAlignMethod>().0;
    let cache = world.get_resource::<CadAlignmentCache>().cloned();
    let aligned = align_scene_reusing(&objects, &db, &ranked, method, |o| {
        cache.as_ref().and_then(|c| c.reuse(o))
    });
    if let Some(mut cache) = cache {
        cache.0 = objects
            .iter()
            .zip(&aligned)
            .map(|(o, a)| (o.id.to_string(), (o.class.to_string(), o.bbox, a.clone())))
            .collect();
        world.insert_resource(cache);
    }
    let alignments = objects
        .iter()
        .map(|o| o.id.to_string())
        .zip(aligned)
        .collect();
    world.insert_resource(CadAlignments(alignments));
}

fn physical_check_stage(world: &mut World) -> Result<(), IsceneError> {
    let Some((mut graph, points)) = observed_scene(world) else {
        return Ok(());
    };
    let (Some(alignments), Some(db)) = (
        world.get_resource::<CadAlignments>(),
        world.get_resource::<CadLibrary>(),
    ) else {
        return Ok(());
    };
    let (ids, options): (Vec<String>, Vec<Vec<Alignment>>) = alignments.0.iter().cloned().unzip();
    let db = db.0.clone();
    let object_count = graph
        .nodes
        .iter()
        .filter(|n| n.kind != crate::classes::EntityKind::Layout)
        .count();
    let placements = check_and_place(&mut graph, &db, &ids, &options, &points);
    let (replaced, unplaced): (Vec<_>, Vec<_>) = placements
        .records
        .into_iter()
        .partition(|r| r.check.conflicts == 0);
    world.insert_resource(SceneModels(Arc::new(db.with_models(placements.built))));
    let by_id: HashMap<String, Entity> = world
        .query::<(Entity, &SceneEntity)>()
        .iter(world)
        .map(|(e, id)| (id.0.clone(), e))
        .collect();
    attach_contact_graph(world, &graph, &by_id)
        .map_err(|problem| IsceneError::Internal(format!("CAD replacement: {problem}")))?;
    let mean_alignment_error_m = (!replaced.is_empty())
        .then(|| replaced.iter().map(|r| r.alignment_error_m).sum::<f32>() / replaced.len() as f32);
    let align_method = world.get_resource_or_init::<CadAlignMethod>().0;
    let rejected = world
        .get_resource::<CadRejections>()
        .map(|r| r.0.clone())
        .unwrap_or_default();
    world.insert_resource(CadReport {
        align_method,
        database_models: db.len(),
        rejected,
        objects: object_count,
        swapped: replaced.iter().filter(|r| r.check.chosen > 0).count(),
        conflicted: unplaced.iter().map(|r| r.id.clone()).collect(),
        unplaced,
        replaced,
        mean_alignment_error_m,
    });
    world.resource_mut::<SceneContactGraph>().graph = graph;
    Ok(())
}

/// Adds the CadMatch, CadAlign and PhysicalCheck stages.
pub struct CadReplacementPlugin;

impl Plugin for CadReplacementPlugin {
    fn build(&self, app: &mut App) {
        use crate::systems::ReconstructionStage as Stage;
        app.add_systems(
            crate::systems::Reconstruct,
            (
                cad_match_stage.in_set(Stage::CadMatch),
                cad_align_stage.in_set(Stage::CadAlign),
                physical_check_stage
                    .pipe(record_failure)
                    .in_set(Stage::PhysicalCheck),
            ),
        );
    }
}
