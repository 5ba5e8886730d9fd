//! YOLOX (Ge et al. 2021) as exported to ONNX without its decoding: the letterboxed input tensor,
//! and the decoding of the raw 1 x N x (5 + classes) output into boxes with class-wise
//! non-maximum suppression.

use image::RgbImage;
use image::imageops::FilterType;

/// The network's square input side.
pub const INPUT_SIDE: u32 = 416;
/// YOLOX's letterbox padding value.
const PAD: f32 = 114.0;
/// The feature-map strides of the three heads, in output order.
const STRIDES: [u32; 3] = [8, 16, 32];

/// One detection in image pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Detection {
    /// Index into the network's class names.
    pub label: usize,
    pub score: f32,
    /// [x0, y0, x1, y1], clamped to the image.
    pub bbox: [f32; 4],
}

impl Detection {
    pub fn area(&self) -> f32 {
        (self.bbox[2] - self.bbox[0]).max(0.0) * (self.bbox[3] - self.bbox[1]).max(0.0)
    }
}

/// The input tensor (1 x 3 x 416 x 416, BGR, 0-255): the image scaled to fit, top-left aligned,
/// the rest padded with 114 as in YOLOX's own preprocessing. Returns the tensor and the scale.
pub fn letterbox(image: &RgbImage) -> (Vec<f32>, f32) {
    let side = INPUT_SIDE as usize;
    let scale =
        (INPUT_SIDE as f32 / image.width() as f32).min(INPUT_SIDE as f32 / image.height() as f32);
    let w = ((image.width() as f32 * scale).round() as u32).clamp(1, INPUT_SIDE);
    let h = ((image.height() as f32 * scale).round() as u32).clamp(1, INPUT_SIDE);
    let resized = image::imageops::resize(image, w, h, FilterType::Triangle);
    let mut tensor = vec![PAD; 3 * side * side];
    for (x, y, p) in resized.enumerate_pixels() {
        let i = y as usize * side + x as usize;
        // BGR planes.
        for (plane, value) in [p[2], p[1], p[0]].into_iter().enumerate() {
            tensor[plane * side * side + i] = f32::from(value);
        }
    }
    (tensor, scale)
}

/// Decodes the raw output (rows of cx, cy, w, h in grid units, objectness and class scores
/// already through their sigmoid) into detections in the original image, keeping those whose
/// objectness x class score reaches `min_score`, then suppresses overlaps per class.
pub fn decode(
    output: &[f32],
    classes: usize,
    scale: f32,
    image_size: (u32, u32),
    min_score: f32,
    nms_iou: f32,
) -> Vec<Detection> {
    let row = 5 + classes;
    let mut detections = Vec::new();
    let mut index = 0;
    for stride in STRIDES {
        let cells = INPUT_SIDE / stride;
        for gy in 0..cells {
            for gx in 0..cells {
                let Some(r) = output.get(index * row..(index + 1) * row) else {
                    return nms(detections, nms_iou);
                };
                index += 1;
                let (label, class_score) =
                    r[5..]
                        .iter()
                        .copied()
                        .enumerate()
                        .fold(
                            (0, f32::MIN),
                            |best, (i, s)| if s > best.1 { (i, s) } else { best },
                        );
                let score = r[4] * class_score;
                // NaN scores fail the comparison and are skipped too.
                if score.partial_cmp(&min_score).is_none_or(|o| o.is_lt()) {
                    continue;
                }
                let s = stride as f32;
                let cx = (r[0] + gx as f32) * s;
                let cy = (r[1] + gy as f32) * s;
                let (w, h) = (r[2].exp() * s, r[3].exp() * s);
                let (iw, ih) = (image_size.0 as f32, image_size.1 as f32);
                let bbox = [
                    ((cx - w / 2.0) / scale).clamp(0.0, iw),
                    ((cy - h / 2.0) / scale).clamp(0.0, ih),
                    ((cx + w / 2.0) / scale).clamp(0.0, iw),
                    ((cy + h / 2.0) / scale).clamp(0.0, ih),
                ];
                detections.push(Detection { label, score, bbox });
            }
        }
    }
    nms(detections, nms_iou)
}

