//! Which instance and class a segment label belongs to.
//!
//! Joint fusion (Han et al.): one triple-wise count Phi(l, c, p) over segment label, class and
//! instance. A mask of class c whose segments carry labels L takes the instance
//! argmax_p sum_{l in L} Phi(l, c, p) when positive, else a new one; integration increments
//! Phi(l, c, p). Instances p1, p2 of one class merge when the counts on labels they share reach
//! `m_th` of all their counts (Eq. 5).
//!
//! The Voxblox++ baseline tracks the two separately: counts of (label, class) and of
//! (label, instance), the instance chosen without regard to class.

use std::collections::BTreeMap;

use crate::map::SegmentLabel;

pub type ClassId = u16;
pub type InstanceId = u32;
/// An instance of a class.
type InstanceKey = (ClassId, InstanceId);

/// A mask of the current frame, after its segments got their labels.
#[derive(Clone, Debug)]
pub struct MaskObservation {
    pub class: ClassId,
    pub labels: Vec<SegmentLabel>,
}

/// How instances are tracked. `--baseline voxblox++` picks the baseline; the joint fusion is
/// the default and has no flag value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum InstanceFusion {
    /// Phi(l, c, p) with Eq. 5 instance merging.
    #[value(skip)]
    Joint,
    /// Separate semantic and instance counts, as Voxblox++.
    #[value(name = "voxblox++")]
    Voxblox,
}

impl InstanceFusion {
    /// The name report.json and the panoptic index record.
    pub fn name(self) -> &'static str {
        match self {
            Self::Joint => "joint",
            Self::Voxblox => "voxblox++",
        }
    }
}

/// What a label resolves to at the end.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelIdentity {
    pub class: ClassId,
    pub instance: InstanceId,
    /// Share of the label's votes that agree with this (class, instance).
    pub support: f32,
    pub votes: u32,
}

#[derive(Clone, Debug)]
pub struct InstanceCounts {
    pub mode: InstanceFusion,
    /// Joint: Phi(l, c, p). Voxblox: (l, c, 0) holds the semantic counts.
    phi: BTreeMap<(SegmentLabel, ClassId, InstanceId), u32>,
    /// Voxblox only: (l, p) instance counts.
    instance_only: BTreeMap<(SegmentLabel, InstanceId), u32>,
    /// Joint only: frames in which two labels (smaller first) were seen in different masks of
    /// one class, and in the same mask. Labels seen apart more than together are two objects.
    apart: BTreeMap<(SegmentLabel, SegmentLabel), u32>,
    together: BTreeMap<(SegmentLabel, SegmentLabel), u32>,
    next_instance: InstanceId,
}

impl InstanceCounts {
    pub fn new(mode: InstanceFusion) -> Self {
        Self {
            mode,
            phi: BTreeMap::new(),
            instance_only: BTreeMap::new(),
            apart: BTreeMap::new(),
            together: BTreeMap::new(),
            next_instance: 1,
        }
    }

    /// Assigns an instance to every mask of a frame (no two masks of a frame share one) and
    /// increments the counts. Returns the instances in mask order.
    pub fn observe_frame(&mut self, masks: &[MaskObservation]) -> Vec<InstanceId> {
        let mut candidates: Vec<(u32, usize, InstanceId)> = Vec::new();
        for (k, mask) in masks.iter().enumerate() {
            let mut score: BTreeMap<InstanceId, u32> = BTreeMap::new();
            for &l in &mask.labels {
                match self.mode {
                    InstanceFusion::Joint => {
                        for ((_, _, p), n) in self
                            .phi
                            .range((l, mask.class, 0)..=(l, mask.class, u32::MAX))
                        {
                            *score.entry(*p).or_default() += n;
                        }
                    }
                    InstanceFusion::Voxblox => {
                        for ((_, p), n) in self.instance_only.range((l, 0)..=(l, u32::MAX)) {
                            *score.entry(*p).or_default() += n;
                        }
                    }
                }
            }
            candidates.extend(score.into_iter().map(|(p, s)| (s, k, p)));
        }
        // Greedy by score, highest first; ties by mask order, then the older instance.
        candidates.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut chosen: Vec<Option<InstanceId>> = vec![None; masks.len()];
        let mut taken = std::collections::BTreeSet::new();
        for (_, k, p) in candidates {
            if chosen[k].is_none() && !taken.contains(&p) {
                chosen[k] = Some(p);
                taken.insert(p);
            }
        }
        let instances: Vec<InstanceId> = chosen
            .into_iter()
            .map(|c| {
                c.unwrap_or_else(|| {
                    self.next_instance += 1;
                    self.next_instance - 1
                })
            })
            .collect();
        if self.mode == InstanceFusion::Joint {
            self.count_co_observations(masks);
        }
        for (mask, &p) in masks.iter().zip(&instances) {
            for &l in &mask.labels {
                match self.mode {
                    InstanceFusion::Joint => *self.phi.entry((l, mask.class, p)).or_default() += 1,
                    InstanceFusion::Voxblox => {
                        *self.phi.entry((l, mask.class, 0)).or_default() += 1;
                        *self.instance_only.entry((l, p)).or_default() += 1;
                    }
                }
            }
        }
        instances
    }

