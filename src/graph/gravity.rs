//! Gravity and the aligned world: estimate the up direction from the dominant horizontal surfaces
//! when the sequence does not give it, then rotate so z is up and translate so the floor is at
//! z = 0. Never assumes the dataset's up axis.

use glam::{Affine3A, Quat, Vec3};

use crate::geometry::TriMesh;
use crate::geometry::plane::fit_plane;

/// The floor's own plane levels the up direction when the two disagree by more than this
/// (degrees; less is within the plane fit's noise on a 2 cm map, and the contact graph takes such
/// a floor as level) ...
pub const LEVEL_MIN_DEG: f32 = 0.5;
/// ... and by less than this (more, and the "floor" is not level ground: a ramp, a wrong label).
const LEVEL_MAX_DEG: f32 = 3.0;
/// Floor points farther than this (metres) from the first plane fit are left out of the second
/// (wall bottoms and furniture feet that took the floor's label).
const FLOOR_BAND_M: f32 = 0.03;

/// Cone half-angles (degrees) of the successive refinements of the up direction: wide enough at
/// first to catch the floor from a hand-held camera's hint, narrow at the end to average only the
/// truly horizontal surfaces.
const CONES_DEG: [f32; 4] = [35.0, 15.0, 7.0, 3.0];

/// The world's up direction from `mesh`: the area-weighted mean normal of the horizontal surfaces
/// (floor, table tops, counters, and the ceiling turned over), found by narrowing cones around
/// `hint_up`. `None` when no surface lies within the widest cone of the hint.
pub fn estimate_up(mesh: &TriMesh, hint_up: Vec3) -> Option<Vec3> {
    let mut up = hint_up.try_normalize()?;
    // Unit normals turned into the hint's hemisphere (a ceiling faces down, a floor up), weighted
    // by area.
    let normals: Vec<(Vec3, f32)> = (0..mesh.triangles.len())
        .filter_map(|t| {
            let [a, b, c] = mesh.triangle(t);
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            let n = cross.try_normalize()?;
            Some((if n.dot(up) < 0.0 { -n } else { n }, area))
        })
        .collect();
    for cone in CONES_DEG {
        let cos = cone.to_radians().cos();
        let sum: Vec3 = normals
            .iter()
            .filter(|(n, _)| n.dot(up) >= cos)
            .map(|(n, a)| *n * *a)
            .sum();
        up = sum.try_normalize()?;
    }
    Some(up)
}

/// A hand-held or robot camera is mostly upright: the mean of its image-up axis (OpenCV: -y) over
/// the trajectory points roughly up.
pub fn camera_up_hint(world_from_cameras: impl Iterator<Item = Affine3A>) -> Option<Vec3> {
    world_from_cameras
        .map(|p| -Vec3::from(p.matrix3.y_axis))
        .sum::<Vec3>()
        .try_normalize()
}

/// The rigid motion taking the world to the aligned frame: `up` to +z, and a floor at height
/// `floor_height` along `up` to z = 0.
pub fn aligned_from_world(up: Vec3, floor_height: f32) -> Affine3A {
    let rotation = Quat::from_rotation_arc(up.normalize(), Vec3::Z);
    Affine3A::from_rotation_translation(rotation, Vec3::new(0.0, 0.0, -floor_height))
}

/// Where the up direction came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GravitySource {
    /// The sequence's gravity file.
    Given,
    /// Estimated from the map's horizontal surfaces.
    Estimated,
    /// Neither: the world's +z (said in the report so nobody mistakes it for a measurement).
    Assumed,
}

/// The gravity the reconstruction used, and how it aligned the world.
#[derive(Clone, Debug, serde::Serialize)]
pub struct GravityReport {
    pub source: GravitySource,
    pub up_in_world: [f32; 3],
    /// Angle between the estimate and the sequence's gravity file, when both exist (degrees).
    pub estimate_to_given_deg: Option<f32>,
    /// How far (degrees) the up direction was turned to the floor's normal, when the floor
    /// tilted against it by 0.5 to 3 degrees (7-Scenes redkitchen's gravity file: 1.7). A
    /// simulator's floor must be level under its gravity, or everything stands on it with one
    /// edge sunk in.
    pub leveled_to_floor_deg: Option<f32>,
    /// Column-major 4x4: the aligned frame (z up, floor at 0) of the contact graph and every
    /// export after it, from the sequence's world frame.
    pub aligned_from_world: [f32; 16],
}

impl GravityReport {
    /// The rotation that turns the map's world into the aligned one (gravity along -z).
    pub fn aligned_from_world(&self) -> Affine3A {
        Affine3A::from_mat4(glam::Mat4::from_cols_array(&self.aligned_from_world))
    }
}

