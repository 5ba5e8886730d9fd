//! How well a fused map agrees with depth frames it did not fuse: the map is raycast from each
//! held-out frame's pose and the first surface crossing is compared with the measured depth.

use glam::Affine3A;
use rayon::prelude::*;

use crate::geometry::Pinhole;
use crate::map::{TsdfMap, median};

/// |measured - raycast| statistics over the pixels where both exist.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct DepthAgreement {
    pub frames: usize,
    /// Pixels compared (both a measurement and a map surface along the ray).
    pub pixels: usize,
    /// Pixels with a measurement whose ray found no surface (unobserved space, or beyond range).
    pub misses: usize,
    pub median_m: f32,
    pub mean_m: f32,
    pub p90_m: f32,
}

/// Absolute depth differences of one frame, sampled every `pixel_step` pixels in both directions.
/// Pixels with no measurement or beyond the map's ray length are skipped; misses are counted.
pub fn depth_residuals(
    map: &TsdfMap,
    depth: &[f32],
    camera: &Pinhole,
    world_from_camera: &Affine3A,
    pixel_step: usize,
) -> (Vec<f32>, usize) {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let rows: Vec<(Vec<f32>, usize)> = (0..h)
        .into_par_iter()
        .step_by(pixel_step)
        .map(|v| {
            let mut residuals = Vec::new();
            let mut misses = 0;
            for u in (0..w).step_by(pixel_step) {
                let d = depth[v * w + u];
                if d <= 0.0 || d > map.max_ray_length {
                    continue;
                }
                match map.raycast_depth(camera, world_from_camera, u as f32, v as f32) {
                    Some(r) => residuals.push((d - r).abs()),
                    None => misses += 1,
                }
            }
            (residuals, misses)
        })
        .collect();
    let misses = rows.iter().map(|r| r.1).sum();
    (rows.into_iter().flat_map(|r| r.0).collect(), misses)
}

/// Summary of residuals pooled over `frames` frames.
pub fn summarise(mut residuals: Vec<f32>, misses: usize, frames: usize) -> DepthAgreement {
    if residuals.is_empty() {
        return DepthAgreement {
            frames,
            misses,
            ..DepthAgreement::default()
        };
    }
    let mean = residuals.iter().map(|&r| f64::from(r)).sum::<f64>() / residuals.len() as f64;
    let p90_index = (residuals.len() * 9 / 10).min(residuals.len() - 1);
    let p90 = *residuals
        .select_nth_unstable_by(p90_index, f32::total_cmp)
        .1;
    DepthAgreement {
        frames,
        pixels: residuals.len(),
        misses,
        median_m: median(&mut residuals),
        mean_m: mean as f32,
        p90_m: p90,
    }
}
