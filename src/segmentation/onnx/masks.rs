//! Panoptic masks from what the networks give: no network here segments instances, so an
//! instance is its detector box cut down to the pixels that agree with it, in class (the semantic
//! network's label, where it knows the class) or else in depth (the object's own distance). Floor
//! and walls come from the room's layout. The mapper then fuses these masks with the geometric
//! segments, which give the exact boundaries.

use crate::segmentation::onnx::layout::LayoutLabel;
use crate::segmentation::{PanopticFrame, PanopticSegment};

/// A detection already mapped to one of the project's classes.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectDetection {
    pub class: String,
    pub score: f32,
    /// [x0, y0, x1, y1] in image pixels.
    pub bbox: [f32; 4],
    /// The semantic network's labels for this class; empty when it has none.
    pub semantic_labels: Vec<u8>,
}

#[derive(Clone, Copy, Debug)]
pub struct MaskParams {
    /// Semantic pixels are used when they fill at least this share of the box's measured pixels;
    /// otherwise (the semantic network missed the object) depth decides.
    pub min_semantic_share: f32,
    /// The depth band around the object's distance: this times its size in metres...
    pub depth_band_factor: f32,
    /// ...between these (metres).
    pub depth_band: [f32; 2],
    /// The central share of the box (per side) whose median depth is the object's distance.
    pub centre_share: f32,
    /// A geometric segment with at least this share of its pixels in the box and depth band is
    /// the object's.
    pub min_inside_share: f32,
    /// Without such a segment, a depth-banded mask leaves out pixels the semantic network gives to other objects when
    /// at least this share of it remains.
    pub min_own_share: f32,
    /// Masks left with fewer pixels are dropped.
    pub min_pixels: u32,
}

impl Default for MaskParams {
    fn default() -> Self {
        Self {
            min_semantic_share: 0.1,
            depth_band_factor: 0.75,
            depth_band: [0.06, 0.6],
            centre_share: 0.4,
            min_inside_share: 0.6,
            min_own_share: 0.3,
            min_pixels: 40,
        }
    }
}

/// One frame's inputs to the masks.
pub struct MaskInputs<'a> {
    pub width: u32,
    pub height: u32,
    /// Metres; 0 where unmeasured.
    pub depth: &'a [f32],
    /// Horizontal focal length in pixels (to size boxes in metres).
    pub fx: f32,
    /// The semantic label of every pixel.
    pub semantic: &'a [u8],
    /// The layout label of every pixel.
    pub layout: &'a [Option<LayoutLabel>],
    /// The geometric segment of every pixel (0 = none) and each segment's size (index = id).
    pub geometric: &'a [u32],
    pub geometric_sizes: &'a [u32],
}

pub fn panoptic_masks(
    inputs: &MaskInputs,
    detections: &[ObjectDetection],
    params: &MaskParams,
) -> PanopticFrame {
    let (w, h) = (inputs.width as usize, inputs.height as usize);
    let mut segment_of_pixel = vec![0u16; w * h];
    let mut segments: Vec<PanopticSegment> = Vec::new();
    // Layout first: ids 1 for the floor and 2.. for walls, so objects painted later win.
    let wall_count = inputs
        .layout
        .iter()
        .filter_map(|l| match l {
            Some(LayoutLabel::Wall(k)) => Some(*k + 1),
            _ => None,
        })
        .max()
        .unwrap_or(0);
    segments.push(segment(1, "floor", 1.0));
    for k in 0..wall_count {
        segments.push(segment(2 + k as u16, "wall", 1.0));
    }
    for (i, l) in inputs.layout.iter().enumerate() {
        segment_of_pixel[i] = match l {
            Some(LayoutLabel::Floor) => 1,
            Some(LayoutLabel::Wall(k)) => 2 + *k as u16,
            None => 0,
        };
    }
    // Larger boxes first, so a cup's mask is painted over the table's.
    let mut order: Vec<&ObjectDetection> = detections.iter().collect();
    order.sort_by(|a, b| area(b).total_cmp(&area(a)));
    for d in order {
        let Some(pixels) = object_pixels(inputs, d, params) else {
            continue;
        };
        let Ok(id) = u16::try_from(segments.len() + 1) else {
            break;
        };
        for i in pixels {
            segment_of_pixel[i] = id;
        }
        segments.push(segment(id, &d.class, d.score));
    }
    // Drop masks that painting left too small, and renumber densely in order.
    let mut counts = vec![0u32; segments.len() + 1];
    for &s in &segment_of_pixel {
        counts[s as usize] += 1;
    }
    let mut new_id = vec![0u16; segments.len() + 1];
    let mut kept = Vec::new();
    for s in segments {
        if counts[s.id as usize] >= params.min_pixels {
            new_id[s.id as usize] = kept.len() as u16 + 1;
            kept.push(PanopticSegment {
                id: kept.len() as u16 + 1,
                ..s
            });
        }
    }
    for s in &mut segment_of_pixel {
        *s = new_id[*s as usize];
    }
    PanopticFrame {
        width: inputs.width,
        height: inputs.height,
        segment_of_pixel,
        segments: kept,
    }
}

