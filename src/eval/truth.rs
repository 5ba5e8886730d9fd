//! Ground truth for evaluated points: the rendered scene's entity meshes, each point taking the
//! nearest mesh within a distance (farther points are void).

use std::collections::HashMap;

use foldhash::fast::FixedState;
use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::geometry::TriMesh;
use crate::geometry::point_triangle::closest_point_on_triangle;

/// Triangles of all meshes bucketed in a uniform grid of `cell`-sized cells, each triangle in
/// every cell its bounds grown by `cell` touch, so one cell answers any query within `cell`.
pub struct NearestMesh<'a> {
    meshes: &'a [TriMesh],
    cell: f32,
    grid: HashMap<IVec3, Vec<(u32, u32)>, FixedState>,
}

impl<'a> NearestMesh<'a> {
    pub fn new(meshes: &'a [TriMesh], max_distance: f32) -> Self {
        let cell = max_distance;
        let mut grid: HashMap<IVec3, Vec<(u32, u32)>, FixedState> = HashMap::default();
        for (m, mesh) in meshes.iter().enumerate() {
            for t in 0..mesh.triangles.len() {
                let [a, b, c] = mesh.triangle(t);
                let lo = ((a.min(b).min(c) - Vec3::splat(cell)) / cell)
                    .floor()
                    .as_ivec3();
                let hi = ((a.max(b).max(c) + Vec3::splat(cell)) / cell)
                    .floor()
                    .as_ivec3();
                for z in lo.z..=hi.z {
                    for y in lo.y..=hi.y {
                        for x in lo.x..=hi.x {
                            grid.entry(IVec3::new(x, y, z))
                                .or_default()
                                .push((m as u32, t as u32));
                        }
                    }
                }
            }
        }
        Self { meshes, cell, grid }
    }

    /// Index plus one of the nearest mesh within the maximum distance, 0 when none is.
    pub fn nearest(&self, p: Vec3) -> u32 {
        let Some(candidates) = self.grid.get(&(p / self.cell).floor().as_ivec3()) else {
            return 0;
        };
        let mut best = (self.cell * self.cell, 0u32);
        for &(m, t) in candidates {
            let q = closest_point_on_triangle(p, self.meshes[m as usize].triangle(t as usize));
            let d = q.distance_squared(p);
            if d < best.0 || (d == best.0 && m + 1 < best.1) {
                best = (d, m + 1);
            }
        }
        best.1
    }

    pub fn label_points(&self, points: &[Vec3]) -> Vec<u32> {
        points.par_iter().map(|p| self.nearest(*p)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn points_take_the_nearest_mesh_or_void() {
        let meshes = vec![
            TriMesh::cuboid(Vec3::ZERO, Vec3::ONE),
            TriMesh::cuboid(Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 1.0, 1.0)),
        ];
        let nearest = NearestMesh::new(&meshes, 0.05);
        assert_eq!(nearest.nearest(Vec3::new(0.5, 0.5, 1.02)), 1);
        assert_eq!(nearest.nearest(Vec3::new(1.98, 0.5, 0.5)), 2);
        assert_eq!(nearest.nearest(Vec3::new(1.5, 0.5, 0.5)), 0);
        // Inside a box, far from every face: void too.
        assert_eq!(nearest.nearest(Vec3::new(0.5, 0.5, 0.5)), 0);
    }
}
