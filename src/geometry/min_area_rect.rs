//! The minimum-area rectangle around points in the plane: convex hull (Andrew's monotone chain),
//! then rotating calipers, since the optimal rectangle has a side on a hull edge (Freeman and
//! Shapira 1975).

use glam::Vec2;

/// A rectangle turned by `angle` (radians, its first side's direction from the x axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect2 {
    pub center: Vec2,
    pub angle: f32,
    /// Full side lengths along the rectangle's own axes.
    pub size: Vec2,
}

impl Rect2 {
    pub fn area(&self) -> f32 {
        self.size.x * self.size.y
    }
}

/// The convex hull of `points`, counter-clockwise, without collinear points; fewer than three
/// points come back as they are (deduplicated).
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let finite: Vec<Vec2> = points.iter().copied().filter(|p| p.is_finite()).collect();
    monotone_chain(outside_extreme_octagon(&finite))
}

/// Andrew's monotone chain over `points` (finite).
fn monotone_chain(mut sorted: Vec<Vec2>) -> Vec<Vec2> {
    // Equal points are interchangeable, so an unstable sort gives the same hull.
    sorted.sort_unstable_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    sorted.dedup();
    if sorted.len() < 3 {
        return sorted;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * sorted.len());
    for pass in [
        &sorted[..],
        &sorted.iter().rev().copied().collect::<Vec<_>>()[..],
    ] {
        let start = hull.len();
        for &p in pass {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        // The last point of each chain is the first of the next.
        hull.pop();
    }
    hull
}

/// Akl and Toussaint's pre-filter: the points extreme in eight directions span a convex octagon,
/// and no point strictly inside it can be a hull vertex. On an entity's surface points that
/// leaves a few percent of them for the sort.
fn outside_extreme_octagon(points: &[Vec2]) -> Vec<Vec2> {
    let Some(&first) = points.first() else {
        return Vec::new();
    };
    // Directions counter-clockwise from +x in 45-degree steps: their extreme points come in
    // counter-clockwise order along the hull.
    let directions = [
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
        Vec2::new(-1.0, 1.0),
        Vec2::new(-1.0, 0.0),
        Vec2::new(-1.0, -1.0),
        Vec2::new(0.0, -1.0),
        Vec2::new(1.0, -1.0),
    ];
    let mut extreme = [first; 8];
    for &p in points {
        for (e, d) in extreme.iter_mut().zip(directions) {
            if p.dot(d) > e.dot(d) {
                *e = p;
            }
        }
    }
    let strictly_inside = |p: Vec2| {
        (0..8).all(|k| {
            let (a, b) = (extreme[k], extreme[(k + 1) % 8]);
            (b - a).perp_dot(p - a) > 0.0
        })
    };
    points
        .iter()
        .copied()
        .filter(|&p| !strictly_inside(p))
        .collect()
}

/// The smallest-area rectangle containing `points`; `None` without a finite point. Degenerate
/// input (one point, collinear points) gives a rectangle of zero width.
pub fn min_area_rect(points: &[Vec2]) -> Option<Rect2> {
    let hull = convex_hull(points);
    match hull.len() {
        0 => return None,
        1 => {
            return Some(Rect2 {
                center: hull[0],
                angle: 0.0,
                size: Vec2::ZERO,
            });
        }
        _ => {}
    }
    let mut best: Option<Rect2> = None;
    for i in 0..hull.len() {
        let edge = hull[(i + 1) % hull.len()] - hull[i];
        let Some(axis) = edge.try_normalize() else {
            continue;
        };
        let normal = axis.perp();
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for p in &hull {
            let local = Vec2::new(p.dot(axis), p.dot(normal));
            lo = lo.min(local);
            hi = hi.max(local);
        }
        let size = hi - lo;
        let area = size.x * size.y;
        // Ties (a square hull, every edge of a rectangle) keep the first edge: deterministic.
        if best.is_none_or(|b| area < b.area() - 1e-9) {
            let mid = (lo + hi) * 0.5;
            best = Some(Rect2 {
                center: axis * mid.x + normal * mid.y,
                angle: axis.y.atan2(axis.x),
                size,
            });
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn inside(r: &Rect2, p: Vec2, margin: f32) -> bool {
        let axis = Vec2::from_angle(r.angle);
        let d = p - r.center;
        let local = Vec2::new(d.dot(axis), d.dot(axis.perp()));
        local.x.abs() <= 0.5 * r.size.x + margin && local.y.abs() <= 0.5 * r.size.y + margin
    }

    #[test]
    fn the_hull_of_a_square_with_inner_points_is_its_corners() {
        let mut points = vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
            Vec2::new(0.5, 0.5),
            Vec2::new(0.5, 0.0),
        ];
        points.extend((0..10).map(|i| Vec2::new(0.1 * i as f32, 0.3)));
        let hull = convex_hull(&points);
        assert_eq!(hull.len(), 4);
        let area: f32 = (0..4)
            .map(|i| hull[i].perp_dot(hull[(i + 1) % 4]))
            .sum::<f32>()
            * 0.5;
        assert!((area - 1.0).abs() < 1e-6, "counter-clockwise, area {area}");
    }

    #[test]
    fn degenerate_input_gives_a_flat_rectangle_or_none() {
        assert_eq!(min_area_rect(&[]), None);
        assert_eq!(min_area_rect(&[Vec2::NAN]), None);
        let line: Vec<Vec2> = (0..5)
            .map(|i| Vec2::new(i as f32, 2.0 * i as f32))
            .collect();
        let r = min_area_rect(&line).expect("a line");
        assert!(r.area().abs() < 1e-5);
        assert!((r.size.max_element() - 80f32.sqrt()).abs() < 1e-4);
    }

    proptest! {
        /// The octagon pre-filter never changes the hull, clustered or spread points alike.
        #[test]
        fn the_prefilter_keeps_the_hull(
            points in proptest::collection::vec((-2.0f32..2.0, -2.0f32..2.0), 0..200),
            snap in prop_oneof![Just(0.0f32), Just(0.25f32)],
        ) {
            // Snapping to a coarse grid makes ties, collinear and duplicate points.
            let points: Vec<Vec2> = points
                .into_iter()
                .map(|(x, y)| if snap > 0.0 {
                    (Vec2::new(x, y) / snap).round() * snap
                } else {
                    Vec2::new(x, y)
                })
                .collect();
            prop_assert_eq!(convex_hull(&points), monotone_chain(points.clone()));
        }

        /// A turned rectangle sampled on its boundary and inside is recovered exactly, and the
        /// answer contains every point.
        #[test]
        fn a_sampled_rectangle_is_recovered(
            cx in -5.0f32..5.0, cy in -5.0f32..5.0, sx in 0.1f32..3.0, sy in 0.1f32..3.0,
            angle in -3.1f32..3.1, seed in 0u32..1000,
        ) {
            let axis = Vec2::from_angle(angle);
            let at = |u: f32, v: f32| Vec2::new(cx, cy) + axis * (u * sx) + axis.perp() * (v * sy);
            let mut points: Vec<Vec2> = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
                .iter().map(|&(u, v)| at(u, v)).collect();
            let mut s = seed;
            for _ in 0..30 {
                s = s.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                let u = (s >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
                s = s.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                let v = (s >> 8) as f32 / (1u32 << 24) as f32 - 0.5;
                points.push(at(u, v));
            }
            let r = min_area_rect(&points).expect("rectangle");
            prop_assert!((r.area() - sx * sy).abs() < 1e-3 * (1.0 + sx * sy));
            prop_assert!((r.center - Vec2::new(cx, cy)).length() < 1e-3);
            for p in &points {
                prop_assert!(inside(&r, *p, 1e-3));
            }
        }
    }
}
