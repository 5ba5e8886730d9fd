//! How precise a depth image is, measured from the image itself: its noise as a multiple of the
//! Kinect-class curve (`free_space::axial_sigma`). Under a pinhole camera the inverse depth of a
//! plane is affine in the pixel coordinates, so its second difference along a row is zero on
//! every plane and small on any smooth surface; what remains is the sensor's noise. A high
//! quantile over the frame, not the median: a real Kinect's depth comes in disparity steps, flat
//! between them, and 7-Scenes' measured a median of zero (its 90th percentile reads 0.85 of the
//! curve, noise-free renderings 0.03, the renderer's Kinect model 1.04). Triples three pixels
//! apart straddle more steps; those across a depth edge are left out.

use crate::map::free_space::axial_sigma;

/// Neighbours further apart in depth than this share of it are across an edge, not on a surface.
const SAME_SURFACE_SHARE: f32 = 0.05;
/// Pixels between the three depths of a second difference.
const SPAN: usize = 3;
/// The quantile of |second difference| / curve taken, and that quantile of |N(0, 1)|.
const QUANTILE: f32 = 0.9;
const QUANTILE_ABS_NORMAL: f32 = 1.6449;

/// The depth noise of a row-major `width`-pixel image relative to `axial_sigma` (about 1 for a
/// Kinect-class sensor, about 0 for noise-free depth), from triples of valid neighbours every
/// `stride` pixels in both directions; `None` when no row holds such a triple.
pub fn noise_scale(depth: &[f32], width: usize, stride: usize) -> Option<f32> {
    let stride = stride.max(1);
    let mut ratios = Vec::new();
    for row in depth.chunks_exact(width.max(1)).step_by(stride) {
        for u in (SPAN..width.saturating_sub(SPAN)).step_by(stride) {
            let (a, b, c) = (row[u - SPAN], row[u], row[u + SPAN]);
            if a <= 0.0 || b <= 0.0 || c <= 0.0 {
                continue;
            }
            if (a - b).abs() > SAME_SURFACE_SHARE * b || (c - b).abs() > SAME_SURFACE_SHARE * b {
                continue;
            }
            // Three independent errors of sigma in depth give a second difference of inverse
            // depth of sigma * sqrt(6) / b^2.
            let second = (1.0 / a - 2.0 / b + 1.0 / c) * b * b / 6f32.sqrt();
            ratios.push(second.abs() / axial_sigma(b));
        }
    }
    if ratios.is_empty() {
        return None;
    }
    let k = ((ratios.len() - 1) as f32 * QUANTILE) as usize;
    Some(*ratios.select_nth_unstable_by(k, f32::total_cmp).1 / QUANTILE_ABS_NORMAL)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Pinhole;
    use rand::{Rng, SeedableRng};
    use rand_distr::StandardNormal;

    /// The z-depth of a plane slanting away to the right and down, 1.5 to 3 m from the camera.
    fn slanted_plane(camera: &Pinhole) -> Vec<f32> {
        let (w, h) = (camera.width as usize, camera.height as usize);
        (0..w * h)
            .map(|i| {
                let (u, v) = ((i % w) as f32, (i / w) as f32);
                // Inverse depth affine in the pixel: a plane.
                1.0 / (0.65 - 0.0004 * u - 0.0003 * v)
            })
            .collect()
    }

    #[test]
    fn noise_free_depth_measures_near_zero_and_kinect_noise_near_one() {
        let camera = Pinhole::KINECT;
        let clean = slanted_plane(&camera);
        let w = camera.width as usize;
        let scale = noise_scale(&clean, w, 2).expect("a plane");
        assert!(scale < 0.01, "noise-free plane measured {scale}");
        // Millimetre steps (a 16-bit depth image) are far below the curve.
        let stored: Vec<f32> = clean
            .iter()
            .map(|d| (d * 1000.0).round() / 1000.0)
            .collect();
        let scale = noise_scale(&stored, w, 2).expect("a plane");
        assert!(scale < 0.1, "millimetre steps measured {scale}");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let noisy: Vec<f32> = clean
            .iter()
            .map(|&d| d + axial_sigma(d) * rng.sample::<f32, _>(StandardNormal))
            .collect();
        let scale = noise_scale(&noisy, w, 2).expect("a plane");
        assert!(
            (0.85..1.15).contains(&scale),
            "Kinect noise measured {scale}"
        );
        // Disparity steps without noise (1.3 cm at 2 m): flat between steps, yet no precise
        // depth.
        let unit = 525.0 * 0.075 * 8.0;
        let stepped: Vec<f32> = clean.iter().map(|d| unit / (unit / d).round()).collect();
        let scale = noise_scale(&stepped, w, 2).expect("a plane");
        assert!(scale > 0.4, "disparity steps measured {scale}");
    }

    #[test]
    fn depth_edges_and_holes_do_not_count() {
        let camera = Pinhole::KINECT;
        let w = camera.width as usize;
        // A clean plane cut by a step every 7 columns and a hole every 5: triples across them
        // are left out.
        let depth: Vec<f32> = slanted_plane(&camera)
            .iter()
            .enumerate()
            .map(|(i, &d)| match i % w {
                u if u % 5 == 0 => 0.0,
                u if (u / 7) % 2 == 1 => d + 0.5,
                _ => d,
            })
            .collect();
        let scale = noise_scale(&depth, w, 1).expect("a plane");
        assert!(scale < 0.01, "edges measured {scale}");
        assert_eq!(noise_scale(&[0.0; 12], 4, 1), None);
    }
}
