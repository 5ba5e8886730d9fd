//! Surface planes of a point set by iterative RANSAC: find the plane with the most inliers, refit
//! it to them by least squares, remove them, repeat.

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::geometry::min_area_rect::min_area_rect;
use crate::geometry::plane::{Plane, fit_plane};

#[derive(Clone, Copy, Debug)]
pub struct RansacParams {
    /// A point this close to a plane (metres) is its inlier.
    pub inlier_distance: f32,
    /// Planes with fewer inliers are not reported, and the search stops at the first one.
    pub min_inliers: usize,
    pub max_planes: usize,
    /// Candidate planes tried per plane found.
    pub iterations: usize,
    /// Candidates are scored on at most this many points (the rest only count for the winner).
    pub score_sample: usize,
    pub seed: u64,
}

impl Default for RansacParams {
    fn default() -> Self {
        Self {
            inlier_distance: 0.02,
            min_inliers: 30,
            max_planes: 8,
            iterations: 150,
            score_sample: 600,
            seed: 0x5eed,
        }
    }
}

/// A plane found in the points, with what supports it.
#[derive(Clone, Debug, PartialEq)]
pub struct DetectedPlane {
    pub plane: Plane,
    /// Indices of its inliers in the input.
    pub inliers: Vec<u32>,
    /// Area of the smallest rectangle around the inliers in the plane (square metres).
    pub extent: f32,
}

/// Planes of `points`, most inliers first. Deterministic for a given `params.seed`.
pub fn ransac_planes(points: &[Vec3], params: &RansacParams) -> Vec<DetectedPlane> {
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut remaining: Vec<u32> = (0..points.len() as u32)
        .filter(|&i| points[i as usize].is_finite())
        .collect();
    let mut planes = Vec::new();
    let min_inliers = params.min_inliers.max(3);
    while planes.len() < params.max_planes && remaining.len() >= min_inliers {
        let Some(candidate) = best_candidate(points, &remaining, params, &mut rng) else {
            break;
        };
        let near = |plane: &Plane, i: &u32| {
            plane.signed_distance(points[*i as usize]).abs() <= params.inlier_distance
        };
        let inliers: Vec<u32> = remaining
            .iter()
            .copied()
            .filter(|i| near(&candidate, i))
            .collect();
        // Least squares on the inliers, then the inliers of the refined plane.
        let inlier_points: Vec<Vec3> = inliers.iter().map(|&i| points[i as usize]).collect();
        let plane = fit_plane(&inlier_points).unwrap_or(candidate);
        let inliers: Vec<u32> = remaining
            .iter()
            .copied()
            .filter(|i| near(&plane, i))
            .collect();
        if inliers.len() < min_inliers {
            break;
        }
        remaining.retain(|i| !near(&plane, i));
        let extent = extent_in_plane(&plane, inliers.iter().map(|&i| points[i as usize]));
        planes.push(DetectedPlane {
            plane,
            inliers,
            extent,
        });
    }
    planes.sort_by_key(|p| std::cmp::Reverse(p.inliers.len()));
    planes
}

/// The candidate through three random remaining points with the most inliers on a sample.
fn best_candidate(
    points: &[Vec3],
    remaining: &[u32],
    params: &RansacParams,
    rng: &mut ChaCha8Rng,
) -> Option<Plane> {
    let pick =
        |rng: &mut ChaCha8Rng| points[remaining[rng.random_range(0..remaining.len())] as usize];
    let sample: Vec<Vec3> = if remaining.len() <= params.score_sample {
        remaining.iter().map(|&i| points[i as usize]).collect()
    } else {
        (0..params.score_sample).map(|_| pick(rng)).collect()
    };
    let mut best: Option<(usize, Plane)> = None;
    for _ in 0..params.iterations {
        let (a, b, c) = (pick(rng), pick(rng), pick(rng));
        let normal = (b - a).cross(c - a);
        // Nearly collinear triples give no reliable normal.
        if normal.length_squared() < 1e-10 {
            continue;
        }
        let plane = Plane::from_point_normal(a, normal);
        let score = sample
            .iter()
            .filter(|p| plane.signed_distance(**p).abs() <= params.inlier_distance)
            .count();
        if best.as_ref().is_none_or(|(s, _)| score > *s) {
            best = Some((score, plane));
        }
    }
    best.map(|(_, plane)| plane)
}