fn segment(id: u16, class: &str, score: f32) -> PanopticSegment {
    PanopticSegment {
        id,
        class: class.to_string(),
        score,
    }
}

fn area(d: &ObjectDetection) -> f32 {
    (d.bbox[2] - d.bbox[0]).max(0.0) * (d.bbox[3] - d.bbox[1]).max(0.0)
}

/// The measured pixels of `d`'s box that agree with it: its semantic pixels when the semantic
/// network saw it, else those within a band around its distance.
fn object_pixels(
    inputs: &MaskInputs,
    d: &ObjectDetection,
    params: &MaskParams,
) -> Option<Vec<usize>> {
    let (w, h) = (inputs.width as usize, inputs.height as usize);
    let x0 = (d.bbox[0].floor().max(0.0) as usize).min(w);
    let y0 = (d.bbox[1].floor().max(0.0) as usize).min(h);
    let x1 = (d.bbox[2].ceil().max(0.0) as usize).min(w);
    let y1 = (d.bbox[3].ceil().max(0.0) as usize).min(h);
    if x1 <= x0 || y1 <= y0 {
        return None;
    }
    let measured: Vec<usize> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| y * w + x))
        .filter(|&i| inputs.depth[i] > 0.0)
        .collect();
    if !d.semantic_labels.is_empty() {
        let semantic: Vec<usize> = measured
            .iter()
            .copied()
            .filter(|&i| d.semantic_labels.contains(&inputs.semantic[i]))
            .collect();
        if semantic.len() as f32 >= params.min_semantic_share * measured.len() as f32
            && !semantic.is_empty()
        {
            return Some(semantic);
        }
    }
    // The object's distance: the median depth of the box's centre.
    let (bw, bh) = (x1 - x0, y1 - y0);
    let margin = |n: usize| ((1.0 - params.centre_share) / 2.0 * n as f32) as usize;
    let (cx0, cx1) = (x0 + margin(bw), x1 - margin(bw));
    let (cy0, cy1) = (y0 + margin(bh), y1 - margin(bh));
    let mut centre: Vec<f32> = measured
        .iter()
        .filter(|&&i| (cx0..cx1).contains(&(i % w)) && (cy0..cy1).contains(&(i / w)))
        .map(|&i| inputs.depth[i])
        .collect();
    if centre.is_empty() {
        return None;
    }
    let mid = centre.len() / 2;
    let distance = *centre.select_nth_unstable_by(mid, f32::total_cmp).1;
    let size = bw.max(bh) as f32 * distance / inputs.fx;
    let band = (params.depth_band_factor * size).clamp(params.depth_band[0], params.depth_band[1]);
    let near: Vec<usize> = measured
        .into_iter()
        .filter(|&i| (inputs.depth[i] - distance).abs() <= band)
        .collect();
    // The geometric segments that lie (mostly) inside the box are the object; the table it
    // stands on runs on outside the box.
    let mut inside: std::collections::BTreeMap<u32, u32> = Default::default();
    for &i in &near {
        *inside.entry(inputs.geometric[i]).or_default() += 1;
    }
    let own_segments: Vec<u32> = inside
        .into_iter()
        .filter(|&(g, n)| {
            g != 0
                && n as f32 >= params.min_inside_share * inputs.geometric_sizes[g as usize] as f32
        })
        .map(|(g, _)| g)
        .collect();
    if !own_segments.is_empty() {
        return Some(
            near.into_iter()
                .filter(|&i| own_segments.contains(&inputs.geometric[i]))
                .collect(),
        );
    }
    // A magazine lies on the table at the table's depth: the semantic network's other objects
    // (the table) leave it, unless that would leave little (the network took the object itself
    // for the table).
    let own: Vec<usize> = near
        .iter()
        .copied()
        .filter(|&i| {
            let label = inputs.semantic[i];
            label == 0 || d.semantic_labels.contains(&label)
        })
        .collect();
    Some(
        if own.len() as f32 >= params.min_own_share * near.len() as f32 {
            own
        } else {
            near
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 40 x 30 frame: floor in the bottom third (depth 2 m), a table (semantic label 11) in the
    /// middle at 1.5 m, a cup on it at 1.4 m in a box that also covers a far wall at 3 m.
    struct Scene {
        depth: Vec<f32>,
        semantic: Vec<u8>,
        layout: Vec<Option<LayoutLabel>>,
        geometric: Vec<u32>,
        geometric_sizes: Vec<u32>,
    }

    fn scene() -> Scene {
        let (w, h) = (40, 30);
        let mut s = Scene {
            depth: vec![3.0; w * h],
            semantic: vec![0; w * h],
            layout: vec![None; w * h],
            geometric: vec![0; w * h],
            geometric_sizes: vec![0],
        };
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if y >= 20 {
                    s.depth[i] = 2.0;
                    s.layout[i] = Some(LayoutLabel::Floor);
                } else if y >= 10 && (5..35).contains(&x) {
                    s.depth[i] = 1.5;
                    s.semantic[i] = 11;
                }
                if (10..14).contains(&x) && (5..10).contains(&y) {
                    s.depth[i] = 1.4;
                }
            }
        }
        s
    }

    fn inputs(s: &Scene) -> MaskInputs<'_> {
        MaskInputs {
            width: 40,
            height: 30,
            depth: &s.depth,
            fx: 40.0,
            semantic: &s.semantic,
            layout: &s.layout,
            geometric: &s.geometric,
            geometric_sizes: &s.geometric_sizes,
        }
    }

    fn params() -> MaskParams {
        MaskParams {
            min_pixels: 5,
            ..MaskParams::default()
        }
    }

    #[test]
    fn the_table_takes_its_semantic_pixels_and_the_cup_its_depth_over_the_floor() {
        let s = scene();
        let detections = vec![
            ObjectDetection {
                class: "cup".into(),
                score: 0.7,
                bbox: [9.0, 4.0, 15.0, 11.0],
                semantic_labels: vec![],
            },
            ObjectDetection {
                class: "table".into(),
                score: 0.9,
                bbox: [4.0, 9.0, 36.0, 25.0],
                semantic_labels: vec![11],
            },
        ];
        let frame = panoptic_masks(&inputs(&s), &detections, &params());
        let classes: Vec<&str> = frame.segments.iter().map(|s| s.class.as_str()).collect();
        assert_eq!(classes, vec!["floor", "table", "cup"]);
        let count = |id: u16| frame.segment_of_pixel.iter().filter(|&&p| p == id).count();
        // Floor: 10 rows of 40, untouched by the table's box because they are not table pixels.
        assert_eq!(count(1), 400);
        // Table: its 30 x 10 semantic pixels. Cup: its 4 x 5 pixels at 1.4 m; its depth band,
        // 0.75 x (7 px x 1.4 m / 40 px) = 0.18 m, also takes in the 6 table pixels 10 cm behind
        // in its box, which it leaves to the table, and not the far wall at 3 m.
        assert_eq!(count(2), 300);
        assert_eq!(count(3), 20);
        assert_eq!(frame.segment_of_pixel[7 * 40 + 11], 3);
        assert_eq!(
            frame.segment_of_pixel[5 * 40 + 9],
            0,
            "the far wall is not the cup"
        );
    }

    #[test]
    fn geometric_segments_inside_the_box_are_the_object_where_the_semantic_network_saw_nothing() {
        let mut s = scene();
        s.semantic.fill(0);
        s.geometric_sizes = vec![0, 20, 300];
        for (i, d) in s.depth.iter().enumerate() {
            s.geometric[i] = match *d {
                1.4 => 1,
                1.5 => 2,
                _ => 0,
            };
        }
        let cup = ObjectDetection {
            class: "cup".into(),
            score: 0.7,
            bbox: [9.0, 4.0, 15.0, 11.0],
            semantic_labels: vec![],
        };
        let with_geometry = panoptic_masks(&inputs(&s), std::slice::from_ref(&cup), &params());
        let count = |f: &PanopticFrame| f.segment_of_pixel.iter().filter(|&&p| p == 2).count();
        assert_eq!(count(&with_geometry), 20);
        // Without segments the depth band keeps the table top behind the cup too.
        s.geometric.fill(0);
        let without = panoptic_masks(&inputs(&s), &[cup], &params());
        assert_eq!(count(&without), 26);
    }

    #[test]
    fn a_class_the_semantic_network_missed_falls_back_to_depth() {
        let s = scene();
        let detections = vec![ObjectDetection {
            class: "chair".into(),
            score: 0.8,
            bbox: [9.0, 4.0, 15.0, 10.0],
            semantic_labels: vec![9],
        }];
        let frame = panoptic_masks(&inputs(&s), &detections, &params());
        let count = frame.segment_of_pixel.iter().filter(|&&p| p == 2).count();
        assert_eq!(frame.segments[1].class, "chair");
        assert_eq!(count, 20);
    }

    #[test]
    fn masks_painted_over_below_the_minimum_are_dropped_and_ids_stay_dense() {
        let s = scene();
        let detections = vec![ObjectDetection {
            class: "book".into(),
            score: 0.5,
            bbox: [0.0, 0.0, 2.0, 2.0],
            semantic_labels: vec![],
        }];
        let frame = panoptic_masks(&inputs(&s), &detections, &params());
        assert_eq!(frame.segments.len(), 1);
        assert_eq!(frame.segments[0].id, 1);
    }
}
