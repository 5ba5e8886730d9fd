//! The per-frame panoptic segmentation service: its output type, the trait every backend
//! implements, and the oracle backend (ground truth through a realistic noise model).

pub mod geometric;
pub mod noise;
pub mod onnx;
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

/// A source of per-frame panoptic masks. The frame's geometric segmentation, which the mapper
/// computes anyway, comes with it for services that cut masks along depth.
pub trait SegmentationService: Send + Sync {
    fn name(&self) -> &str;
    fn segment(
        &self,
        frame: &crate::io::Frame,
        geometry: &crate::segmentation::geometric::GeometricSegmentation,
    ) -> Result<PanopticFrame, crate::error::IsceneError>;

    /// The masks this service gives without running its networks, for the frames between
    /// those it segments (`--segment-every`): the surveyed floor and walls, which cost a plane
    /// test per pixel. `None`: the frame is fused with its geometric segments only.
    fn segment_without_networks(
        &self,
        _frame: &crate::io::Frame,
        _geometry: &crate::segmentation::geometric::GeometricSegmentation,
    ) -> Option<PanopticFrame> {
        None
    }

    /// Classes whose masks follow the true boundary (layout found from planes, not a network's
    /// blurred outline): the fusion cuts geometric segments to them instead of extending them
    /// over whole segments.
    fn exact_classes(&self) -> &'static [&'static str] {
        &[]
    }

    /// Where the service knows the room's layout exactly, the part of a layout entity's mesh
    /// that lies on it: labels creep in the map, from the floor up a cabinet front that depth
    /// noise joined to it in some frames. `None` keeps the mesh as mapped.
    fn layout_part(
        &self,
        _class: &str,
        _mesh: &crate::geometry::TriMesh,
    ) -> Option<crate::geometry::TriMesh> {
        None
    }
}

/// Which segmentation service labels the frames (`--segmentation`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SegmentationChoice {
    /// Ground truth of a rendered sequence through the noise model it was rendered with.
    Oracle,
    /// Pretrained networks through ONNX Runtime.
    Onnx,
    /// Geometry only: segments without classes.
    None,
}
