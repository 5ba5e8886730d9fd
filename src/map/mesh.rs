//! Marching cubes over the hashed TSDF that is seamless across blocks (cubes at a block's far
//! faces read the neighbouring blocks, vertices on shared edges are welded) and labelled (each
//! triangle takes the segment label of the labelled cube corner nearest to it).

use std::collections::HashMap;

use foldhash::fast::FixedState;
use glam::{IVec3, Vec3};
use marching_cubes::tables::{EDGE_TABLE, TRI_TABLE};
use rayon::prelude::*;

use crate::geometry::TriMesh;
use crate::map::tsdf::{BLOCK_SIDE, SegmentLabel, TsdfMap, Voxel};

/// Cube corners in the order of the Lorensen-Cline tables (offsets in voxels).
const CORNERS: [IVec3; 8] = [
    IVec3::new(0, 0, 0),
    IVec3::new(1, 0, 0),
    IVec3::new(1, 1, 0),
    IVec3::new(0, 1, 0),
    IVec3::new(0, 0, 1),
    IVec3::new(1, 0, 1),
    IVec3::new(1, 1, 1),
    IVec3::new(0, 1, 1),
];

/// The two corners of each of the 12 cube edges.
const EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// A triangle mesh of the zero level set with one segment label per triangle.
#[derive(Clone, Debug, Default)]
pub struct LabelledMesh {
    pub mesh: TriMesh,
    pub triangle_labels: Vec<SegmentLabel>,
}

impl LabelledMesh {
    /// The sub-mesh of the triangles whose label satisfies `keep`, with its own compact vertices.
    pub fn select(&self, keep: impl Fn(SegmentLabel) -> bool) -> TriMesh {
        self.split(1, |l| keep(l).then_some(0))
            .pop()
            .unwrap_or_default()
    }

    /// `groups` sub-meshes in one pass: triangle t goes to `group_of(its label)` (none: dropped).
    pub fn split(
        &self,
        groups: usize,
        group_of: impl Fn(SegmentLabel) -> Option<usize>,
    ) -> Vec<TriMesh> {
        let mut remaps: Vec<HashMap<u32, u32, FixedState>> = vec![HashMap::default(); groups];
        let mut out = vec![TriMesh::default(); groups];
        for (tri, &label) in self.mesh.triangles.iter().zip(&self.triangle_labels) {
            let Some(g) = group_of(label).filter(|&g| g < groups) else {
                continue;
            };
            let (remap, mesh) = (&mut remaps[g], &mut out[g]);
            let mut new = [0u32; 3];
            for (slot, &v) in new.iter_mut().zip(tri) {
                *slot = *remap.entry(v).or_insert_with(|| {
                    mesh.positions.push(self.mesh.positions[v as usize]);
                    mesh.positions.len() as u32 - 1
                });
            }
            mesh.triangles.push(new);
        }
        out
    }
}

/// A vertex on the cube edge that starts at voxel `origin` and runs along `axis` (0 = x).
type EdgeKey = (IVec3, u8);

/// A triangle before welding: its vertices' edge keys and positions, and its label.
type LooseTriangle = ([EdgeKey; 3], [Vec3; 3], SegmentLabel);

/// Extracts the surface where every cube corner has weight of at least `min_weight`.
pub fn extract_mesh(map: &TsdfMap, min_weight: f32) -> LabelledMesh {
    let per_block: Vec<Vec<LooseTriangle>> = map
        .blocks
        .par_iter()
        .map(|block| block_triangles(map, block.key, min_weight))
        .collect();
    let mut welded: HashMap<EdgeKey, u32, FixedState> = HashMap::default();
    let mut out = LabelledMesh::default();
    for triangles in per_block {
        for (keys, positions, label) in triangles {
            let mut tri = [0u32; 3];
            for ((slot, key), p) in tri.iter_mut().zip(keys).zip(positions) {
                *slot = *welded.entry(key).or_insert_with(|| {
                    out.mesh.positions.push(p);
                    out.mesh.positions.len() as u32 - 1
                });
            }
            // Cubes where the surface grazes a corner give zero-area triangles: drop them.
            if tri[0] != tri[1] && tri[1] != tri[2] && tri[0] != tri[2] {
                // The tables wind triangles clockwise seen from the positive side; TriMesh wants
                // normals towards free space.
                out.mesh.triangles.push([tri[0], tri[2], tri[1]]);
                out.triangle_labels.push(label);
            }
        }
    }
    out
}

