//! Writing frames in the native sequence layout.

use std::io::BufWriter;
use std::path::Path;

use glam::{Affine3A, Mat4};
use image::ImageEncoder;
use image::codecs::png::{CompressionType, FilterType, PngEncoder};

use crate::error::IsceneError;
use crate::geometry::Pinhole;
use crate::io::intrinsics::CameraJson;

fn write_png(
    path: &Path,
    bytes: &[u8],
    camera: &Pinhole,
    color: image::ExtendedColorType,
) -> Result<(), IsceneError> {
    let file = std::fs::File::create(path)
        .map_err(|e| IsceneError::io(format!("creating {}", path.display()), e))?;
    // Fast compression: rendering 300 frames is dominated by PNG encoding otherwise.
    let encoder =
        PngEncoder::new_with_quality(BufWriter::new(file), CompressionType::Fast, FilterType::Sub);
    encoder
        .write_image(bytes, camera.width, camera.height, color)
        .map_err(|e| IsceneError::Internal(format!("encoding {}: {e}", path.display())))
}

pub fn write_color(path: &Path, rgb: &[u8], camera: &Pinhole) -> Result<(), IsceneError> {
    write_png(path, rgb, camera, image::ExtendedColorType::Rgb8)
}

/// 16-bit samples; the encoder takes them in native byte order and writes PNG's big-endian.
fn u16_png(path: &Path, values: &[u16], camera: &Pinhole) -> Result<(), IsceneError> {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_ne_bytes()).collect();
    write_png(path, &bytes, camera, image::ExtendedColorType::L16)
}

/// Depth in metres to millimetres (0 = no measurement, values past 65.534 m dropped).
pub fn write_depth(path: &Path, depth: &[f32], camera: &Pinhole) -> Result<(), IsceneError> {
    let mm: Vec<u16> = depth
        .iter()
        .map(|&d| {
            if d > 0.0 && d * 1000.0 < 65534.5 {
                (d * 1000.0).round() as u16
            } else {
                0
            }
        })
        .collect();
    u16_png(path, &mm, camera)
}

pub fn write_labels(path: &Path, labels: &[u16], camera: &Pinhole) -> Result<(), IsceneError> {
    u16_png(path, labels, camera)
}

/// A 4x4 row-major matrix, one row per line, as 7-Scenes writes poses.
pub fn pose_text(world_from_camera: &Affine3A) -> String {
    let m = Mat4::from(*world_from_camera);
    (0..4)
        .map(|r| m.row(r).to_array().map(|v| format!("{v:.9}")).join(" ") + "\n")
        .collect()
}

pub fn write_text(path: &Path, text: &str) -> Result<(), IsceneError> {
    std::fs::write(path, text)
        .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
}

/// `camera-intrinsics.txt` and `camera.json`.
pub fn write_camera(dir: &Path, camera: &Pinhole, depth_scale: f32) -> Result<(), IsceneError> {
    let k = format!(
        "{:.6} 0 {:.6}\n0 {:.6} {:.6}\n0 0 1\n",
        camera.fx, camera.cx, camera.fy, camera.cy
    );
    write_text(&dir.join("camera-intrinsics.txt"), &k)?;
    let json = CameraJson {
        width: camera.width,
        height: camera.height,
        depth_scale,
    };
    write_text(
        &dir.join("camera.json"),
        &serde_json::to_string_pretty(&json).unwrap_or_default(),
    )
}
