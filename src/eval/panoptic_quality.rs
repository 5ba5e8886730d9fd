//! Panoptic quality (Kirillov et al.) and instance mAP@0.5 over the map's surface voxels.
//!
//! Every evaluated voxel has a ground-truth segment (or void) and a predicted segment (or none).
//! A prediction and a truth of the same class match when their IoU exceeds 0.5 (unique, as in
//! COCO panoptic); IoU ignores the prediction's void voxels, and predictions that are mostly void
//! are not false positives. PQ = sum IoU(TP) / (TP + FP/2 + FN/2) = SQ * RQ per class,
//! averaged over the classes present in truth or prediction.

use std::collections::BTreeMap;

use serde::Serialize;

/// One segment: its name (entity id), class and, for predictions, a confidence.
#[derive(Clone, Debug)]
pub struct Segment {
    pub name: String,
    pub class: String,
    pub score: f32,
}

#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct ClassQuality {
    pub pq: f64,
    pub sq: f64,
    pub rq: f64,
    pub tp: usize,
    pub fp: usize,
    #[serde(rename = "fn")]
    pub fn_: usize,
}

#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct PanopticMetrics {
    pub pq: f64,
    pub sq: f64,
    pub rq: f64,
    pub per_class: BTreeMap<String, ClassQuality>,
    /// Mean over object classes in the truth of the average precision at IoU 0.5.
    pub instance_map50: f64,
    pub instance_ap50: BTreeMap<String, f64>,
    pub evaluated_voxels: usize,
    pub void_voxels: usize,
    /// Every truth segment with its best-overlapping prediction, then every counted prediction
    /// that matched nothing with its best-overlapping truth: where the mistakes are.
    pub matches: Vec<SegmentMatch>,
}

/// One segment of one side and the segment of the other side it overlaps most.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SegmentMatch {
    pub truth: Option<String>,
    pub truth_class: Option<String>,
    pub prediction: Option<String>,
    pub prediction_class: Option<String>,
    pub truth_voxels: usize,
    pub prediction_voxels: usize,
    pub iou: f64,
    /// A true positive: same class and IoU above 0.5.
    pub matched: bool,
}

