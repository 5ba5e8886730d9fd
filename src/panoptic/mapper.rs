//! The panoptic mapper: per frame, geometric segmentation fused with the masks, association of
//! the frame's segments to global segment labels by voxel overlap, instance fusion, and TSDF plus
//! label integration; every few frames, regularisation (label and instance merging).

use std::collections::BTreeMap;

use glam::Affine3A;
use rayon::prelude::*;

use crate::geometry::Pinhole;
use crate::map::{FrameLabelStore, FrameLabels, SegmentLabel, TsdfFrame, TsdfMap};
use crate::panoptic::fusion::{FusedFrame, FusionParams, cut_to_exact_masks, fuse_masks};
use crate::panoptic::instances::{ClassId, InstanceCounts, InstanceFusion, MaskObservation};
use crate::segmentation::PanopticFrame;
use crate::segmentation::geometric::{GeometricParams, GeometricSegmentation};

#[derive(Clone, Debug)]
pub struct MapperParams {
    pub voxel_size: f32,
    pub fusion: InstanceFusion,
    pub geometric: GeometricParams,
    pub masks: FusionParams,
    /// Pixels sampled for association, every this many in each direction.
    pub association_stride: usize,
    /// Metres: a sampled pixel's point counts for the label of the voxel it lands in when that
    /// voxel is this close to the surface, or two voxels if that is more. Two 2 cm voxels, kept
    /// in metres: depth noise does not shrink with the voxel, and with two 1 cm voxels noisy
    /// points missed their labels and objects came out in pieces (the noisy bedroom at 1 cm:
    /// GED 18, 4 with this band).
    pub association_band: f32,
    /// A segment continues a label when that label holds this fraction of its sampled voxels.
    pub min_overlap: f32,
    /// Two labels merge after a segment overlapped both by this fraction...
    pub merge_overlap: f32,
    /// ...in this many frames (Han et al.: 0.2 over 3 frames).
    pub merge_frames: u32,
    /// Eq. 5's m_th.
    pub instance_merge_ratio: f32,
    /// Labels of one instance seen in different masks this often (and more often than in one)
    /// are split apart.
    pub min_apart_frames: u32,
    /// Regularise every this many frames (and once at the end).
    pub regularise_every: usize,
    /// A cut-out segment's label votes this many times its weight: where a mask had to part an
    /// object from the segment geometry joined it to (a mug on a table, seen from where the
    /// crease at its foot blurs), the frames that do not see the object at all would otherwise
    /// write the table's label over it.
    pub cut_out_label_gain: u8,
    /// Frames are segmented every this many (the first included); the others are fused with their
    /// geometric segments, which continue the labels the map already has, and the masks the
    /// segmentation service gives without its networks (`segment_without_networks`).
    pub segment_every: usize,
    /// The frames' label images kept for the checks after mapping (carving, sightings) take at
    /// most this many bytes (`FrameLabelStore`: past it, the kept frames thin out evenly).
    pub frame_labels_budget_bytes: usize,
}

/// The frames' label images take about 0.1 MB a frame on 7-Scenes with geometric segments
/// (73 MB over 1000 frames): 256 MB keeps every frame's for some 2,500 frames, and bounds a
/// longer sequence's.
pub const FRAME_LABELS_BUDGET_BYTES: usize = 256 << 20;

impl MapperParams {
    pub fn new(voxel_size: f32, fusion: InstanceFusion) -> Self {
        Self {
            voxel_size,
            fusion,
            geometric: GeometricParams::default(),
            masks: FusionParams {
                refine: fusion == InstanceFusion::Joint,
                ..FusionParams::default()
            },
            association_stride: 2,
            association_band: 0.04,
            min_overlap: 0.2,
            merge_overlap: 0.2,
            merge_frames: 3,
            instance_merge_ratio: 0.5,
            min_apart_frames: 2,
            regularise_every: 25,
            cut_out_label_gain: 2,
            segment_every: 1,
            frame_labels_budget_bytes: FRAME_LABELS_BUDGET_BYTES,
        }
    }
}