    /// Whether labels `a` and `b` were ever seen in different masks of one class in a frame.
    pub fn seen_apart(&self, a: SegmentLabel, b: SegmentLabel) -> bool {
        self.apart.contains_key(&(a.min(b), a.max(b)))
    }

    fn count_co_observations(&mut self, masks: &[MaskObservation]) {
        for (a, ma) in masks.iter().enumerate() {
            for (b, mb) in masks.iter().enumerate().skip(a) {
                if ma.class != mb.class {
                    continue;
                }
                for &la in &ma.labels {
                    for &lb in &mb.labels {
                        // Within one mask each unordered pair once.
                        if la == lb || (a == b && la > lb) {
                            continue;
                        }
                        let key = (la.min(lb), la.max(lb));
                        let table = if a == b {
                            &mut self.together
                        } else {
                            &mut self.apart
                        };
                        *table.entry(key).or_default() += 1;
                    }
                }
            }
        }
    }

    /// Undoes wrong merges: when two labels resolved to one instance were seen in different masks
    /// of their class more often than in one (at least `min_apart` times), the label with fewer
    /// votes moves to a new instance. An instance born from a merged mask thus splits once the
    /// objects are seen apart. Returns the number of splits.
    pub fn split_instances(&mut self, min_apart: u32) -> usize {
        if self.mode != InstanceFusion::Joint {
            return 0;
        }
        let mut splits = 0;
        let pairs: Vec<((SegmentLabel, SegmentLabel), u32)> =
            self.apart.iter().map(|(k, v)| (*k, *v)).collect();
        for ((la, lb), apart) in pairs {
            let together = self.together.get(&(la, lb)).copied().unwrap_or(0);
            if apart < min_apart || apart <= together {
                continue;
            }
            let (Some(ia), Some(ib)) = (self.identity(la), self.identity(lb)) else {
                continue;
            };
            if (ia.class, ia.instance) != (ib.class, ib.instance) {
                continue;
            }
            let (mover, id) = if (ia.votes, lb) > (ib.votes, la) {
                (lb, ib)
            } else {
                (la, ia)
            };
            let n = self
                .phi
                .remove(&(mover, id.class, id.instance))
                .unwrap_or(0);
            let fresh = self.next_instance;
            self.next_instance += 1;
            self.phi.insert((mover, id.class, fresh), n);
            splits += 1;
        }
        splits
    }

    /// Moves every count of label `from` onto label `into`.
    pub fn merge_labels(&mut self, from: SegmentLabel, into: SegmentLabel) {
        for table in [&mut self.apart, &mut self.together] {
            let old = std::mem::take(table);
            for ((a, b), n) in old {
                let (a, b) = (
                    if a == from { into } else { a },
                    if b == from { into } else { b },
                );
                if a != b {
                    *table.entry((a.min(b), a.max(b))).or_default() += n;
                }
            }
        }
        let moved: Vec<_> = self
            .phi
            .range((from, 0, 0)..=(from, ClassId::MAX, InstanceId::MAX))
            .map(|(k, v)| (*k, *v))
            .collect();
        for ((_, c, p), n) in moved {
            self.phi.remove(&(from, c, p));
            *self.phi.entry((into, c, p)).or_default() += n;
        }
        let moved: Vec<_> = self
            .instance_only
            .range((from, 0)..=(from, InstanceId::MAX))
            .map(|(k, v)| (*k, *v))
            .collect();
        for ((_, p), n) in moved {
            self.instance_only.remove(&(from, p));
            *self.instance_only.entry((into, p)).or_default() += n;
        }
    }

