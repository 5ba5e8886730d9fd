//! An RGB-D sequence whatever its layout: camera, depth scale, gravity, and per-frame files.

use std::path::{Path, PathBuf};

use glam::{Affine3A, Vec3};
use serde::Serialize;

use crate::error::InputError;
use crate::geometry::Pinhole;
use crate::io::images::{check_header, read_color, read_depth, read_labels};
use crate::io::labels::Labels;
use crate::io::{native, open3d_log, tum};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SequenceFormat {
    /// The native layout, which is also 7-Scenes' and tsdf-fusion's (`frame-NNNNNN.*`).
    Native,
    /// TUM RGB-D: `rgb.txt`, `depth.txt`, `groundtruth.txt`, depth scale 5000.
    Tum,
    /// Open3D's reconstruction-system layout: `color/`, `depth/`, `trajectory.log`.
    Open3dLog,
}

/// One frame's files and its validated pose.
#[derive(Clone, Debug)]
pub struct FrameRecord {
    pub index: usize,
    pub color: PathBuf,
    pub depth: PathBuf,
    pub label: Option<PathBuf>,
    pub world_from_camera: Affine3A,
}

#[derive(Clone, Debug)]
pub struct Sequence {
    pub root: PathBuf,
    pub format: SequenceFormat,
    pub camera: Pinhole,
    /// Depth image value per metre (1000 for millimetres, 5000 for TUM).
    pub depth_scale: f32,
    /// Gravity as a unit vector in the world frame, when the sequence says.
    pub gravity: Option<Vec3>,
    pub frames: Vec<FrameRecord>,
    pub labels: Option<Labels>,
}

/// One loaded frame.
#[derive(Clone, Debug)]
pub struct Frame {
    pub index: usize,
    pub camera: Pinhole,
    /// Row-major RGB, 8 bits per channel.
    pub color: Vec<u8>,
    /// Row-major depth in metres along the optical axis; 0 where there is no measurement.
    pub depth: Vec<f32>,
    pub world_from_camera: Affine3A,
    /// Ground-truth instance ids, when the sequence has them.
    pub labels: Option<Vec<u16>>,
}

/// What a set of depth images measured: pixels with a depth, all pixels, and the depth range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DepthStats {
    pub valid_pixels: usize,
    pub pixels: usize,
    pub min_m: f32,
    pub max_m: f32,
}

impl Default for DepthStats {
    fn default() -> Self {
        Self {
            valid_pixels: 0,
            pixels: 0,
            min_m: f32::INFINITY,
            max_m: 0.0,
        }
    }
}

impl DepthStats {
    /// One depth image's (metres, 0 = none).
    pub fn of(depth: &[f32]) -> Self {
        let mut stats = Self {
            pixels: depth.len(),
            ..Self::default()
        };
        for &d in depth.iter().filter(|&&d| d > 0.0) {
            stats.valid_pixels += 1;
            stats.min_m = stats.min_m.min(d);
            stats.max_m = stats.max_m.max(d);
        }
        stats
    }

    pub fn add(&mut self, other: &DepthStats) {
        self.valid_pixels += other.valid_pixels;
        self.pixels += other.pixels;
        self.min_m = self.min_m.min(other.min_m);
        self.max_m = self.max_m.max(other.max_m);
    }

    pub fn valid_fraction(&self) -> f64 {
        if self.pixels > 0 {
            self.valid_pixels as f64 / self.pixels as f64
        } else {
            0.0
        }
    }
}

impl Sequence {
    /// Path length of the camera trajectory, metres.
    pub fn trajectory_length_m(&self) -> f32 {
        self.frames
            .windows(2)
            .map(|w| {
                Vec3::from(w[1].world_from_camera.translation)
                    .distance(w[0].world_from_camera.translation.into())
            })
            .sum()
    }

    /// Opens a sequence folder, recognising its layout from the files in it.
    pub fn open(root: &Path) -> Result<Sequence, InputError> {
        if !root.is_dir() {
            return Err(InputError::missing(root, "sequence folder not found"));
        }
        if root.join("rgb.txt").is_file() || root.join("depth.txt").is_file() {
            return tum::open(root);
        }
        if root.join("trajectory.log").is_file() {
            return open3d_log::open(root);
        }
        if root.join("camera-intrinsics.txt").is_file() {
            return native::open(root);
        }
        Err(InputError::invalid(
            root,
            "not an RGB-D sequence: expected camera-intrinsics.txt and frame-NNNNNN.* files (native/7-Scenes), rgb.txt/depth.txt/groundtruth.txt (TUM) or trajectory.log with color/ and depth/ (Open3D)",
        ))
    }

    /// Keeps frames `start..end` stepping by `step` (indices into the frame list).
    pub fn select(&mut self, start: usize, end: Option<usize>, step: usize) {
        let end = end.unwrap_or(self.frames.len()).min(self.frames.len());
        self.frames = self
            .frames
            .iter()
            .take(end)
            .skip(start)
            .step_by(step.max(1))
            .cloned()
            .collect();
    }

    /// Frame `i`'s record, or an error naming the sequence.
    fn record(&self, i: usize) -> Result<&FrameRecord, InputError> {
        self.frames.get(i).ok_or_else(|| {
            InputError::invalid(
                &self.root,
                format!(
                    "frame {i} requested but the sequence has {} frames",
                    self.frames.len()
                ),
            )
        })
    }

    /// Frame `i`'s depth image (metres, 0 = none), for passes that need no colour or labels.
    pub fn load_depth(&self, i: usize) -> Result<Vec<f32>, InputError> {
        let record = self.record(i)?;
        read_depth(&record.depth, &self.camera, self.depth_scale)
    }

    /// Frame `i`'s depth, decoded and checked, and its colour and label images checked from their
    /// headers: what ingest needs to fail on bad input before the mapping starts, without decoding
    /// the colour twice. A colour or label image that is broken past its header fails when the
    /// mapping decodes it, still before anything is written.
    pub fn check_frame(&self, i: usize) -> Result<Vec<f32>, InputError> {
        let record = self.record(i)?;
        check_header(&record.color, &self.camera)?;
        if let Some(labels) = &record.label {
            check_header(labels, &self.camera)?;
        }
        read_depth(&record.depth, &self.camera, self.depth_scale)
    }

    /// Loads and checks frame `i` of the (selected) frame list.
    pub fn load_frame(&self, i: usize) -> Result<Frame, InputError> {
        let record = self.record(i)?;
        let depth = read_depth(&record.depth, &self.camera, self.depth_scale)?;
        let color = read_color(&record.color, &self.camera)?;
        let labels = record
            .label
            .as_deref()
            .map(|p| read_labels(p, &self.camera))
            .transpose()?;
        Ok(Frame {
            index: record.index,
            camera: self.camera,
            color,
            depth,
            world_from_camera: record.world_from_camera,
            labels,
        })
    }
}
