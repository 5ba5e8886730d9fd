//! Surfaces of one depth image for the layout survey: a triangle mesh over its pixel grid, and
//! surface elements from planes fitted to square patches of it.

use glam::{Affine3A, Vec3};

use crate::geometry::plane::fit_plane;
use crate::geometry::{Pinhole, TriMesh};

/// A triangle mesh over a depth image's pixel grid (every `stride` pixels), in the world frame,
/// with no triangle across a depth jump.
pub fn depth_grid_mesh(
    depth: &[f32],
    camera: &Pinhole,
    world_from_camera: &Affine3A,
    stride: usize,
) -> TriMesh {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let (gw, gh) = (w.div_ceil(stride), h.div_ceil(stride));
    let mut index = vec![u32::MAX; gw * gh];
    let mut mesh = TriMesh::default();
    let mut z = vec![0.0; gw * gh];
    for gy in 0..gh {
        for gx in 0..gw {
            let (u, v) = (gx * stride, gy * stride);
            let d = depth[v * w + u];
            if d > 0.0 && d.is_finite() {
                index[gy * gw + gx] = mesh.positions.len() as u32;
                z[gy * gw + gx] = d;
                mesh.positions.push(
                    world_from_camera.transform_point3(camera.unproject(u as f32, v as f32, d)),
                );
            }
        }
    }
    // Neighbours at most this far apart in depth are one surface (structured-light noise grows
    // with the square of the distance).
    let joined = |a: usize, b: usize| {
        let (za, zb) = (z[a], z[b]);
        (za - zb).abs() <= 0.03 + 0.02 * za.min(zb) * za.min(zb)
    };
    for gy in 0..gh.saturating_sub(1) {
        for gx in 0..gw.saturating_sub(1) {
            let [a, b, c, d] = [
                gy * gw + gx,
                gy * gw + gx + 1,
                (gy + 1) * gw + gx,
                (gy + 1) * gw + gx + 1,
            ];
            for [p, q, r] in [[a, c, b], [b, c, d]] {
                if [p, q, r].iter().all(|&i| index[i] != u32::MAX)
                    && joined(p, q)
                    && joined(q, r)
                    && joined(p, r)
                {
                    mesh.triangles.push([index[p], index[q], index[r]]);
                }
            }
        }
    }
    mesh
}

/// A surface element: centre, unit normal, area (square metres).
pub type Surfel = (Vec3, Vec3, f32);

