//! The 24 rotations that map coordinate axes onto coordinate axes: every way a CAD model can be
//! stood into an object's box before the continuous yaw is optimised.

use glam::{Mat3, Vec3};

/// The 24 axis-to-axis rotations, upright ones first (index `k` in 0..4 turns the model by
/// `k` quarter turns about +z), then the model's +z mapped to -z, +x, -x, +y, -y, four yaws each.
pub fn axis_rotations() -> [Mat3; 24] {
    use std::f32::consts::{FRAC_PI_2, PI};
    let stand: [Mat3; 6] = [
        Mat3::IDENTITY,
        Mat3::from_rotation_x(PI),
        Mat3::from_rotation_y(FRAC_PI_2),
        Mat3::from_rotation_y(-FRAC_PI_2),
        Mat3::from_rotation_x(-FRAC_PI_2),
        Mat3::from_rotation_x(FRAC_PI_2),
    ];
    std::array::from_fn(|i| {
        let r = Mat3::from_rotation_z(FRAC_PI_2 * (i % 4) as f32) * stand[i / 4];
        // Exact signed permutations: no 1e-8 residue from the sines and cosines.
        Mat3::from_cols(r.x_axis.round(), r.y_axis.round(), r.z_axis.round())
    })
}

/// The yaw (about +z) that an upright axis rotation adds, radians; `None` for one that lays the
/// model down.
pub fn upright_yaw(rotation: &Mat3) -> Option<f32> {
    (rotation.z_axis == Vec3::Z).then(|| rotation.x_axis.y.atan2(rotation.x_axis.x))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn there_are_24_distinct_proper_rotations_and_the_first_four_are_upright() {
        let all = axis_rotations();
        for (i, r) in all.iter().enumerate() {
            assert!(
                (r.determinant() - 1.0).abs() < 1e-6,
                "{i}: det {}",
                r.determinant()
            );
            assert!((*r * r.transpose()).abs_diff_eq(Mat3::IDENTITY, 1e-6));
            for (j, s) in all.iter().enumerate().skip(i + 1) {
                assert!(
                    !r.abs_diff_eq(*s, 1e-3),
                    "{i} and {j} are the same rotation"
                );
            }
            assert_eq!(upright_yaw(r).is_some(), i < 4, "{i}");
        }
        assert_eq!(all[0], Mat3::IDENTITY);
        let yaw = upright_yaw(&all[1]).expect("upright");
        assert!((yaw - std::f32::consts::FRAC_PI_2).abs() < 1e-6);
    }
}
