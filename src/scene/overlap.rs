//! Objects of a specification must not stand in each other: the deepest interpenetration of
//! any two objects' solid pieces, with their doors and drawers where the specification sets them.

use rayon::prelude::*;

use crate::cad::placed_solid::{PlacedSolid, penetration_depth};
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
/// index order among equals). An object inside a container is not tested against the container:
/// an imported container's solid pieces are the hulls of its meshes, which hold its inside.
pub fn deepest_overlap(world: &SceneWorld) -> Option<Overlap> {
    let solids: Vec<PlacedSolid> = world
        .objects
        .par_iter()
        .map(|o| PlacedSolid::from_world_mesh(&o.world_mesh()))
        .collect();
    let pairs: Vec<(usize, usize)> = (0..solids.len())
        .flat_map(|a| (a + 1..solids.len()).map(move |b| (a, b)))
        .filter(|&(a, b)| {
            let inside = |child: usize, parent: usize| {
                world.objects[child].support == Support::InObject(parent)
            };
            !inside(a, b) && !inside(b, a)
        })
        .collect();
    pairs
        .par_iter()
        .map(|&(a, b)| Overlap {
            a,
            b,
            depth: penetration_depth(&solids[a], &solids[b]),
        })
        .filter(|o| o.depth > MAX_OVERLAP_M)
        .max_by(|x, y| {
            x.depth
                .total_cmp(&y.depth)
                .then(y.a.cmp(&x.a))
                .then(y.b.cmp(&x.b))
        })
}
