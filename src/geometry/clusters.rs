//! Euclidean clusters of points on a voxel grid: points whose cells touch (26-neighbourhood)
//! belong together. Used to drop the stray pieces a noisy segmentation leaves on an entity, and
//! to tell a front's handles apart.

use std::collections::HashMap;

use glam::{IVec3, Vec3};

/// Per point, whether it belongs to the largest cluster (most points) at grid resolution `cell`
/// metres; ties keep the cluster that starts first.
pub fn in_largest_cluster(points: &[Vec3], cell: f32) -> Vec<bool> {
    let roots = cluster_roots(points, cell);
    let mut count: HashMap<usize, usize> = HashMap::new();
    for r in roots.iter().flatten() {
        *count.entry(*r).or_default() += 1;
    }
    let best = count
        .iter()
        .max_by(|a, b| a.1.cmp(b.1).then(b.0.cmp(a.0)))
        .map(|(r, _)| *r);
    roots
        .into_iter()
        .map(|r| r.is_some() && r == best)
        .collect()
}

/// Per point, its cluster at grid resolution `cell` metres, named by the cluster's first cell in
/// the order of the points (`None` for a point that is not finite).
pub fn cluster_roots(points: &[Vec3], cell: f32) -> Vec<Option<usize>> {
    let key = |p: &Vec3| (*p / cell).floor().as_ivec3();
    let mut cells: HashMap<IVec3, usize> = HashMap::new();
    for p in points.iter().filter(|p| p.is_finite()) {
        let next = cells.len();
        cells.entry(key(p)).or_insert(next);
    }
    // Union-find over occupied cells.
    let mut parent: Vec<usize> = (0..cells.len()).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for (c, &i) in &cells {
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if let Some(&j) = cells.get(&(*c + IVec3::new(dx, dy, dz))) {
                        let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                        if a != b {
                            parent[a.max(b)] = a.min(b);
                        }
                    }
                }
            }
        }
    }
    points
        .iter()
        .map(|p| p.is_finite().then(|| find(&mut parent, cells[&key(p)])))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stray_blob_is_dropped_and_a_connected_shape_kept() {
        let mut points: Vec<Vec3> = (0..50)
            .map(|i| Vec3::new(i as f32 * 0.02, 0.0, 0.0))
            .collect();
        points.extend((0..10).map(|i| Vec3::new(3.0 + i as f32 * 0.02, 1.0, 0.0)));
        let keep = in_largest_cluster(&points, 0.05);
        assert_eq!(keep.iter().filter(|k| **k).count(), 50);
        assert!(points.iter().zip(&keep).all(|(p, k)| *k == (p.x < 1.0)));
        assert!(in_largest_cluster(&[], 0.05).is_empty());
    }
}
