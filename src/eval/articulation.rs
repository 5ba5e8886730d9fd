//! Articulation against the truth: for every door and drawer of the truth (its model's joints,
//! placed in the world), the predicted part that stands for it, and whether it reproduces it:
//! joint type, axis, hinge line, the side it opens to, and how much of the truth's range the
//! predicted part can really move through in the reconstructed scene (its joint sweep).

use std::collections::BTreeMap;

use glam::{Affine3A, Vec3};
use serde::Serialize;

use crate::cad::db::database::CadDatabase;
use crate::cad::model_parts::model_parts;
use crate::eval::pairing::greedy_pairs;
use crate::graph::parts::{PartJointType, PartJson};
use crate::graph::{ContactGraph, GraphNode};

/// A predicted part may stand for a truth part when their fronts' centres are this close, metres.
pub const PAIR_DISTANCE_M: f32 = 0.3;
/// What "reproduced" asks: axis within this many degrees ...
pub const AXIS_TOLERANCE_DEG: f32 = 10.0;
/// ... a hinge line within this distance (revolute joints), metres ...
pub const HINGE_TOLERANCE_M: f32 = 0.05;
/// ... and at least this share of the truth's range free.
pub const MIN_FREE_SHARE: f32 = 0.8;

/// One truth part and the predicted part paired with it.
#[derive(Clone, Debug, Serialize)]
pub struct PartScore {
    /// `<truth node>/<part>`.
    pub truth: String,
    pub truth_type: PartJointType,
    /// `<predicted node>/<part>`, or `None` when nothing stands for it.
    pub predicted: Option<String>,
    pub type_correct: bool,
    pub axis_error_deg: Option<f32>,
    /// Revolute joints: how far the predicted hinge line passes from the truth's, at the height
    /// of the truth front's centre, metres.
    pub hinge_distance_m: Option<f32>,
    pub same_side: bool,
    /// The share of the truth's range the predicted part moves through freely.
    pub free_share: Option<f32>,
    pub reproduced: bool,
}

#[derive(Clone, Debug, Serialize)]
pub struct ArticulationMetrics {
    pub precision: Option<f64>,
    pub recall: Option<f64>,
    pub f1: Option<f64>,
    pub truth_parts: usize,
    pub predicted_parts: usize,
    pub parts: Vec<PartScore>,
}

/// The parts of a predicted node: those it lists, else its model's.
fn predicted_parts(node: &GraphNode, db: &CadDatabase) -> Vec<PartJson> {
    if !node.parts.is_empty() {
        return node.parts.clone();
    }
    let Some(cad) = &node.cad else {
        return Vec::new();
    };
    let Some(model) = db.get(&cad.model) else {
        return Vec::new();
    };
    let frame = Affine3A::from_mat4(glam::Mat4::from_cols_array(&cad.world_from_model));
    model_parts(&model.model, &frame)
}

/// The range a predicted link moves through freely, from the reconstruction's joint sweeps
/// (`report.json` physics.joints): narrowed where the sweep met something, nothing where it was
/// blocked, the whole range where it was free or not swept.
pub type SweptRanges = BTreeMap<String, Option<(f32, f32)>>;

/// Reads the sweeps of `report.json` (`None` for a report without them).
pub fn swept_ranges(report: &serde_json::Value) -> SweptRanges {
    let mut ranges = SweptRanges::new();
    let Some(joints) = report.pointer("/physics/joints").and_then(|j| j.as_array()) else {
        return ranges;
    };
    for j in joints {
        let Some(link) = j.get("link").and_then(|l| l.as_str()) else {
            continue;
        };
        let free = j.get("free").and_then(|f| f.as_bool()).unwrap_or(true);
        let reachable = j
            .get("reachable")
            .and_then(|r| r.as_array())
            .and_then(|r| Some((r.first()?.as_f64()? as f32, r.get(1)?.as_f64()? as f32)));
        let range = match (free, reachable) {
            (_, Some(r)) => Some(Some(r)),
            (true, None) => None,
            (false, None) => Some(None),
        };
        if let Some(r) = range {
            ranges.insert(link.to_string(), r);
        }
    }
    ranges
}

