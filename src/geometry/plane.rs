//! Planes as `[n, d]` with `n . x + d = 0` and `n` a unit vector.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A plane `normal . x + offset = 0`. `signed_distance` is positive on the side the normal points to.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Plane {
    pub normal: Vec3,
    pub offset: f32,
}

impl Plane {
    /// The plane through `point` with unit `normal`.
    pub fn from_point_normal(point: Vec3, normal: Vec3) -> Self {
        let normal = normal.normalize();
        Self {
            normal,
            offset: -normal.dot(point),
        }
    }

    pub fn signed_distance(&self, point: Vec3) -> f32 {
        self.normal.dot(point) + self.offset
    }

    /// The `[nx, ny, nz, d]` form of the contact-graph schema.
    pub fn to_array(&self) -> [f32; 4] {
        [self.normal.x, self.normal.y, self.normal.z, self.offset]
    }

    pub fn from_array(a: [f32; 4]) -> Self {
        Self {
            normal: Vec3::new(a[0], a[1], a[2]),
            offset: a[3],
        }
    }
}

/// The least-squares plane of `points` (the normal is the covariance's direction of least
/// spread), or `None` for fewer than three points or points on a line.
pub fn fit_plane(points: &[Vec3]) -> Option<Plane> {
    if points.len() < 3 {
        return None;
    }
    let n = points.len() as f64;
    let mean = points
        .iter()
        .fold(glam::DVec3::ZERO, |a, p| a + p.as_dvec3())
        / n;
    let mut cov = glam::DMat3::ZERO;
    for p in points {
        let d = p.as_dvec3() - mean;
        cov += glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    // Inverse iteration converges on the smallest eigenvalue's vector at the rate of the ratio of
    // the two smallest: fast for anything plane-like. A tiny ridge keeps the inverse finite for
    // points exactly on a plane.
    let ridge = 1e-12 * (cov.x_axis.x + cov.y_axis.y + cov.z_axis.z).max(1e-30);
    let inverse = (cov + glam::DMat3::from_diagonal(glam::DVec3::splat(ridge))).inverse();
    if !inverse.is_finite() {
        return None;
    }
    let mut normal = glam::DVec3::new(0.577, 0.577, 0.577);
    for _ in 0..32 {
        normal = (inverse * normal).try_normalize()?;
    }
    // Points on a line leave two directions of no spread: no unique plane.
    let spread = |v: glam::DVec3| v.dot(cov * v);
    let second = normal.any_orthonormal_vector();
    let third = normal.cross(second);
    if spread(second).min(spread(third)) <= 1e-9 * (spread(second) + spread(third)) {
        return None;
    }
    Some(Plane::from_point_normal(mean.as_vec3(), normal.as_vec3()))
}

/// The planes that carry the most surface area of `mesh`: triangles are grouped by normal (within
/// about 2.5 degrees) and offset (within 1 cm); groups with at least `min_area` square metres are
/// returned, largest first, at most `max_count`. This is the exact answer RANSAC estimates from data.
pub fn dominant_planes(
    mesh: &crate::geometry::TriMesh,
    min_area: f32,
    max_count: usize,
) -> Vec<(Plane, f32)> {
    let mut groups: Vec<(Plane, f32)> = Vec::new();
    for i in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(i);
        let cross = (b - a).cross(c - a);
        let area = 0.5 * cross.length();
        if area < 1e-9 {
            continue;
        }
        let plane = Plane::from_point_normal(a, cross);
        match groups.iter_mut().find(|(p, _)| {
            p.normal.dot(plane.normal) > 0.999 && (p.offset - plane.offset).abs() < 0.01
        }) {
            Some((_, total)) => *total += area,
            None => groups.push((plane, area)),
        }
    }
    groups.retain(|(_, area)| *area >= min_area);
    // Ties broken by the plane's numbers so the order never depends on triangle order.
    groups.sort_by(|x, y| {
        y.1.total_cmp(&x.1).then_with(|| {
            x.0.to_array()
                .partial_cmp(&y.0.to_array())
                .unwrap_or(std::cmp::Ordering::Equal)
        })
    });
    groups.truncate(max_count);
    groups
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_noisy_tilted_plane_is_fitted_and_a_line_is_refused() {
        let truth = Plane::from_point_normal(Vec3::new(0.3, -1.0, 2.0), Vec3::new(0.2, 1.0, 0.3));
        let (u, v) = truth.normal.any_orthonormal_pair();
        let mut points = Vec::new();
        for i in 0..40 {
            for j in 0..25 {
                // Deterministic +-3 mm "noise" along the normal.
                let noise = 0.003 * (((i * 7 + j * 13) % 5) as f32 - 2.0) / 2.0;
                points.push(
                    Vec3::new(0.3, -1.0, 2.0)
                        + u * (i as f32 * 0.05)
                        + v * (j as f32 * 0.04)
                        + truth.normal * noise,
                );
            }
        }
        let fitted = fit_plane(&points).expect("a plane");
        assert!(fitted.normal.dot(truth.normal).abs() > 0.9999);
        assert!(
            points
                .iter()
                .all(|p| fitted.signed_distance(*p).abs() < 0.005)
        );
        let line: Vec<Vec3> = (0..10).map(|i| Vec3::X * i as f32).collect();
        assert_eq!(fit_plane(&line), None);
        assert_eq!(fit_plane(&points[..2]), None);
    }
    use crate::geometry::TriMesh;

    #[test]
    fn a_box_has_six_planes_and_the_largest_come_first() {
        let mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::new(2.0, 1.0, 0.1));
        let planes = dominant_planes(&mesh, 0.01, 10);
        assert_eq!(planes.len(), 6);
        assert!((planes[0].1 - 2.0).abs() < 1e-5);
        let top = planes.iter().find(|(p, _)| p.normal.z > 0.99).expect("top");
        assert!((top.0.signed_distance(Vec3::new(0.3, 0.3, 0.1))).abs() < 1e-6);
    }
}
