//! The CadMatch, CadAlign and PhysicalCheck stages: rank the database's models for every object
//! of the contact graph, align the best candidates to the object's observed surface, choose
//! among them so the models neither interpenetrate nor overhang their supports, snap them on,
//! and let each chosen model's frame become its entity's frame in the transform tree. Each
//! stage leaves its result on the object's entity (`CadCandidates`, `ShapeRejection`,
//! `CadAlignments`, `CadModel`); the Bevy-free algorithms of `cad::replace` read the contact
//! graph the entities hold (`SceneNodes`) and return what they decided, which the stage puts on
//! the entities.

use std::collections::HashMap;
use std::sync::Arc;

use bevy::prelude::*;
use serde::Serialize;

use crate::cad::db::database::CadDatabase;
use crate::cad::replace::alignment::{Alignment, choice_score};
use crate::cad::replace::matching::{Candidate, ObservedObject};
use crate::cad::replace::observed_objects::observed_objects;
use crate::cad::replace::replacement::{
    AlignMethod, ReplacementRecord, align_scene_reusing, check_and_place, rank_scene,
};
use crate::cad::replace::shape_filter::{Rejection, layout_planes, rejection};
use crate::cad::replace::synthesis::add_perceived_candidates;
use crate::components::{
    CadAlignments, CadCandidates, CadModel, ObservedSurface, PerceivedFront, SceneEntity,
    ShapeRejection,
};
use crate::geometry::GravityBox;
use crate::perception::front_marks::{FrontMarks, marks_seen};
use crate::perception::front_texture::{View, ViewImages};
use crate::perception::fronts::fitted_to_front;
use crate::systems::contact_graph::SceneGravity;
use crate::systems::ingest::InputSequence;
use crate::systems::scene_graph::hang_frames;
use crate::systems::scene_nodes::SceneNodes;

/// The database replacement chooses from (the parametric library unless one is given).
#[derive(Resource, Clone)]
pub struct CadLibrary(pub Arc<CadDatabase>);

/// The models CadAlign's alignments refer to: the database replacement chooses from and, after
/// its models, the mirrored and built ones the perceived parts asked for.
#[derive(Resource, Clone)]
pub struct AlignedModels(pub Arc<CadDatabase>);

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

/// What replacement did, for report.json.
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
    /// The fronts perceived on objects of articulated classes, with their handles.
    pub fronts: Vec<FrontRecord>,
}

/// The front perceived on one object.
#[derive(Clone, Debug, Serialize)]
pub struct FrontRecord {
    pub id: String,
    #[serde(flatten)]
    pub front: crate::perception::fronts::PerceivedFront,
}

/// Each entity id's observed surface points.
fn observed_points<'a>(
    surfaces: impl IntoIterator<Item = (&'a SceneEntity, &'a ObservedSurface)>,
) -> HashMap<String, Vec<Vec3>> {
    surfaces
        .into_iter()
        .map(|(id, surface)| (id.0.clone(), surface.0.clone()))
        .collect()
}

/// The replacement database, the parametric library unless the caller gave one.
fn library(commands: &mut Commands, given: Option<Res<CadLibrary>>) -> Arc<CadDatabase> {
    match given {
        Some(library) => library.0.clone(),
        None => {
            let db = Arc::new(CadDatabase::parametric());
            commands.insert_resource(CadLibrary(db.clone()));
            db
        }
    }
}

/// What the frames show of the fronts on which the map's handles open no part, by object id
/// (`perception::front_marks`): CadMatch reads them once, CadAlign perceives the fronts with them
/// again.
#[derive(Resource, Clone, Debug, Default)]
pub struct SeenFrontMarks(pub HashMap<String, FrontMarks>);

/// The marks the frames of `sequence` show on the clear fronts of `objects` on which the map's
/// handles open no part.
fn marks_from_frames(
    objects: &[ObservedObject],
    sequence: &crate::io::sequence::Sequence,
    gravity: &SceneGravity,
) -> HashMap<String, FrontMarks> {
    let aligned_from_world = gravity.0.aligned_from_world();
    let views: Vec<View> = sequence
        .frames
        .iter()
        .enumerate()
        .map(|(frame, record)| View {
            frame,
            world_from_camera: aligned_from_world * record.world_from_camera,
        })
        .collect();
    let load = |frame: usize| {
        sequence
            .load_frame(frame)
            .inspect_err(|e| tracing::warn!("a front's image: {e}"))
            .ok()
            .map(|f| ViewImages {
                color: f.color,
                depth: f.depth,
            })
    };
    objects
        .iter()
        .filter_map(|o| {
            let front = o.front.as_ref()?;
            if !front.clear || !front.parts.is_empty() {
                return None;
            }
            let marks = marks_seen(front, &sequence.camera, &views, load)?;
            tracing::debug!("{}: its image shows {marks:?}", o.id);
            Some((o.id.to_string(), marks))
        })
        .collect()
}

