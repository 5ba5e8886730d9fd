//! How many ways a true object looks the same turned about the vertical: the yaw of a chair is
//! measured modulo its own symmetry. The class table says a chair has a front (symmetry 1), but
//! a round four-legged stool (chair_03) looks the same every quarter turn: a model of it turned
//! 90 degrees is the very same object, and counting it as a yaw error measured nothing.

use glam::{Affine3A, Quat, Vec3};
use parry3d::query::PointQuery;

use crate::cad::db::database::parry_mesh;
use crate::eval::chamfer::surface_samples;
use crate::geometry::TriMesh;

/// Points spread over the surface for the test.
const SAMPLES: usize = 4000;
/// The surface turned by a symmetry lies this close (metres) to itself, at this share of its
/// points: a chair's back turned a quarter stands 20-30 cm off anything.
const SYMMETRY_TOLERANCE_M: f32 = 0.01;
const SYMMETRY_QUANTILE: f32 = 0.95;

/// The largest n of 4 and 2 for which `mesh` (world frame) turned by a 1/n turn about the
/// vertical through `axis` lies on itself; 1 when neither does.
pub fn yaw_symmetry(mesh: &TriMesh, axis: Vec3) -> u32 {
    let Ok(shape) = parry_mesh(mesh) else {
        return 1;
    };
    let samples = surface_samples(mesh, SAMPLES);
    if samples.is_empty() {
        return 1;
    }
    for n in [4u32, 2] {
        let turn = Affine3A::from_translation(axis)
            * Affine3A::from_quat(Quat::from_rotation_z(std::f32::consts::TAU / n as f32))
            * Affine3A::from_translation(-axis);
        let mut distances: Vec<f32> = samples
            .iter()
            .map(|p| shape.distance_to_local_point(turn.transform_point3(*p), false))
            .collect();
        distances.sort_by(f32::total_cmp);
        let at = ((distances.len() - 1) as f32 * SYMMETRY_QUANTILE) as usize;
        if distances[at] <= SYMMETRY_TOLERANCE_M {
            return n;
        }
    }
    1
}

/// The smallest turn (radians) between yaws `a` and `b` of an object with `symmetry` (>= 1).
pub fn yaw_difference(a: f32, b: f32, symmetry: u32) -> f32 {
    let period = std::f32::consts::TAU / symmetry.max(1) as f32;
    let d = (a - b).rem_euclid(period);
    d.min(period - d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::library::ParametricLibrary;

    fn placed(id: &str, at: Vec3, yaw: f32) -> TriMesh {
        let model = ParametricLibrary::get(id).expect("model").model();
        model
            .merged_visual_mesh(&[])
            .transformed(&Affine3A::from_rotation_translation(
                Quat::from_rotation_z(yaw),
                at,
            ))
    }

    #[test]
    fn a_stool_looks_the_same_every_quarter_turn_and_chairs_with_backs_do_not() {
        let at = Vec3::new(1.0, 2.0, 0.0);
        assert_eq!(yaw_symmetry(&placed("chair_03", at, 0.3), at), 4);
        for chair in ["chair_01", "chair_02", "chair_04", "chair_05"] {
            assert_eq!(yaw_symmetry(&placed(chair, at, 0.3), at), 1, "{chair}");
        }
        assert_eq!(yaw_symmetry(&placed("cabinet_01", at, 0.0), at), 1);
    }

    #[test]
    fn yaw_differences_wrap_at_the_symmetry() {
        use std::f32::consts::{FRAC_PI_2, PI};
        assert!((yaw_difference(0.1, 0.1 + PI, 1) - PI).abs() < 1e-5);
        assert!(yaw_difference(0.1, 0.1 + PI, 2) < 1e-5);
        assert!(yaw_difference(0.0, FRAC_PI_2 + 0.05, 4) < 0.051);
    }
}
