//! A child's bottom rectangle, and how much of it other things cover.

use glam::Vec2;

use crate::geometry::GravityBox;

/// The child's bottom rectangle, sampled on a grid to measure what covers it.
pub(super) struct Footprint {
    pub(super) bbox: GravityBox,
}

impl Footprint {
    pub(super) fn of(bbox: &GravityBox) -> Self {
        Self { bbox: *bbox }
    }

    pub(super) fn area(&self) -> f32 {
        self.bbox.size.x * self.bbox.size.y
    }

    pub(super) fn contains(&self, p: Vec2) -> bool {
        let l = self.local(p);
        l.x.abs() <= 0.5 * self.bbox.size.x && l.y.abs() <= 0.5 * self.bbox.size.y
    }

    pub(super) fn local(&self, p: Vec2) -> Vec2 {
        let axis = Vec2::from_angle(self.bbox.yaw);
        let d = p - self.bbox.center.truncate();
        Vec2::new(d.dot(axis), d.dot(axis.perp()))
    }

    /// Share of the footprint whose grid cells hold at least one of `points`.
    pub(super) fn covered_by(&self, points: impl Iterator<Item = Vec2>, cell: f32) -> f32 {
        let half = self.bbox.size.truncate() * 0.5;
        let cells = (self.bbox.size.truncate() / cell)
            .ceil()
            .max(Vec2::ONE)
            .as_uvec2();
        let mut hit = vec![false; (cells.x * cells.y) as usize];
        for p in points {
            let l = self.local(p) + half;
            if l.x < 0.0 || l.y < 0.0 || l.x >= self.bbox.size.x || l.y >= self.bbox.size.y {
                continue;
            }
            let (i, j) = ((l.x / cell) as u32, (l.y / cell) as u32);
            hit[(j.min(cells.y - 1) * cells.x + i.min(cells.x - 1)) as usize] = true;
        }
        let covered = hit.iter().filter(|h| **h).count() as f32 * cell * cell;
        (covered / self.area().max(1e-6)).min(1.0)
    }

    /// Share of the footprint inside `other`'s footprint, on an 8 x 8 sample grid.
    pub(super) fn overlap_with_box(&self, other: &GravityBox) -> f32 {
        const N: usize = 8;
        let axis = Vec2::from_angle(self.bbox.yaw);
        let other_axis = Vec2::from_angle(other.yaw);
        let mut inside = 0;
        for i in 0..N {
            for j in 0..N {
                let u = ((i as f32 + 0.5) / N as f32 - 0.5) * self.bbox.size.x;
                let v = ((j as f32 + 0.5) / N as f32 - 0.5) * self.bbox.size.y;
                let p = self.bbox.center.truncate() + axis * u + axis.perp() * v;
                let d = p - other.center.truncate();
                if d.dot(other_axis).abs() <= 0.5 * other.size.x
                    && d.dot(other_axis.perp()).abs() <= 0.5 * other.size.y
                {
                    inside += 1;
                }
            }
        }
        inside as f32 / (N * N) as f32
    }
}
