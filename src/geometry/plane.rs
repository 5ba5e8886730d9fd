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