/// Decides the up direction: the given gravity unless `estimate` asks to ignore it, else the
/// estimate from `map_mesh` with the cameras' hint, else +z. `floor_points` (world frame), when
/// there are any, put the floor at z = 0 by their median height.
pub fn resolve_gravity(
    given: Option<Vec3>,
    estimate: bool,
    hint_up: Option<Vec3>,
    map_mesh: impl FnOnce() -> TriMesh,
    floor_points: &[Vec3],
) -> GravityReport {
    let given_up = given.and_then(|g| (-g).try_normalize());
    let estimated = (estimate || given_up.is_none())
        .then(|| hint_up.and_then(|hint| estimate_up(&map_mesh(), hint)))
        .flatten();
    let (source, up) = match (given_up, estimated) {
        (Some(g), _) if !estimate => (GravitySource::Given, g),
        (_, Some(e)) => (GravitySource::Estimated, e),
        (Some(g), None) => (GravitySource::Given, g),
        (None, None) => (GravitySource::Assumed, Vec3::Z),
    };
    let floor_up = floor_normal(floor_points, up);
    let leveled_to_floor_deg = floor_up
        .map(|n| angle_deg(n, up))
        .filter(|a| (LEVEL_MIN_DEG..=LEVEL_MAX_DEG).contains(a));
    let up = match (leveled_to_floor_deg, floor_up) {
        (Some(_), Some(n)) => n,
        _ => up,
    };
    let mut heights: Vec<f32> = floor_points.iter().map(|p| p.dot(up)).collect();
    heights.sort_by(f32::total_cmp);
    let floor_height = heights.get(heights.len() / 2).copied().unwrap_or(0.0);
    GravityReport {
        source,
        up_in_world: up.to_array(),
        estimate_to_given_deg: estimated.zip(given_up).map(|(e, g)| angle_deg(e, g)),
        leveled_to_floor_deg,
        aligned_from_world: glam::Mat4::from(aligned_from_world(up, floor_height)).to_cols_array(),
    }
}

/// The floor's normal (towards `up`) from its points: a least-squares plane, then again over
/// the points within `FLOOR_BAND_M` of it. `None` for too few points.
fn floor_normal(floor_points: &[Vec3], up: Vec3) -> Option<Vec3> {
    const MIN_POINTS: usize = 100;
    if floor_points.len() < MIN_POINTS {
        return None;
    }
    let first = fit_plane(floor_points)?;
    let near: Vec<Vec3> = floor_points
        .iter()
        .copied()
        .filter(|p| first.signed_distance(*p).abs() <= FLOOR_BAND_M)
        .collect();
    let plane = if near.len() >= MIN_POINTS {
        fit_plane(&near)?
    } else {
        first
    };
    Some(if plane.normal.dot(up) < 0.0 {
        -plane.normal
    } else {
        plane.normal
    })
}

/// Angle between two directions in degrees.
pub fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    a.normalize()
        .dot(b.normalize())
        .clamp(-1.0, 1.0)
        .acos()
        .to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Floor points on a 4 x 3 m grid tilted `tilt_deg` about x from the world's z = 0, with a
    /// strip of wall bottom that took the floor's label.
    fn tilted_floor(tilt_deg: f32) -> Vec<Vec3> {
        let tilt = Quat::from_rotation_x(tilt_deg.to_radians());
        let mut points: Vec<Vec3> = (0..40)
            .flat_map(|i| (0..30).map(move |j| Vec3::new(i as f32 * 0.1, j as f32 * 0.1, 0.0)))
            .map(|p| tilt * p)
            .collect();
        points.extend((0..40).map(|i| Vec3::new(i as f32 * 0.1, 3.0, 0.25)));
        points
    }

    #[test]
    fn a_floor_tilted_against_the_given_gravity_by_a_degree_or_two_levels_it() {
        let report = resolve_gravity(
            Some(-Vec3::Z),
            false,
            None,
            TriMesh::default,
            &tilted_floor(1.5),
        );
        assert_eq!(report.source, GravitySource::Given);
        let leveled = report.leveled_to_floor_deg.expect("leveled");
        assert!((leveled - 1.5).abs() < 0.05, "{leveled}");
        // The floor is now level at z = 0 in the aligned frame.
        let aligned = report.aligned_from_world();
        for p in tilted_floor(1.5).iter().take(1200) {
            assert!(aligned.transform_point3(*p).z.abs() < 0.005, "{p}");
        }
        // Within the fit's noise, or too steep to be level ground: the given gravity stands.
        for tilt in [0.2, 5.0] {
            let report = resolve_gravity(
                Some(-Vec3::Z),
                false,
                None,
                TriMesh::default,
                &tilted_floor(tilt),
            );
            assert_eq!(report.leveled_to_floor_deg, None, "{tilt}");
            assert_eq!(report.up_in_world, [0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn the_floor_and_a_table_give_up_despite_a_wide_hint_and_walls() {
        let tilt = Quat::from_rotation_x(0.5) * Quat::from_rotation_y(-0.3);
        let mut room = TriMesh::cuboid(Vec3::new(0.0, 0.0, -0.1), Vec3::new(5.0, 4.0, 0.0));
        room.append(&TriMesh::cuboid(
            Vec3::new(1.0, 1.0, 0.7),
            Vec3::new(2.4, 1.8, 0.75),
        ));
        room.append(&TriMesh::cuboid(
            Vec3::new(0.0, 3.9, 0.0),
            Vec3::new(5.0, 4.0, 2.6),
        ));
        let tilted = room.transformed(&Affine3A::from_quat(tilt));
        let truth = tilt * Vec3::Z;
        let hint = Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.45) * truth;
        assert!(angle_deg(hint, truth) > 20.0);
        let up = estimate_up(&tilted, hint).expect("up");
        assert!(
            angle_deg(up, truth) < 0.5,
            "off by {} degrees",
            angle_deg(up, truth)
        );
        let aligned = aligned_from_world(up, 0.0);
        assert!((aligned.transform_vector3(truth) - Vec3::Z).length() < 0.01);
    }

    #[test]
    fn an_upright_camera_hints_up() {
        // OpenCV camera looking along +x of a z-up world: image down (+y) is world -z.
        let world_from_camera = Affine3A::from_cols(
            Vec3::new(0.0, -1.0, 0.0).into(),
            Vec3::new(0.0, 0.0, -1.0).into(),
            Vec3::new(1.0, 0.0, 0.0).into(),
            Vec3::ZERO.into(),
        );
        let hint = camera_up_hint(std::iter::once(world_from_camera)).expect("hint");
        assert!(angle_deg(hint, Vec3::Z) < 1e-3);
    }
}
