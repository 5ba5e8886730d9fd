//! `iscene eval DIR --gt SEQ`: scores a reconstruction against the ground truth of a rendered
//! sequence. Panoptic quality and instance mAP for now; the contact-graph, CAD and physics
//! figures of the report are `null` until their stages exist.

pub mod panoptic_quality;
pub mod truth;

use std::path::Path;

use serde::Serialize;

use crate::classes::{ClassTable, EntityKind};
use crate::error::InputError;
use crate::io::Sequence;
use crate::io::panoptic_dir::read_panoptic;
use crate::io::ply::read_mesh_ply;
use panoptic_quality::{PanopticMetrics, Segment, evaluate};
use truth::NearestMesh;

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
    pub ged: Option<f64>,
    pub cad_class_accuracy: Option<f64>,
    pub mean_alignment_error: Option<f64>,
    pub stable_fraction: Option<f64>,
    pub max_penetration_m: Option<f64>,
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
    Ok(EvalReport {
        panoptic,
        truth_distance_m,
        obb_map50: None,
        ged: None,
        cad_class_accuracy: None,
        mean_alignment_error: None,
        stable_fraction: None,
        max_penetration_m: None,
    })
}
