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

/// Sub-pixel precision of the rasteriser's fixed-point coordinates (8 bits).
const SUBPIXEL: f32 = 256.0;

/// Draws one triangle with exact integer edge functions and the top-left fill rule, so that
/// triangles sharing an edge leave no gap and cover no pixel twice.
fn draw(camera: &Pinhole, tri: [Vec3; 3], index: u32, depth: &mut [f32], triangle: &mut [u32]) {
    let projected = tri.map(|v| camera.project(v));
    let mut p = projected.map(|q| {
        (
            (q.x * SUBPIXEL).round() as i64,
            (q.y * SUBPIXEL).round() as i64,
        )
    });
    let mut inv_z = tri.map(|v| 1.0 / v.z);
    let edge = |a: (i64, i64), b: (i64, i64), x: i64, y: i64| {
        (b.0 - a.0) * (y - a.1) - (b.1 - a.1) * (x - a.0)
    };
    let mut area = edge(p[0], p[1], p[2].0, p[2].1);
    if area == 0 {
        return;
    }
    if area < 0 {
        // Work with one winding; which one the image shows does not matter here.
        p.swap(1, 2);
        inv_z.swap(1, 2);
        area = -area;
    }
    let (w, h) = (camera.width as i64, camera.height as i64);
    let s = SUBPIXEL as i64;
    let min_x = ((p[0].0.min(p[1].0).min(p[2].0) + s - 1).div_euclid(s)).max(0);
    let max_x = (p[0].0.max(p[1].0).max(p[2].0).div_euclid(s)).min(w - 1);
    let min_y = ((p[0].1.min(p[1].1).min(p[2].1) + s - 1).div_euclid(s)).max(0);
    let max_y = (p[0].1.max(p[1].1).max(p[2].1).div_euclid(s)).min(h - 1);
    if min_x > max_x || min_y > max_y {
        return;
    }
    // Top-left rule: a pixel exactly on an edge belongs to the triangle only for top or left edges.
    let bias = |a: (i64, i64), b: (i64, i64)| {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let top_left = (dy == 0 && dx < 0) || dy > 0;
        if top_left { 0 } else { -1 }
    };
    let edges = [(p[1], p[2]), (p[2], p[0]), (p[0], p[1])];
    let biases = edges.map(|(a, b)| bias(a, b));
    let steps = edges.map(|(a, b)| -(b.1 - a.1) * s);
    let inv_area = 1.0 / area as f64;
    for y in min_y..=max_y {
        let (fx, fy) = (min_x * s, y * s);
        let mut e = [0, 1, 2].map(|k| edge(edges[k].0, edges[k].1, fx, fy));
        let row = (y * w) as usize;
        for x in min_x..=max_x {
            if e[0] + biases[0] >= 0 && e[1] + biases[1] >= 0 && e[2] + biases[2] >= 0 {
                let inv = (e[0] as f64 * inv_z[0] as f64
                    + e[1] as f64 * inv_z[1] as f64
                    + e[2] as f64 * inv_z[2] as f64)
                    * inv_area;
                let z = (1.0 / inv) as f32;
                let i = row + x as usize;
                if z < depth[i] {
                    depth[i] = z;
                    triangle[i] = index;
                }
            }
            for k in 0..3 {
                e[k] += steps[k];
            }
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
