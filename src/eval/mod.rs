//! `iscene eval DIR --gt SEQ`: scores a reconstruction against the ground truth of a rendered
//! sequence: panoptic quality and instance mAP, contact-graph and CAD figures; the physics
//! figures are `null` until their stages exist.

pub mod articulation;
pub mod cad;
pub mod chamfer;
pub mod contact;
pub mod ged;
pub mod pairing;
pub mod panoptic_quality;
pub mod symmetry;
pub mod truth;

use std::path::Path;

use serde::Serialize;

use crate::cad::db::database::CadDatabase;
use crate::classes::{ClassTable, EntityKind};
use crate::error::InputError;
use crate::io::Sequence;
use crate::io::ply::read_mesh_ply;
use crate::panoptic::panoptic_dir::{aligned_from_world_in, read_panoptic};
use panoptic_quality::{PanopticMetrics, Segment, evaluate};
use truth::NearestMesh;

use std::collections::{BTreeMap, HashSet};

use articulation::{ArticulationMetrics, evaluate_articulation, swept_ranges};
use cad::{CadMetrics, evaluate_cad};
use contact::{ContactMetrics, evaluate_contact_graph, seen_subgraph};

use crate::graph::ContactGraph;

/// Truth segments with fewer evaluated voxels than this are void: too little of them was seen
/// to ask for a match.
const MIN_TRUTH_VOXELS: usize = 10;

#[derive(Clone, Debug, Serialize)]
pub struct EvalReport {
    #[serde(flatten)]
    pub panoptic: PanopticMetrics,
    /// Metres: evaluated voxels farther than this from every truth mesh are void.
    pub truth_distance_m: f32,
    pub obb_map50: Option<f64>,
    /// Graph edit distance to the truth's contact graph (unit costs).
    pub ged: Option<u32>,
    /// Whether `ged` is exact (small graphs) or the bipartite upper bound.
    pub ged_exact: Option<bool>,
    /// Per-class box AP and the truth nodes left out as unseen.
    pub contact_graph: Option<ContactMetrics>,
    /// Of the objects whose front matters: the share whose model yaw is within 15 degrees.
    pub cad_yaw_accuracy: Option<f64>,
    /// Per object: the paired prediction, its model, class, yaw error and alignment error.
    pub cad: Option<CadMetrics>,
    pub cad_class_accuracy: Option<f64>,
    /// The fit's own residual (kept under its first name; `fit_residual_m` is the same).
    pub mean_alignment_error: Option<f64>,
    pub fit_residual_m: Option<f64>,
    /// Mean symmetric Chamfer distance between placed models and the truth's meshes, metres.
    pub cad_chamfer_m: Option<f64>,
    /// The reconstruction's own rest-test verdicts (report.json): the share of objects stable.
    pub stable_fraction: Option<f64>,
    pub max_penetration_m: Option<f64>,
    /// The edit distance where a predicted node stands for a truth node only where it is.
    pub ged_positional: Option<u32>,
    pub articulation_precision: Option<f64>,
    pub articulation_recall: Option<f64>,
    pub articulation_f1: Option<f64>,
    /// Every door and drawer of the truth and what stands for it.
    pub articulation: Option<Vec<articulation::PartScore>>,
}

