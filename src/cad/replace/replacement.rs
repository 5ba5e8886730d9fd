//! CAD replacement of a whole scene: the objects of a contact graph with their observed surface
//! points, ranked against the database, aligned, checked together for physical plausibility, and
//! written back into the graph's nodes.

use std::collections::HashMap;

use glam::{Affine3A, Mat4, Vec3};
use rayon::prelude::*;
use serde::Serialize;

use crate::cad::db::database::{CadDatabase, DatabaseModel};
use crate::cad::replace::alignment::{Alignment, align_all, alignment_error, choice_score};
use crate::cad::replace::icp;
use crate::cad::replace::matching::{Candidate, KEEP_CANDIDATES, ObservedObject, rank_candidates};
use crate::cad::replace::physical_check::{Holder, PlacedSolid, PlacementCheck, check_placements};
use crate::cad::replace::sizing::pose_scale;
use crate::classes::{ClassTable, EntityKind};
use crate::geometry::{GravityBox, Plane};
use crate::graph::build::COUNTER_CLASS;
use crate::graph::{CadPlacement, ContactGraph};

/// How candidates are chosen and aligned (`--align`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum AlignMethod {
    /// Han et al.: the 10 best of the ranking by matching error, aligned by Levenberg-Marquardt
    /// over per-axis scale, yaw and translation.
    #[default]
    Lm,
    /// Sivananda et al.: every model of the class, a yaw sweep, then ICP over yaw, floor
    /// position and width and depth scales ([`icp`]).
    Icp,
}

/// The candidates of every object (CadMatch): the ranking's best, or for ICP every model of the
/// class.
pub fn rank_scene(
    objects: &[ObservedObject],
    db: &CadDatabase,
    method: AlignMethod,
) -> Vec<Vec<Candidate>> {
    objects
        .par_iter()
        .map(|o| match method {
            AlignMethod::Lm => rank_candidates(o, db, KEEP_CANDIDATES),
            AlignMethod::Icp => icp::class_candidates(o, db),
        })
        .collect()
}

/// Every object's candidates aligned, best first (CadAlign); empty where none could be.
pub fn align_scene(
    objects: &[ObservedObject],
    db: &CadDatabase,
    candidates: &[Vec<Candidate>],
    method: AlignMethod,
) -> Vec<Vec<Alignment>> {
    align_scene_reusing(objects, db, candidates, method, |_| None)
}

/// [`align_scene`], taking an object's alignments from `reuse` where it has them.
pub fn align_scene_reusing(
    objects: &[ObservedObject],
    db: &CadDatabase,
    candidates: &[Vec<Candidate>],
    method: AlignMethod,
    reuse: impl Fn(&ObservedObject) -> Option<Vec<Alignment>> + Sync,
) -> Vec<Vec<Alignment>> {
    objects
        .par_iter()
        .zip(candidates)
        .map(|(o, c)| {
            reuse(o).unwrap_or_else(|| match method {
                AlignMethod::Lm => align_all(o, db, c),
                AlignMethod::Icp => icp::align_all(o, db, c),
            })
        })
        .collect()
}

/// The physical check may choose a candidate whose choice score (AE plus priors) exceeds the
/// best's by this share of it, or by `SWAP_SLACK_M`, whichever is more.
const SWAP_SLACK_RATIO: f32 = 0.5;
const SWAP_SLACK_M: f32 = 0.01;

/// What the physical check placed: every checked object's record, the placement of each object
/// placed without conflict (by id, in the order of the ids checked), and the library models it
/// built to an object's size that a placement uses (the database does not hold them).
pub struct Placements {
    pub records: Vec<ReplacementRecord>,
    pub placed: Vec<(String, CadPlacement)>,
    pub built: Vec<DatabaseModel>,
}

/// One object's replacement, as report.json lists it.
#[derive(Clone, Debug, Serialize)]
pub struct ReplacementRecord {
    pub id: String,
    pub model: String,
    pub alignment_error_m: f32,
    pub matching_error: f32,
    /// Per model axis, relative to the database's model: the stretch of an imported model, or
    /// the size a library model was built to over its nominal size.
    pub scale: [f32; 3],
    /// The physical check's verdict on the final placement.
    #[serde(flatten)]
    pub check: PlacementCheck,
}

