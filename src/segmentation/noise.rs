//! The segmentation noise model: what a real panoptic network gets wrong, applied to ground-truth
//! instance labels. Boundary bleeding, missed small instances, class confusion, split and merged
//! instances, and frame-local ids.

use std::collections::{BTreeMap, BTreeSet};

use rand::Rng;
use rand::seq::SliceRandom;
use serde::{Deserialize, Serialize};

use crate::classes::ClassTable;
use crate::segmentation::{PanopticFrame, PanopticSegment};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SegmentationNoise {
    /// Labels bleed across boundaries by up to this many pixels...
    pub bleed_radius_px: u32,
    /// ...at this rate per pixel near a boundary.
    pub bleed_probability: f32,
    /// Instances with fewer pixels than this in a frame...
    pub small_instance_px: u32,
    /// ...are missed with this probability.
    pub miss_probability: f32,
    /// A segment's class becomes one it is confusable with (class table) at this rate.
    pub confusion_probability: f32,
    /// An instance is split in two along its main axis at this rate.
    pub split_probability: f32,
    /// Two touching instances of one class become one at this rate.
    pub merge_probability: f32,
}

impl Default for SegmentationNoise {
    fn default() -> Self {
        Self::REALISTIC
    }
}

impl SegmentationNoise {
    pub const REALISTIC: SegmentationNoise = SegmentationNoise {
        bleed_radius_px: 3,
        bleed_probability: 0.35,
        small_instance_px: 400,
        miss_probability: 0.5,
        confusion_probability: 0.03,
        split_probability: 0.05,
        merge_probability: 0.1,
    };

    pub const HEAVY: SegmentationNoise = SegmentationNoise {
        bleed_radius_px: 6,
        bleed_probability: 0.5,
        small_instance_px: 900,
        miss_probability: 0.7,
        confusion_probability: 0.1,
        split_probability: 0.15,
        merge_probability: 0.25,
    };