/// CadMatch: every object either rejected by the shape filters or given its ranked candidates.
fn cad_match_stage(
    mut commands: Commands,
    nodes: SceneNodes,
    surfaces: Query<(&SceneEntity, &ObservedSurface)>,
    given: Option<Res<CadLibrary>>,
    method: Res<CadAlignMethod>,
    (sequence, gravity): (Option<Res<InputSequence>>, Res<SceneGravity>),
) {
    let db = library(&mut commands, given);
    let graph = nodes.contact_graph();
    let points = observed_points(surfaces.iter());
    let entity_of = nodes.entities_by_id();
    let layout = layout_planes(&graph);
    // The fronts perceived in the map say which to read in the frames; only what the frames
    // showed asks for the objects again.
    let unmarked = observed_objects(&graph, &points, &HashMap::new());
    let marks = match sequence {
        Some(sequence) => marks_from_frames(&unmarked, &sequence.0, &gravity),
        None => HashMap::new(),
    };
    let observed = if marks.is_empty() {
        unmarked
    } else {
        observed_objects(&graph, &points, &marks)
    };
    let mut objects = Vec::new();
    for object in observed {
        if let Some(front) = &object.front {
            commands
                .entity(entity_of[object.id])
                .insert(PerceivedFront(front.clone()));
        }
        match rejection(&object, &layout) {
            Some(rejection) => {
                commands
                    .entity(entity_of[object.id])
                    .insert(ShapeRejection(rejection));
            }
            None => objects.push(object),
        }
    }
    let ranked = rank_scene(&objects, &db, method.0);
    for (object, candidates) in objects.iter().zip(ranked) {
        commands
            .entity(entity_of[object.id])
            .insert(CadCandidates(candidates));
    }
    commands.insert_resource(SeenFrontMarks(marks));
}

/// CadAlign: every object's candidates aligned to its observed surface (a rejected object gets
/// none), reusing a live session's earlier alignments of objects that have not changed, and the
/// candidates the perceived parts ask for (mirrored models, a model built from the parts).
fn cad_align_stage(
    mut commands: Commands,
    nodes: SceneNodes,
    surfaces: Query<(&SceneEntity, &ObservedSurface)>,
    candidates: Query<&CadCandidates>,
    library: Res<CadLibrary>,
    method: Res<CadAlignMethod>,
    (cache, marks): (
        Option<ResMut<CadAlignmentCache>>,
        Option<Res<SeenFrontMarks>>,
    ),
) {
    let graph = nodes.contact_graph();
    let points = observed_points(surfaces.iter());
    let entity_of = nodes.entities_by_id();
    let objects = observed_objects(
        &graph,
        &points,
        &marks.map(|m| m.0.clone()).unwrap_or_default(),
    );
    let ranked: Vec<Vec<Candidate>> = objects
        .iter()
        .map(|o| {
            candidates
                .get(entity_of[o.id])
                .map(|c| c.0.clone())
                .unwrap_or_default()
        })
        .collect();
    let mut aligned = align_scene_reusing(&objects, &library.0, &ranked, method.0, |o| {
        cache.as_ref().and_then(|c| c.reuse(o))
    });
    if let Some(mut cache) = cache {
        cache.0 = objects
            .iter()
            .zip(&aligned)
            .map(|(o, a)| (o.id.to_string(), (o.class.to_string(), o.bbox, a.clone())))
            .collect();
    }
    // After the cache took the database's alignments: the built models' indices hold for this
    // pass only.
    let perceived = add_perceived_candidates(&objects, &library.0, &mut aligned);
    let models = if perceived.is_empty() {
        library.0.clone()
    } else {
        Arc::new(library.0.with_models(perceived))
    };
    for (object, alignments) in objects.iter().zip(&aligned) {
        log_leading_choices(object, &models, alignments);
    }
    commands.insert_resource(AlignedModels(models));
    for (object, alignments) in objects.iter().zip(aligned) {
        commands
            .entity(entity_of[object.id])
            .insert(CadAlignments(alignments));
    }
}

/// How many of an object's alignments the debug log lists.
const LOGGED_CHOICES: usize = 4;

/// The leading alignments of `object` and what their choice scores are made of, at debug level
/// (`RUST_LOG=iscene=debug`): why one model won over another.
fn log_leading_choices(object: &ObservedObject, models: &CadDatabase, alignments: &[Alignment]) {
    if !tracing::enabled!(tracing::Level::DEBUG) {
        return;
    }
    for a in alignments.iter().take(LOGGED_CHOICES) {
        let model = models
            .models()
            .get(a.candidate.model)
            .map_or("?", |m| m.model.id.as_str());
        tracing::debug!(
            "{}: {model} score {:.4} = alignment {:.4}, facing {:.2}, upright {:.2}, layout {:.2}",
            object.id,
            choice_score(a),
            a.alignment_error,
            a.candidate.facing_error,
            a.candidate.upright_error,
            a.layout_error,
        );
    }
}