/// One frame as the mapper needs it.
pub struct MapperFrame<'a> {
    pub depth: &'a [f32],
    pub color: &'a [u8],
    pub camera: &'a Pinhole,
    pub world_from_camera: &'a Affine3A,
}

/// A frame's segmentation, ready for association: fused segments and the class of each mask.
pub struct SegmentedFrame {
    pub fused: FusedFrame,
    pub mask_class: BTreeMap<u16, ClassId>,
}

/// Runs the per-frame, map-independent part (geometric segmentation and mask fusion); frames can
/// go through it in parallel.
pub fn segment_frame(
    frame: &MapperFrame,
    geometry: &GeometricSegmentation,
    masks: Option<&PanopticFrame>,
    class_id: &impl Fn(&str) -> Option<ClassId>,
    exact_classes: &[&str],
    params: &MapperParams,
) -> SegmentedFrame {
    let empty;
    let masks = match masks {
        Some(m) => m,
        None => {
            empty = PanopticFrame {
                width: frame.camera.width,
                height: frame.camera.height,
                segment_of_pixel: vec![0; frame.depth.len()],
                segments: Vec::new(),
            };
            &empty
        }
    };
    let mask_class = masks
        .segments
        .iter()
        .filter_map(|s| class_id(&s.class).map(|c| (s.id, c)))
        .collect::<BTreeMap<_, _>>();
    let mut fused = fuse_masks(geometry, masks, &params.masks);
    let exact: Vec<u16> = masks
        .segments
        .iter()
        .filter(|s| exact_classes.contains(&s.class.as_str()))
        .map(|s| s.id)
        .collect();
    cut_to_exact_masks(&mut fused, masks, &exact);
    // Masks of classes the table does not know are background.
    for s in &mut fused.segments {
        if s.mask.is_some_and(|m| !mask_class.contains_key(&m)) {
            s.mask = None;
        }
    }
    SegmentedFrame { fused, mask_class }
}

/// The state of the panoptic map.
#[derive(Clone)]
pub struct PanopticMapper {
    pub params: MapperParams,
    pub tsdf: TsdfMap,
    pub instances: InstanceCounts,
    next_label: SegmentLabel,
    /// Every label's label now (merges relabel the map's voxels; frames keep the old labels).
    label_now: Vec<SegmentLabel>,
    /// Each integrated frame's label image, in order: what the frame said each pixel was
    /// (within a budget: some dropped on a long sequence).
    frame_labels: FrameLabelStore,
    /// How often a segment overlapped both labels of a pair (smaller label first).
    pair_counts: BTreeMap<(SegmentLabel, SegmentLabel), u32>,
    frames: usize,
    pub label_merges: usize,
    pub instance_merges: usize,
    pub instance_splits: usize,
}

impl PanopticMapper {
    pub fn new(params: MapperParams) -> Self {
        let budget = params.frame_labels_budget_bytes;
        Self {
            tsdf: TsdfMap::new(params.voxel_size),
            instances: InstanceCounts::new(params.fusion),
            params,
            next_label: 1,
            label_now: Vec::new(),
            frame_labels: FrameLabelStore::new(budget),
            pair_counts: BTreeMap::new(),
            frames: 0,
            label_merges: 0,
            instance_merges: 0,
            instance_splits: 0,
        }
    }

    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The label images of the frames integrated, in order (a dropped one reads 0 everywhere).
    pub fn frame_labels(&self) -> &[FrameLabels] {
        self.frame_labels.frames()
    }

    /// Bytes the kept label images take, and how many frames' are kept.
    pub fn frame_labels_kept(&self) -> (usize, usize) {
        (self.frame_labels.bytes(), self.frame_labels.kept())
    }

