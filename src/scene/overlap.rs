//! Objects of a specification must not stand in each other: the deepest interpenetration of
//! any two objects' solid pieces, with their doors and drawers where the specification sets them.

use rayon::prelude::*;

use crate::cad::placed_solid::{PlacedSolid, penetration_depth};
use crate::geometry::TriMesh;
use crate::scene::world::{SceneWorld, Support};

/// The most two objects of a specification may interpenetrate, metres: touching within the
/// rounding of their sizes, not standing in each other.
pub const MAX_OVERLAP_M: f32 = 0.005;

/// Two objects (indices into `SceneWorld::objects`, `a < b`) and how deep they interpenetrate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    pub a: usize,
    pub b: usize,
    pub depth: f32,
}

/// The deepest overlap past `MAX_OVERLAP_M` of two objects of `world`, if any (the first pair in
/// index order among equals). An object inside a container is tested against the container's
/// pieces but those that hold its centre: an imported container's pieces may be the hulls of its
/// meshes, which hold its inside; a shelf's boards do not, and one cutting through a box on the
/// board below is an overlap.
pub fn deepest_overlap(world: &SceneWorld) -> Option<Overlap> {
    let solids = Solids::of(world);
    let count = world.objects.len();
    let pairs: Vec<(usize, usize)> = (0..count)
        .flat_map(|a| (a + 1..count).map(move |b| (a, b)))
        .collect();
    pairs
        .par_iter()
        .map(|&(a, b)| Overlap {
            a,
            b,
            depth: solids.depth(world, a, b),
        })
        .filter(|o| o.depth > MAX_OVERLAP_M)
        .max_by(|x, y| {
            x.depth
                .total_cmp(&y.depth)
                .then(y.a.cmp(&x.a))
                .then(y.b.cmp(&x.b))
        })
}

/// How deep object `index` of `world` stands in any other object, metres (0 when in none).
/// Only objects whose bounds meet its bounds are made solid: `generate` asks this of every
/// object it tries.
pub fn deepest_overlap_of(world: &SceneWorld, index: usize) -> f32 {
    let meshes: Vec<TriMesh> = world.objects.par_iter().map(|o| o.world_mesh()).collect();
    let bounds = |i: usize| meshes[i].bounds();
    let near: Vec<bool> = (0..meshes.len())
        .map(|i| match (bounds(index), bounds(i)) {
            (Some((alo, ahi)), Some((blo, bhi))) => alo.cmple(bhi).all() && blo.cmple(ahi).all(),
            _ => false,
        })
        .collect();
    let solids = Solids::from_meshes(meshes, &near);
    (0..world.objects.len())
        .into_par_iter()
        .filter(|&other| other != index && near[other])
        .map(|other| solids.depth(world, index.min(other), index.max(other)))
        .reduce(|| 0.0, f32::max)
}

/// Every object's posed mesh and, where wanted, its solid pieces.
struct Solids {
    meshes: Vec<TriMesh>,
    solids: Vec<Option<PlacedSolid>>,
}

impl Solids {
    fn of(world: &SceneWorld) -> Self {
        let meshes: Vec<TriMesh> = world.objects.par_iter().map(|o| o.world_mesh()).collect();
        let all = vec![true; meshes.len()];
        Self::from_meshes(meshes, &all)
    }

    fn from_meshes(meshes: Vec<TriMesh>, wanted: &[bool]) -> Self {
        let solids = meshes
            .par_iter()
            .zip(wanted)
            .map(|(m, &w)| w.then(|| PlacedSolid::from_world_mesh(m)))
            .collect();
        Self { meshes, solids }
    }

    /// How deep objects `a` and `b` (both made solid) interpenetrate.
    fn depth(&self, world: &SceneWorld, a: usize, b: usize) -> f32 {
        let (Some(solid_a), Some(solid_b)) = (&self.solids[a], &self.solids[b]) else {
            return 0.0;
        };
        let inside =
            |child: usize, parent: usize| world.objects[child].support == Support::InObject(parent);
        if inside(a, b) || inside(b, a) {
            let (child, parent) = if inside(a, b) { (a, b) } else { (b, a) };
            let child_solid = if child == a { solid_a } else { solid_b };
            let centre = child_solid.centre();
            let mut walls = TriMesh::default();
            for piece in self.meshes[parent].connected_components() {
                if !piece.convex_hull().is_some_and(|h| hull_holds(&h, centre)) {
                    walls.append(&piece);
                }
            }
            penetration_depth(child_solid, &PlacedSolid::from_world_mesh(&walls))
        } else {
            penetration_depth(solid_a, solid_b)
        }
    }
}

/// Whether the closed convex `hull` (outward faces) holds `point`.
fn hull_holds(hull: &TriMesh, point: glam::Vec3) -> bool {
    (0..hull.triangles.len()).all(|t| {
        let normal = hull.face_normal(t);
        normal == glam::Vec3::ZERO || normal.dot(point - hull.triangle(t)[0]) <= 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneSpec;

    /// A cup standing where a book lies on a table: their bottoms are coplanar, which parry's
    /// EPA took for touching.
    #[test]
    fn a_cup_standing_in_a_book_is_an_overlap() {
        let json = r#"{"name": "t", "seed": 1, "room": {"size": [4, 4, 2.6]}, "objects": [
            {"class": "table", "id": "table_1", "model": "table_01", "position": [2, 2],
             "size": [1.01, 0.52, 0.47], "yaw_deg": 180},
            {"class": "book", "id": "book_2", "model": "book_02", "offset": [-0.26, -0.01],
             "on": "table_1", "yaw_deg": 160.8},
            {"class": "cup", "id": "cup_5", "model": "cup_01", "offset": [-0.26, -0.01],
             "on": "table_1", "yaw_deg": -160.5}]}"#;
        let path = std::path::Path::new("t.json");
        let spec = SceneSpec::parse(json, path).expect("a valid specification");
        let err = SceneWorld::from_spec(&spec, path).expect_err("the cup stands in the book");
        let text = err.to_string();
        assert!(
            text.contains("book_2") && text.contains("cup_5") && text.contains("overlap by 20"),
            "{text}"
        );
    }
}
