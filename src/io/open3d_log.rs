//! Open3D's reconstruction-system layout: `color/`, `depth/`, `trajectory.log` (one entry per
//! frame: a metadata line, then a 4x4 world_from_camera), intrinsics in a JSON file.

use std::path::{Path, PathBuf};

use crate::error::InputError;
use crate::geometry::Pinhole;
use crate::io::intrinsics;
use crate::io::pose::parse_matrix;
use crate::io::sequence::{FrameRecord, Sequence, SequenceFormat};

fn sorted_images(dir: &Path) -> Result<Vec<PathBuf>, InputError> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| InputError::io(dir, &e))?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| {
            matches!(
                p.extension().and_then(|e| e.to_str()),
                Some("png" | "jpg" | "jpeg")
            )
        })
        .collect();
    files.sort();
    Ok(files)
}

/// An Open3D intrinsics JSON in the folder or its parent, else `camera-intrinsics.txt`, else the
/// PrimeSense default Open3D itself uses.
fn find_camera(root: &Path, width: u32, height: u32) -> Result<Pinhole, InputError> {
    for dir in [Some(root), root.parent()].into_iter().flatten() {
        let Ok(entries) = std::fs::read_dir(dir) else {
            continue;
        };
        let mut candidates: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .collect();
        candidates.sort();
        for path in candidates {
            let is_intrinsic =
                std::fs::read_to_string(&path).is_ok_and(|t| t.contains("intrinsic_matrix"));
            if is_intrinsic {
                return intrinsics::read_open3d_json(&path);
            }
        }
    }
    let txt = root.join("camera-intrinsics.txt");
    if txt.is_file() {
        return intrinsics::read_matrix_file(&txt, width, height);
    }
    Ok(Pinhole {
        width,
        height,
        fx: 525.0,
        fy: 525.0,
        cx: 319.5,
        cy: 239.5,
    })
}

pub fn open(root: &Path) -> Result<Sequence, InputError> {
    let log = root.join("trajectory.log");
    let text = std::fs::read_to_string(&log).map_err(|e| InputError::io(&log, &e))?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    if !lines.len().is_multiple_of(5) {
        return Err(InputError::invalid(
            &log,
            format!(
                "{} non-empty lines: entries are 5 lines (metadata + 4x4 matrix)",
                lines.len()
            ),
        ));
    }
    let depth = sorted_images(&root.join("depth"))?;
    let color = sorted_images(&root.join("color"))?;
    let entries = lines.len() / 5;
    if depth.len() != entries || color.len() != entries {
        return Err(InputError::invalid(
            &log,
            format!(
                "{entries} poses but {} depth and {} colour images",
                depth.len(),
                color.len()
            ),
        ));
    }
    let mut frames = Vec::with_capacity(entries);
    for (k, chunk) in lines.chunks(5).enumerate() {
        let pose = parse_matrix(&chunk[1..].join("\n"), &log, &format!("entry {k}"))?;
        frames.push(FrameRecord {
            index: k,
            color: color[k].clone(),
            depth: depth[k].clone(),
            label: None,
            world_from_camera: pose,
        });
    }
    let (w, h) = match frames.first() {
        Some(f) => crate::io::images::dimensions(&f.depth)?,
        None => return Err(InputError::invalid(&log, "no poses")),
    };
    let camera = find_camera(root, w, h)?;
    if (camera.width, camera.height) != (w, h) {
        return Err(InputError::invalid(
            root,
            format!(
                "intrinsics are for {}x{} images but depth images are {w}x{h}",
                camera.width, camera.height
            ),
        ));
    }
    let gravity = crate::io::native::read_gravity(&root.join("gravity-direction.txt"))?;
    Ok(Sequence {
        root: root.to_path_buf(),
        format: SequenceFormat::Open3dLog,
        camera,
        depth_scale: 1000.0,
        gravity,
        frames,
        labels: None,
    })
}
