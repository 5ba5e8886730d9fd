//! Objects no model of the database fits (issue 36, section 2): an object of an articulated
//! class whose clear front shows doors and drawers where no aligned candidate has a single handle
//! gets a model built from its box and those parts (`cad::library::perceived`) as one more
//! candidate, chosen by the same score as the database's.
//!
//! Only then: on held-out rooms (`iscene benchmark`) a model built whenever no candidate agreed
//! with half of the perceived handles lost to the library's true model in 3 of 20 rooms, where a
//! handle was missed or an open door's edge read as one (articulation F1 0.803 to 0.705 on seeds
//! 10-19, docs/cad_replacement.md).

use glam::Vec3;
use rayon::prelude::*;

use crate::cad::db::database::{CadDatabase, DatabaseModel};
use crate::cad::library::perceived::perceived_model;
use crate::cad::replace::alignment::{
    Alignment, alignment_error, choice_score, placed_layout_error,
};
use crate::cad::replace::matching::{Candidate, ObservedObject};

/// A candidate's layout error below this pairs at least one handle with a perceived one.
const SOME_HANDLE_PAIRED: f32 = 1.0 - 1e-4;

/// For every object (in `objects`' order) with a clear front (`PerceivedFront::clear`) where
/// none of its `alignments` pairs a handle with a perceived one, the model built from its
/// perceived parts, aligned and sorted in among its alignments by
/// [`choice_score`]; the candidates of such models index past `db`'s models, in the order of the
/// returned models (`db.with_models(returned)` holds them all).
pub fn add_perceived_models(
    objects: &[ObservedObject],
    db: &CadDatabase,
    alignments: &mut [Vec<Alignment>],
) -> Vec<DatabaseModel> {
    let built: Vec<Option<(DatabaseModel, Alignment)>> = objects
        .par_iter()
        .zip(alignments.par_iter())
        .map(|(object, aligned)| {
            let clear = object.front.as_ref().is_some_and(|f| f.clear);
            let some_fit = aligned.iter().any(|a| a.layout_error < SOME_HANDLE_PAIRED);
            if !clear || some_fit {
                return None;
            }
            perceived_alignment(object)
        })
        .collect();
    let mut models = Vec::new();
    for ((model, mut alignment), aligned) in built
        .into_iter()
        .zip(alignments.iter_mut())
        .filter_map(|(b, a)| Some((b?, a)))
    {
        alignment.candidate.model = db.len() + models.len();
        models.push(model);
        aligned.push(alignment);
        // A stable sort: equal scores keep the database's candidates first.
        aligned.sort_by(|a, b| choice_score(a).total_cmp(&choice_score(b)));
    }
    models
}

/// The model built from `object`'s perceived parts, placed on its box, with its alignment
/// (its candidate's model index left 0 for the caller to set); `None` without perceived parts.
fn perceived_alignment(object: &ObservedObject) -> Option<(DatabaseModel, Alignment)> {
    let front = object.front.as_ref()?;
    let (model, world_from_model) = perceived_model(object.id, object.class, &object.bbox, front)?;
    let model = DatabaseModel::new(model)
        .inspect_err(|e| tracing::warn!("{}: the model of its perceived parts: {e}", object.id))
        .ok()?;
    let alignment_error = alignment_error(&object.points, &model, &world_from_model)?;
    let facing_error = object.facing.map_or(0.0, |f| {
        f.error(world_from_model.transform_vector3(-Vec3::Y))
    });
    let layout_error = placed_layout_error(object, &model, &world_from_model);
    let alignment = Alignment {
        candidate: Candidate {
            model: 0,
            orientation: 0,
            matching_error: 0.0,
            upright_error: 0.0,
            facing_error,
        },
        world_from_model,
        scale: Vec3::ONE,
        alignment_error,
        layout_error,
    };
    Some((model, alignment))
}
