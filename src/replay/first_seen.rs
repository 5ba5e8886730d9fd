//! When each point of the final map was first observed: the first frame whose depth image
//! shows a surface at the point's depth where the point projects. The replay reveals the map in
//! that order, as the sensor saw it, without storing the map at every frame.

use glam::{Affine3A, Vec3};
use rayon::prelude::*;

use crate::error::InputError;
use crate::geometry::Pinhole;
use crate::io::Sequence;

/// Whether each of `points_in_world` is seen in one depth image: in front of the camera,
/// inside the image, and within `tolerance_m` of the measured depth (neither occluded nor in
/// free space).
pub fn seen_in_frame(
    points_in_world: &[Vec3],
    camera: &Pinhole,
    world_from_camera: &Affine3A,
    depth: &[f32],
    tolerance_m: f32,
) -> Vec<bool> {
    let camera_from_world = world_from_camera.inverse();
    points_in_world
        .iter()
        .map(|p| pixel_seen(*p, camera, &camera_from_world, depth, tolerance_m).is_some())
        .collect()
}

/// The pixel (column, row) where a depth image sees `point_in_world`, if it does (see
/// `seen_in_frame`).
pub fn pixel_seen(
    point_in_world: Vec3,
    camera: &Pinhole,
    camera_from_world: &Affine3A,
    depth: &[f32],
    tolerance_m: f32,
) -> Option<(usize, usize)> {
    let c = camera_from_world.transform_point3(point_in_world);
    if c.z <= 0.05 {
        return None;
    }
    let px = camera.project(c).round();
    if px.x < 0.0 || px.y < 0.0 {
        return None;
    }
    let (u, v) = (px.x as usize, px.y as usize);
    if u >= camera.width as usize || v >= camera.height as usize {
        return None;
    }
    let measured = depth[v * camera.width as usize + u];
    (measured > 0.0 && measured.is_finite() && (measured - c.z).abs() <= tolerance_m)
        .then_some((u, v))
}

/// For each point, the position in `sequence.frames` of the first frame that sees it (see
/// `seen_in_frame`); `None` for a point no frame sees within the tolerance.
pub fn first_seen(
    points_in_world: &[Vec3],
    sequence: &Sequence,
    tolerance_m: f32,
) -> Result<Vec<Option<u32>>, InputError> {
    let mut first: Vec<Option<u32>> = vec![None; points_in_world.len()];
    let n = sequence.frames.len();
    // A few frames at a time in parallel, folded in frame order: the earliest frame wins.
    let batch = 2 * rayon::current_num_threads().max(1);
    for start in (0..n).step_by(batch) {
        let seen: Vec<Vec<bool>> = (start..(start + batch).min(n))
            .into_par_iter()
            .map(|i| {
                let frame = sequence.load_frame(i)?;
                Ok(seen_in_frame(
                    points_in_world,
                    &frame.camera,
                    &frame.world_from_camera,
                    &frame.depth,
                    tolerance_m,
                ))
            })
            .collect::<Result<_, InputError>>()?;
        for (offset, flags) in seen.iter().enumerate() {
            for (slot, &flag) in first.iter_mut().zip(flags) {
                if flag && slot.is_none() {
                    *slot = Some((start + offset) as u32);
                }
            }
        }
    }
    Ok(first)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A camera at the origin looking down +z at a wall 2 m away that fills the picture.
    fn wall_view() -> (Pinhole, Affine3A, Vec<f32>) {
        let camera = Pinhole {
            width: 64,
            height: 48,
            fx: 50.0,
            fy: 50.0,
            cx: 31.5,
            cy: 23.5,
        };
        (camera, Affine3A::IDENTITY, vec![2.0; 64 * 48])
    }

    #[test]
    fn a_point_is_seen_on_the_surface_and_not_behind_it_or_outside_the_picture() {
        let (camera, pose, depth) = wall_view();
        let points = [
            Vec3::new(0.1, -0.2, 2.01), // on the wall
            Vec3::new(0.1, -0.2, 2.5),  // behind it
            Vec3::new(0.1, -0.2, 1.0),  // in the free space before it
            Vec3::new(5.0, 0.0, 2.0),   // outside the picture
            Vec3::new(0.0, 0.0, -2.0),  // behind the camera
        ];
        let seen = seen_in_frame(&points, &camera, &pose, &depth, 0.05);
        assert_eq!(seen, [true, false, false, false, false]);
        // Where it is seen: its projection, rounded (50 * 0.1 / 2.01 + 31.5, 50 * -0.2 / 2.01 + 23.5).
        let at = pixel_seen(points[0], &camera, &pose.inverse(), &depth, 0.05);
        assert_eq!(at, Some((34, 19)));
        // A turned and moved camera sees the same wall point through its own pose.
        let moved = Affine3A::from_translation(Vec3::new(0.0, 0.0, -1.0));
        let seen = seen_in_frame(&points[..1], &camera, &moved, &vec![3.01; 64 * 48], 0.05);
        assert_eq!(seen, [true]);
    }

    #[test]
    fn missing_depth_sees_nothing() {
        let (camera, pose, _) = wall_view();
        let seen = seen_in_frame(
            &[Vec3::new(0.0, 0.0, 2.0)],
            &camera,
            &pose,
            &vec![0.0; 64 * 48],
            0.05,
        );
        assert_eq!(seen, [false]);
    }
}
