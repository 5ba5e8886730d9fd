//! Camera poses: parsing 4x4 matrices and quaternion poses, and checking they are rigid motions.

use std::path::Path;

use glam::{Affine3A, Mat3, Mat4, Quat, Vec3, Vec4};

use crate::error::InputError;

/// Largest deviation of R^T R from the identity accepted for a rotation (poses from real
/// trackers are stored with a few significant digits).
const ORTHONORMAL_TOLERANCE: f32 = 2e-3;

/// Parses a whitespace-separated 4x4 row-major matrix and checks it is a rigid motion.
pub fn parse_matrix(text: &str, path: &Path, what: &str) -> Result<Affine3A, InputError> {
    let values: Vec<f64> = text
        .split_whitespace()
        .map(|t| {
            t.parse::<f64>()
                .map_err(|_| InputError::invalid(path, format!("{what}: {t:?} is not a number")))
        })
        .collect::<Result<_, _>>()?;
    if values.len() != 16 {
        return Err(InputError::invalid(
            path,
            format!(
                "{what}: expected 16 numbers of a 4x4 matrix, found {}",
                values.len()
            ),
        ));
    }
    let rows: Vec<Vec4> = values
        .chunks(4)
        .map(|r| Vec4::new(r[0] as f32, r[1] as f32, r[2] as f32, r[3] as f32))
        .collect();
    let m = Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose();
    rigid_from_matrix(m, path, what)
}

/// Checks `m` is finite with a proper rotation and a last row of 0 0 0 1.
pub fn rigid_from_matrix(m: Mat4, path: &Path, what: &str) -> Result<Affine3A, InputError> {
    if !m.is_finite() {
        return Err(InputError::invalid(
            path,
            format!("{what}: the pose has NaN or infinite entries"),
        ));
    }
    let last_row = m.row(3);
    if (last_row - Vec4::new(0.0, 0.0, 0.0, 1.0))
        .abs()
        .max_element()
        > 1e-6
    {
        return Err(InputError::invalid(
            path,
            format!("{what}: the last row is {last_row}, not 0 0 0 1"),
        ));
    }
    let r = Mat3::from_mat4(m);
    let deviation = (r.transpose() * r - Mat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f32, |a, v| a.max(v.abs()));
    if deviation > ORTHONORMAL_TOLERANCE {
        return Err(InputError::invalid(
            path,
            format!("{what}: the rotation is not orthonormal (|R^T R - I| = {deviation:.3})"),
        ));
    }
    if r.determinant() < 0.0 {
        return Err(InputError::invalid(
            path,
            format!("{what}: the rotation is a reflection (det < 0)"),
        ));
    }
    let t = m.col(3).truncate();
    check_translation(t, path, what)?;
    // Re-orthonormalise so that downstream code works with an exact rotation.
    let rotation = Quat::from_mat3(&r).normalize();
    Ok(Affine3A::from_rotation_translation(rotation, t))
}

/// The farthest a camera may be from the origin, metres: a building, not a planet. Past it, f32
/// positions lose the millimetres mapping needs.
pub const MAX_TRANSLATION_M: f32 = 10_000.0;

fn check_translation(t: Vec3, path: &Path, what: &str) -> Result<(), InputError> {
    if t.abs().max_element() > MAX_TRANSLATION_M {
        return Err(InputError::invalid(
            path,
            format!(
                "{what}: the translation {t} lies more than {MAX_TRANSLATION_M} m from the origin"
            ),
        ));
    }
    Ok(())
}

/// Reads a pose file holding one 4x4 matrix.
pub fn read_pose_file(path: &Path) -> Result<Affine3A, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
    parse_matrix(&text, path, "pose")
}

/// A pose from translation and quaternion (x, y, z, w), as in TUM's groundtruth.txt.
pub fn from_translation_quaternion(
    t: Vec3,
    q: Quat,
    path: &Path,
    what: &str,
) -> Result<Affine3A, InputError> {
    if !t.is_finite() || !q.is_finite() {
        return Err(InputError::invalid(
            path,
            format!("{what}: NaN or infinite pose"),
        ));
    }
    check_translation(t, path, what)?;
    let norm = q.length();
    if (norm - 1.0).abs() > 0.01 {
        return Err(InputError::invalid(
            path,
            format!("{what}: quaternion norm {norm:.4} is not 1"),
        ));
    }
    Ok(Affine3A::from_rotation_translation(q.normalize(), t))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn good_and_bad_matrices() {
        let p = Path::new("pose.txt");
        let ok = parse_matrix("1 0 0 1\n0 1 0 2\n0 0 1 3\n0 0 0 1\n", p, "pose").expect("valid");
        assert_eq!(ok.translation, Vec3::new(1.0, 2.0, 3.0).into());
        for (text, needle) in [
            ("1 0 0 1\n0 1 0 2\n0 0 1 3\n", "16 numbers"),
            ("1 0 0 nan\n0 1 0 2\n0 0 1 3\n0 0 0 1", "NaN"),
            ("2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1", "orthonormal"),
            ("-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1", "reflection"),
            ("1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1", "last row"),
            ("1 0 0 x\n0 1 0 0\n0 0 1 0\n0 0 0 1", "not a number"),
        ] {
            let err = parse_matrix(text, p, "pose").expect_err(needle).to_string();
            assert!(err.contains(needle) && err.contains("pose.txt"), "{err}");
        }
    }
}