/// `truth_of[v]` and `pred_of[v]`: segment index plus one per voxel (0 = void / none).
/// `is_object(class)` says which classes count for instance mAP (layout does not).
pub fn evaluate(
    truth_of: &[u32],
    pred_of: &[u32],
    truth: &[Segment],
    pred: &[Segment],
    is_object: impl Fn(&str) -> bool,
) -> PanopticMetrics {
    let mut intersection: BTreeMap<(u32, u32), usize> = BTreeMap::new();
    let mut truth_size = vec![0usize; truth.len() + 1];
    let mut pred_size = vec![0usize; pred.len() + 1];
    let mut pred_void = vec![0usize; pred.len() + 1];
    let mut void = 0;
    for (&t, &p) in truth_of.iter().zip(pred_of) {
        if t == 0 {
            void += 1;
            pred_void[p as usize] += 1;
            continue;
        }
        truth_size[t as usize] += 1;
        pred_size[p as usize] += 1;
        if p != 0 {
            *intersection.entry((t, p)).or_default() += 1;
        }
    }
    let iou = |t: u32, p: u32| -> f64 {
        let i = intersection.get(&(t, p)).copied().unwrap_or(0);
        let union = truth_size[t as usize] + pred_size[p as usize] - i;
        if union == 0 {
            0.0
        } else {
            i as f64 / union as f64
        }
    };
    let present_truth = |t: usize| truth_size[t] > 0;
    // A prediction counts when at most half of it is void.
    let counted_pred = |p: usize| pred_size[p] > 0 && pred_void[p] <= pred_size[p];

    let mut per_class: BTreeMap<String, ClassQuality> = BTreeMap::new();
    let mut matched_truth = vec![false; truth.len() + 1];
    let mut matched_pred = vec![false; pred.len() + 1];
    let mut iou_sum: BTreeMap<String, f64> = BTreeMap::new();
    for &(t, p) in intersection.keys() {
        if truth[t as usize - 1].class != pred[p as usize - 1].class {
            continue;
        }
        let value = iou(t, p);
        if value > 0.5 {
            matched_truth[t as usize] = true;
            matched_pred[p as usize] = true;
            let class = &truth[t as usize - 1].class;
            per_class.entry(class.clone()).or_default().tp += 1;
            *iou_sum.entry(class.clone()).or_default() += value;
        }
    }
    for t in 1..=truth.len() {
        if present_truth(t) && !matched_truth[t] {
            per_class.entry(truth[t - 1].class.clone()).or_default().fn_ += 1;
        }
    }
    for p in 1..=pred.len() {
        if counted_pred(p) && !matched_pred[p] {
            per_class.entry(pred[p - 1].class.clone()).or_default().fp += 1;
        }
    }
    for (class, q) in &mut per_class {
        let sum = iou_sum.get(class).copied().unwrap_or(0.0);
        let denominator = q.tp as f64 + 0.5 * q.fp as f64 + 0.5 * q.fn_ as f64;
        q.sq = if q.tp > 0 { sum / q.tp as f64 } else { 0.0 };
        q.rq = if denominator > 0.0 {
            q.tp as f64 / denominator
        } else {
            0.0
        };
        q.pq = q.sq * q.rq;
    }
    let mean = |f: fn(&ClassQuality) -> f64| {
        if per_class.is_empty() {
            0.0
        } else {
            per_class.values().map(f).sum::<f64>() / per_class.len() as f64
        }
    };

    // Instance AP@0.5 per object class of the truth: predictions by falling score.
    let mut instance_ap50 = BTreeMap::new();
    let classes: std::collections::BTreeSet<&str> = (1..=truth.len())
        .filter(|&t| present_truth(t) && is_object(&truth[t - 1].class))
        .map(|t| truth[t - 1].class.as_str())
        .collect();
    for class in classes {
        let truths: Vec<u32> = (1..=truth.len() as u32)
            .filter(|&t| present_truth(t as usize) && truth[t as usize - 1].class == class)
            .collect();
        let mut preds: Vec<u32> = (1..=pred.len() as u32)
            .filter(|&p| counted_pred(p as usize) && pred[p as usize - 1].class == class)
            .collect();
        preds.sort_by(|a, b| {
            pred[*b as usize - 1]
                .score
                .total_cmp(&pred[*a as usize - 1].score)
                .then(a.cmp(b))
        });
        let mut taken = vec![false; truths.len()];
        let mut hits = Vec::with_capacity(preds.len());
        for &p in &preds {
            let best = truths
                .iter()
                .enumerate()
                .filter(|(k, _)| !taken[*k])
                .map(|(k, &t)| (k, iou(t, p)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((k, v)) if v > 0.5 => {
                    taken[k] = true;
                    hits.push(true);
                }
                _ => hits.push(false),
            }
        }
        instance_ap50.insert(class.to_string(), average_precision(&hits, truths.len()));
    }
    let best_pred = |t: u32| {
        intersection
            .range((t, 0)..=(t, u32::MAX))
            .map(|(&(_, p), _)| (p, iou(t, p)))
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
    };
    let best_truth = |p: u32| {
        intersection
            .iter()
            .filter(|(k, _)| k.1 == p)
            .map(|(&(t, _), _)| (t, iou(t, p)))
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
    };
    let entry = |t: Option<(u32, f64)>, p: Option<u32>, matched: bool| {
        let (t, value) = t.map_or((None, 0.0), |(t, v)| (Some(t), v));
        SegmentMatch {
            truth: t.map(|t| truth[t as usize - 1].name.clone()),
            truth_class: t.map(|t| truth[t as usize - 1].class.clone()),
            prediction: p.map(|p| pred[p as usize - 1].name.clone()),
            prediction_class: p.map(|p| pred[p as usize - 1].class.clone()),
            truth_voxels: t.map_or(0, |t| truth_size[t as usize]),
            prediction_voxels: p.map_or(0, |p| pred_size[p as usize]),
            iou: value,
            matched,
        }
    };
    let mut matches = Vec::new();
    for t in (1..=truth.len() as u32).filter(|&t| present_truth(t as usize)) {
        let best = best_pred(t);
        let same_class = best.is_some_and(|(p, v)| {
            v > 0.5 && pred[p as usize - 1].class == truth[t as usize - 1].class
        });
        matches.push(entry(
            Some((t, best.map_or(0.0, |(_, v)| v))),
            best.map(|(p, _)| p),
            same_class,
        ));
    }
    for p in
        (1..=pred.len() as u32).filter(|&p| counted_pred(p as usize) && !matched_pred[p as usize])
    {
        matches.push(entry(best_truth(p), Some(p), false));
    }
    let instance_map50 = if instance_ap50.is_empty() {
        0.0
    } else {
        instance_ap50.values().sum::<f64>() / instance_ap50.len() as f64
    };
    PanopticMetrics {
        pq: mean(|q| q.pq),
        sq: mean(|q| q.sq),
        rq: mean(|q| q.rq),
        per_class,
        instance_map50,
        instance_ap50,
        evaluated_voxels: truth_of.len() - void,
        void_voxels: void,
        matches,
    }
}

/// Area under the precision-recall curve with precision made monotone (VOC, all points).
pub fn average_precision(hits_by_score: &[bool], positives: usize) -> f64 {
    if positives == 0 {
        return 0.0;
    }
    let mut points = Vec::new();
    let mut tp = 0;
    for (k, &hit) in hits_by_score.iter().enumerate() {
        tp += usize::from(hit);
        points.push((tp as f64 / positives as f64, tp as f64 / (k + 1) as f64));
    }
    let mut ap = 0.0;
    let mut previous_recall = 0.0;
    for k in 0..points.len() {
        let precision = points[k..].iter().map(|p| p.1).fold(0.0, f64::max);
        ap += (points[k].0 - previous_recall) * precision;
        previous_recall = points[k].0;
    }
    ap
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seg(class: &str, score: f32) -> Segment {
        Segment {
            name: class.to_string(),
            class: class.into(),
            score,
        }
    }

    #[test]
    fn perfect_prediction_scores_one() {
        let truth_of = [1, 1, 2, 2, 2, 0];
        let m = evaluate(
            &truth_of,
            &[2, 2, 1, 1, 1, 1],
            &[seg("cup", 1.0), seg("floor", 1.0)],
            &[seg("floor", 0.9), seg("cup", 0.8)],
            |c| c != "floor",
        );
        assert_eq!((m.pq, m.sq, m.rq, m.instance_map50), (1.0, 1.0, 1.0, 1.0));
        assert_eq!(m.void_voxels, 1);
    }

    #[test]
    fn a_merged_prediction_matches_one_truth_and_misses_the_other() {
        // Two cups (4 voxels each) predicted as one segment of 8: IoU 0.5 each, not > 0.5.
        let truth_of = [1, 1, 1, 1, 2, 2, 2, 2];
        let m = evaluate(
            &truth_of,
            &[1; 8],
            &[seg("cup", 1.0), seg("cup", 1.0)],
            &[seg("cup", 0.7)],
            |_| true,
        );
        let cup = &m.per_class["cup"];
        assert_eq!((cup.tp, cup.fp, cup.fn_), (0, 1, 2));
        assert_eq!(m.pq, 0.0);
        // Five of the eight: IoU 5/8 with the first cup... split differently: 5 on cup 1.
        let m = evaluate(
            &[1, 1, 1, 1, 1, 2, 2, 2],
            &[1, 1, 1, 1, 1, 1, 0, 0],
            &[seg("cup", 1.0), seg("cup", 1.0)],
            &[seg("cup", 0.7)],
            |_| true,
        );
        let cup = &m.per_class["cup"];
        assert_eq!((cup.tp, cup.fp, cup.fn_), (1, 0, 1));
        assert!((cup.sq - 5.0 / 6.0).abs() < 1e-12);
        assert!((cup.rq - 1.0 / 1.5).abs() < 1e-12);
        assert!((m.instance_map50 - 0.5).abs() < 1e-12);
    }

    #[test]
    fn average_precision_of_a_ranked_list() {
        // Hit, miss, hit with 2 positives: recall 0.5 at precision 1, 1.0 at precision 2/3.
        let ap = average_precision(&[true, false, true], 2);
        assert!((ap - (0.5 * 1.0 + 0.5 * 2.0 / 3.0)).abs() < 1e-12);
        assert_eq!(average_precision(&[], 3), 0.0);
    }
}
