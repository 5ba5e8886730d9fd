//! Indexed triangle meshes and the primitives the parametric CAD library is built from.

use std::f32::consts::FRAC_PI_2;

use glam::{Affine3A, Vec2, Vec3};
use serde::{Deserialize, Serialize};

/// An indexed triangle mesh. Triangles wind counter-clockwise seen from outside (normals point out).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Appends `other`, re-indexing its triangles.
    pub fn append(&mut self, other: &TriMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// The triangles `keep` accepts, with only the vertices they use (in first-use order).
    pub fn filtered(&self, keep: impl Fn([Vec3; 3]) -> bool) -> TriMesh {
        self.with_triangles(|t| keep(self.triangle(t)))
    }

    /// The triangles whose three vertices `keep` (one flag per vertex) holds, with only the
    /// vertices they use (in first-use order).
    pub fn with_vertices(&self, keep: &[bool]) -> TriMesh {
        self.with_triangles(|t| self.triangles[t].iter().all(|&v| keep[v as usize]))
    }

    /// The triangles (by index) `keep` accepts, with only the vertices they use.
    fn with_triangles(&self, keep: impl Fn(usize) -> bool) -> TriMesh {
        let mut new_index = vec![u32::MAX; self.positions.len()];
        let mut out = TriMesh::default();
        for (t, tri) in self.triangles.iter().enumerate() {
            if !keep(t) {
                continue;
            }
            let mut new = [0u32; 3];
            for (slot, &v) in new.iter_mut().zip(tri) {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = out.positions.len() as u32;
                    out.positions.push(self.positions[v as usize]);
                }
                *slot = new_index[v as usize];
            }
            out.triangles.push(new);
        }
        out
    }

    /// The mesh simplified by vertex clustering (Rossignac and Borrel): the vertices in each cube
    /// of a `cell`-sized grid merge into their mean, and triangles that collapse or repeat are
    /// dropped. The shape moves by at most a cell; a dense mesh keeps a few triangles per cell.
    pub fn clustered(&self, cell: f32) -> TriMesh {
        if !(cell.is_finite() && cell > 0.0) {
            return self.clone();
        }
        let mut cluster_of_cell: std::collections::HashMap<glam::IVec3, u32> =
            std::collections::HashMap::new();
        let mut sums: Vec<(Vec3, f32)> = Vec::new();
        let cluster: Vec<u32> = self
            .positions
            .iter()
            .map(|p| {
                let key = (*p / cell).floor().as_ivec3();
                let next = sums.len() as u32;
                let c = *cluster_of_cell.entry(key).or_insert(next);
                if c == next {
                    sums.push((Vec3::ZERO, 0.0));
                }
                sums[c as usize].0 += *p;
                sums[c as usize].1 += 1.0;
                c
            })
            .collect();
        let mut seen = std::collections::HashSet::new();
        let triangles = self
            .triangles
            .iter()
            .map(|t| t.map(|v| cluster[v as usize]))
            .filter(|[a, b, c]| a != b && b != c && a != c)
            .filter(|t| {
                // The same three clusters in the same turning order are the same triangle.
                let first = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
                seen.insert([t[first], t[(first + 1) % 3], t[(first + 2) % 3]])
            })
            .collect();
        let clustered = TriMesh {
            positions: sums.iter().map(|(sum, n)| *sum / *n).collect(),
            triangles,
        };
        // Drop the clusters no remaining triangle uses.
        clustered.filtered(|_| true)
    }

    /// The mesh with every vertex mapped by `to_from_mesh`.
    pub fn transformed(&self, to_from_mesh: &Affine3A) -> TriMesh {
        TriMesh {
            positions: self
                .positions
                .iter()
                .map(|p| to_from_mesh.transform_point3(*p))
                .collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// Axis-aligned bounds `(min, max)`; `None` for a mesh without vertices.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        points_bounds(&self.positions)
    }

    /// Per-vertex unit normals: the area-weighted mean of the adjacent triangles' normals (zero
    /// for a vertex without a proper triangle).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for (i, t) in self.triangles.iter().enumerate() {
            let [a, b, c] = self.triangle(i);
            // Twice the area along the normal: larger triangles weigh more.
            let n = (b - a).cross(c - a);
            if n.is_finite() {
                for &v in t {
                    normals[v as usize] += n;
                }
            }
        }
        normals.iter().map(|n| n.normalize_or_zero()).collect()
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let t = self.triangles[i];
        [
            self.positions[t[0] as usize],
            self.positions[t[1] as usize],
            self.positions[t[2] as usize],
        ]
    }

    /// Unit normal of triangle `i` (zero for a degenerate triangle).
    pub fn face_normal(&self, i: usize) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// Total surface area in square metres.
    pub fn area(&self) -> f32 {
        (0..self.triangles.len())
            .map(|i| {
                let [a, b, c] = self.triangle(i);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// Signed volume by the divergence theorem; positive for a closed outward-wound mesh.
    pub fn signed_volume(&self) -> f32 {
        (0..self.triangles.len())
            .map(|i| {
                let [a, b, c] = self.triangle(i);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    /// A closed box spanning `min..max`.
    pub fn cuboid(min: Vec3, max: Vec3) -> TriMesh {
        let positions = box_corners(min, max).to_vec();
        // Quads as corner indices, each counter-clockwise seen from outside.
        const QUADS: [[u32; 4]; 6] = [
            [0, 2, 3, 1], // -z
            [4, 5, 7, 6], // +z
            [0, 1, 5, 4], // -y
            [2, 6, 7, 3], // +y
            [0, 4, 6, 2], // -x
            [1, 3, 7, 5], // +x
        ];
        let triangles = QUADS
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        TriMesh {
            positions,
            triangles,
        }
    }

    /// A closed box given by its centre and full size.
    pub fn cuboid_centered(center: Vec3, size: Vec3) -> TriMesh {
        TriMesh::cuboid(center - size * 0.5, center + size * 0.5)
    }

    /// A closed surface of revolution about the z axis through `(center.x, center.y)`.
    ///
    /// `profile` holds `(radius, z)` pairs from bottom to top, relative to `center`; the ends are
    /// capped with fans when their radius is not zero. A profile that goes up the outside and
    /// back down the inside gives a cup or bowl with a wall thickness; one that ends where it
    /// starts sweeps a ring and gets no caps.
    pub fn lathe(center: Vec3, profile: &[Vec2], segments: u32) -> TriMesh {
        let segments = segments.max(3);
        let rings = profile.len() as u32;
        let mut positions = Vec::with_capacity((rings * segments + 2) as usize);
        for p in profile {
            for s in 0..segments {
                let angle = std::f32::consts::TAU * s as f32 / segments as f32;
                positions.push(center + Vec3::new(p.x * angle.cos(), p.x * angle.sin(), p.y));
            }
        }
        let mut triangles = Vec::new();
        for r in 0..rings.saturating_sub(1) {
            for s in 0..segments {
                let a = r * segments + s;
                let b = r * segments + (s + 1) % segments;
                let c = a + segments;
                let d = b + segments;
                triangles.push([a, b, d]);
                triangles.push([a, d, c]);
            }
        }
        let mut cap = |ring: u32, z: f32, up: bool| {
            let centre_index = positions.len() as u32;
            positions.push(center + Vec3::new(0.0, 0.0, z));
            for s in 0..segments {
                let a = ring * segments + s;
                let b = ring * segments + (s + 1) % segments;
                triangles.push(if up {
                    [centre_index, a, b]
                } else {
                    [centre_index, b, a]
                });
            }
        };
        if let (Some(first), Some(last)) = (profile.first(), profile.last()) {
            if first == last {
                // A closed loop (a ring): the sweep alone is closed.
                return TriMesh {
                    positions,
                    triangles,
                };
            }
            if first.x > 0.0 {
                cap(0, first.y, false);
            }
            if last.x > 0.0 && rings > 1 {
                // The top cap faces up when the profile ends going outward-up, as for a solid.
                cap(rings - 1, last.y, true);
            }
        }
        TriMesh {
            positions,
            triangles,
        }
    }

    /// A closed vertical cylinder standing on `bottom_center`.
    pub fn cylinder(bottom_center: Vec3, radius: f32, height: f32, segments: u32) -> TriMesh {
        TriMesh::lathe(
            bottom_center,
            &[Vec2::new(radius, 0.0), Vec2::new(radius, height)],
            segments,
        )
    }

    /// A closed ellipsoid with semi-axes `radii`, centred on the origin.
    pub fn ellipsoid(radii: Vec3, segments: u32) -> TriMesh {
        let rings = (segments / 2).max(2);
        let profile: Vec<Vec2> = (0..=rings)
            .map(|i| {
                let a = -FRAC_PI_2 + std::f32::consts::PI * i as f32 / rings as f32;
                Vec2::new(a.cos().max(0.0), a.sin())
            })
            .collect();
        TriMesh::lathe(Vec3::ZERO, &profile, segments).transformed(&Affine3A::from_scale(radii))
    }

    /// A closed capsule along z centred on the origin: radius `radius`, its cylinder from
    /// `-half_length` to `half_length`.
    pub fn capsule(radius: f32, half_length: f32, segments: u32) -> TriMesh {
        let quarter = (segments / 4).max(1);
        let mut profile = Vec::new();
        for i in 0..=quarter {
            let a = -FRAC_PI_2 * (1.0 - i as f32 / quarter as f32);
            profile.push(Vec2::new(
                radius * a.cos().max(0.0),
                -half_length + radius * a.sin(),
            ));
        }
        for i in 0..=quarter {
            let a = FRAC_PI_2 * i as f32 / quarter as f32;
            profile.push(Vec2::new(
                radius * a.cos().max(0.0),
                half_length + radius * a.sin(),
            ));
        }
        TriMesh::lathe(Vec3::ZERO, &profile, segments)
    }

    /// A closed cylinder between two points (legs that splay, a star base's spokes).
    pub fn rod(from: Vec3, to: Vec3, radius: f32, segments: u32) -> TriMesh {
        let axis = to - from;
        let length = axis.length();
        let upright = TriMesh::cylinder(Vec3::ZERO, radius, length, segments);
        let rotation = glam::Quat::from_rotation_arc(Vec3::Z, axis / length.max(f32::EPSILON));
        upright.transformed(&Affine3A::from_rotation_translation(rotation, from))
    }
}

/// The 8 corners of the box `min..max`; corner `i` takes max on x, y, z for bits 1, 2, 4 of `i`.
/// Axis-aligned bounds `(min, max)` of `points`; `None` when there are none.
pub fn points_bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
    )
}

pub fn box_corners(min: Vec3, max: Vec3) -> [Vec3; 8] {
    std::array::from_fn(|i| {
        Vec3::new(
            if i & 1 == 0 { min.x } else { max.x },
            if i & 2 == 0 { min.y } else { max.y },
            if i & 4 == 0 { min.z } else { max.z },
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clustering_a_dense_sphere_keeps_its_shape_with_fewer_triangles() {
        let profile: Vec<Vec2> = (0..=64)
            .map(|i| {
                let a = std::f32::consts::PI * i as f32 / 64.0;
                Vec2::new(a.sin() * 0.5, 0.5 - a.cos() * 0.5)
            })
            .collect();
        let sphere = TriMesh::lathe(Vec3::ZERO, &profile, 128);
        let cell = 0.05;
        let simple = sphere.clustered(cell);
        assert!(simple.triangles.len() * 4 < sphere.triangles.len());
        assert!(simple.triangles.len() > 200);
        // Every vertex stays within a cell of the sphere, and the volume within a few percent.
        let centre = Vec3::new(0.0, 0.0, 0.5);
        for p in &simple.positions {
            assert!(((*p - centre).length() - 0.5).abs() < cell, "{p}");
        }
        let (v0, v1) = (sphere.signed_volume(), simple.signed_volume());
        assert!((v1 / v0 - 1.0).abs() < 0.05, "{v0} {v1}");
        // No triangle is degenerate or repeated, and every vertex is used.
        let mut used = vec![false; simple.positions.len()];
        for t in &simple.triangles {
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2]);
            t.iter().for_each(|&v| used[v as usize] = true);
        }
        assert!(used.iter().all(|u| *u));
        // A cell as large as the mesh leaves a few triangles at most; a cell of zero changes
        // nothing.
        assert!(sphere.clustered(2.0).triangles.len() <= 8);
        assert_eq!(sphere.clustered(0.0), sphere);
    }

    #[test]
    fn cuboid_is_closed_and_outward() {
        let m = TriMesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        assert!(
            (m.signed_volume() - 6.0).abs() < 1e-5,
            "volume {}",
            m.signed_volume()
        );
        assert!((m.area() - 22.0).abs() < 1e-5);
    }

    #[test]
    fn vertex_normals_are_unit_and_point_out() {
        let m = TriMesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let centre = Vec3::new(0.5, 1.0, 1.5);
        for (p, n) in m.positions.iter().zip(m.vertex_normals()) {
            assert!((n.length() - 1.0).abs() < 1e-5);
            assert!(n.dot(*p - centre) > 0.0, "{n} at {p}");
        }
    }

    #[test]
    fn cylinder_volume_approaches_pi_r2_h() {
        let m = TriMesh::cylinder(Vec3::ZERO, 0.5, 2.0, 64);
        let exact = std::f32::consts::PI * 0.25 * 2.0;
        assert!(
            (m.signed_volume() - exact).abs() / exact < 0.01,
            "volume {}",
            m.signed_volume()
        );
    }

    #[test]
    fn rod_spans_its_endpoints() {
        let m = TriMesh::rod(Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 2.0), 0.1, 8);
        let (lo, hi) = m.bounds().expect("vertices");
        assert!((lo.z - 0.0).abs() < 1e-5 && (hi.z - 2.0).abs() < 1e-5);
        assert!(m.signed_volume() > 0.0);
    }
}