/// PhysicalCheck: chooses among each object's alignments so the models neither interpenetrate
/// nor overhang their supports, gives the placed objects their `CadModel`s, and reports what
/// replacement did. `hang_frames` runs after it: a placed object's frame becomes its model's,
/// and a movable one floats on its support.
fn physical_check_stage(
    mut commands: Commands,
    nodes: SceneNodes,
    surfaces: Query<(&SceneEntity, &ObservedSurface)>,
    aligned: Query<&CadAlignments>,
    findings: Query<(Option<&ShapeRejection>, Option<&PerceivedFront>)>,
    // What the alignments refer to, and the database searched (for the report's count).
    (aligned_models, library): (Option<Res<AlignedModels>>, Option<Res<CadLibrary>>),
    method: Res<CadAlignMethod>,
) {
    let Some(db) = aligned_models.map(|l| l.0.clone()) else {
        return;
    };
    let graph = nodes.contact_graph();
    let entity_of = nodes.entities_by_id();
    // Each placement's residual is measured on what its model was fitted to: an open door's or
    // drawer's points are no part of the closed model.
    let points: HashMap<String, Vec<Vec3>> = observed_points(surfaces.iter())
        .into_iter()
        .map(|(id, p)| {
            let front = entity_of
                .get(id.as_str())
                .and_then(|e| findings.get(*e).ok()?.1);
            let fitted = match (graph.node(&id), front) {
                (Some(n), Some(f)) => fitted_to_front(&GravityBox::from(&n.bbox), Some(&f.0), &p)
                    .1
                    .into_owned(),
                _ => p,
            };
            (id, fitted)
        })
        .collect();
    let order = nodes.entities();
    // The aligned objects, in the graph's order (CadAlign's).
    let (ids, options): (Vec<String>, Vec<Vec<Alignment>>) = order
        .iter()
        .filter_map(|&e| Some((nodes.id(e)?.to_string(), aligned.get(e).ok()?.0.clone())))
        .unzip();
    let rejected: Vec<RejectedObject> = order
        .iter()
        .filter_map(|&e| {
            Some(RejectedObject {
                id: nodes.id(e)?.to_string(),
                rejection: findings.get(e).ok()?.0?.0.clone(),
            })
        })
        .collect();
    let fronts: Vec<FrontRecord> = order
        .iter()
        .filter_map(|&e| {
            Some(FrontRecord {
                id: nodes.id(e)?.to_string(),
                front: findings.get(e).ok()?.1?.0.clone(),
            })
        })
        .collect();
    let object_count = graph
        .nodes
        .iter()
        .filter(|n| n.kind != crate::classes::EntityKind::Layout)
        .count();
    let placements = check_and_place(&graph, &db, &ids, &options, &points);
    let (replaced, unplaced): (Vec<_>, Vec<_>) = placements
        .records
        .into_iter()
        .partition(|r| r.check.conflicts == 0);
    commands.insert_resource(SceneModels(Arc::new(db.with_models(placements.built))));
    for (id, placement) in &placements.placed {
        commands
            .entity(entity_of[id])
            .insert(CadModel::from(placement));
    }
    let mean_alignment_error_m = (!replaced.is_empty())
        .then(|| replaced.iter().map(|r| r.alignment_error_m).sum::<f32>() / replaced.len() as f32);
    commands.insert_resource(CadReport {
        align_method: method.0,
        database_models: library.map_or(db.len(), |l| l.0.len()),
        rejected,
        objects: object_count,
        swapped: replaced.iter().filter(|r| r.check.chosen > 0).count(),
        conflicted: unplaced.iter().map(|r| r.id.clone()).collect(),
        unplaced,
        replaced,
        mean_alignment_error_m,
        fronts,
    });
}

/// Adds the CadMatch, CadAlign and PhysicalCheck stages.
pub struct CadReplacementPlugin;

impl Plugin for CadReplacementPlugin {
    fn build(&self, app: &mut App) {
        use crate::systems::ReconstructionStage as Stage;
        // The stages run once the ContactGraph stage has built the graph.
        let graph_built = resource_exists::<SceneGravity>;
        app.init_resource::<CadAlignMethod>().add_systems(
            crate::systems::Reconstruct,
            (
                cad_match_stage.run_if(graph_built).in_set(Stage::CadMatch),
                cad_align_stage.run_if(graph_built).in_set(Stage::CadAlign),
                (physical_check_stage, hang_frames)
                    .chain()
                    .run_if(graph_built)
                    .in_set(Stage::PhysicalCheck),
            ),
        );
    }
}
