//! The per-frame panoptic segmentation service: its output type, the trait every backend
//! implements, and the oracle backend (ground truth through a realistic noise model).

pub mod noise;
pub mod oracle;

use serde::{Deserialize, Serialize};

/// One segment of a frame: a frame-local id (ids are not consistent across frames), a class
/// and a confidence.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanopticSegment {
    pub id: u16,
    pub class: String,
    pub score: f32,
}

/// Per-pixel segment ids (0 = unlabelled) and the segments they refer to.
#[derive(Clone, Debug, PartialEq)]
pub struct PanopticFrame {
    pub width: u32,
    pub height: u32,
    pub segment_of_pixel: Vec<u16>,
    pub segments: Vec<PanopticSegment>,
}

impl PanopticFrame {
    pub fn segment(&self, id: u16) -> Option<&PanopticSegment> {
        self.segments.iter().find(|s| s.id == id)
    }
}

/// A source of per-frame panoptic masks.
pub trait SegmentationService: Send + Sync {
    fn name(&self) -> &str;
    fn segment(&self, frame: &crate::io::Frame)
    -> Result<PanopticFrame, crate::error::IsceneError>;
}

/// Which segmentation service labels the frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SegmentationChoice {
    /// Ground truth of a rendered sequence through the noise model it was rendered with.
    Oracle,
    /// Pretrained networks through ONNX Runtime.
    Onnx,
    /// Geometry only: segments without classes.
    None,
}