    /// The map's label now for label `l` of a frame (labels merged since carry the one they
    /// merged into).
    pub fn label_now(&self, l: SegmentLabel) -> SegmentLabel {
        self.label_now.get(l as usize).copied().unwrap_or(l)
    }

    /// One more than the largest label given out.
    pub fn label_count(&self) -> SegmentLabel {
        self.next_label
    }

    /// Associates, fuses instances and integrates one segmented frame.
    pub fn integrate(&mut self, frame: &MapperFrame, segmented: &SegmentedFrame) {
        let labels_of_segment = self.associate(frame, &segmented.fused);
        let mut by_mask: BTreeMap<u16, Vec<SegmentLabel>> = BTreeMap::new();
        for (s, seg) in segmented.fused.segments.iter().enumerate() {
            if let Some(m) = seg.mask
                && labels_of_segment[s] != 0
            {
                by_mask.entry(m).or_default().push(labels_of_segment[s]);
            }
        }
        let observations: Vec<MaskObservation> = by_mask
            .iter()
            .map(|(m, labels)| MaskObservation {
                class: segmented.mask_class[m],
                labels: labels.clone(),
            })
            .collect();
        self.instances.observe_frame(&observations);
        let label_image: Vec<SegmentLabel> = segmented
            .fused
            .segment_of_pixel
            .par_iter()
            .map(|&s| {
                if s == 0 {
                    0
                } else {
                    labels_of_segment[s as usize - 1]
                }
            })
            .collect();
        let segments = &segmented.fused.segments;
        let label_gains: Option<Vec<u8>> = segments.iter().any(|s| s.cut_out).then(|| {
            segmented
                .fused
                .segment_of_pixel
                .par_iter()
                .map(|&s| {
                    let cut_out = s != 0 && segments[s as usize - 1].cut_out;
                    if cut_out {
                        self.params.cut_out_label_gain
                    } else {
                        1
                    }
                })
                .collect()
        });
        self.frame_labels
            .push(|| FrameLabels::encode(&label_image, frame.camera.width, frame.camera.height));
        self.tsdf.integrate(&TsdfFrame {
            depth: frame.depth,
            color: frame.color,
            labels: Some(&label_image),
            label_gains: label_gains.as_deref(),
            camera: frame.camera,
            world_from_camera: frame.world_from_camera,
        });
        self.frames += 1;
        if self.frames.is_multiple_of(self.params.regularise_every) {
            self.regularise();
        }
    }

