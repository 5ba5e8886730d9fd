//! Contact-graph metrics against the ground truth: oriented box mAP@0.5 over object classes, and
//! the graph edit distance. Truth entities the reconstruction never saw (a box in a closed
//! fridge) are left out of both, and listed.

use std::collections::{BTreeMap, HashSet};

use glam::{Affine3A, Vec3};
use serde::Serialize;

use crate::classes::EntityKind;
use crate::eval::ged::{EditDistance, EditGraph, graph_edit_distance, graph_edit_distance_where};
use crate::eval::panoptic_quality::average_precision;
use crate::geometry::GravityBox;
use crate::graph::{ContactGraph, GraphEdge};

/// A predicted node may stand for a truth node in `ged_positional` when their boxes overlap by
/// this 3D IoU, or their centres are this close (metres).
pub const POSITIONAL_IOU: f32 = 0.1;
pub const POSITIONAL_DISTANCE_M: f32 = 0.3;

#[derive(Clone, Debug, Serialize)]
pub struct ContactMetrics {
    pub obb_map50: f64,
    /// AP@0.5 of oriented boxes per object class of the truth.
    pub obb_ap50: BTreeMap<String, f64>,
    pub ged: EditDistance,
    /// The edit distance where a predicted node may stand for a truth node only where their
    /// boxes are: 3D IoU over `POSITIONAL_IOU` or centres within `POSITIONAL_DISTANCE_M`.
    pub ged_positional: EditDistance,
    /// Truth nodes left out because nothing of them was seen.
    pub unseen_truth: Vec<String>,
}

/// `truth` restricted to `seen` nodes and the edges among them.
pub fn seen_subgraph(truth: &ContactGraph, seen: &HashSet<String>) -> ContactGraph {
    let keep = |id: &str| seen.contains(id);
    ContactGraph {
        nodes: truth
            .nodes
            .iter()
            .filter(|n| keep(&n.id))
            .cloned()
            .collect(),
        edges: truth
            .edges
            .iter()
            .filter(|e| match e {
                GraphEdge::Support { parent, child } => keep(parent) && keep(child),
                GraphEdge::Proximal { a, b } => keep(a) && keep(b),
            })
            .cloned()
            .collect(),
    }
}

/// Scores `pred` against `truth` (already restricted to what was seen). `truth_from_pred` takes
/// predicted boxes into the truth's frame (the reconstruction's aligned frame may differ from the
/// sequence's); `scores` rank predictions for AP (1 when missing).
pub fn evaluate_contact_graph(
    pred: &ContactGraph,
    truth: &ContactGraph,
    truth_from_pred: &Affine3A,
    scores: &BTreeMap<String, f32>,
    unseen_truth: Vec<String>,
) -> ContactMetrics {
    let yaw_turn = {
        let x = truth_from_pred.transform_vector3(Vec3::X);
        x.y.atan2(x.x)
    };
    let pred_box = |b: &GravityBox| GravityBox {
        center: truth_from_pred.transform_point3(b.center),
        yaw: b.yaw + yaw_turn,
        size: b.size,
    };
    let is_object = |kind: EntityKind| kind != EntityKind::Layout;
    let classes: Vec<&str> = {
        let mut c: Vec<&str> = truth
            .nodes
            .iter()
            .filter(|n| is_object(n.kind))
            .map(|n| n.class.as_str())
            .collect();
        c.sort_unstable();
        c.dedup();
        c
    };
    let mut obb_ap50 = BTreeMap::new();
    for class in classes {
        let truths: Vec<GravityBox> = truth
            .nodes
            .iter()
            .filter(|n| n.class == class)
            .map(|n| GravityBox::from(&n.bbox))
            .collect();
        let mut preds: Vec<(f32, GravityBox)> = pred
            .nodes
            .iter()
            .filter(|n| n.class == class)
            .map(|n| {
                (
                    scores.get(&n.id).copied().unwrap_or(1.0),
                    pred_box(&GravityBox::from(&n.bbox)),
                )
            })
            .collect();
        preds.sort_by(|a, b| b.0.total_cmp(&a.0));
        let mut taken = vec![false; truths.len()];
        let hits: Vec<bool> = preds
            .iter()
            .map(|(_, p)| {
                let best = (0..truths.len())
                    .filter(|&t| !taken[t])
                    .map(|t| (t, p.iou(&truths[t])))
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                match best {
                    Some((t, iou)) if iou > 0.5 => {
                        taken[t] = true;
                        true
                    }
                    _ => false,
                }
            })
            .collect();
        obb_ap50.insert(class.to_string(), average_precision(&hits, truths.len()));
    }
    let obb_map50 = if obb_ap50.is_empty() {
        0.0
    } else {
        obb_ap50.values().sum::<f64>() / obb_ap50.len() as f64
    };
    let mut aligned = pred.clone();
    for n in &mut aligned.nodes {
        n.bbox = pred_box(&GravityBox::from(&n.bbox)).into();
    }
    let (pred_graph, truth_graph) = (
        EditGraph::from_contact_graph(&aligned),
        EditGraph::from_contact_graph(truth),
    );
    let ged = graph_edit_distance(&pred_graph, &truth_graph);
    let allowed: Vec<Vec<bool>> = aligned
        .nodes
        .iter()
        .map(|p| {
            let pb = GravityBox::from(&p.bbox);
            truth
                .nodes
                .iter()
                .map(|t| {
                    let tb = GravityBox::from(&t.bbox);
                    pb.center.distance(tb.center) <= POSITIONAL_DISTANCE_M
                        || pb.iou(&tb) > POSITIONAL_IOU
                })
                .collect()
        })
        .collect();
    let ged_positional = graph_edit_distance_where(&pred_graph, &truth_graph, Some(&allowed));
    ContactMetrics {
        obb_map50,
        obb_ap50,
        ged,
        ged_positional,
        unseen_truth,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_node_moved_away_costs_in_the_positional_distance_only() {
        let truth = crate::scene::kitchen_contact_graph();
        let mut moved = truth.clone();
        let table = moved
            .nodes
            .iter_mut()
            .find(|n| n.id == "table_1")
            .expect("table");
        table.bbox.center[0] += 1.5;
        let scores = BTreeMap::new();
        let m = evaluate_contact_graph(&moved, &truth, &Affine3A::IDENTITY, &scores, Vec::new());
        assert_eq!(m.ged.cost, 0);
        // Deleted and inserted, with its support edge and its children's, and its proximal edges.
        assert!(m.ged_positional.cost >= 2 + 2, "{:?}", m.ged_positional);
        let same = evaluate_contact_graph(&truth, &truth, &Affine3A::IDENTITY, &scores, Vec::new());
        assert_eq!(same.ged_positional.cost, 0);
    }
}
