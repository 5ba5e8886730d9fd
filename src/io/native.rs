//! The native sequence layout, which 7-Scenes and tsdf-fusion folders already follow.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::error::InputError;
use crate::io::intrinsics::{self, CameraJson};
use crate::io::labels::Labels;
use crate::io::pose::read_pose_file;
use crate::io::sequence::{FrameRecord, Sequence, SequenceFormat};

pub fn open(root: &Path) -> Result<Sequence, InputError> {
    let mut depth_files: BTreeMap<usize, PathBuf> = BTreeMap::new();
    let entries = std::fs::read_dir(root).map_err(|e| InputError::io(root, &e))?;
    for entry in entries {
        let entry = entry.map_err(|e| InputError::io(root, &e))?;
        let name = entry.file_name().to_string_lossy().into_owned();
        if let Some(n) = name
            .strip_prefix("frame-")
            .and_then(|s| s.strip_suffix(".depth.png"))
        {
            let index = n
                .parse()
                .map_err(|_| InputError::invalid(entry.path(), "frame number is not a number"))?;
            depth_files.insert(index, entry.path());
        }
    }
    let Some((&first, first_depth)) = depth_files.iter().next() else {
        return Err(InputError::invalid(root, "no frame-NNNNNN.depth.png files"));
    };
    let (last, _) = depth_files
        .iter()
        .next_back()
        .map(|(k, v)| (*k, v))
        .unwrap_or((first, first_depth));
    if last - first + 1 != depth_files.len() {
        let missing = (first..=last)
            .find(|i| !depth_files.contains_key(i))
            .unwrap_or(first);
        return Err(InputError::missing(
            root.join(format!("frame-{missing:06}.depth.png")),
            format!("frames run {first}..={last} but this one is missing"),
        ));
    }
    let camera_json = root.join("camera.json");
    let (width, height, depth_scale) = if camera_json.is_file() {
        let text =
            std::fs::read_to_string(&camera_json).map_err(|e| InputError::io(&camera_json, &e))?;
        let c: CameraJson = serde_json::from_str(&text)
            .map_err(|e| InputError::invalid(&camera_json, format!("invalid camera.json: {e}")))?;
        if !(c.depth_scale.is_finite() && c.depth_scale > 0.0) {
            return Err(InputError::invalid(
                &camera_json,
                format!("depth_scale {} must be positive", c.depth_scale),
            ));
        }
        (c.width, c.height, c.depth_scale)
    } else {
        let (w, h) = crate::io::images::dimensions(first_depth)?;
        (w, h, 1000.0)
    };
    let camera = intrinsics::read_matrix_file(&root.join("camera-intrinsics.txt"), width, height)?;
    let gravity = read_gravity(&root.join("gravity-direction.txt"))?;
    let labels_path = root.join("labels.json");
    let labels = if labels_path.is_file() {
        let text =
            std::fs::read_to_string(&labels_path).map_err(|e| InputError::io(&labels_path, &e))?;
        let labels = serde_json::from_str::<Labels>(&text)
            .map_err(|e| InputError::invalid(&labels_path, format!("invalid labels.json: {e}")))?;
        for entry in labels.instances.values() {
            crate::file_name::check_file_name(&entry.entity)
                .map_err(|e| InputError::invalid(&labels_path, format!("entity: {e}")))?;
        }
        Some(labels)
    } else {
        None
    };
    let mut frames = Vec::with_capacity(depth_files.len());
    for (index, depth) in depth_files {
        let stem = root.join(format!("frame-{index:06}"));
        let with = |suffix: &str| PathBuf::from(format!("{}.{suffix}", stem.display()));
        let color = [with("color.png"), with("color.jpg")]
            .into_iter()
            .find(|p| p.is_file())
            .ok_or_else(|| {
                InputError::missing(
                    with("color.png"),
                    "colour image (.color.png or .color.jpg) for this frame",
                )
            })?;
        let world_from_camera = read_pose_file(&with("pose.txt"))?;
        let label = Some(with("label.png")).filter(|p| p.is_file());
        frames.push(FrameRecord {
            index,
            color,
            depth,
            label,
            world_from_camera,
        });
    }
    Ok(Sequence {
        root: root.to_path_buf(),
        format: SequenceFormat::Native,
        camera,
        depth_scale,
        gravity,
        frames,
        labels,
    })
}

/// The optional gravity file: a unit vector (normalised here) in the world frame.
pub fn read_gravity(path: &Path) -> Result<Option<Vec3>, InputError> {
    if !path.is_file() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    let v: Vec<f32> = text
        .split_whitespace()
        .map(|t| {
            t.parse::<f32>()
                .map_err(|_| InputError::invalid(path, format!("{t:?} is not a number")))
        })
        .collect::<Result<_, _>>()?;
    let [x, y, z] = v[..] else {
        return Err(InputError::invalid(
            path,
            format!("expected 3 numbers of a gravity vector, found {}", v.len()),
        ));
    };
    let g = Vec3::new(x, y, z);
    if !g.is_finite() || g.length() < 0.5 || g.length() > 1.5 {
        return Err(InputError::invalid(
            path,
            format!("gravity {g} is not a unit vector"),
        ));
    }
    Ok(Some(g.normalize()))
}