/// The global physical check (PhysicalCheck): chooses among the aligned candidates of the
/// objects `ids` (`alignments`, best first) so that models neither interpenetrate nor overhang
/// their supports, snaps them onto what holds them (as `graph`'s support edges say), and returns
/// each placement (the scale there is the geometric mean of what is left in `world_from_model`:
/// a library model is built to its fitted size instead, and the models so built that placements
/// use are returned beside the records) with its alignment error measured again on `points`
/// (the check moves models by millimetres to centimetres). An object whose final placement
/// still conflicts gets no placement and keeps its segment mesh,
/// which every simulator holds still: a model left 10 cm inside a counter, or on nothing,
/// would fly off at the first step (a chair in the knee space between two counters, a book on
/// a chair-shaped segment of label bleeding, in 7-Scenes redkitchen). Its record is returned
/// all the same, with the conflicts.
pub fn check_and_place(
    graph: &ContactGraph,
    db: &CadDatabase,
    ids: &[String],
    alignments: &[Vec<Alignment>],
    points: &HashMap<String, Vec<Vec3>>,
) -> Placements {
    let layout_plane = |id: &str| {
        graph
            .node(id)
            .and_then(|n| n.planes.first())
            .map(|p| Plane::from_array(*p))
    };
    let floor = layout_plane("floor");
    let layout: Vec<Plane> = graph
        .nodes
        .iter()
        .filter(|n| n.class == "wall" || n.class == "floor")
        .filter_map(|n| layout_plane(&n.id))
        .collect();
    // The objects no model replaces keep their segment meshes (simulators collide them as the
    // pieces of what was seen, `kinematics::link::observed_surface`), here their boxes: the
    // models must not enter those either (chairs tucked under a counter that no model
    // replaced), and what stands on one is snapped onto its top.
    // A counter's solid is its own (`graph::build`): what no model replaced reaches into it only
    // by its label bleeding down the counter's front, and stands above its top.
    let counters: Vec<(&str, GravityBox)> = graph
        .nodes
        .iter()
        .filter(|n| n.class == COUNTER_CLASS)
        .map(|n| (n.id.as_str(), GravityBox::from(&n.bbox)))
        .collect();
    let (obstacle_ids, obstacles): (Vec<&str>, Vec<PlacedSolid>) = graph
        .nodes
        .iter()
        .filter(|n| n.kind != EntityKind::Layout)
        .filter(|n| {
            ids.iter()
                .position(|id| *id == n.id)
                .is_none_or(|i| alignments[i].is_empty())
        })
        .filter_map(|n| {
            let others = counters
                .iter()
                .filter(|(id, _)| *id != n.id)
                .map(|(_, c)| c);
            let gbox = above_counters(GravityBox::from(&n.bbox), others)?;
            let solid = PlacedSolid::from_hull(&gbox.corners())?;
            Some((n.id.as_str(), solid))
        })
        .unzip();
    let holders: Vec<Holder> = ids
        .iter()
        .map(|id| match graph.parent_of(id) {
            Some("floor") => floor.map_or(Holder::Other, Holder::Floor),
            Some(parent) => match ids.iter().position(|o| o == parent) {
                Some(p) if !alignments[p].is_empty() => Holder::Object(p),
                _ => obstacle_ids
                    .iter()
                    .position(|o| *o == parent)
                    .map_or(Holder::Other, Holder::Obstacle),
            },
            None => Holder::Other,
        })
        .collect();
    // Only candidates that explain the points about as well as the best may replace it: a
    // table lying on its side conflicts with nothing, and explains nothing. But when none of
    // those stands by itself (a mug seen from above, fitted best lying on its side), the best
    // that does is tried as well: a worse fit beats one that rolls over.
    let picked: Vec<Vec<usize>> = alignments
        .iter()
        .map(|list| {
            let best = list.first().map_or(0.0, choice_score);
            let stands = |k: &usize| {
                let a = &list[*k];
                PlacedSolid::new(&db.models()[a.candidate.model], &a.world_from_model).stands()
            };
            let close = list
                .iter()
                .take_while(|a| {
                    choice_score(a) <= best + (SWAP_SLACK_RATIO * best).max(SWAP_SLACK_M)
                })
                .count();
            let mut picked: Vec<usize> = (0..close).collect();
            if !picked.iter().any(stands)
                && let Some(standing) = (close..list.len()).find(stands)
            {
                picked.push(standing);
            }
            picked
        })
        .collect();
    let options: Vec<Vec<(&DatabaseModel, Affine3A)>> = picked
        .iter()
        .zip(alignments)
        .map(|(picked, list)| {
            picked
                .iter()
                .map(|&k| {
                    (
                        &db.models()[list[k].candidate.model],
                        list[k].world_from_model,
                    )
                })
                .collect()
        })
        .collect();
    let table = ClassTable::builtin();
    let movable: Vec<bool> = ids
        .iter()
        .map(|id| {
            graph
                .node(id)
                .and_then(|n| table.get(&n.class))
                .is_some_and(|c| c.movable)
        })
        .collect();
    let obstacle_holders: Vec<Option<usize>> = obstacle_ids
        .iter()
        .map(|id| {
            let parent = graph.parent_of(id)?;
            ids.iter().position(|o| o == parent)
        })
        .collect();
    let checked = check_placements(
        &options,
        &holders,
        &movable,
        &layout,
        &obstacles,
        &obstacle_holders,
    );
    let mut records = Vec::new();
    let mut placed = Vec::new();
    let mut built = Vec::new();
    for (i, id) in ids.iter().enumerate() {
        let (Some((k, pose)), Some(check)) = (checked.chosen[i], checked.checks[i].clone()) else {
            continue;
        };
        if graph.node(id).is_none() {
            continue;
        }
        let a = &alignments[i][picked[i][k]];
        let sized = checked.built[i].as_ref();
        let entry = sized.unwrap_or(options[i][k].0);
        let model = &entry.model;
        // Relative to the database's model, whether stretched or built to this size.
        let scale = pose_scale(&pose) * model.size / options[i][k].0.model.size;
        let error = points
            .get(id)
            .and_then(|p| alignment_error(p, entry, &pose))
            .unwrap_or(a.alignment_error);
        if check.conflicts == 0 {
            placed.push((
                id.clone(),
                CadPlacement {
                    model: model.id.clone(),
                    world_from_model: Mat4::from(pose).to_cols_array(),
                    scale: pose_scale(&pose).element_product().cbrt(),
                    alignment_error: error,
                },
            ));
            built.extend(sized.cloned());
        }
        records.push(ReplacementRecord {
            id: id.clone(),
            model: model.id.clone(),
            alignment_error_m: error,
            matching_error: a.candidate.matching_error,
            scale: scale.to_array(),
            check,
        });
    }
    Placements {
        records,
        placed,
        built,
    }
}

