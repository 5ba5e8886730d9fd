//! Points sampled over a mesh's surface, no farther apart than a given spacing.

use glam::Vec3;

use crate::geometry::TriMesh;

/// Points on a mesh's surface with the surface's unit normal at each (zero where undefined).
pub struct SurfacePoints {
    pub points: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// The mesh's vertices, plus points on a barycentric grid inside every triangle with an edge
/// longer than `spacing`, so no two neighbouring surface points are farther apart than that.
pub fn surface_points(mesh: &TriMesh, spacing: f32) -> SurfacePoints {
    let (mut points, mut normals): (Vec<Vec3>, Vec<Vec3>) = mesh
        .positions
        .iter()
        .copied()
        .zip(mesh.vertex_normals())
        .filter(|(p, _)| p.is_finite())
        .unzip();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let longest = (b - a).length().max((c - b).length()).max((a - c).length());
        if !longest.is_finite() || longest <= spacing {
            continue;
        }
        let normal = mesh.face_normal(t);
        let k = (longest / spacing).ceil() as usize;
        for i in 0..=k {
            for j in 0..=(k - i) {
                // Corners are vertices already.
                if (i == k) || (j == k) || (i == 0 && j == 0) {
                    continue;
                }
                let (u, v) = (i as f32 / k as f32, j as f32 / k as f32);
                points.push(a + (b - a) * u + (c - a) * v);
                normals.push(normal);
            }
        }
    }
    SurfacePoints { points, normals }
}
