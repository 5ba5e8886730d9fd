//! TUM RGB-D folders: `rgb.txt`, `depth.txt` and `groundtruth.txt` associated by timestamp.

use std::path::Path;

use glam::{Quat, Vec3};

use crate::error::InputError;
use crate::file_name::inside_folder;
use crate::geometry::Pinhole;
use crate::io::intrinsics;
use crate::io::pose::from_translation_quaternion;
use crate::io::sequence::{FrameRecord, Sequence, SequenceFormat};

/// TUM's depth images store 5000 per metre.
pub const TUM_DEPTH_SCALE: f32 = 5000.0;
/// Largest timestamp difference (seconds) for two entries to describe one frame (TUM's associate.py).
const MAX_TIME_DIFFERENCE: f64 = 0.02;

/// Parses a TUM list file: lines of `timestamp value...`, `#` comments.
fn read_list(path: &Path, columns: usize) -> Result<Vec<(f64, Vec<String>)>, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    let mut rows = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        if fields.len() != columns + 1 {
            return Err(InputError::invalid(
                path,
                format!(
                    "line {}: expected a timestamp and {columns} values, found {} fields",
                    n + 1,
                    fields.len()
                ),
            ));
        }
        let t: f64 = fields[0].parse().map_err(|_| {
            InputError::invalid(
                path,
                format!("line {}: timestamp {:?} is not a number", n + 1, fields[0]),
            )
        })?;
        rows.push((t, fields[1..].iter().map(|s| s.to_string()).collect()));
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(rows)
}

fn nearest<T>(rows: &[(f64, T)], t: f64) -> Option<&(f64, T)> {
    let i = rows.partition_point(|(s, _)| *s < t);
    [i.checked_sub(1), Some(i)]
        .into_iter()
        .flatten()
        .filter_map(|k| rows.get(k))
        .min_by(|a, b| (a.0 - t).abs().total_cmp(&(b.0 - t).abs()))
        .filter(|r| (r.0 - t).abs() <= MAX_TIME_DIFFERENCE)
}

/// The published calibration of the TUM sensor named in the folder name (fr1, fr2, fr3), else
/// the ROS default TUM recommends.
fn default_camera(root: &Path, width: u32, height: u32) -> Pinhole {
    let name = root
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let (fx, fy, cx, cy) = if name.contains("freiburg1") || name.contains("fr1") {
        (517.3, 516.5, 318.6, 255.3)
    } else if name.contains("freiburg2") || name.contains("fr2") {
        (520.9, 521.0, 325.1, 249.7)
    } else if name.contains("freiburg3") || name.contains("fr3") {
        (535.4, 539.2, 320.1, 247.6)
    } else {
        (525.0, 525.0, 319.5, 239.5)
    };
    Pinhole {
        width,
        height,
        fx,
        fy,
        cx,
        cy,
    }
}

pub fn open(root: &Path) -> Result<Sequence, InputError> {
    let rgb = read_list(&root.join("rgb.txt"), 1)?;
    let depth = read_list(&root.join("depth.txt"), 1)?;
    let truth = read_list(&root.join("groundtruth.txt"), 7)?;
    let mut frames = Vec::new();
    let gt_path = root.join("groundtruth.txt");
    for (t, d) in &depth {
        let (Some((_, c)), Some((_, g))) = (nearest(&rgb, *t), nearest(&truth, *t)) else {
            continue;
        };
        let v: Vec<f32> = g
            .iter()
            .map(|s| s.parse::<f32>())
            .collect::<Result<_, _>>()
            .map_err(|_| InputError::invalid(&gt_path, format!("pose at {t}: not numbers")))?;
        let pose = from_translation_quaternion(
            Vec3::new(v[0], v[1], v[2]),
            Quat::from_xyzw(v[3], v[4], v[5], v[6]),
            &gt_path,
            &format!("pose at {t}"),
        )?;
        let listed = |list: &str, name: &str| {
            inside_folder(root, Path::new(name))
                .map_err(|e| InputError::invalid(root.join(list), format!("at {t}: {e}")))
        };
        frames.push(FrameRecord {
            index: frames.len(),
            color: listed("rgb.txt", &c[0])?,
            depth: listed("depth.txt", &d[0])?,
            label: None,
            world_from_camera: pose,
        });
    }
    let Some(first) = frames.first() else {
        return Err(InputError::invalid(
            root,
            "no depth frame has both a colour image and a ground-truth pose within 0.02 s",
        ));
    };
    let (w, h) = crate::io::images::dimensions(&first.depth)?;
    let intrinsics_file = root.join("camera-intrinsics.txt");
    let camera = if intrinsics_file.is_file() {
        intrinsics::read_matrix_file(&intrinsics_file, w, h)?
    } else {
        default_camera(root, w, h)
    };
    let gravity = crate::io::native::read_gravity(&root.join("gravity-direction.txt"))?;
    Ok(Sequence {
        root: root.to_path_buf(),
        format: SequenceFormat::Tum,
        camera,
        depth_scale: TUM_DEPTH_SCALE,
        gravity,
        frames,
        labels: None,
    })
}