pub fn evaluate_articulation(
    pred: &ContactGraph,
    truth: &ContactGraph,
    truth_from_pred: &Affine3A,
    db: &CadDatabase,
    swept: &SweptRanges,
) -> ArticulationMetrics {
    let truth_parts: Vec<(String, PartJson)> = truth
        .nodes
        .iter()
        .flat_map(|n| n.parts.iter().map(move |p| (n.id.clone(), p.clone())))
        .collect();
    let pred_parts: Vec<(String, PartJson)> = pred
        .nodes
        .iter()
        .flat_map(|n| {
            predicted_parts(n, db)
                .into_iter()
                .map(move |p| (n.id.clone(), p.transformed(truth_from_pred)))
        })
        .collect();
    // Greedy pairing, nearest fronts first.
    let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
    for (t, (_, tp)) in truth_parts.iter().enumerate() {
        for (p, (_, pp)) in pred_parts.iter().enumerate() {
            let d = tp.front_center().distance(pp.front_center());
            if d <= PAIR_DISTANCE_M {
                pairs.push((d, t, p));
            }
        }
    }
    let pred_of = greedy_pairs(pairs, truth_parts.len(), pred_parts.len(), false);
    let parts: Vec<PartScore> = truth_parts
        .iter()
        .zip(&pred_of)
        .map(|((tid, tp), p)| {
            let paired = p.map(|p| &pred_parts[p]);
            score(tid, tp, paired, swept)
        })
        .collect();
    let reproduced = parts.iter().filter(|s| s.reproduced).count();
    let ratio = |n: usize, d: usize| (d > 0).then(|| n as f64 / d as f64);
    let precision = ratio(reproduced, pred_parts.len());
    let recall = ratio(reproduced, truth_parts.len());
    let f1 = match (precision, recall) {
        (Some(p), Some(r)) if p + r > 0.0 => Some(2.0 * p * r / (p + r)),
        (Some(_), Some(_)) => Some(0.0),
        _ => None,
    };
    ArticulationMetrics {
        precision,
        recall,
        f1,
        truth_parts: truth_parts.len(),
        predicted_parts: pred_parts.len(),
        parts,
    }
}

fn score(
    truth_id: &str,
    tp: &PartJson,
    paired: Option<&(String, PartJson)>,
    swept: &SweptRanges,
) -> PartScore {
    let mut s = PartScore {
        truth: format!("{truth_id}/{}", tp.name),
        truth_type: tp.joint.kind,
        predicted: None,
        type_correct: false,
        axis_error_deg: None,
        hinge_distance_m: None,
        same_side: false,
        free_share: None,
        reproduced: false,
    };
    let Some((pid, pp)) = paired else {
        return s;
    };
    s.predicted = Some(format!("{pid}/{}", pp.name));
    s.type_correct = pp.joint.kind == tp.joint.kind;
    // An axis is a line: its sign says which way the part turns, which `same_side` checks.
    let cos = pp.axis().dot(tp.axis()).abs().min(1.0);
    s.axis_error_deg = Some(cos.acos().to_degrees());
    if tp.joint.kind == PartJointType::Revolute && s.type_correct {
        let at = {
            let o = Vec3::from_array(tp.joint.origin);
            o + tp.axis() * tp.axis().dot(tp.front_center() - o)
        };
        let po = Vec3::from_array(pp.joint.origin);
        let offset = at - po;
        s.hinge_distance_m = Some((offset - pp.axis() * pp.axis().dot(offset)).length());
    }
    s.same_side = pp.opening_direction().dot(tp.opening_direction()) > 0.5;
    let truth_span = (tp.joint.upper - tp.joint.lower).max(1e-6);
    let predicted_span = match swept.get(&format!("{pid}_{}", pp.name)) {
        Some(Some((lo, hi))) => hi - lo,
        Some(None) => 0.0,
        None => pp.joint.upper - pp.joint.lower,
    };
    s.free_share = s
        .type_correct
        .then(|| (predicted_span / truth_span).clamp(0.0, 1.0));
    s.reproduced = s.type_correct
        && s.axis_error_deg.is_some_and(|e| e <= AXIS_TOLERANCE_DEG)
        && s.hinge_distance_m.is_none_or(|d| d <= HINGE_TOLERANCE_M)
        && s.same_side
        && s.free_share.is_some_and(|f| f >= MIN_FREE_SHARE);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kitchen() -> ContactGraph {
        crate::scene::kitchen_contact_graph()
    }

    #[test]
    fn the_truth_reproduces_itself_and_a_shifted_hinge_does_not() {
        let truth = kitchen();
        let db = CadDatabase::parametric();
        let same = evaluate_articulation(
            &truth,
            &truth,
            &Affine3A::IDENTITY,
            &db,
            &SweptRanges::new(),
        );
        assert!(same.truth_parts >= 8, "{}", same.truth_parts);
        assert_eq!(same.recall, Some(1.0), "{:?}", same.parts);
        assert_eq!(same.precision, Some(1.0));
        // Everything 7 cm along each axis: every hinge line (vertical or horizontal) misses by
        // 10 cm, drawers still slide the same way.
        let shifted = evaluate_articulation(
            &truth,
            &truth,
            &Affine3A::from_translation(Vec3::splat(0.07)),
            &db,
            &SweptRanges::new(),
        );
        for p in &shifted.parts {
            assert_eq!(
                p.reproduced,
                p.truth_type == PartJointType::Prismatic,
                "{p:?}"
            );
        }
        // A door its sweep stopped at a quarter of its range is not reproduced.
        let door = same
            .parts
            .iter()
            .find(|p| p.truth_type == PartJointType::Revolute)
            .expect("a door");
        let (node, part) = door.truth.split_once('/').expect("node/part");
        let link = format!("{node}_{part}");
        let swept = SweptRanges::from([(link, Some((0.0, 0.45)))]);
        let narrowed = evaluate_articulation(&truth, &truth, &Affine3A::IDENTITY, &db, &swept);
        let scored = narrowed
            .parts
            .iter()
            .find(|p| p.truth == door.truth)
            .expect("scored");
        assert!(
            !scored.reproduced && scored.free_share < Some(0.3),
            "{scored:?}"
        );
    }
}