    /// Eq. 5: merges instances of one class whose counts lie mostly on labels they share.
    /// Returns the number of merges. Joint mode only (the baseline does not regularise instances).
    pub fn merge_instances(&mut self, m_th: f32) -> usize {
        if self.mode != InstanceFusion::Joint {
            return 0;
        }
        let mut merges = 0;
        loop {
            // Per (class, instance): label -> count.
            let mut table: BTreeMap<(ClassId, InstanceId), BTreeMap<SegmentLabel, u32>> =
                BTreeMap::new();
            for (&(l, c, p), &n) in &self.phi {
                table.entry((c, p)).or_default().insert(l, n);
            }
            let keys: Vec<_> = table.keys().copied().collect();
            let mut best: Option<(f32, InstanceKey, InstanceKey)> = None;
            for (i, a) in keys.iter().enumerate() {
                for b in keys[i + 1..].iter().take_while(|b| b.0 == a.0) {
                    let (ta, tb) = (&table[a], &table[b]);
                    let all: u32 = ta.values().sum::<u32>() + tb.values().sum::<u32>();
                    let shared: u32 = ta
                        .iter()
                        .filter_map(|(l, na)| tb.get(l).map(|nb| na + nb))
                        .sum();
                    let ratio = shared as f32 / all.max(1) as f32;
                    if ratio >= m_th && best.is_none_or(|(r, _, _)| ratio > r) {
                        best = Some((ratio, *a, *b));
                    }
                }
            }
            let Some((_, (c, keep), (_, gone))) = best else {
                return merges;
            };
            let moved: Vec<_> = self
                .phi
                .iter()
                .filter(|((_, cc, p), _)| *cc == c && *p == gone)
                .map(|(k, v)| (*k, *v))
                .collect();
            for ((l, _, _), n) in moved {
                self.phi.remove(&(l, c, gone));
                *self.phi.entry((l, c, keep)).or_default() += n;
            }
            merges += 1;
        }
    }

    /// Every (class, instance, count) vote of label `l` (joint: Phi(l, ., .); baseline: the
    /// semantic counts with instance 0).
    pub fn votes(&self, l: SegmentLabel) -> Vec<(ClassId, InstanceId, u32)> {
        self.phi
            .range((l, 0, 0)..=(l, ClassId::MAX, InstanceId::MAX))
            .map(|((_, c, p), n)| (*c, *p, *n))
            .collect()
    }

    /// Whether `a` and `b` resolve to two classes, each on at least `min_votes` mask votes (the
    /// floor and the wall meeting it): two surfaces, however much their voxels overlap. A label
    /// with fewer votes may be a fragment whose class the segmenter confused. Joint only.
    pub fn of_different_classes(&self, a: SegmentLabel, b: SegmentLabel, min_votes: u32) -> bool {
        if self.mode != InstanceFusion::Joint {
            return false;
        }
        match (self.identity(a), self.identity(b)) {
            (Some(x), Some(y)) => x.class != y.class && x.votes.min(y.votes) >= min_votes,
            _ => false,
        }
    }