    /// The global label of every segment of the frame (0 for segments too small to sample):
    /// pairs (segment, label) by voxel overlap, greedily from the largest overlap, each label to at
    /// most one segment; segments left over start new labels. Counts pair overlaps for merging.
    fn associate(&mut self, frame: &MapperFrame, fused: &FusedFrame) -> Vec<SegmentLabel> {
        let n = fused.segments.len();
        let w = frame.camera.width as usize;
        let stride = self.params.association_stride;
        let tsdf = &self.tsdf;
        let near_surface = (2.0 * tsdf.voxel_size).max(self.params.association_band);
        // (overlap counts per label, sampled pixels) per segment.
        let samples: Vec<(BTreeMap<SegmentLabel, u32>, u32)> = (0..frame.camera.height as usize)
            .into_par_iter()
            .step_by(stride)
            .fold(
                || vec![(BTreeMap::new(), 0u32); n],
                |mut acc, v| {
                    for u in (0..w).step_by(stride) {
                        let i = v * w + u;
                        let s = fused.segment_of_pixel[i];
                        if s == 0 {
                            continue;
                        }
                        let entry = &mut acc[s as usize - 1];
                        entry.1 += 1;
                        let point =
                            frame
                                .world_from_camera
                                .transform_point3(frame.camera.unproject(
                                    u as f32,
                                    v as f32,
                                    frame.depth[i],
                                ));
                        if let Some(voxel) = tsdf.voxel_at(point)
                            && voxel.label != 0
                            && voxel.is_observed()
                            && voxel.sdf.abs() < near_surface
                        {
                            *entry.0.entry(voxel.label).or_default() += 1;
                        }
                    }
                    acc
                },
            )
            .reduce(
                || vec![(BTreeMap::new(), 0u32); n],
                |mut a, b| {
                    for (x, y) in a.iter_mut().zip(b) {
                        x.1 += y.1;
                        for (l, c) in y.0 {
                            *x.0.entry(l).or_default() += c;
                        }
                    }
                    a
                },
            );
        let mut candidates: Vec<(u32, usize, SegmentLabel)> = Vec::new();
        for (s, (counts, sampled)) in samples.iter().enumerate() {
            for (&l, &c) in counts {
                if c as f32 >= self.params.min_overlap * *sampled as f32 {
                    candidates.push((c, s, l));
                }
            }
        }
        candidates.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        let mut label_of = vec![0 as SegmentLabel; n];
        let mut used = std::collections::BTreeSet::new();
        for (_, s, l) in candidates {
            if label_of[s] == 0 && !used.contains(&l) {
                label_of[s] = l;
                used.insert(l);
            }
        }
        // A segment worth a label: as small as fusion makes them (a cup far away is a few dozen
        // pixels), at the sampling stride.
        let min_samples =
            (self.params.masks.min_remainder_pixels as usize / (stride * stride)) as u32;
        for (s, label) in label_of.iter_mut().enumerate() {
            if *label == 0 && samples[s].1 >= min_samples.max(1) {
                *label = self.next_label;
                self.next_label += 1;
            }
        }
        // Labels a segment overlapped besides its own are merge candidates.
        for (s, (counts, sampled)) in samples.iter().enumerate() {
            let own = label_of[s];
            if own == 0 {
                continue;
            }
            for (&l, &c) in counts {
                if l != own && c as f32 >= self.params.merge_overlap * *sampled as f32 {
                    *self
                        .pair_counts
                        .entry((own.min(l), own.max(l)))
                        .or_default() += 1;
                }
            }
        }
        label_of
    }

    /// Merges labels that overlapped often enough (the map's voxels are relabelled), then
    /// instances by Eq. 5.
    pub fn regularise(&mut self) {
        let mut parent: Vec<SegmentLabel> = (0..self.next_label).collect();
        let mut merged = 0;
        for (&(a, b), &n) in &self.pair_counts {
            // Never merge what a segmenter saw as two objects (flush cabinet fronts, for one) nor
            // what resolved to two classes (the floor and the wall meeting it in a corner).
            if n >= self.params.merge_frames
                && !self.instances.seen_apart(a, b)
                && !self
                    .instances
                    .of_different_classes(a, b, self.params.merge_frames)
            {
                crate::segmentation::geometric::union(&mut parent, a, b);
                merged += 1;
            }
        }
        if merged > 0 {
            let roots: Vec<SegmentLabel> = (0..self.next_label)
                .map(|l| crate::segmentation::geometric::find(&mut parent, l))
                .collect();
            for (l, &root) in roots.iter().enumerate() {
                if root != l as SegmentLabel {
                    self.instances.merge_labels(l as SegmentLabel, root);
                }
            }
            self.tsdf.relabel(&roots);
            self.label_now = (0..self.next_label)
                .map(|l| roots[self.label_now(l) as usize])
                .collect();
            let old = std::mem::take(&mut self.pair_counts);
            for ((a, b), n) in old {
                let (ra, rb) = (roots[a as usize], roots[b as usize]);
                if ra != rb {
                    *self
                        .pair_counts
                        .entry((ra.min(rb), ra.max(rb)))
                        .or_default() += n;
                }
            }
            self.label_merges += roots
                .iter()
                .enumerate()
                .filter(|(l, r)| **r != *l as SegmentLabel)
                .count();
        }
        self.instance_splits += self.instances.split_instances(self.params.min_apart_frames);
        self.instance_merges += self
            .instances
            .merge_instances(self.params.instance_merge_ratio);
    }
}
