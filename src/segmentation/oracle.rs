//! The oracle backend: a rendered sequence's ground-truth labels through the segmentation noise
//! model, deterministic per frame for a seed.

use std::collections::BTreeMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::base::stable_hash;
use crate::error::{InputError, IsceneError};
use crate::io::{Frame, Sequence};
use crate::segmentation::noise::SegmentationNoise;
use crate::segmentation::{PanopticFrame, PanopticSegment, SegmentationService};

pub struct OracleSegmentation {
    classes: BTreeMap<u16, String>,
    noise: Option<SegmentationNoise>,
    seed: u64,
}

/// The part of `gt/render.json` the oracle needs: the segmentation noise the scene asked for.
#[derive(serde::Deserialize)]
struct RenderRecord {
    seed: u64,
    segmentation_noise: Option<SegmentationNoise>,
}

impl OracleSegmentation {
    /// An oracle with the noise model and seed the sequence was rendered with (`gt/render.json`);
    /// the realistic preset when the sequence does not say.
    pub fn for_sequence(sequence: &Sequence) -> Result<Self, InputError> {
        let path = sequence.root.join("gt").join("render.json");
        if !path.is_file() {
            return Self::new(sequence, Some(SegmentationNoise::REALISTIC), 0);
        }
        let text = std::fs::read_to_string(&path).map_err(|e| InputError::io(&path, &e))?;
        let record: RenderRecord = serde_json::from_str(&text)
            .map_err(|e| InputError::invalid(&path, format!("not a render record: {e}")))?;
        Self::new(sequence, record.segmentation_noise, record.seed)
    }

    /// An oracle for `sequence`, which must carry ground-truth labels (labels.json and label images).
    pub fn new(
        sequence: &Sequence,
        noise: Option<SegmentationNoise>,
        seed: u64,
    ) -> Result<Self, InputError> {
        let Some(labels) = &sequence.labels else {
            return Err(InputError::missing(
                sequence.root.join("labels.json"),
                "the oracle segmentation needs ground-truth labels; use --segmentation onnx or none for real data",
            ));
        };
        let classes = labels
            .by_instance()
            .into_iter()
            .map(|(id, e)| (id, e.class.clone()))
            .collect();
        Ok(Self {
            classes,
            noise,
            seed,
        })
    }
}

impl SegmentationService for OracleSegmentation {
    fn name(&self) -> &str {
        "oracle"
    }

    fn segment(
        &self,
        frame: &Frame,
        _geometry: &crate::segmentation::geometric::GeometricSegmentation,
    ) -> Result<PanopticFrame, IsceneError> {
        let Some(labels) = &frame.labels else {
            return Err(IsceneError::Internal(format!(
                "frame {} has no label image",
                frame.index
            )));
        };
        let width = frame.camera.width;
        Ok(match &self.noise {
            Some(noise) => {
                let mut rng = ChaCha8Rng::seed_from_u64(stable_hash(
                    self.seed,
                    &format!("segmentation-{}", frame.index),
                ));
                noise.apply(labels, width, &self.classes, &mut rng)
            }
            None => {
                let present: std::collections::BTreeSet<u16> =
                    labels.iter().copied().filter(|&l| l != 0).collect();
                let segments = present
                    .into_iter()
                    .map(|id| PanopticSegment {
                        id,
                        class: self
                            .classes
                            .get(&id)
                            .cloned()
                            .unwrap_or_else(|| "unknown".into()),
                        score: 1.0,
                    })
                    .collect();
                PanopticFrame {
                    width,
                    height: frame.camera.height,
                    segment_of_pixel: labels.clone(),
                    segments,
                }
            }
        })
    }
}