/// `bbox` cut to above the top of the counter among `counters` its centre stands over, if it
/// reaches into one; `None` when nothing of it is left above.
fn above_counters<'a>(
    bbox: GravityBox,
    mut counters: impl Iterator<Item = &'a GravityBox>,
) -> Option<GravityBox> {
    let Some(counter) = counters.find(|c| c.contains(bbox.center.with_z(c.center.z), 0.0)) else {
        return Some(bbox);
    };
    let (bottom, top) = (bbox.bottom_z().max(counter.top_z()), bbox.top_z());
    (top > bottom).then(|| GravityBox {
        center: bbox.center.with_z(0.5 * (bottom + top)),
        size: bbox.size.with_z(top - bottom),
        ..bbox
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Affine3A;

    /// The rendered kitchen's ground-truth contact graph, without its models.
    fn kitchen_graph() -> ContactGraph {
        let mut graph = crate::scene::kitchen_contact_graph();
        for node in &mut graph.nodes {
            node.cad = None;
        }
        graph
    }

    /// `model` standing on the floor at `node`'s box centre, as the only candidate.
    fn standing_at(db: &CadDatabase, model: &str, graph: &ContactGraph, node: &str) -> Alignment {
        let index = db
            .models()
            .iter()
            .position(|m| m.model.id == model)
            .expect("model");
        let centre = Vec3::from_array(graph.node(node).expect("node").bbox.center);
        Alignment {
            candidate: Candidate {
                model: index,
                orientation: 0,
                matching_error: 0.1,
                upright_error: 0.0,
                facing_error: 0.0,
            },
            world_from_model: Affine3A::from_translation(centre.with_z(0.0)),
            scale: Vec3::ONE,
            alignment_error: 0.01,
            layout_error: 0.0,
        }
    }

    #[test]
    fn what_no_model_replaced_reaches_into_a_counter_only_above_its_top() {
        let counter = GravityBox {
            center: Vec3::new(0.0, 3.0, 0.46),
            yaw: 0.0,
            size: Vec3::new(1.8, 0.6, 0.92),
        };
        // A bottle on the counter whose label ran down its front to the floor (7-Scenes).
        let bled = GravityBox {
            center: Vec3::new(0.2, 2.95, 0.565),
            yaw: 0.3,
            size: Vec3::new(0.16, 0.11, 1.13),
        };
        let cut = above_counters(bled, [counter].iter()).expect("its top");
        assert!((cut.bottom_z() - 0.92).abs() < 1e-5 && (cut.top_z() - 1.13).abs() < 1e-5);
        // A chair beside the counter, and one inside it entirely, below its top.
        let beside = GravityBox {
            center: Vec3::new(1.2, 3.0, 0.4),
            ..bled
        };
        assert_eq!(above_counters(beside, [counter].iter()), Some(beside));
        let under = GravityBox {
            center: Vec3::new(0.0, 3.0, 0.3),
            size: Vec3::new(0.4, 0.4, 0.6),
            ..bled
        };
        assert_eq!(above_counters(under, [counter].iter()), None);
    }

    #[test]
    fn an_object_left_in_conflict_keeps_its_segment_and_its_record_names_the_conflict() {
        let db = CadDatabase::parametric();
        let graph = kitchen_graph();
        // chair_1's only candidate stands in the middle of the table (which no model replaces
        // here: an obstacle), far deeper than pulling apart may undo; chair_2's stands where
        // chair_2 is.
        let ids = vec!["chair_1".to_string(), "chair_2".to_string()];
        let alignments = vec![
            vec![standing_at(&db, "chair_01", &graph, "table_1")],
            vec![standing_at(&db, "chair_01", &graph, "chair_2")],
        ];
        let placements = check_and_place(&graph, &db, &ids, &alignments, &HashMap::new());
        let records = &placements.records;
        let record = |id: &str| records.iter().find(|r| r.id == id).expect("record");
        let placed = |id: &str| placements.placed.iter().any(|(p, _)| p == id);
        assert!(record("chair_1").check.conflicts > 0);
        assert!(record("chair_1").check.max_penetration_m > 0.1);
        assert!(!placed("chair_1"));
        assert_eq!(
            record("chair_2").check.conflicts,
            0,
            "{:?}",
            record("chair_2")
        );
        assert!(placed("chair_2"));
    }
}
