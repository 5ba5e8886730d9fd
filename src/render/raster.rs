//! Z-buffer rasterisation of a `RenderScene` into per-pixel depth and triangle index.
//!
//! Depth is the camera-frame z (what depth cameras store), sampled at integer pixel coordinates
//! (pixel centres in OpenCV's convention) by interpolating 1/z, which is exact for planar triangles.

use glam::{Affine3A, Vec3};

use crate::geometry::Pinhole;
use crate::render::RenderScene;

/// Geometry closer than this to the camera centre (metres) is clipped away.
pub const NEAR: f32 = 0.05;

/// No triangle at this pixel.
pub const NO_TRIANGLE: u32 = u32::MAX;

pub struct RasterFrame {
    pub camera: Pinhole,
    /// Camera-frame z in metres; 0 where nothing was hit.
    pub depth: Vec<f32>,
    /// Index into the scene's triangles, or `NO_TRIANGLE`.
    pub triangle: Vec<u32>,
}

/// Renders `scene` seen from `camera_from_world`.
pub fn rasterize(
    scene: &RenderScene,
    camera: &Pinhole,
    camera_from_world: &Affine3A,
) -> RasterFrame {
    let n = camera.pixel_count();
    let mut depth = vec![f32::INFINITY; n];
    let mut triangle = vec![NO_TRIANGLE; n];
    for (t, corners) in scene.corners.iter().enumerate() {
        let c = corners.map(|p| camera_from_world.transform_point3(p));
        // Back faces of closed meshes and the outside of the room's walls are never visible.
        let normal = camera_from_world.transform_vector3(scene.normals[t]);
        if normal.dot(c[0]) >= 0.0 {
            continue;
        }
        if c.iter().all(|p| p.z < NEAR) {
            continue;
        }
        let mut polygon = [Vec3::ZERO; 4];
        let count = clip_near(&c, &mut polygon);
        for k in 1..count.saturating_sub(1) {
            draw(
                camera,
                [polygon[0], polygon[k], polygon[k + 1]],
                t as u32,
                &mut depth,
                &mut triangle,
            );
        }
    }
    for d in &mut depth {
        if !d.is_finite() {
            *d = 0.0;
        }
    }
    RasterFrame {
        camera: *camera,
        depth,
        triangle,
    }
}

/// Clips triangle `c` against the plane z = NEAR (Sutherland-Hodgman); returns the vertex count.
fn clip_near(c: &[Vec3; 3], out: &mut [Vec3; 4]) -> usize {
    let mut count = 0;
    for i in 0..3 {
        let a = c[i];
        let b = c[(i + 1) % 3];
        let a_in = a.z >= NEAR;
        let b_in = b.z >= NEAR;
        if a_in {
            out[count] = a;
            count += 1;
        }
        if a_in != b_in && count < 4 {
            let s = (NEAR - a.z) / (b.z - a.z);
            out[count] = a + (b - a) * s;
            count += 1;
        }
    }
    count
}

fn draw(camera: &Pinhole, tri: [Vec3; 3], index: u32, depth: &mut [f32], triangle: &mut [u32]) {
    let p = tri.map(|v| camera.project(v));
    let inv_z = tri.map(|v| 1.0 / v.z);
    let edge = |a: glam::Vec2, b: glam::Vec2, x: f32, y: f32| {
        (b.x - a.x) * (y - a.y) - (b.y - a.y) * (x - a.x)
    };
    let area = edge(p[0], p[1], p[2].x, p[2].y);
    if area.abs() < 1e-9 {
        return;
    }
    let (w, h) = (camera.width as i64, camera.height as i64);
    let min_x = (p[0].x.min(p[1].x).min(p[2].x).ceil() as i64).max(0);
    let max_x = (p[0].x.max(p[1].x).max(p[2].x).floor() as i64).min(w - 1);
    let min_y = (p[0].y.min(p[1].y).min(p[2].y).ceil() as i64).max(0);
    let max_y = (p[0].y.max(p[1].y).max(p[2].y).floor() as i64).min(h - 1);
    if min_x > max_x || min_y > max_y {
        return;
    }
    let inv_area = 1.0 / area;
    // Edge functions are affine in x: step them along each row instead of re-evaluating.
    let (dx0, dx1, dx2) = (
        -(p[2].y - p[1].y) * inv_area,
        -(p[0].y - p[2].y) * inv_area,
        -(p[1].y - p[0].y) * inv_area,
    );
    for y in min_y..=max_y {
        let fy = y as f32;
        let fx = min_x as f32;
        let mut b0 = edge(p[1], p[2], fx, fy) * inv_area;
        let mut b1 = edge(p[2], p[0], fx, fy) * inv_area;
        let mut b2 = edge(p[0], p[1], fx, fy) * inv_area;
        let row = (y * w) as usize;
        for x in min_x..=max_x {
            if b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0 {
                let z = 1.0 / (b0 * inv_z[0] + b1 * inv_z[1] + b2 * inv_z[2]);
                let i = row + x as usize;
                if z < depth[i] {
                    depth[i] = z;
                    triangle[i] = index;
                }
            }
            b0 += dx0;
            b1 += dx1;
            b2 += dx2;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;

    fn wall_scene(z: f32) -> RenderScene {
        // A large quad facing the camera (normal -z) at depth z.
        let mesh = TriMesh {
            positions: vec![
                Vec3::new(-10.0, -10.0, z),
                Vec3::new(-10.0, 10.0, z),
                Vec3::new(10.0, 10.0, z),
                Vec3::new(10.0, -10.0, z),
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
        };
        let mut scene = RenderScene::default();
        for i in 0..2 {
            scene.corners.push(mesh.triangle(i));
            scene.normals.push(mesh.face_normal(i));
            scene.instances.push(1);
            scene.colors.push([1.0; 3]);
            scene
                .surfaces
                .push(crate::render::render_scene::Surface::Plain);
        }
        scene
    }

    #[test]
    fn a_fronto_parallel_wall_fills_the_image_at_its_depth() {
        let scene = wall_scene(2.0);
        assert!(scene.normals[0].z < 0.0, "the quad must face the camera");
        let frame = rasterize(&scene, &Pinhole::KINECT, &Affine3A::IDENTITY);
        assert!(
            frame.depth.iter().all(|d| (d - 2.0).abs() < 1e-5),
            "every pixel at 2 m"
        );
        assert!(frame.triangle.iter().all(|&t| t != NO_TRIANGLE));
    }

    #[test]
    fn a_wall_behind_the_camera_is_not_drawn() {
        let frame = rasterize(&wall_scene(-2.0), &Pinhole::KINECT, &Affine3A::IDENTITY);
        assert!(frame.depth.iter().all(|&d| d == 0.0));
    }
}
