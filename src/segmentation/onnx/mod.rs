//! The `onnx` backend: pretrained COCO detection (YOLOX) and PASCAL-VOC semantic segmentation
//! (DeepLabV3) through ONNX Runtime, combined into per-frame panoptic masks (`masks`), with floor
//! and walls from a survey of the room's planes (`layout`).

pub mod bench;
pub mod deeplab;
pub mod depth_surface;
pub mod layout;
pub mod masks;
pub mod runtime;
pub mod yolox;

use std::path::{Path, PathBuf};
use std::sync::{Condvar, Mutex};

use image::RgbImage;
use ort::session::Session;
use ort::value::Tensor;
use rayon::prelude::*;

use crate::classes::ClassTable;
use crate::error::{InputError, IsceneError};
use crate::geometry::TriMesh;
use crate::io::{Frame, Sequence};
use crate::segmentation::geometric::GeometricSegmentation;
use crate::segmentation::onnx::layout::{LayoutLabel, LayoutParams, RoomLayout};
use crate::segmentation::onnx::masks::{MaskInputs, MaskParams, ObjectDetection, panoptic_masks};
pub use crate::segmentation::onnx::runtime::OnnxDevice;
use crate::segmentation::onnx::yolox::Detection;
use crate::segmentation::{PanopticFrame, SegmentationService};

/// The PASCAL-VOC labels in the semantic network's output order.
pub const VOC_LABELS: [&str; 21] = [
    "background",
    "aeroplane",
    "bicycle",
    "bird",
    "boat",
    "bottle",
    "bus",
    "car",
    "cat",
    "chair",
    "cow",
    "diningtable",
    "dog",
    "horse",
    "motorbike",
    "person",
    "pottedplant",
    "sheep",
    "sofa",
    "train",
    "tvmonitor",
];

/// Where the models are: a folder with the detector, the semantic network and the detector's
/// class names, one per line.
#[derive(Clone, Debug)]
pub struct OnnxModels {
    pub detector: PathBuf,
    pub semantic: PathBuf,
    pub detector_names: PathBuf,
}

impl OnnxModels {
    /// The shared data's models, relative to the checkout (where tests and the README run).
    pub const DEFAULT_DIR: &'static str = "../shared/data/models";

