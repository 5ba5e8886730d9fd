//! Camera intrinsics files: the 3x3 `camera-intrinsics.txt`, the optional `camera.json`, and
//! Open3D's `PinholeCameraIntrinsic` JSON.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::error::InputError;
use crate::geometry::Pinhole;

/// `camera.json` of the native layout.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraJson {
    pub width: u32,
    pub height: u32,
    pub depth_scale: f32,
}

/// Reads `fx 0 cx / 0 fy cy / 0 0 1`; the image size comes from elsewhere.
pub fn read_matrix_file(path: &Path, width: u32, height: u32) -> Result<Pinhole, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    let v: Vec<f32> = text
        .split_whitespace()
        .map(|t| {
            t.parse::<f32>()
                .map_err(|_| InputError::invalid(path, format!("{t:?} is not a number")))
        })
        .collect::<Result<_, _>>()?;
    if v.len() != 9 {
        return Err(InputError::invalid(
            path,
            format!(
                "expected the 9 numbers of a 3x3 camera matrix, found {}",
                v.len()
            ),
        ));
    }
    let camera = Pinhole {
        width,
        height,
        fx: v[0],
        fy: v[4],
        cx: v[2],
        cy: v[5],
    };
    if v[3] != 0.0 || v[6] != 0.0 || v[7] != 0.0 || (v[8] - 1.0).abs() > 1e-6 {
        return Err(InputError::invalid(
            path,
            "not a camera matrix: expected fx 0 cx / 0 fy cy / 0 0 1",
        ));
    }
    check(camera, path)
}

pub fn check(camera: Pinhole, path: &Path) -> Result<Pinhole, InputError> {
    let numbers = [camera.fx, camera.fy, camera.cx, camera.cy];
    if numbers.iter().any(|v| !v.is_finite()) || camera.fx <= 0.0 || camera.fy <= 0.0 {
        return Err(InputError::invalid(
            path,
            format!(
                "focal lengths must be positive and finite (fx {}, fy {})",
                camera.fx, camera.fy
            ),
        ));
    }
    if camera.width == 0 || camera.height == 0 || camera.width > 8192 || camera.height > 8192 {
        return Err(InputError::invalid(
            path,
            format!(
                "image size {}x{} is not plausible",
                camera.width, camera.height
            ),
        ));
    }
    // A field of view between about 5 and 170 degrees: a focal length of 1 px would spread a
    // frame over a whole house and fill the map's memory.
    let (lo, hi) = (0.05 * camera.width as f32, 25.0 * camera.width as f32);
    if !(lo..=hi).contains(&camera.fx) || !(lo..=hi).contains(&camera.fy) {
        return Err(InputError::invalid(
            path,
            format!(
                "focal lengths fx {} and fy {} px are implausible for a {} px wide image \
                 (expected {lo:.0}..{hi:.0} px)",
                camera.fx, camera.fy, camera.width
            ),
        ));
    }
    Ok(camera)
}

#[derive(Deserialize)]
struct Open3dIntrinsic {
    width: u32,
    height: u32,
    /// Column-major 3x3.
    intrinsic_matrix: [f32; 9],
}

/// Reads Open3D's `{"width", "height", "intrinsic_matrix": [column-major 3x3]}`.
pub fn read_open3d_json(path: &Path) -> Result<Pinhole, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    let j: Open3dIntrinsic = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(path, format!("invalid camera intrinsics: {e}")))?;
    let m = j.intrinsic_matrix;
    check(
        Pinhole {
            width: j.width,
            height: j.height,
            fx: m[0],
            fy: m[4],
            cx: m[6],
            cy: m[7],
        },
        path,
    )
}
