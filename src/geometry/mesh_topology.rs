//! How a triangle mesh is put together: its connected components, whether it is closed, its
//! convex hull, and its feature edges. Mass properties and collision shapes are computed per
//! component.

use std::collections::HashMap;
use std::hash::{Hash, Hasher};
use std::sync::{Mutex, OnceLock};

use glam::Vec3;
use parry3d::transformation::vhacd::VHACDParameters;
use parry3d::transformation::voxelization::FillMode;

use crate::geometry::TriMesh;

/// A component whose hull holds more than this many times its volume is hollow.
const HOLLOW_HULL_RATIO: f32 = 2.0;
/// V-HACD's voxels along a hollow component's longest side (4.7 mm in a 15 cm bowl, whose wall
/// is 5 mm), and the most pieces it makes of it.
const HOLLOW_RESOLUTION: u32 = 32;
const HOLLOW_PIECES: u32 = 24;
const REMEMBERED_DECOMPOSITIONS: usize = 256;

/// V-HACD's voxel edge along a surface seen from one side (a segment of the map, whose own voxels
/// are 1-2 cm), the least and most voxels along its longest side, and the most pieces made of it.
const SURFACE_VOXEL_M: f32 = 0.02;
const SURFACE_RESOLUTION: (u32, u32) = (16, 96);
const SURFACE_PIECES: u32 = 32;

/// The V-HACD pieces of `mesh` at `resolution` and `max_pieces`, made once per process for each
/// mesh (a world is built again for the checks of every simulated step, and one cup takes
/// 140 ms), at most `REMEMBERED_DECOMPOSITIONS` remembered.
fn remembered_decomposition(mesh: &TriMesh, params: &VHACDParameters) -> Vec<TriMesh> {
    type Made = Mutex<HashMap<u64, Vec<TriMesh>>>;
    static MADE: OnceLock<Made> = OnceLock::new();
    let key = {
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        format!("{params:?}").hash(&mut hasher);
        for p in &mesh.positions {
            p.to_array().map(f32::to_bits).hash(&mut hasher);
        }
        mesh.triangles.hash(&mut hasher);
        hasher.finish()
    };
    let made = MADE.get_or_init(Made::default);
    if let Some(pieces) = made.lock().ok().and_then(|m| m.get(&key).cloned()) {
        return pieces;
    }
    let pieces = mesh.decomposed(params);
    if let Ok(mut m) = made.lock() {
        if m.len() >= REMEMBERED_DECOMPOSITIONS {
            m.clear();
        }
        m.insert(key, pieces.clone());
    }
    pieces
}

impl TriMesh {
    /// The sets of triangles connected through shared vertex indices, each re-indexed as its own
    /// mesh, in the order of their first triangle.
    pub fn connected_components(&self) -> Vec<TriMesh> {
        let n = self.positions.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for t in &self.triangles {
            let a = root(&mut parent, t[0] as usize);
            for &v in &t[1..] {
                let b = root(&mut parent, v as usize);
                parent[b] = a;
            }
        }
        let mut component_of_root: HashMap<usize, usize> = HashMap::new();
        let mut components: Vec<(TriMesh, HashMap<u32, u32>)> = Vec::new();
        for t in &self.triangles {
            let r = root(&mut parent, t[0] as usize);
            let k = *component_of_root.entry(r).or_insert_with(|| {
                components.push((TriMesh::default(), HashMap::new()));
                components.len() - 1
            });
            let (mesh, index) = &mut components[k];
            let tri = t.map(|v| {
                *index.entry(v).or_insert_with(|| {
                    mesh.positions.push(self.positions[v as usize]);
                    (mesh.positions.len() - 1) as u32
                })
            });
            mesh.triangles.push(tri);
        }
        components.into_iter().map(|(mesh, _)| mesh).collect()
    }

