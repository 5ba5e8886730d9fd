//! The colour the camera saw on a surface: the mean of the map's voxel colours where a placed
//! model's surface meets the observed surface, so that the twin's models look like the room's
//! objects (a red counter stays red) instead of wearing their library colours.

use glam::{IVec3, Vec3};

use crate::base::srgb::srgb_to_linear;
use crate::map::tsdf::{SegmentLabel, TsdfMap};

/// Fewer seen points than this say nothing about a surface's colour: it keeps its own.
pub const MIN_SEEN_POINTS: usize = 20;

/// The mean colour (linear RGB in 0..1) the map saw at `points` (map frame), or `None` when fewer
/// than [`MIN_SEEN_POINTS`] of them were seen. A point is seen when an observed voxel of the
/// observed surface (signed distance under one voxel) whose label `belongs` accepts lies in the
/// 3x3x3 voxels around it; it takes the colour of the one nearest the surface. Points on the
/// hidden side of a model (its back against a wall, its inside) find no such voxel of their own
/// object, so they do not pull the mean to a neighbour's colour.
pub fn seen_color(
    map: &TsdfMap,
    points: impl IntoIterator<Item = Vec3>,
    belongs: impl Fn(SegmentLabel) -> bool,
) -> Option<[f32; 3]> {
    let mut sum = [0.0f64; 3];
    let mut seen = 0usize;
    for p in points {
        let centre = map.voxel_coords(p);
        let mut best: Option<(f32, [u8; 3])> = None;
        for z in -1..=1 {
            for y in -1..=1 {
                for x in -1..=1 {
                    let Some(v) = map.voxel(centre + IVec3::new(x, y, z)) else {
                        continue;
                    };
                    // A voxel no colour frame reached keeps [0, 0, 0] (a sequence without
                    // colour images): it says nothing of the colour.
                    let surface = v.is_observed()
                        && v.sdf.abs() < map.voxel_size
                        && v.color != [0, 0, 0]
                        && belongs(v.label);
                    if surface && best.is_none_or(|(d, _)| v.sdf.abs() < d) {
                        best = Some((v.sdf.abs(), v.color));
                    }
                }
            }
        }
        if let Some((_, color)) = best {
            for (s, c) in sum.iter_mut().zip(color) {
                *s += f64::from(srgb_to_linear(c));
            }
            seen += 1;
        }
    }
    (seen >= MIN_SEEN_POINTS).then(|| sum.map(|s| (s / seen as f64) as f32))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::tsdf::{BLOCK_SIDE, BLOCK_VOXELS, Voxel, voxel_local};

    /// A map of the plane z = 0.5 seen from above: red where x < 0.5 (label 1), blue beyond
    /// (label 2).
    fn two_coloured_plane() -> TsdfMap {
        let mut map = TsdfMap::new(0.02);
        for x in 0..6 {
            for y in 0..6 {
                for z in 2..5 {
                    map.ensure_block(IVec3::new(x, y, z));
                }
            }
        }
        let vs = map.voxel_size;
        let truncation = map.truncation;
        for block in &mut map.blocks {
            for i in 0..BLOCK_VOXELS {
                let p = ((block.key * BLOCK_SIDE as i32 + voxel_local(i)).as_vec3() + 0.5) * vs;
                let sdf = (p.z - 0.5).clamp(-truncation, truncation);
                let (color, label) = if p.x < 0.5 {
                    ([200, 30, 20], 1)
                } else {
                    ([20, 40, 180], 2)
                };
                block.voxels_mut()[i] = Voxel::observed(sdf, 1.0, color, label);
            }
        }
        map
    }

    fn grid(x0: f32, x1: f32, z: f32) -> Vec<Vec3> {
        (0..20)
            .flat_map(|i| {
                (0..20).map(move |j| {
                    Vec3::new(
                        x0 + (x1 - x0) * i as f32 / 20.0,
                        0.2 + 0.5 * j as f32 / 20.0,
                        z,
                    )
                })
            })
            .collect()
    }

    #[test]
    fn a_surface_takes_the_colour_seen_on_it_in_linear_light() {
        let map = two_coloured_plane();
        // A model's face 1 cm off the observed surface, over the red half.
        let red = seen_color(&map, grid(0.1, 0.4, 0.51), |_| true).expect("seen");
        let expected = [200, 30, 20].map(srgb_to_linear);
        for (c, e) in red.iter().zip(expected) {
            assert!((c - e).abs() < 1e-4, "{red:?} vs {expected:?}");
        }
        let blue = seen_color(&map, grid(0.6, 0.9, 0.49), |_| true).expect("seen");
        assert!(blue[2] > 0.4 && blue[0] < 0.02, "{blue:?}");
    }

    #[test]
    fn only_the_objects_own_voxels_and_only_the_surface_count() {
        let map = two_coloured_plane();
        // Across both halves, the red object's labels only: red.
        let red = seen_color(&map, grid(0.1, 0.9, 0.5), |l| l == 1).expect("seen");
        assert!(red[0] > 0.5 && red[2] < 0.02, "{red:?}");
        // Points 6 cm above the surface (a hidden face, a model far off) see nothing.
        assert_eq!(seen_color(&map, grid(0.1, 0.9, 0.56), |_| true), None);
        // Too few points say nothing.
        let few = grid(0.1, 0.4, 0.5).into_iter().take(MIN_SEEN_POINTS - 1);
        assert_eq!(seen_color(&map, few, |_| true), None);
    }
}