fn block_triangles(map: &TsdfMap, key: IVec3, min_weight: f32) -> Vec<LooseTriangle> {
    let mut triangles = Vec::new();
    let base = key * BLOCK_SIDE as i32;
    let mut corners: [Voxel; 8] = [Voxel::default(); 8];
    for z in 0..BLOCK_SIDE as i32 {
        for y in 0..BLOCK_SIDE as i32 {
            'cube: for x in 0..BLOCK_SIDE as i32 {
                let origin = base + IVec3::new(x, y, z);
                let mut cube_index = 0usize;
                for (c, offset) in CORNERS.iter().enumerate() {
                    match map.voxel(origin + *offset) {
                        Some(v) if v.is_observed() && v.weight() >= min_weight => {
                            corners[c] = v;
                            if v.sdf < 0.0 {
                                cube_index |= 1 << c;
                            }
                        }
                        _ => continue 'cube,
                    }
                }
                if EDGE_TABLE[cube_index] == 0 {
                    continue;
                }
                let row = &TRI_TABLE[cube_index];
                for t in row.chunks_exact(3).take_while(|t| t[0] >= 0) {
                    let mut keys = [(IVec3::ZERO, 0u8); 3];
                    let mut positions = [Vec3::ZERO; 3];
                    for k in 0..3 {
                        let (a, b) = EDGES[t[k] as usize];
                        let (pa, pb) = (origin + CORNERS[a], origin + CORNERS[b]);
                        let (sa, sb) = (corners[a].sdf, corners[b].sdf);
                        let f = if (sa - sb).abs() > 1e-9 {
                            sa / (sa - sb)
                        } else {
                            0.5
                        };
                        positions[k] =
                            map.voxel_center(pa) + (pb - pa).as_vec3() * (f * map.voxel_size);
                        let axis = (pb - pa).abs().to_array().iter().position(|&d| d == 1);
                        keys[k] = (pa.min(pb), axis.unwrap_or(0) as u8);
                    }
                    let centroid = (positions[0] + positions[1] + positions[2]) / 3.0;
                    let label = CORNERS
                        .iter()
                        .zip(&corners)
                        .filter(|(_, v)| v.label != 0)
                        .min_by(|(oa, _), (ob, _)| {
                            let da = map.voxel_center(origin + **oa).distance_squared(centroid);
                            let db = map.voxel_center(origin + **ob).distance_squared(centroid);
                            da.total_cmp(&db)
                        })
                        .map_or(0, |(_, v)| v.label);
                    triangles.push((keys, positions, label));
                }
            }
        }
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::tsdf::{BLOCK_VOXELS, voxel_local};

    /// A map holding the exact signed distance of a sphere, labelled by the side of x = 0.
    fn sphere_map(center: Vec3, radius: f32) -> TsdfMap {
        let mut map = TsdfMap::new(0.02);
        let r = (radius / map.block_size()).ceil() as i32 + 1;
        let c = (center / map.block_size()).floor().as_ivec3();
        for z in -r..=r {
            for y in -r..=r {
                for x in -r..=r {
                    map.ensure_block(c + IVec3::new(x, y, z));
                }
            }
        }
        let vs = map.voxel_size;
        let truncation = map.truncation;
        for block in &mut map.blocks {
            for i in 0..BLOCK_VOXELS {
                let local = voxel_local(i);
                let p = ((block.key * BLOCK_SIDE as i32 + local).as_vec3() + 0.5) * vs;
                let sdf = (p.distance(center) - radius).clamp(-truncation, truncation);
                let label = if p.x < center.x { 1 } else { 2 };
                block.voxels_mut()[i] = Voxel::observed(sdf, 1.0, [0; 3], label);
            }
        }
        map
    }

    #[test]
    fn a_sphere_becomes_a_closed_outward_facing_mesh_split_by_label() {
        let (center, radius) = (Vec3::new(0.31, -0.07, 0.52), 0.3);
        let map = sphere_map(center, radius);
        let out = extract_mesh(&map, 0.5);
        let area = out.mesh.area();
        let expected = 4.0 * std::f32::consts::PI * radius * radius;
        assert!(
            (area / expected - 1.0).abs() < 0.02,
            "area {area} vs {expected}"
        );
        // Closed and consistently oriented: every directed edge appears once and its reverse once.
        let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &out.mesh.triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        assert!(
            edges
                .iter()
                .all(|(&(a, b), &n)| n == 1 && edges.get(&(b, a)) == Some(&1))
        );
        // Normals point out of the sphere, into free space (positive sdf).
        let outward = (0..out.mesh.triangles.len())
            .filter(|&i| {
                let [a, b, c] = out.mesh.triangle(i);
                out.mesh.face_normal(i).dot((a + b + c) / 3.0 - center) > 0.0
            })
            .count();
        assert_eq!(outward, out.mesh.triangles.len());
        for (label, side) in [(1, -1.0f32), (2, 1.0)] {
            let half = out.select(|l| l == label);
            assert!((half.area() / (0.5 * expected) - 1.0).abs() < 0.05);
            assert!(
                half.positions
                    .iter()
                    .all(|p| (p.x - center.x) * side > -0.03)
            );
        }
    }
}