/// Surface elements of a depth image, in the world frame: a plane fitted to each square patch of
/// `patch` x `patch` samples (every `stride` pixels) that is planar within the depth noise.
/// Depth quantisation stair-steps a far wall (a Kinect's steps are centimetres at 3 m), which
/// turns the normals of small triangles by tens of degrees; a plane through 64 points averages
/// the steps out, so a far wall's patches are vertical where its triangles are not.
pub fn depth_patches(
    depth: &[f32],
    camera: &Pinhole,
    world_from_camera: &Affine3A,
    stride: usize,
    patch: usize,
) -> Vec<Surfel> {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let side = stride * patch;
    let mut surfels = Vec::new();
    let mut points = Vec::with_capacity(patch * patch);
    for v0 in (0..h.saturating_sub(side - 1)).step_by(side) {
        for u0 in (0..w.saturating_sub(side - 1)).step_by(side) {
            points.clear();
            for v in (v0..v0 + side).step_by(stride) {
                for u in (u0..u0 + side).step_by(stride) {
                    let d = depth[v * w + u];
                    if d > 0.0 && d.is_finite() {
                        points.push(camera.unproject(u as f32, v as f32, d));
                    }
                }
            }
            // Most of the patch measured, and one surface (no depth jump, no corner).
            if points.len() * 4 < patch * patch * 3 {
                continue;
            }
            let Some(plane) = fit_plane(&points) else {
                continue;
            };
            let centre = points.iter().sum::<Vec3>() / points.len() as f32;
            let z = centre.z;
            let noise = 0.005 + 0.004 * z * z;
            let rms = (points
                .iter()
                .map(|p| plane.signed_distance(*p).powi(2))
                .sum::<f32>()
                / points.len() as f32)
                .sqrt();
            if rms > noise {
                continue;
            }
            // The patch's footprint on its plane: the pixels' footprint over the obliquity.
            let view = centre.normalize();
            let obliquity = plane.normal.dot(view).abs().max(0.2);
            let pixel = z / camera.fx.max(1.0) * stride as f32;
            let area = points.len() as f32 * pixel * pixel / obliquity;
            surfels.push((
                world_from_camera.transform_point3(centre),
                world_from_camera.transform_vector3(plane.normal),
                area,
            ));
        }
    }
    surfels
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Plane;

    #[test]
    fn patches_of_a_far_wall_with_quantised_depth_are_upright_where_its_triangles_are_not() {
        // A wall 3 m ahead, seen obliquely (30 degrees) by a camera pitched 20 degrees down,
        // its depth quantised in a Kinect's disparity steps (2.85 mm x depth squared). The
        // camera frame is the world's; its up is -y pitched.
        let camera = Pinhole::KINECT;
        let (w, h) = (camera.width as usize, camera.height as usize);
        let up = glam::Quat::from_rotation_x(-20f32.to_radians()) * -Vec3::Y;
        let facing = glam::Quat::from_axis_angle(up, 30f32.to_radians())
            * (Vec3::Z - up * Vec3::Z.dot(up)).normalize();
        let wall = Plane::from_point_normal(Vec3::Z * 3.0, facing);
        let depth: Vec<f32> = (0..w * h)
            .map(|i| {
                let ray = camera.unproject((i % w) as f32, (i / w) as f32, 1.0);
                let d = -wall.offset / wall.normal.dot(ray);
                let step = 2.85e-3 * d * d;
                if (0.5..8.0).contains(&d) {
                    (d / step).round() * step
                } else {
                    0.0
                }
            })
            .collect();
        let upright = |n: Vec3| n.dot(up).abs() <= 10f32.to_radians().sin();
        let mesh = depth_grid_mesh(&depth, &camera, &Affine3A::IDENTITY, 4);
        let (mut upright_area, mut area) = (0.0, 0.0);
        for t in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.triangle(t);
            let cross = (b - a).cross(c - a);
            area += 0.5 * cross.length();
            if cross.try_normalize().is_some_and(upright) {
                upright_area += 0.5 * cross.length();
            }
        }
        let triangles_upright = upright_area / area;
        let patches = depth_patches(&depth, &camera, &Affine3A::IDENTITY, 4, 8);
        assert!(patches.len() >= 250, "{} patches", patches.len());
        let patch_area: f32 = patches.iter().map(|p| p.2).sum();
        let patches_upright = patches
            .iter()
            .filter(|p| upright(p.1))
            .map(|p| p.2)
            .sum::<f32>()
            / patch_area;
        assert!(
            triangles_upright < 0.5 && patches_upright > 0.95,
            "upright: {triangles_upright} of the triangles' area, {patches_upright} of the patches'"
        );
        // The patches cover the wall: its area seen, within 20 %.
        assert!(
            (patch_area / area - 1.0).abs() < 0.2,
            "{patch_area} of {area} m2"
        );
    }

    #[test]
    fn a_depth_grid_mesh_does_not_bridge_a_depth_jump() {
        let camera = Pinhole {
            width: 8,
            height: 4,
            fx: 10.0,
            fy: 10.0,
            cx: 4.0,
            cy: 2.0,
        };
        // Left half at 1 m, right half at 2 m.
        let depth: Vec<f32> = (0..32).map(|i| if i % 8 < 4 { 1.0 } else { 2.0 }).collect();
        let mesh = depth_grid_mesh(&depth, &camera, &Affine3A::IDENTITY, 1);
        assert_eq!(mesh.positions.len(), 32);
        // 3 x 3 quads on each side, none across the jump.
        assert_eq!(mesh.triangles.len(), 2 * 2 * 9);
    }
}