    /// Whether every edge is shared by exactly two triangles, once in each direction: a closed,
    /// consistently wound surface whose signed volume is its volume.
    pub fn is_closed(&self) -> bool {
        if self.triangles.is_empty() {
            return false;
        }
        let mut directed: HashMap<(u32, u32), i32> = HashMap::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a == b {
                    return false;
                }
                *directed.entry((a, b)).or_default() += 1;
            }
        }
        directed
            .iter()
            .all(|(&(a, b), &count)| count == 1 && directed.get(&(b, a)) == Some(&1))
    }

    /// The convex hull of the vertices, wound outwards; `None` when they span no volume.
    pub fn convex_hull(&self) -> Option<TriMesh> {
        if self.positions.len() < 4 {
            return None;
        }
        let (positions, triangles) =
            parry3d::transformation::try_convex_hull(&self.positions).ok()?;
        let hull = TriMesh {
            positions,
            triangles,
        };
        (hull.signed_volume() > 1e-12).then_some(hull)
    }

    /// Convex pieces covering the mesh, what collides for it: the hull of each connected
    /// component, but a hollow one (a bowl, a cup: its hull holds more than twice its own
    /// volume) decomposed by V-HACD, so that what is open stays open (a finger goes in a bowl
    /// as far as its rim grasp needs, an object fits in it).
    pub fn collision_pieces(&self) -> Vec<TriMesh> {
        self.hulls_and_collision_pieces().1
    }

    /// Convex pieces along a surface seen from one side (what the map saw of an object no model
    /// replaced): V-HACD of its surface voxels at about the map's voxel size, so a shelf's
    /// boards stay boards with room between them, where the hull of the shelf is a solid block
    /// with the bottles inside it. Empty when nothing spans volume.
    pub fn surface_pieces(&self) -> Vec<TriMesh> {
        let Some((lo, hi)) = self.bounds() else {
            return Vec::new();
        };
        let longest = (hi - lo).max_element();
        let (least, most) = SURFACE_RESOLUTION;
        let resolution = ((longest / SURFACE_VOXEL_M).ceil() as u32).clamp(least, most);
        // An open surface has no inside to fill; with V-HACD's default concavity (0.01) and
        // its plane and hull downsampling, the front half of a shelf's lower level stayed one
        // piece, boards, sides and the air between them.
        remembered_decomposition(
            self,
            &VHACDParameters {
                resolution,
                max_convex_hulls: SURFACE_PIECES,
                concavity: 0.001,
                plane_downsampling: 1,
                convex_hull_downsampling: 1,
                fill_mode: FillMode::SurfaceOnly,
                ..Default::default()
            },
        )
    }

    /// The hull of each connected component, and [`Self::collision_pieces`] made from them.
    pub fn hulls_and_collision_pieces(&self) -> (Vec<TriMesh>, Vec<TriMesh>) {
        let mut hulls = Vec::new();
        let mut pieces = Vec::new();
        for component in self.connected_components() {
            let Some(hull) = component.convex_hull() else {
                continue;
            };
            let hollow = hull.signed_volume() > HOLLOW_HULL_RATIO * component.signed_volume().abs();
            let open = if hollow {
                remembered_decomposition(
                    &component,
                    &VHACDParameters {
                        resolution: HOLLOW_RESOLUTION,
                        max_convex_hulls: HOLLOW_PIECES,
                        ..Default::default()
                    },
                )
            } else {
                Vec::new()
            };
            if open.is_empty() {
                pieces.push(hull.clone());
            } else {
                pieces.extend(open);
            }
            hulls.push(hull);
        }
        (hulls, pieces)
    }

    /// The mesh split into at most `max_pieces` convex pieces by V-HACD (parry's), each the exact
    /// hull of the mesh inside one part of the voxelised volume (`resolution` voxels along the
    /// longest side), wound outwards. Works on meshes that are not closed: their surface voxels
    /// are decomposed. Empty when nothing spans volume.
    pub fn convex_decomposition(&self, resolution: u32, max_pieces: u32) -> Vec<TriMesh> {
        self.decomposed(&VHACDParameters {
            resolution,
            max_convex_hulls: max_pieces,
            ..Default::default()
        })
    }

    /// [`Self::convex_decomposition`] with all of V-HACD's parameters given.
    fn decomposed(&self, params: &VHACDParameters) -> Vec<TriMesh> {
        use parry3d::transformation::vhacd::VHACD;
        if self.triangles.is_empty() {
            return Vec::new();
        }
        let decomposition = VHACD::decompose(params, &self.positions, &self.triangles, true);
        decomposition
            .compute_exact_convex_hulls(&self.positions, &self.triangles)
            .into_iter()
            .filter_map(|(positions, _)| {
                TriMesh {
                    positions,
                    triangles: Vec::new(),
                }
                .convex_hull()
            })
            .collect()
    }

    /// The edges a wireframe should show: borders (one triangle) and creases, where the two
    /// triangles' normals differ by more than `crease_deg`. The diagonals that triangulate a flat
    /// face are not among them. Edges are matched by shared vertex indices.
    pub fn feature_edges(&self, crease_deg: f32) -> Vec<[Vec3; 2]> {
        let mut faces_of_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
        for (i, t) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                faces_of_edge
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push(i);
            }
        }
        let cos_crease = crease_deg.to_radians().cos();
        let mut edges: Vec<((u32, u32), [Vec3; 2])> = faces_of_edge
            .into_iter()
            .filter(|(_, faces)| match faces[..] {
                [f, g] => self.face_normal(f).dot(self.face_normal(g)) < cos_crease,
                _ => true,
            })
            .map(|((a, b), _)| {
                let ends = [self.positions[a as usize], self.positions[b as usize]];
                ((a, b), ends)
            })
            .collect();
        // In index order, so the same mesh always gives the same list.
        edges.sort_unstable_by_key(|(key, _)| *key);
        edges.into_iter().map(|(_, ends)| ends).collect()
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    #[test]
    fn a_u_shape_decomposes_into_convex_pieces_that_leave_its_gap_empty() {
        // Two posts and a bridge: the hull of the whole fills the gap between the posts.
        let mut u = TriMesh::cuboid(Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.2, 0.2, 1.0));
        u.append(&TriMesh::cuboid(
            Vec3::new(0.8, 0.0, 0.0),
            Vec3::new(1.0, 0.2, 1.0),
        ));
        u.append(&TriMesh::cuboid(
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.2, 1.2),
        ));
        let pieces = u.convex_decomposition(64, 16);
        assert!(pieces.len() >= 2, "{} pieces", pieces.len());
        let volume: f32 = pieces.iter().map(TriMesh::signed_volume).sum();
        let solid = 2.0 * 0.2 * 0.2 * 1.0 + 1.0 * 0.2 * 0.2;
        assert!(
            volume > 0.8 * solid && volume < 1.5 * solid,
            "{volume} against {solid}"
        );
        for piece in &pieces {
            assert!(piece.signed_volume() > 0.0, "wound outwards");
            let hull = piece.convex_hull().expect("volume");
            assert!(
                (hull.signed_volume() - piece.signed_volume()).abs() < 1e-4,
                "convex"
            );
        }
        // The middle of the gap lies in no piece.
        let gap = Vec3::new(0.5, 0.1, 0.5);
        for piece in &pieces {
            let inside = piece.triangles.iter().enumerate().all(|(i, _)| {
                let [a, _, _] = piece.triangle(i);
                piece.face_normal(i).dot(gap - a) <= 0.0
            });
            assert!(!inside);
        }
    }

    #[test]
    fn a_bowl_collides_as_pieces_that_leave_its_inside_open_and_a_box_as_its_hull() {
        // The library's deep bowl: 15 cm wide, 8 cm high, a 5 mm wall.
        let (r, h, wall) = (0.075, 0.08, 0.005);
        let profile = [
            glam::Vec2::new(0.4 * r, 0.0),
            glam::Vec2::new(0.45 * r, 0.1 * h),
            glam::Vec2::new(0.8 * r, 0.45 * h),
            glam::Vec2::new(r, h),
            glam::Vec2::new(r - wall, h),
            glam::Vec2::new(0.8 * r - wall, 0.45 * h + wall),
            glam::Vec2::new(0.45 * r - wall, 0.1 * h + wall),
        ];
        let mesh = TriMesh::lathe(Vec3::ZERO, &profile, 24);
        let pieces = mesh.collision_pieces();
        assert!(pieces.len() > 4, "{} pieces", pieces.len());
        let inside = |p: Vec3| {
            pieces.iter().any(|piece| {
                piece.triangles.iter().enumerate().all(|(i, _)| {
                    let [a, _, _] = piece.triangle(i);
                    piece.face_normal(i).dot(p - a) <= 0.0
                })
            })
        };
        // A finger's width inside the rim, half way down: open.
        assert!(!inside(Vec3::new(0.055, 0.0, 0.06)));
        assert!(!inside(Vec3::new(0.0, 0.0, 0.05)));
        assert!(!inside(Vec3::new(0.05, 0.0, 0.05)));
        // The wall at the rim: covered.
        assert!(inside(Vec3::new(0.0725, 0.0, 0.079)));
        let book = TriMesh::cuboid(Vec3::ZERO, Vec3::new(0.2, 0.15, 0.03));
        assert_eq!(book.collision_pieces().len(), 1);
    }

    #[test]
    fn two_boxes_are_two_closed_components() {
        let mut mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::ONE);
        mesh.append(&TriMesh::cuboid(Vec3::splat(2.0), Vec3::splat(3.0)));
        let components = mesh.connected_components();
        assert_eq!(components.len(), 2);
        for c in &components {
            assert!(c.is_closed());
            assert_eq!(c.positions.len(), 8);
            assert!((c.signed_volume() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn an_open_box_is_not_closed_and_its_hull_is_the_box() {
        let mut mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 0.5));
        mesh.triangles.truncate(10);
        assert!(!mesh.is_closed());
        let hull = mesh.convex_hull().expect("a box spans volume");
        assert!(hull.is_closed());
        assert!((hull.signed_volume() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn a_box_shows_its_twelve_edges_and_an_open_one_its_border() {
        let cube = TriMesh::cuboid(Vec3::ZERO, Vec3::ONE);
        let hull = cube.convex_hull().expect("hull");
        for mesh in [&cube, &hull] {
            let edges = mesh.feature_edges(1.0);
            assert_eq!(edges.len(), 12);
            for [a, b] in edges {
                // Every edge of a unit cube is one unit long along one axis.
                assert!(((a - b).length() - 1.0).abs() < 1e-5);
            }
        }
        let flat = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE.with_z(0.0)],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        assert_eq!(flat.feature_edges(1.0).len(), 4);
    }

    #[test]
    fn a_flat_mesh_has_no_hull() {
        let mesh = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::ONE.with_z(0.0)],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        assert!(mesh.convex_hull().is_none());
    }
}
