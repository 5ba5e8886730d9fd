//! Colour of a rendered pixel: Lambertian shading of the triangle's base colour under a ceiling
//! light and a head light, in sRGB.

use glam::{Affine3A, Vec3};

use crate::render::raster::{NO_TRIANGLE, RasterFrame};
use crate::render::render_scene::{RenderScene, Surface};

const AMBIENT: f32 = 0.35;
const SUN: f32 = 0.45;
const HEADLIGHT: f32 = 0.3;

/// Entries of the linear-to-sRGB table: finer than 8-bit output needs near black.
const SRGB_STEPS: usize = 4096;

/// Linear 0..1 to 8-bit sRGB as a table (`powf` per channel per pixel cost more than the rest of
/// shading); fetch it once per frame, index it per pixel with `srgb`.
fn srgb_table() -> &'static [u8] {
    static TABLE: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        (0..=SRGB_STEPS)
            .map(|i| {
                let c = i as f32 / SRGB_STEPS as f32;
                let s = if c <= 0.003_130_8 {
                    12.92 * c
                } else {
                    1.055 * c.powf(1.0 / 2.4) - 0.055
                };
                (s * 255.0).round() as u8
            })
            .collect()
    })
}

fn srgb(table: &[u8], linear: f32) -> u8 {
    table
        .get((linear.clamp(0.0, 1.0) * SRGB_STEPS as f32) as usize)
        .copied()
        .unwrap_or(u8::MAX)
}

/// Row-major RGB of the frame.
pub fn shade(scene: &RenderScene, frame: &RasterFrame, world_from_camera: &Affine3A) -> Vec<u8> {
    let light = Vec3::new(0.3, 0.2, 1.0).normalize();
    let eye = Vec3::from(world_from_camera.translation);
    let camera = &frame.camera;
    let (w, h) = (camera.width as usize, camera.height as usize);
    // The world-space ray through pixel (u, v) at unit depth is column[u] + row[v]: both parts are
    // tabulated once per frame instead of unprojecting every pixel.
    let axes = world_from_camera.matrix3;
    let column: Vec<Vec3> = (0..w)
        .map(|u| Vec3::from(axes.x_axis) * ((u as f32 - camera.cx) / camera.fx))
        .collect();
    let row: Vec<Vec3> = (0..h)
        .map(|v| {
            Vec3::from(axes.y_axis) * ((v as f32 - camera.cy) / camera.fy) + Vec3::from(axes.z_axis)
        })
        .collect();
    let table = srgb_table();
    let mut rgb = vec![0u8; w * h * 3];
    for (v, (pixels, triangles)) in rgb
        .chunks_exact_mut(3 * w)
        .zip(frame.triangle.chunks_exact(w))
        .enumerate()
    {
        let depths = &frame.depth[v * w..(v + 1) * w];
        for (u, (&t, px)) in triangles.iter().zip(pixels.chunks_exact_mut(3)).enumerate() {
            if t == NO_TRIANGLE {
                continue;
            }
            let t = t as usize;
            let ray = column[u] + row[v];
            let normal = scene.normals[t];
            let towards_eye = -ray.normalize_or_zero();
            let lit = AMBIENT
                + SUN * normal.dot(light).max(0.0)
                + HEADLIGHT * normal.dot(towards_eye).max(0.0);
            let mut base = scene.colors[t];
            if scene.surfaces[t] == Surface::FloorTiles {
                let point = eye + ray * depths[u];
                if ((point.x * 2.0).floor() as i64 + (point.y * 2.0).floor() as i64) % 2 == 0 {
                    base = base.map(|c| c * 0.8);
                }
            }
            for (out, c) in px.iter_mut().zip(base) {
                *out = srgb(table, c * lit);
            }
        }
    }
    rgb
}
