//! Colour of a rendered pixel: Lambertian shading of the triangle's base colour under a ceiling
//! light and a head light, in sRGB.

use glam::{Affine3A, Vec3};

use crate::render::raster::{NO_TRIANGLE, RasterFrame};
use crate::render::render_scene::{RenderScene, Surface};

const AMBIENT: f32 = 0.35;
const SUN: f32 = 0.45;
const HEADLIGHT: f32 = 0.3;

fn to_srgb(linear: f32) -> u8 {
    let c = linear.clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

/// Row-major RGB of the frame.
pub fn shade(scene: &RenderScene, frame: &RasterFrame, world_from_camera: &Affine3A) -> Vec<u8> {
    let light = Vec3::new(0.3, 0.2, 1.0).normalize();
    let eye = Vec3::from(world_from_camera.translation);
    let w = frame.camera.width as usize;
    let mut rgb = vec![0u8; frame.depth.len() * 3];
    for (i, &t) in frame.triangle.iter().enumerate() {
        if t == NO_TRIANGLE {
            continue;
        }
        let t = t as usize;
        let (u, v) = ((i % w) as f32, (i / w) as f32);
        let point =
            world_from_camera.transform_point3(frame.camera.unproject(u, v, frame.depth[i]));
        let normal = scene.normals[t];
        let view = (eye - point).normalize_or_zero();
        let lit =
            AMBIENT + SUN * normal.dot(light).max(0.0) + HEADLIGHT * normal.dot(view).max(0.0);
        let mut base = scene.colors[t];
        if scene.surfaces[t] == Surface::FloorTiles
            && ((point.x * 2.0).floor() as i64 + (point.y * 2.0).floor() as i64) % 2 == 0
        {
            base = base.map(|c| c * 0.8);
        }
        for c in 0..3 {
            rgb[3 * i + c] = to_srgb(base[c] * lit);
        }
    }
    rgb
}
