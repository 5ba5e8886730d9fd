//! Trimming the sparse ends of an object's footprint. A map's labels bleed along surfaces that
//! run on past an object into its neighbour (a counter top over a row of cabinets, a toe kick):
//! a strip of the neighbour's surface comes with the object, connected to it, and stretches its
//! box into the neighbour's. Such a strip holds a small fraction of the points the object holds
//! per unit of length; the object's own extent does not.

use glam::{Vec2, Vec3};

/// Sparse ends shorter than this many bins are kept.
const MIN_STRIP_BINS: usize = 2;

/// Which points to keep: along each of the two floor axes at `yaw` (radians), all the points are
/// counted in bins `bin` metres wide, and the runs of bins at either end holding fewer than
/// `share` of the lower median count of the non-empty bins are cut off when they are at least
/// `MIN_STRIP_BINS` long. The median adapts to the object: where sparse bins are most of its
/// length (a monitor's stand behind its screen), nothing is cut.
pub fn keep_dense_extent(points: &[Vec3], yaw: f32, bin: f32, share: f32) -> Vec<bool> {
    let (s, c) = yaw.sin_cos();
    let mut keep = vec![true; points.len()];
    for axis in [Vec2::new(c, s), Vec2::new(-s, c)] {
        let along: Vec<f32> = points.iter().map(|p| p.truncate().dot(axis)).collect();
        let Some(lo) = along.iter().copied().reduce(f32::min) else {
            return keep;
        };
        let index = |t: f32| ((t - lo) / bin) as usize;
        let mut counts = vec![0usize; along.iter().map(|&t| index(t)).max().unwrap_or(0) + 1];
        for &t in &along {
            counts[index(t)] += 1;
        }
        let mut occupied: Vec<usize> = counts.iter().copied().filter(|&n| n > 0).collect();
        occupied.sort_unstable();
        // The lower median: two bins (a flat front's depth spread by noise) never cut one.
        let least = share * occupied[(occupied.len() - 1) / 2] as f32;
        let dense = |n: &usize| *n as f32 >= least;
        let (Some(mut first), Some(mut last)) = (
            counts.iter().position(dense),
            counts.iter().rposition(dense),
        ) else {
            continue;
        };
        // One sparse bin at an end is the edge's own (a top's last row in the crease with the
        // wall behind it, half of it claimed by the wall): strips are longer.
        if first < MIN_STRIP_BINS {
            first = 0;
        }
        if counts.len() - 1 - last < MIN_STRIP_BINS {
            last = counts.len() - 1;
        }
        for (k, &t) in keep.iter_mut().zip(&along) {
            *k &= (first..=last).contains(&index(t));
        }
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cabinet front 60 cm wide and 88 cm high sampled every 2 cm, with a strip of its
    /// neighbour's top (40 cm long, one row of samples) bled onto it at its right top edge.
    fn front_with_strip(yaw: f32) -> Vec<Vec3> {
        let turn = glam::Quat::from_rotation_z(yaw);
        let mut points = Vec::new();
        for i in 0..30 {
            for k in 0..44 {
                points.push(Vec3::new(
                    0.01 + 0.02 * i as f32,
                    0.0,
                    0.01 + 0.02 * k as f32,
                ));
            }
        }
        for i in 0..20 {
            points.push(Vec3::new(0.61 + 0.02 * i as f32, 0.05, 0.88));
        }
        points.into_iter().map(|p| turn * p).collect()
    }

    #[test]
    fn a_bled_strip_is_cut_and_the_front_is_kept_whole() {
        for yaw in [0.0f32, 0.7] {
            let points = front_with_strip(yaw);
            let keep = keep_dense_extent(&points, yaw, 0.02, 0.2);
            assert!(keep[..30 * 44].iter().all(|&k| k), "the front is kept");
            assert!(keep[30 * 44..].iter().all(|&k| !k), "the strip is cut");
        }
    }

    #[test]
    fn a_stand_behind_a_screen_is_kept() {
        // A screen (dense, one bin deep) and its stand reaching 20 cm behind it, sparse but most
        // of the depth: nothing is cut.
        let mut points = Vec::new();
        for i in 0..30 {
            for k in 0..20 {
                points.push(Vec3::new(0.02 * i as f32, 0.0, 0.3 + 0.02 * k as f32));
            }
        }
        for j in 1..10 {
            for k in 0..3 {
                points.push(Vec3::new(0.3, 0.02 * j as f32, 0.02 * k as f32));
            }
        }
        assert!(
            keep_dense_extent(&points, 0.0, 0.02, 0.2)
                .iter()
                .all(|&k| k)
        );
    }
}