pub fn evaluate_reconstruction(dir: &Path, gt: &Path) -> Result<EvalReport, InputError> {
    let (index, voxels) = read_panoptic(&dir.join("panoptic"))?;
    let sequence = Sequence::open(gt)?;
    let Some(labels) = &sequence.labels else {
        return Err(InputError::missing(
            gt.join("labels.json"),
            "evaluation needs a rendered sequence with ground truth (iscene render)",
        ));
    };
    let mut truth = Vec::new();
    let mut meshes = Vec::new();
    for entry in labels.by_instance().values() {
        let path = gt
            .join("gt")
            .join("meshes")
            .join(format!("{}.ply", entry.entity));
        if !path.is_file() {
            return Err(InputError::missing(
                &path,
                "ground-truth mesh of a labelled entity",
            ));
        }
        meshes.push(read_mesh_ply(&path)?);
        truth.push(Segment {
            name: entry.entity.clone(),
            class: entry.class.clone(),
            score: 1.0,
        });
    }
    let truth_distance_m = (2.0 * index.voxel_size).max(0.04);
    let points: Vec<glam::Vec3> = voxels.iter().map(|(p, _)| *p).collect();
    let mut truth_of = NearestMesh::new(&meshes, truth_distance_m).label_points(&points);
    let mut size = vec![0usize; truth.len() + 1];
    for &t in &truth_of {
        size[t as usize] += 1;
    }
    for t in &mut truth_of {
        if size[*t as usize] < MIN_TRUTH_VOXELS {
            *t = 0;
        }
    }
    let seen: HashSet<String> = truth
        .iter()
        .enumerate()
        .filter(|(i, _)| size[i + 1] >= MIN_TRUTH_VOXELS)
        .map(|(_, t)| t.name.clone())
        .collect();
    let pred_of: Vec<u32> = voxels.iter().map(|(_, e)| *e).collect();
    let pred: Vec<Segment> = index
        .entities
        .iter()
        .map(|e| Segment {
            name: e.id.clone(),
            class: e.class.clone(),
            score: e.score,
        })
        .collect();
    let table = ClassTable::builtin();
    let panoptic = evaluate(&truth_of, &pred_of, &truth, &pred, |class| {
        table
            .get(class)
            .is_some_and(|c| c.kind != EntityKind::Layout)
    });
    let scores: BTreeMap<String, f32> = index
        .entities
        .iter()
        .map(|e| (e.id.clone(), e.score))
        .collect();
    let truth_meshes: BTreeMap<String, crate::geometry::TriMesh> =
        truth.iter().map(|t| t.name.clone()).zip(meshes).collect();
    let report = read_report(&dir.join("report.json"))?;
    let (contact, cad, articulation) =
        match contact_metrics(dir, gt, &seen, &scores, &truth_meshes, &report)? {
            Some((c, cad, a)) => (Some(c), cad, Some(a)),
            None => (None, None, None),
        };
    let stable_fraction = report
        .pointer("/physics/stable_fraction")
        .and_then(serde_json::Value::as_f64);
    Ok(EvalReport {
        panoptic,
        truth_distance_m,
        obb_map50: contact.as_ref().map(|c| c.obb_map50),
        ged: contact.as_ref().map(|c| c.ged.cost),
        ged_exact: contact.as_ref().map(|c| c.ged.exact),
        ged_positional: contact.as_ref().map(|c| c.ged_positional.cost),
        contact_graph: contact,
        cad_class_accuracy: cad.as_ref().map(|c| c.class_accuracy),
        mean_alignment_error: cad.as_ref().and_then(|c| c.mean_alignment_error_m),
        fit_residual_m: cad.as_ref().and_then(|c| c.mean_alignment_error_m),
        cad_chamfer_m: cad.as_ref().and_then(|c| c.mean_chamfer_m),
        articulation_precision: articulation.as_ref().and_then(|a| a.precision),
        articulation_recall: articulation.as_ref().and_then(|a| a.recall),
        articulation_f1: articulation.as_ref().and_then(|a| a.f1),
        articulation: articulation.map(|a| a.parts),
        cad_yaw_accuracy: cad.as_ref().and_then(|c| c.yaw_accuracy),
        max_penetration_m: cad.as_ref().and_then(|c| c.max_penetration_m),
        cad,
        stable_fraction,
    })
}

/// Contact-graph and CAD metrics when both the reconstruction and the truth have a contact
/// graph (CAD ones when the reconstruction placed models).
fn contact_metrics(
    dir: &Path,
    gt: &Path,
    seen: &HashSet<String>,
    scores: &BTreeMap<String, f32>,
    truth_meshes: &BTreeMap<String, crate::geometry::TriMesh>,
    report: &serde_json::Value,
) -> Result<Option<(ContactMetrics, Option<CadMetrics>, ArticulationMetrics)>, InputError> {
    let pred_path = dir.join("contact_graph.json");
    let truth_path = gt.join("gt").join("contact_graph.json");
    if !pred_path.is_file() || !truth_path.is_file() {
        return Ok(None);
    }
    let pred = ContactGraph::load(&pred_path)?;
    let truth = ContactGraph::load(&truth_path)?;
    let unseen: Vec<String> = truth
        .nodes
        .iter()
        .filter(|n| !seen.contains(&n.id))
        .map(|n| n.id.clone())
        .collect();
    let truth = seen_subgraph(&truth, seen);
    let truth_from_pred = aligned_from_world_in(report, &dir.join("report.json"))?.inverse();
    let db = CadDatabase::for_scene(dir)?;
    let cad = evaluate_cad(&pred, &truth, &truth_from_pred, &db, truth_meshes);
    let articulation =
        evaluate_articulation(&pred, &truth, &truth_from_pred, &db, &swept_ranges(report));
    let contact = evaluate_contact_graph(&pred, &truth, &truth_from_pred, scores, unseen);
    Ok(Some((contact, cad, articulation)))
}

/// `report.json` of a reconstruction (`null` when it has none).
fn read_report(path: &Path) -> Result<serde_json::Value, InputError> {
    if !path.is_file() {
        return Ok(serde_json::Value::Null);
    }
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    serde_json::from_str(&text).map_err(|e| InputError::invalid(path, format!("invalid JSON: {e}")))
}