fn iou(a: &[f32; 4], b: &[f32; 4]) -> f32 {
    let w = (a[2].min(b[2]) - a[0].max(b[0])).max(0.0);
    let h = (a[3].min(b[3]) - a[1].max(b[1])).max(0.0);
    let inter = w * h;
    let area = |r: &[f32; 4]| (r[2] - r[0]) * (r[3] - r[1]);
    let union = area(a) + area(b) - inter;
    if union > 0.0 { inter / union } else { 0.0 }
}

/// Greedy class-wise non-maximum suppression, best score first; ties broken by position so the
/// result does not depend on the input order.
fn nms(mut detections: Vec<Detection>, max_iou: f32) -> Vec<Detection> {
    detections.sort_by(|a, b| {
        b.score
            .total_cmp(&a.score)
            .then(a.label.cmp(&b.label))
            .then(a.bbox[0].total_cmp(&b.bbox[0]))
            .then(a.bbox[1].total_cmp(&b.bbox[1]))
    });
    let mut kept: Vec<Detection> = Vec::new();
    for d in detections {
        if kept
            .iter()
            .all(|k| k.label != d.label || iou(&k.bbox, &d.bbox) <= max_iou)
        {
            kept.push(d);
        }
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A raw output with every row empty except those given as (row, label, cx, cy, w, h, score)
    /// in grid units of that row's stride.
    fn output(classes: usize, rows: &[(usize, usize, f32, f32, f32, f32, f32)]) -> Vec<f32> {
        let n: u32 = STRIDES.iter().map(|s| (INPUT_SIDE / s).pow(2)).sum();
        let mut out = vec![0.0; n as usize * (5 + classes)];
        for &(i, label, x, y, w, h, score) in rows {
            let r = &mut out[i * (5 + classes)..(i + 1) * (5 + classes)];
            r[..5].copy_from_slice(&[x, y, w.ln(), h.ln(), 1.0]);
            r[5 + label] = score;
        }
        out
    }

    #[test]
    fn rows_decode_on_their_grids_and_scale_back_to_the_image() {
        // Row 53 is cell (1, 1) of the stride-8 grid (52 cells a row); row 2704 is cell (0, 0) of
        // the stride-16 grid.
        let out = output(
            3,
            &[
                (53, 2, 0.5, 0.5, 2.0, 4.0, 0.9),
                (2704, 0, 0.0, 0.0, 1.0, 1.0, 0.8),
            ],
        );
        let d = decode(&out, 3, 0.5, (640, 480), 0.3, 0.45);
        assert_eq!(d.len(), 2);
        // Centre (1.5 * 8, 1.5 * 8) = (12, 12), size 16 x 32 in the input; twice that in the image.
        assert_eq!(d[0].label, 2);
        assert_eq!(d[0].bbox, [8.0, 0.0, 40.0, 56.0]);
        assert_eq!(d[1].label, 0);
        assert_eq!(d[1].bbox, [0.0, 0.0, 16.0, 16.0]);
    }

    #[test]
    fn overlapping_boxes_of_one_class_keep_the_best_and_other_classes_stay() {
        let out = output(
            2,
            &[
                (53, 0, 0.5, 0.5, 4.0, 4.0, 0.6),
                (54, 0, 0.5, 0.5, 4.0, 4.0, 0.9),
                (55, 1, 0.5, 0.5, 4.0, 4.0, 0.7),
                (60, 0, 0.5, 0.5, 4.0, 4.0, 0.2),
            ],
        );
        let d = decode(&out, 2, 1.0, (416, 416), 0.3, 0.45);
        let labels_scores: Vec<(usize, f32)> = d.iter().map(|d| (d.label, d.score)).collect();
        assert_eq!(labels_scores, vec![(0, 0.9), (1, 0.7)]);
    }

    #[test]
    fn the_letterbox_keeps_the_aspect_and_pads_below() {
        let image = RgbImage::from_pixel(640, 480, image::Rgb([10, 20, 30]));
        let (tensor, scale) = letterbox(&image);
        assert!((scale - 0.65).abs() < 1e-6);
        let side = INPUT_SIDE as usize;
        // Blue first (BGR), inside the image; padding below row 312.
        assert_eq!(tensor[0], 30.0);
        assert_eq!(tensor[2 * side * side], 10.0);
        assert_eq!(tensor[320 * side], PAD);
    }
}