    /// Turns ground-truth instance labels into a noisy panoptic frame. `classes` maps instance id
    /// to class. The outcome depends only on the inputs and the state of `rng`.
    pub fn apply(
        &self,
        labels: &[u16],
        width: u32,
        classes: &BTreeMap<u16, String>,
        rng: &mut impl Rng,
    ) -> PanopticFrame {
        let w = width as usize;
        let h = labels.len() / w.max(1);
        let mut image = labels.to_vec();
        let mut class_of: BTreeMap<u16, String> = BTreeMap::new();
        // Per-pixel work goes through tables indexed by label, not tree lookups.
        let mut pixels_of = vec![0usize; 1 << 16];
        for &l in &image {
            pixels_of[l as usize] += 1;
        }
        let counts: BTreeMap<u16, usize> = (1..=u16::MAX)
            .filter(|&l| pixels_of[l as usize] > 0)
            .map(|l| (l, pixels_of[l as usize]))
            .collect();
        for &id in counts.keys() {
            class_of.insert(
                id,
                classes
                    .get(&id)
                    .cloned()
                    .unwrap_or_else(|| "unknown".into()),
            );
        }
        // Missed small instances.
        let missed: BTreeSet<u16> = counts
            .iter()
            .filter(|(_, n)| **n < self.small_instance_px as usize)
            .map(|(id, _)| *id)
            .filter(|_| rng.random::<f32>() < self.miss_probability)
            .collect();
        // Merges of touching instances of one class (decided per touching pair).
        let mut touching: BTreeSet<(u16, u16)> = BTreeSet::new();
        for y in 0..h {
            for x in 0..w {
                let a = image[y * w + x];
                for (nx, ny) in [(x + 1, y), (x, y + 1)] {
                    if nx < w && ny < h {
                        let b = image[ny * w + nx];
                        if a != 0 && b != 0 && a != b && class_of.get(&a) == class_of.get(&b) {
                            touching.insert((a.min(b), a.max(b)));
                        }
                    }
                }
            }
        }
        let mut merged_into: BTreeMap<u16, u16> = BTreeMap::new();
        for (a, b) in touching {
            if rng.random::<f32>() < self.merge_probability
                && !merged_into.contains_key(&a)
                && !merged_into.contains_key(&b)
            {
                merged_into.insert(b, a);
            }
        }
        let mut relabel: Vec<u16> = (0..=u16::MAX).collect();
        for &id in &missed {
            relabel[id as usize] = 0;
        }
        for (&from, &into) in &merged_into {
            if !missed.contains(&from) {
                relabel[from as usize] = into;
            }
        }
        for l in &mut image {
            *l = relabel[*l as usize];
        }
        // Splits along the main axis of the instance's pixels.
        let mut next_id = counts.keys().max().copied().unwrap_or(0).saturating_add(1);
        let survivors: Vec<u16> = counts
            .keys()
            .copied()
            .filter(|id| !missed.contains(id) && !merged_into.contains_key(id))
            .collect();
        for id in survivors {
            if rng.random::<f32>() >= self.split_probability
                || counts[&id] < 2 * self.small_instance_px as usize
                || next_id == u16::MAX
            {
                continue;
            }
            let pixels: Vec<usize> = (0..image.len()).filter(|&i| image[i] == id).collect();
            let n = pixels.len() as f64;
            let (mut mx, mut my) = (0.0, 0.0);
            for &i in &pixels {
                mx += (i % w) as f64 / n;
                my += (i / w) as f64 / n;
            }
            let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
            for &i in &pixels {
                let (dx, dy) = ((i % w) as f64 - mx, (i / w) as f64 - my);
                sxx += dx * dx;
                sxy += dx * dy;
                syy += dy * dy;
            }
            let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
            let (axis_x, axis_y) = (angle.cos(), angle.sin());
            for &i in &pixels {
                if ((i % w) as f64 - mx) * axis_x + ((i / w) as f64 - my) * axis_y > 0.0 {
                    image[i] = next_id;
                }
            }
            class_of.insert(next_id, class_of[&id].clone());
            next_id += 1;
        }
        // Boundary bleeding: a pixel takes the label of a random nearby pixel.
        let r = self.bleed_radius_px as i64;
        if r > 0 && self.bleed_probability > 0.0 {
            let before = image.clone();
            for y in 0..h as i64 {
                for x in 0..w as i64 {
                    let dx = rng.random_range(-r..=r);
                    let dy = rng.random_range(-r..=r);
                    let u: f32 = rng.random();
                    let (sx, sy) = (x + dx, y + dy);
                    if sx < 0 || sy < 0 || sx >= w as i64 || sy >= h as i64 {
                        continue;
                    }
                    let other = before[(sy * w as i64 + sx) as usize];
                    let i = (y * w as i64 + x) as usize;
                    if other != before[i] && u < self.bleed_probability {
                        image[i] = other;
                    }
                }
            }
        }
        // Frame-local ids in random order, and class confusion.
        let mut seen = vec![false; 1 << 16];
        for &l in &image {
            seen[l as usize] = true;
        }
        let mut present: Vec<u16> = (1..=u16::MAX).filter(|&l| seen[l as usize]).collect();
        present.shuffle(rng);
        let local: BTreeMap<u16, u16> = present
            .iter()
            .enumerate()
            .map(|(k, &id)| (id, k as u16 + 1))
            .collect();
        let mut to_local = vec![0u16; 1 << 16];
        for (&id, &k) in &local {
            to_local[id as usize] = k;
        }
        for l in &mut image {
            *l = to_local[*l as usize];
        }
        let table = ClassTable::builtin();
        let mut segments: Vec<PanopticSegment> = present
            .iter()
            .map(|id| {
                let mut class = class_of[id].clone();
                let confusable = table
                    .get(&class)
                    .map(|c| c.confusable.clone())
                    .unwrap_or_default();
                let confused =
                    rng.random::<f32>() < self.confusion_probability && !confusable.is_empty();
                if confused {
                    class = confusable[rng.random_range(0..confusable.len())].clone();
                }
                let score = if confused {
                    0.4 + 0.2 * rng.random::<f32>()
                } else {
                    0.7 + 0.3 * rng.random::<f32>()
                };
                PanopticSegment {
                    id: local[id],
                    class,
                    score,
                }
            })
            .collect();
        segments.sort_by_key(|s| s.id);
        PanopticFrame {
            width,
            height: h as u32,
            segment_of_pixel: image,
            segments,
        }
    }
}

/// A segmentation noise setting: a preset name or explicit parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SegmentationNoiseSetting {
    Preset(SegmentationPreset),
    Custom(SegmentationNoise),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SegmentationPreset {
    Realistic,
    Heavy,
    None,
}