    /// class = argmax_c sum_p Phi(l, c, p); instance = argmax_p Phi(l, class, p) (joint), or the
    /// separately counted majorities (baseline). `None` for labels no mask ever covered.
    pub fn identity(&self, l: SegmentLabel) -> Option<LabelIdentity> {
        let mut per_class: BTreeMap<ClassId, u32> = BTreeMap::new();
        for ((_, c, _), n) in self
            .phi
            .range((l, 0, 0)..=(l, ClassId::MAX, InstanceId::MAX))
        {
            *per_class.entry(*c).or_default() += n;
        }
        let total: u32 = per_class.values().sum();
        let (&class, _) = per_class
            .iter()
            .max_by_key(|(c, n)| (**n, std::cmp::Reverse(**c)))?;
        let (instance, agreeing, instance_total) = match self.mode {
            InstanceFusion::Joint => {
                let (p, n) = self
                    .phi
                    .range((l, class, 0)..=(l, class, InstanceId::MAX))
                    .max_by_key(|((_, _, p), n)| (**n, std::cmp::Reverse(*p)))?;
                (p.2, *n, total)
            }
            InstanceFusion::Voxblox => {
                let counts = self.instance_only.range((l, 0)..=(l, InstanceId::MAX));
                let all: u32 = counts.clone().map(|(_, n)| n).sum();
                let (p, n) = counts.max_by_key(|((_, p), n)| (**n, std::cmp::Reverse(*p)))?;
                // Support: the class majority times the instance majority.
                let class_share = per_class[&class] as f32 / total.max(1) as f32;
                (p.1, (*n as f32 * class_share) as u32, all)
            }
        };
        Some(LabelIdentity {
            class,
            instance,
            support: agreeing as f32 / instance_total.max(1) as f32,
            votes: total,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mask(class: ClassId, labels: &[SegmentLabel]) -> MaskObservation {
        MaskObservation {
            class,
            labels: labels.to_vec(),
        }
    }

    #[test]
    fn a_mask_takes_the_instance_its_labels_voted_for_in_its_class() {
        let mut counts = InstanceCounts::new(InstanceFusion::Joint);
        let first = counts.observe_frame(&[mask(1, &[10, 11]), mask(2, &[20])]);
        assert_eq!(first, vec![1, 2]);
        // Same labels again: same instances. A confused class on label 20 starts a new instance
        // of that class instead of corrupting instance 2.
        let second = counts.observe_frame(&[mask(1, &[11]), mask(3, &[20])]);
        assert_eq!(second, vec![1, 3]);
        for _ in 0..3 {
            counts.observe_frame(&[mask(2, &[20])]);
        }
        let id = counts.identity(20).expect("seen");
        assert_eq!((id.class, id.instance), (2, 2));
        assert!((id.support - 4.0 / 5.0).abs() < 1e-6);
        assert_eq!(counts.identity(99), None);
    }

    #[test]
    fn two_masks_of_a_frame_never_share_an_instance() {
        let mut counts = InstanceCounts::new(InstanceFusion::Joint);
        counts.observe_frame(&[mask(1, &[10, 11])]);
        // The instance was split by the segmenter: the half with more votes keeps it.
        let split = counts.observe_frame(&[mask(1, &[10]), mask(1, &[11, 11])]);
        assert_eq!(split, vec![2, 1]);
    }

    #[test]
    fn instances_sharing_most_labels_merge_and_labels_move() {
        let mut counts = InstanceCounts::new(InstanceFusion::Joint);
        counts.observe_frame(&[mask(1, &[10, 11])]);
        counts.observe_frame(&[mask(1, &[10]), mask(1, &[11, 12])]);
        // Instances 1 {10: 2, 11: 1} and 2 {11: 1, 12: 1}: shared label 11 holds 2 of 5 counts.
        assert_eq!(counts.merge_instances(0.5), 0);
        assert_eq!(counts.merge_instances(0.4), 1);
        assert_eq!(counts.identity(12).map(|i| i.instance), Some(1));
        counts.merge_labels(12, 10);
        assert_eq!(counts.identity(12), None);
        assert_eq!(counts.identity(10).map(|i| i.votes), Some(3));
    }

    #[test]
    fn labels_voted_into_two_classes_are_of_different_classes() {
        let mut counts = InstanceCounts::new(InstanceFusion::Joint);
        for _ in 0..3 {
            counts.observe_frame(&[mask(1, &[10]), mask(2, &[20])]);
        }
        // A fragment seen once under a confused class.
        counts.observe_frame(&[mask(2, &[30])]);
        assert!(counts.of_different_classes(10, 20, 3));
        assert!(
            !counts.of_different_classes(10, 30, 3),
            "too few votes to tell"
        );
        assert!(!counts.of_different_classes(10, 99, 3), "never seen");
        let mut baseline = InstanceCounts::new(InstanceFusion::Voxblox);
        baseline.observe_frame(&[mask(1, &[10]), mask(2, &[20])]);
        assert!(!baseline.of_different_classes(10, 20, 1));
    }

    #[test]
    fn an_instance_born_of_a_merged_mask_splits_when_its_labels_are_seen_apart() {
        let mut counts = InstanceCounts::new(InstanceFusion::Joint);
        // Two walls under one mask at first, then seen alone, then apart in one frame twice.
        counts.observe_frame(&[mask(1, &[10, 11])]);
        for _ in 0..3 {
            counts.observe_frame(&[mask(1, &[10])]);
        }
        counts.observe_frame(&[mask(1, &[11])]);
        counts.observe_frame(&[mask(1, &[10]), mask(1, &[11])]);
        counts.observe_frame(&[mask(1, &[10]), mask(1, &[11])]);
        assert_eq!(counts.split_instances(2), 1);
        let (a, b) = (
            counts.identity(10).expect("a"),
            counts.identity(11).expect("b"),
        );
        assert_ne!(a.instance, b.instance);
        // Once apart, they stay apart.
        let next = counts.observe_frame(&[mask(1, &[10]), mask(1, &[11])]);
        assert_eq!(next, vec![a.instance, b.instance]);
    }

    #[test]
    fn the_baseline_tracks_instances_without_class() {
        let mut counts = InstanceCounts::new(InstanceFusion::Voxblox);
        counts.observe_frame(&[mask(2, &[20])]);
        // A confused class still takes the old instance in the baseline.
        assert_eq!(counts.observe_frame(&[mask(3, &[20])]), vec![1]);
    }
}