    pub fn in_dir(dir: &Path) -> Self {
        Self {
            detector: dir.join("yolox_nano.onnx"),
            semantic: dir.join("deeplab_v3_1_default_1.opset13.onnx"),
            detector_names: dir.join("coco.names"),
        }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct OnnxParams {
    /// Detections below this objectness x class score are ignored.
    pub min_score: f32,
    /// Same-class boxes overlapping more than this are one detection.
    pub nms_iou: f32,
    pub masks: MaskParams,
    pub layout: LayoutParams,
    /// Where the two networks run.
    pub device: OnnxDevice,
}

impl Default for OnnxParams {
    fn default() -> Self {
        Self {
            min_score: 0.3,
            nms_iou: 0.45,
            masks: MaskParams::default(),
            layout: LayoutParams::default(),
            device: OnnxDevice::Cpu,
        }
    }
}

/// The two networks; `Session::run` needs `&mut`, so each worker borrows a pair from a pool.
struct Networks {
    detector: Session,
    semantic: Session,
}

/// The pairs not in use, and how many are open in all.
#[derive(Default)]
struct NetworkPool {
    idle: Vec<Networks>,
    open: usize,
}

/// Pairs open at most on a GPU. Each CUDA session starts its own kernels and memory arena, and
/// the sessions share one device: with one pair per CPU worker (16 on the H200 machine) their
/// start-up and contention cost more than the networks (100 frames of 7-Scenes took 41 s to map
/// that way, 14.7-15.1 s with four pairs, 10.3-11.5 s with two, all with cuDNN's exhaustive
/// search). Two pairs overlap one frame's pre- and post-processing with another's inference.
const MAX_GPU_NETWORKS: usize = 2;

pub struct OnnxSegmentation {
    models: OnnxModels,
    /// Per detector label, the project class and its semantic labels.
    class_of_label: Vec<Option<(String, Vec<u8>)>>,
    layout: RoomLayout,
    params: OnnxParams,
    pool: Mutex<NetworkPool>,
    /// Signalled when a pair goes back to the pool.
    returned: Condvar,
}

/// Labels compare without case or spaces ("dining table" is the names file's "diningtable").
fn normalised(label: &str) -> String {
    label
        .to_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect()
}

impl OnnxSegmentation {
    /// Loads ONNX Runtime and the models (a missing one is a clear error), maps the detector's
    /// labels to the class table, and surveys `sequence` for its floor and walls.
    pub fn for_sequence(
        sequence: &Sequence,
        models: &OnnxModels,
        params: OnnxParams,
    ) -> Result<Self, InputError> {
        let names = std::fs::read_to_string(&models.detector_names)
            .map_err(|e| InputError::io(&models.detector_names, &e))?;
        let table = ClassTable::builtin();
        let class_of_label = names
            .lines()
            .map(|label| {
                let label = normalised(label);
                table
                    .iter()
                    .find(|(_, info)| info.coco.iter().any(|c| normalised(c) == label))
                    .map(|(class, info)| {
                        let semantic = VOC_LABELS
                            .iter()
                            .enumerate()
                            .filter(|(_, v)| info.voc.iter().any(|c| normalised(c) == **v))
                            .map(|(i, _)| i as u8)
                            .collect();
                        (class.to_string(), semantic)
                    })
            })
            .collect::<Vec<_>>();
        if class_of_label.iter().all(Option::is_none) {
            return Err(InputError::invalid(
                &models.detector_names,
                "no label in this names file maps to a class of assets/classes.json",
            ));
        }
        let backend = Self {
            models: models.clone(),
            class_of_label,
            layout: RoomLayout::survey(sequence, params.layout)?,
            params,
            pool: Mutex::new(NetworkPool::default()),
            returned: Condvar::new(),
        };
        // Open one pair now, so a missing library or model fails before any mapping starts.
        let networks = backend.take_networks()?;
        backend.give_back(networks);
        Ok(backend)
    }

    pub fn layout(&self) -> &RoomLayout {
        &self.layout
    }

    fn open_networks(&self) -> Result<Networks, InputError> {
        Ok(Networks {
            detector: runtime::open_session(&self.models.detector, self.params.device)?,
            semantic: runtime::open_session(&self.models.semantic, self.params.device)?,
        })
    }

    /// A pair from the pool: an idle one, else a new one while the device allows more (on the
    /// CPU one per worker; on a GPU `MAX_GPU_NETWORKS`), else the next one given back.
    fn take_networks(&self) -> Result<Networks, InputError> {
        let limit = match self.params.device {
            OnnxDevice::Cpu => usize::MAX,
            OnnxDevice::Cuda => MAX_GPU_NETWORKS,
        };
        let poisoned = |_| InputError::invalid(&self.models.detector, "a network worker panicked");
        let mut pool = self.pool.lock().map_err(poisoned)?;
        loop {
            if let Some(n) = pool.idle.pop() {
                return Ok(n);
            }
            if pool.open < limit {
                pool.open += 1;
                drop(pool);
                let opened = self.open_networks();
                if opened.is_err() {
                    self.pool.lock().map_err(poisoned)?.open -= 1;
                }
                return opened;
            }
            pool = self.returned.wait(pool).map_err(poisoned)?;
        }
    }

    fn give_back(&self, networks: Networks) {
        if let Ok(mut pool) = self.pool.lock() {
            pool.idle.push(networks);
        }
        self.returned.notify_one();
    }

    /// The detector's boxes on `image`, with labels mapped to project classes (others dropped).
    pub fn detect(&self, image: &RgbImage) -> Result<Vec<ObjectDetection>, IsceneError> {
        let mut networks = self.take_networks()?;
        let result = self.run_detector(&mut networks.detector, image);
        self.give_back(networks);
        Ok(self.classify(result?))
    }

    /// Detections of labels that map to a project class, as that class.
    fn classify(&self, detections: Vec<Detection>) -> Vec<ObjectDetection> {
        detections
            .into_iter()
            .filter_map(|d| {
                let (class, semantic_labels) = self.class_of_label.get(d.label)?.clone()?;
                Some(ObjectDetection {
                    class,
                    score: d.score,
                    bbox: d.bbox,
                    semantic_labels,
                })
            })
            .collect()
    }

    fn run_detector(
        &self,
        session: &mut Session,
        image: &RgbImage,
    ) -> Result<Vec<Detection>, IsceneError> {
        let (tensor, scale) = yolox::letterbox(image);
        let side = yolox::INPUT_SIDE as i64;
        let output = run_single(session, &self.models.detector, [1, 3, side, side], tensor)?;
        Ok(yolox::decode(
            &output,
            self.class_of_label.len(),
            scale,
            image.dimensions(),
            self.params.min_score,
            self.params.nms_iou,
        ))
    }

    /// The semantic label of every pixel of `image`.
    pub fn semantic_labels(&self, image: &RgbImage) -> Result<Vec<u8>, IsceneError> {
        let mut networks = self.take_networks()?;
        let result = self.run_semantic(&mut networks.semantic, image);
        self.give_back(networks);
        result
    }

    fn run_semantic(
        &self,
        session: &mut Session,
        image: &RgbImage,
    ) -> Result<Vec<u8>, IsceneError> {
        let side = deeplab::INPUT_SIDE;
        let logits = run_single(
            session,
            &self.models.semantic,
            [1, side as i64, side as i64, 3],
            deeplab::input(image),
        )?;
        let labels = deeplab::argmax(&logits, VOC_LABELS.len());
        Ok(deeplab::to_image(
            &labels,
            side,
            image.width(),
            image.height(),
        ))
    }
}

/// Runs a one-input, one-output model.
fn run_single(
    session: &mut Session,
    model: &Path,
    shape: [i64; 4],
    data: Vec<f32>,
) -> Result<Vec<f32>, IsceneError> {
    let fail = |e: &dyn std::fmt::Display| {
        IsceneError::Internal(format!("{}: inference failed: {e}", model.display()))
    };
    let input_name = session.inputs()[0].name().to_string();
    let tensor = Tensor::from_array((shape, data)).map_err(|e| fail(&e))?;
    let outputs = session
        .run(ort::inputs![input_name => tensor])
        .map_err(|e| fail(&e))?;
    let (_, values) = outputs[0]
        .try_extract_tensor::<f32>()
        .map_err(|e| fail(&e))?;
    Ok(values.to_vec())
}

impl SegmentationService for OnnxSegmentation {
    fn name(&self) -> &str {
        "onnx"
    }

    /// Floor and walls are the survey's planes, exact to a few centimetres.
    fn exact_classes(&self) -> &'static [&'static str] {
        &["floor", "wall"]
    }

    fn layout_part(&self, class: &str, mesh: &TriMesh) -> Option<TriMesh> {
        let on_it = |label: Option<LayoutLabel>| {
            matches!(
                (class, label),
                ("floor", Some(LayoutLabel::Floor)) | ("wall", Some(LayoutLabel::Wall(_)))
            )
        };
        matches!(class, "floor" | "wall")
            .then(|| mesh.filtered(|[a, b, c]| on_it(self.layout.label((a + b + c) / 3.0))))
    }

    fn segment(
        &self,
        frame: &Frame,
        geometry: &GeometricSegmentation,
    ) -> Result<PanopticFrame, IsceneError> {
        let camera = &frame.camera;
        let image = RgbImage::from_raw(camera.width, camera.height, frame.color.clone())
            .ok_or_else(|| {
                IsceneError::Internal(format!(
                    "frame {}: colour image of the wrong size",
                    frame.index
                ))
            })?;
        let mut networks = self.take_networks()?;
        let detections = self.run_detector(&mut networks.detector, &image);
        let semantic = self.run_semantic(&mut networks.semantic, &image);
        self.give_back(networks);
        let detections = self.classify(detections?);
        Ok(self.masks(frame, geometry, &semantic?, &detections))
    }

    fn segment_without_networks(
        &self,
        frame: &Frame,
        geometry: &GeometricSegmentation,
    ) -> Option<PanopticFrame> {
        // No detections: the semantic labels, which only shape objects' masks, are not read.
        Some(self.masks(frame, geometry, &[], &[]))
    }
}

impl OnnxSegmentation {
    /// The frame's panoptic masks: the survey's floor and walls, then the detected objects.
    fn masks(
        &self,
        frame: &Frame,
        geometry: &GeometricSegmentation,
        semantic: &[u8],
        detections: &[ObjectDetection],
    ) -> PanopticFrame {
        let camera = &frame.camera;
        let layout: Vec<_> = (0..frame.depth.len())
            .into_par_iter()
            .map(|i| {
                let d = frame.depth[i];
                (d > 0.0).then(|| {
                    let (u, v) = (
                        (i % camera.width as usize) as f32,
                        (i / camera.width as usize) as f32,
                    );
                    let p = frame
                        .world_from_camera
                        .transform_point3(camera.unproject(u, v, d));
                    self.layout.label(p)
                })?
            })
            .collect();
        let mut geometric_sizes = vec![0u32; geometry.count as usize + 1];
        for &g in &geometry.segment_of_pixel {
            geometric_sizes[g as usize] += 1;
        }
        panoptic_masks(
            &MaskInputs {
                geometric: &geometry.segment_of_pixel,
                geometric_sizes: &geometric_sizes,
                width: camera.width,
                height: camera.height,
                depth: &frame.depth,
                fx: camera.fx,
                semantic,
                layout: &layout,
            },
            detections,
            &self.params.masks,
        )
    }
}