impl SegmentationNoiseSetting {
    pub fn model(&self) -> Option<SegmentationNoise> {
        match self {
            Self::Preset(SegmentationPreset::Realistic) => Some(SegmentationNoise::REALISTIC),
            Self::Preset(SegmentationPreset::Heavy) => Some(SegmentationNoise::HEAVY),
            Self::Preset(SegmentationPreset::None) => None,
            Self::Custom(params) => Some(*params),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// A 100x60 image: a big table (id 7), a small cup (id 8) on it, floor (id 1) elsewhere.
    fn scene() -> (Vec<u16>, BTreeMap<u16, String>) {
        let (w, h) = (100, 60);
        let mut labels = vec![1u16; w * h];
        for y in 10..50 {
            for x in 10..90 {
                labels[y * w + x] = 7;
            }
        }
        for y in 20..30 {
            for x in 40..50 {
                labels[y * w + x] = 8;
            }
        }
        let classes = BTreeMap::from([(1, "floor".into()), (7, "table".into()), (8, "cup".into())]);
        (labels, classes)
    }

    #[test]
    fn small_instances_are_missed_at_the_model_rate() {
        let (labels, classes) = scene();
        let noise = SegmentationNoise {
            bleed_probability: 0.0,
            split_probability: 0.0,
            merge_probability: 0.0,
            ..SegmentationNoise::REALISTIC
        };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let trials = 400;
        let missed = (0..trials)
            .filter(|_| {
                let f = noise.apply(&labels, 100, &classes, &mut rng);
                !f.segments
                    .iter()
                    .any(|s| s.class == "cup" || classes_confused_from_cup(&s.class))
            })
            .count();
        let rate = missed as f32 / trials as f32;
        assert!(
            (rate - noise.miss_probability).abs() < 0.08,
            "miss rate {rate}, model {}",
            noise.miss_probability
        );
    }

    fn classes_confused_from_cup(class: &str) -> bool {
        ClassTable::builtin()
            .get("cup")
            .is_some_and(|c| c.confusable.iter().any(|k| k == class))
    }

    #[test]
    fn bleeding_stays_within_its_radius_of_a_boundary() {
        let (labels, classes) = scene();
        let noise = SegmentationNoise {
            bleed_probability: 1.0,
            miss_probability: 0.0,
            split_probability: 0.0,
            merge_probability: 0.0,
            confusion_probability: 0.0,
            ..SegmentationNoise::REALISTIC
        };
        let f = noise.apply(&labels, 100, &classes, &mut ChaCha8Rng::seed_from_u64(2));
        // Map local ids back by class to compare with ground truth.
        let gt_class = |i: usize| classes[&labels[i]].clone();
        let r = noise.bleed_radius_px as i64;
        let mut changed = 0;
        for i in 0..labels.len() {
            let class = f
                .segment(f.segment_of_pixel[i])
                .map(|s| s.class.clone())
                .unwrap_or_default();
            if class != gt_class(i) {
                changed += 1;
                let (x, y) = ((i % 100) as i64, (i / 100) as i64);
                let near_boundary = (-r..=r).any(|dy| {
                    (-r..=r).any(|dx| {
                        let (sx, sy) = (x + dx, y + dy);
                        sx >= 0
                            && sy >= 0
                            && sx < 100
                            && sy < 60
                            && labels[(sy * 100 + sx) as usize] != labels[i]
                    })
                });
                assert!(near_boundary, "pixel {x},{y} changed far from any boundary");
            }
        }
        assert!(changed > 100, "bleeding changed only {changed} pixels");
    }

    #[test]
    fn splits_give_two_segments_of_one_class_and_ids_are_frame_local() {
        let (labels, classes) = scene();
        let noise = SegmentationNoise {
            split_probability: 1.0,
            bleed_probability: 0.0,
            miss_probability: 0.0,
            merge_probability: 0.0,
            confusion_probability: 0.0,
            ..SegmentationNoise::REALISTIC
        };
        let f = noise.apply(&labels, 100, &classes, &mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(f.segments.iter().filter(|s| s.class == "table").count(), 2);
        let mut ids: Vec<u16> = f.segments.iter().map(|s| s.id).collect();
        ids.sort_unstable();
        assert_eq!(ids, (1..=ids.len() as u16).collect::<Vec<_>>());
    }

    #[test]
    fn the_same_seed_gives_the_same_frame() {
        let (labels, classes) = scene();
        let a = SegmentationNoise::HEAVY.apply(
            &labels,
            100,
            &classes,
            &mut ChaCha8Rng::seed_from_u64(9),
        );
        let b = SegmentationNoise::HEAVY.apply(
            &labels,
            100,
            &classes,
            &mut ChaCha8Rng::seed_from_u64(9),
        );
        assert_eq!(a, b);
    }
}
