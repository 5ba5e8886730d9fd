//! An object's box fitted to what the frames measured of its outline (`panoptic::sighted`): the
//! map's mesh ends at its last voxel column, up to a voxel short of a top's unseen back edge,
//! which decides whether the object touches the wall behind it, and a stray vertex of run-on
//! over a gap can stick out a voxel past a side. Each side of the footprint goes to the extent
//! `MIN_FRAMES` frames measured it (one frame's stray boundary pixel does not move it): out to
//! it, or in towards it where the mesh reaches more than `slack` past it, by at most
//! `max_shrink`: the mesh is within a voxel of the surface, and what reaches further than the
//! silhouettes is surface no silhouette shows (something lying flat on its support, seen only
//! against it). Only across the floor: heights come from the mesh, whose horizontal surfaces
//! sit at their interpolated crossings.

use glam::Vec3;

use crate::geometry::{GravityBox, Plane};

/// A side of the footprint moves out to the extent this many frames reached at least.
pub const MIN_FRAMES: usize = 3;

/// `bbox` (z up) with each side of its footprint moved to the extent that `MIN_FRAMES` of
/// `frames` (each frame's outline points, same frame as the box) reached: out to it, or in to
/// `slack` metres past it (by at most `max_shrink`) where the box reaches further; points
/// outside the box's height (what stands on it, the floor under it) or within `band` metres of
/// a `layout` plane (the wall behind, which a frame's labels bleed onto) are left out.
pub fn reach_sighted(
    bbox: &GravityBox,
    frames: &[Vec<Vec3>],
    layout: &[Plane],
    band: f32,
    slack: f32,
    max_shrink: f32,
) -> GravityBox {
    if frames.len() < MIN_FRAMES {
        return *bbox;
    }
    let box_from_world = bbox.world_from_box().inverse();
    let half = bbox.size * 0.5;
    // Per frame, the farthest reach along +x, -x, +y, -y of the box.
    let mut reaches: [Vec<f32>; 4] = Default::default();
    for points in frames {
        let mut reach = [f32::NEG_INFINITY; 4];
        for p in points {
            let local = box_from_world.transform_point3(*p);
            if local.z.abs() > half.z || layout.iter().any(|l| l.signed_distance(*p).abs() < band) {
                continue;
            }
            for (r, along) in reach.iter_mut().zip([local.x, -local.x, local.y, -local.y]) {
                *r = r.max(along);
            }
        }
        for (all, r) in reaches.iter_mut().zip(reach) {
            if r.is_finite() {
                all.push(r);
            }
        }
    }
    let extent = |all: &mut Vec<f32>, half: f32| {
        if all.len() < MIN_FRAMES {
            return half;
        }
        all.sort_by(|a, b| b.total_cmp(a));
        let measured = all[MIN_FRAMES - 1];
        half.min((measured + slack).max(half - max_shrink))
            .max(measured)
    };
    let [px, nx, py, ny] = &mut reaches;
    let (px, nx) = (extent(px, half.x), extent(nx, half.x));
    let (py, ny) = (extent(py, half.y), extent(ny, half.y));
    let shift =
        bbox.world_from_box()
            .transform_vector3(Vec3::new(0.5 * (px - nx), 0.5 * (py - ny), 0.0));
    GravityBox {
        center: bbox.center + shift,
        yaw: bbox.yaw,
        size: Vec3::new(px + nx, py + ny, bbox.size.z),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cabinet() -> GravityBox {
        // 80 x 58 x 88 cm, turned 30 degrees.
        GravityBox {
            center: Vec3::new(1.0, 2.0, 0.44),
            yaw: 30f32.to_radians(),
            size: Vec3::new(0.8, 0.58, 0.88),
        }
    }

    /// A frame's silhouette of the top: a rectangle at top height reaching `right` along the
    /// box's +x and `back` along its +y from the centre, and as far as the box on the other
    /// sides.
    fn top_outline(b: &GravityBox, right: f32, back: f32) -> Vec<Vec3> {
        let (left, front) = (-0.5 * b.size.x, -0.5 * b.size.y);
        let along =
            |from: f32, to: f32| (0..=10).map(move |k| from + (to - from) * k as f32 / 10.0);
        along(left, right)
            .flat_map(|x| [Vec3::new(x, front, 0.43), Vec3::new(x, back, 0.43)])
            .chain(
                along(front, back)
                    .flat_map(|y| [Vec3::new(left, y, 0.43), Vec3::new(right, y, 0.43)]),
            )
            .map(|local| b.world_from_box().transform_point3(local))
            .collect()
    }

    fn side(g: &GravityBox, local: Vec3) -> Vec3 {
        g.world_from_box().transform_point3(local * 0.5 * g.size)
    }

    /// `reach_sighted` with a 2 cm map's band, slack and limit, `count` copies of one frame.
    fn reach(b: &GravityBox, frame: Vec<Vec3>, count: usize, layout: &[Plane]) -> GravityBox {
        reach_sighted(b, &vec![frame; count], layout, 0.005, 0.01, 0.02)
    }

    #[test]
    fn the_back_grows_to_what_three_frames_measured_and_no_further() {
        let b = cabinet();
        // Five frames saw the back edge 1.2 cm past the box; one stray frame 5 cm past.
        let mut frames = vec![top_outline(&b, 0.4, 0.302); 5];
        frames.push(top_outline(&b, 0.4, 0.34));
        let grown = reach_sighted(&b, &frames, &[], 0.005, 0.01, 0.02);
        assert!(
            (grown.size.y - 0.592).abs() < 1e-4,
            "depth {}",
            grown.size.y
        );
        assert!((grown.size.x - 0.8).abs() < 1e-5 && (grown.size.z - 0.88).abs() < 1e-6);
        // The front stayed where it was.
        assert!(side(&grown, -Vec3::Y).distance(side(&b, -Vec3::Y)) < 1e-4);
        assert!((grown.yaw - b.yaw).abs() < 1e-6);
    }

    #[test]
    fn a_side_the_mesh_ran_on_past_moves_in_to_the_slack_past_the_outline() {
        let b = cabinet();
        // The frames saw the right side 3 cm inside the box: it moves in to 1 cm past that.
        let moved = reach(&b, top_outline(&b, 0.37, 0.29), 4, &[]);
        assert!((moved.size.x - 0.78).abs() < 1e-4, "width {}", moved.size.x);
        assert!(side(&moved, -Vec3::X).distance(side(&b, -Vec3::X)) < 1e-4);
        // Frames that miss most of a side (surface no silhouette shows) move it in by no more
        // than the limit.
        let limited = reach(&b, top_outline(&b, 0.2, 0.29), 4, &[]);
        assert!(
            (limited.size.x - 0.78).abs() < 1e-4,
            "width {}",
            limited.size.x
        );
        // Within the slack it stays.
        let kept = reach(&b, top_outline(&b, 0.395, 0.29), 4, &[]);
        assert!((kept.size.x - 0.8).abs() < 1e-5, "width {}", kept.size.x);
    }

    #[test]
    fn too_few_frames_and_points_above_or_on_the_layout_change_nothing() {
        let b = cabinet();
        let far = top_outline(&b, 0.45, 0.35);
        assert_eq!(reach(&b, far.clone(), 2, &[]), b);
        let above: Vec<Vec3> = far.iter().map(|p| *p + Vec3::Z * 0.1).collect();
        assert_eq!(reach(&b, above, 5, &[]), b);
        // The wall 6 cm behind the box claims what was measured on it.
        let wall_point = side(&b, Vec3::Y) + b.world_from_box().transform_vector3(Vec3::Y * 0.06);
        let wall =
            Plane::from_point_normal(wall_point, -b.world_from_box().transform_vector3(Vec3::Y));
        let onto_wall = top_outline(&b, 0.4, 0.35);
        let grown = reach(&b, onto_wall, 5, &[wall]);
        assert!((grown.size.y - 0.58).abs() < 1e-4, "depth {}", grown.size.y);
    }
}
