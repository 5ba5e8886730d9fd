//! The boxes that links and motions occupy in the world: a link's box in its frame, a body's
//! world box, the box a moving subtree sweeps along a path (sampled at a few poses), and
//! whether two boxes come near each other. What a motion check uses to choose the objects it
//! simulates.

use glam::{Affine3A, Vec3};

use crate::kinematics::joint_sweep::world_bounds;
use crate::kinematics::tree::KinematicTree;

/// A box holding nothing: the start of a union.
pub const EMPTY_BOX: (Vec3, Vec3) = (Vec3::MAX, Vec3::MIN);
/// The swept volume is sampled at this many poses along the path (and its end).
const SWEEP_SAMPLES: usize = 24;

/// The world box of `links`' collision pieces at `poses`.
pub fn body_bounds(
    tree: &KinematicTree,
    links: &[usize],
    poses: &[Affine3A],
) -> Option<(Vec3, Vec3)> {
    links
        .iter()
        .filter_map(|&l| {
            let (lo, hi) = link_bounds(tree, l)?;
            Some(world_bounds(&poses[l], lo, hi))
        })
        .reduce(|a, b| (a.0.min(b.0), a.1.max(b.1)))
}

/// The box, in the link's frame, of its collision pieces.
pub fn link_bounds(tree: &KinematicTree, link: usize) -> Option<(Vec3, Vec3)> {
    let g = tree.links[link].geometry.as_ref()?;
    g.collision
        .iter()
        .flat_map(|piece| piece.positions.iter())
        .fold(None, |acc: Option<(Vec3, Vec3)>, p| {
            Some(acc.map_or((*p, *p), |(lo, hi)| (lo.min(*p), hi.max(*p))))
        })
}

/// The world box the links marked `moving` (at `poses`) pass through as link `link` follows
/// `path`.
pub fn swept_bounds(
    tree: &KinematicTree,
    moving: &[bool],
    poses: &[Affine3A],
    link: usize,
    path: &[Affine3A],
) -> (Vec3, Vec3) {
    let mover_from_world = poses[link].inverse();
    let local: Vec<(Affine3A, Vec3, Vec3)> = (0..tree.links.len())
        .filter(|&l| moving[l])
        .filter_map(|l| {
            let (lo, hi) = link_bounds(tree, l)?;
            Some((mover_from_world * poses[l], lo, hi))
        })
        .collect();
    sampled(path.len())
        .flat_map(|k| {
            let world_from_mover = path[k];
            local.iter().map(move |(mover_from_link, lo, hi)| {
                world_bounds(&(world_from_mover * *mover_from_link), *lo, *hi)
            })
        })
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), (lo, hi)| {
            (a.min(lo), b.max(hi))
        })
}

/// The instants of a path of `len` at which its swept volume is sampled: [`SWEEP_SAMPLES`]
/// spread along it, and its end.
pub fn sampled(len: usize) -> impl Iterator<Item = usize> {
    let last = len.saturating_sub(1);
    let stride = (last / SWEEP_SAMPLES).max(1);
    (0..=last).step_by(stride).chain(std::iter::once(last))
}

/// Whether two boxes come within `margin` of each other.
pub fn overlaps(a: (Vec3, Vec3), b: (Vec3, Vec3), margin: f32) -> bool {
    (a.0 - margin).cmple(b.1).all() && (b.0 - margin).cmple(a.1).all()
}
