//! The symmetric Chamfer distance between two surfaces: the mean distance from points spread
//! evenly over each surface to the other surface, averaged over both directions.

use glam::Vec3;
use parry3d::query::PointQuery;

use crate::cad::db::database::parry_mesh;
use crate::geometry::TriMesh;

/// Points per surface, at most: a 1 m^2 cabinet front gets a point every ~7 mm.
const SAMPLES: usize = 20_000;

/// Points spread over `mesh` in proportion to area: each triangle gets its share of `count`,
/// placed on a regular barycentric lattice (deterministic, no random numbers).
pub fn surface_samples(mesh: &TriMesh, count: usize) -> Vec<Vec3> {
    let areas: Vec<f32> = (0..mesh.triangles.len())
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            0.5 * (b - a).cross(c - a).length()
        })
        .collect();
    let total: f32 = areas.iter().sum();
    if total <= 0.0 {
        return mesh.positions.clone();
    }
    let mut points = Vec::with_capacity(count + mesh.triangles.len());
    for (t, area) in areas.iter().enumerate() {
        let [a, b, c] = mesh.triangle(t);
        let share = area / total * count as f32;
        // A lattice of k rows holds k (k + 1) / 2 points.
        let k = ((2.0 * share).sqrt().round() as usize).max(1);
        for i in 0..k {
            for j in 0..k - i {
                let u = (i as f32 + 1.0 / 3.0) / k as f32;
                let v = (j as f32 + 1.0 / 3.0) / k as f32;
                points.push(a + (b - a) * u + (c - a) * v);
            }
        }
    }
    points
}

/// The symmetric Chamfer distance between the surfaces of `a` and `b`, metres; `None` when
/// either has no triangles.
pub fn chamfer_distance(a: &TriMesh, b: &TriMesh) -> Option<f32> {
    if a.triangles.is_empty() || b.triangles.is_empty() {
        return None;
    }
    let (shape_a, shape_b) = (parry_mesh(a).ok()?, parry_mesh(b).ok()?);
    let one_way = |points: &[Vec3], shape: &parry3d::shape::TriMesh| {
        let sum: f64 = points
            .iter()
            .map(|p| f64::from(shape.distance_to_local_point(*p, false)))
            .sum();
        sum / points.len().max(1) as f64
    };
    let to_b = one_way(&surface_samples(a, SAMPLES), &shape_b);
    let to_a = one_way(&surface_samples(b, SAMPLES), &shape_a);
    Some((0.5 * (to_a + to_b)) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Affine3A;

    fn cube(size: f32) -> TriMesh {
        TriMesh::cuboid_centered(Vec3::ZERO, Vec3::splat(size))
    }

    #[test]
    fn a_surface_is_at_zero_from_itself_and_a_shift_is_measured() {
        let a = cube(1.0);
        assert!(chamfer_distance(&a, &a).expect("meshes") < 1e-4);
        let shifted = a.transformed(&Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.02)));
        let d = chamfer_distance(&a, &shifted).expect("meshes");
        // Top and bottom faces move 2 cm, the sides slide along themselves.
        assert!((0.004..0.02).contains(&d), "{d}");
        let bigger = cube(1.2);
        let d = chamfer_distance(&a, &bigger).expect("meshes");
        assert!((0.05..0.15).contains(&d), "{d}");
    }

    #[test]
    fn samples_follow_area() {
        let points = surface_samples(&cube(1.0), 6000);
        assert!((4000..9000).contains(&points.len()), "{}", points.len());
    }
}
