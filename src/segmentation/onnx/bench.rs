//! `iscene bench segmentation`: the onnx backend's time per frame on one core, and, on a rendered
//! sequence, how well its masks overlap the ground truth per class.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::time::Instant;

use crate::error::{InputError, IsceneError};
use crate::io::Sequence;
use crate::segmentation::SegmentationService;
use crate::segmentation::geometric::{GeometricParams, segment_depth};
use crate::segmentation::onnx::{OnnxDevice, OnnxModels, OnnxParams, OnnxSegmentation};

pub struct SegmentationBenchOptions {
    pub sequence: PathBuf,
    pub frames: (usize, Option<usize>, usize),
    pub models: PathBuf,
    /// Where the networks run.
    pub device: OnnxDevice,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct SegmentationBenchReport {
    pub sequence: PathBuf,
    pub frames: usize,
    /// Where the networks ran.
    pub device: OnnxDevice,
    /// Loading ONNX Runtime and the models, and the layout survey (once per sequence).
    pub setup_s: f64,
    /// Per frame on one thread: both networks, the layout labels and the masks (the geometric
    /// segmentation they use is the mapper's, computed anyway, and not counted).
    pub mean_ms_per_frame: f64,
    pub median_ms_per_frame: f64,
    pub max_ms_per_frame: f64,
    /// Masks per class over all frames.
    pub masks_per_class: BTreeMap<String, usize>,
    /// With ground truth: per class, intersection over union of the predicted and the true
    /// pixels of that class, summed over the frames where either has any.
    pub iou_per_class: BTreeMap<String, f64>,
}

pub fn bench_segmentation(
    options: &SegmentationBenchOptions,
) -> Result<SegmentationBenchReport, IsceneError> {
    let mut sequence = Sequence::open(&options.sequence)?;
    let (start, end, step) = options.frames;
    sequence.select(start, end, step);
    if sequence.frames.is_empty() {
        return Err(InputError::invalid(&options.sequence, "the frame selection is empty").into());
    }
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .map_err(|e| IsceneError::Internal(format!("thread pool: {e}")))?;
    one_thread.install(|| {
        let clock = Instant::now();
        let backend = OnnxSegmentation::for_sequence(
            &sequence,
            &OnnxModels::in_dir(&options.models),
            OnnxParams {
                device: options.device,
                ..OnnxParams::default()
            },
        )?;
        let setup_s = clock.elapsed().as_secs_f64();
        let true_class: BTreeMap<u16, String> = sequence
            .labels
            .as_ref()
            .map(|l| {
                l.by_instance()
                    .into_iter()
                    .map(|(id, e)| (id, e.class.clone()))
                    .collect()
            })
            .unwrap_or_default();
        let mut times = Vec::new();
        let mut masks_per_class: BTreeMap<String, usize> = BTreeMap::new();
        // (intersection, union) per class.
        let mut overlap: BTreeMap<String, (u64, u64)> = BTreeMap::new();
        for i in 0..sequence.frames.len() {
            let frame = sequence.load_frame(i)?;
            // The mapper's own geometric segmentation, not the service's cost.
            let geometry = segment_depth(&frame.depth, &frame.camera, &GeometricParams::default());
            let clock = Instant::now();
            let masks = backend.segment(&frame, &geometry)?;
            times.push(clock.elapsed().as_secs_f64() * 1e3);
            for s in &masks.segments {
                *masks_per_class.entry(s.class.clone()).or_default() += 1;
            }
            let Some(truth) = &frame.labels else {
                continue;
            };
            let predicted_class: BTreeMap<u16, &str> = masks
                .segments
                .iter()
                .map(|s| (s.id, s.class.as_str()))
                .collect();
            for class in ["chair", "table"] {
                let (mut inter, mut union) = (0u64, 0u64);
                for (p, t) in masks.segment_of_pixel.iter().zip(truth) {
                    let predicted = predicted_class.get(p).is_some_and(|c| *c == class);
                    let true_ = true_class.get(t).is_some_and(|c| c == class);
                    inter += u64::from(predicted && true_);
                    union += u64::from(predicted || true_);
                }
                let e = overlap.entry(class.to_string()).or_default();
                e.0 += inter;
                e.1 += union;
            }
        }
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        Ok(SegmentationBenchReport {
            sequence: options.sequence.clone(),
            frames: times.len(),
            device: options.device,
            setup_s,
            mean_ms_per_frame: times.iter().sum::<f64>() / times.len() as f64,
            median_ms_per_frame: sorted[sorted.len() / 2],
            max_ms_per_frame: sorted[sorted.len() - 1],
            masks_per_class,
            iou_per_class: overlap
                .into_iter()
                .filter(|(_, (_, u))| *u > 0)
                .map(|(c, (i, u))| (c, i as f64 / u as f64))
                .collect(),
        })
    })
}