/// Area of the smallest rectangle, in the plane, around `points` projected onto it.
pub fn extent_in_plane(plane: &Plane, points: impl Iterator<Item = Vec3>) -> f32 {
    let (u, v) = plane.normal.any_orthonormal_pair();
    let flat: Vec<Vec2> = points.map(|p| Vec2::new(p.dot(u), p.dot(v))).collect();
    min_area_rect(&flat).map_or(0.0, |r| r.area())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on the five visible faces of a box (no bottom), 1 cm apart, with +-3 mm noise.
    fn open_box(size: Vec3) -> Vec<Vec3> {
        let mut points = Vec::new();
        let mut s = 7u32;
        let mut noise = || {
            s = s.wrapping_mul(1_103_515_245).wrapping_add(12_345);
            0.003 * ((s >> 8) as f32 / (1u32 << 24) as f32 * 2.0 - 1.0)
        };
        let step = 0.01;
        let n = |l: f32| (l / step) as usize;
        for i in 0..=n(size.x) {
            for j in 0..=n(size.y) {
                points.push(Vec3::new(
                    i as f32 * step,
                    j as f32 * step,
                    size.z + noise(),
                ));
            }
        }
        for i in 0..=n(size.x) {
            for k in 0..n(size.z) {
                points.push(Vec3::new(i as f32 * step, noise(), k as f32 * step));
                points.push(Vec3::new(
                    i as f32 * step,
                    size.y + noise(),
                    k as f32 * step,
                ));
            }
        }
        for j in 0..=n(size.y) {
            for k in 0..n(size.z) {
                points.push(Vec3::new(noise(), j as f32 * step, k as f32 * step));
                points.push(Vec3::new(
                    size.x + noise(),
                    j as f32 * step,
                    k as f32 * step,
                ));
            }
        }
        points
    }

    #[test]
    fn the_faces_of_a_noisy_box_are_found_with_their_extents() {
        let size = Vec3::new(0.8, 0.5, 0.3);
        let points = open_box(size);
        let planes = ransac_planes(&points, &RansacParams::default());
        assert_eq!(
            planes.len(),
            5,
            "{:?}",
            planes.iter().map(|p| p.plane).collect::<Vec<_>>()
        );
        let top = &planes[0];
        assert!(
            top.plane.normal.z.abs() > 0.999,
            "largest face first: the top"
        );
        assert!((top.plane.signed_distance(Vec3::new(0.4, 0.25, size.z))).abs() < 0.002);
        assert!(
            (top.extent - size.x * size.y).abs() < 0.02,
            "extent {}",
            top.extent
        );
        for p in &planes[1..] {
            assert!(p.plane.normal.z.abs() < 0.01, "sides are vertical");
        }
        let total: usize = planes.iter().map(|p| p.inliers.len()).sum();
        assert!(total as f32 > 0.97 * points.len() as f32);
    }

    #[test]
    fn the_same_seed_gives_the_same_planes_and_scattered_points_give_none() {
        let points = open_box(Vec3::new(0.4, 0.3, 0.2));
        let params = RansacParams::default();
        assert_eq!(
            ransac_planes(&points, &params),
            ransac_planes(&points, &params)
        );
        let mut s = 1u32;
        let scattered: Vec<Vec3> = (0..200)
            .map(|_| {
                let mut r = || {
                    s = s.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                    (s >> 8) as f32 / (1u32 << 24) as f32
                };
                Vec3::new(r(), r(), r())
            })
            .collect();
        assert!(ransac_planes(&scattered, &params).is_empty());
    }
}
