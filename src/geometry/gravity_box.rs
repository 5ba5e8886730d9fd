//! Gravity-aligned oriented boxes: a centre, a yaw about +z and a size.

use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::geometry::Plane;
use crate::geometry::min_area_rect::min_area_rect;

/// A box whose z axis is the world's up axis. `size` is the full extent along the box's own axes;
/// `yaw` (radians) turns the box's x axis counter-clockwise from the world's x axis.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GravityBox {
    pub center: Vec3,
    pub yaw: f32,
    pub size: Vec3,
}

impl GravityBox {
    pub fn world_from_box(&self) -> Affine3A {
        Affine3A::from_rotation_translation(Quat::from_rotation_z(self.yaw), self.center)
    }

    /// The eight corners in world space; bit 0 picks +x, bit 1 +y, bit 2 +z.
    pub fn corners(&self) -> [Vec3; 8] {
        let world_from_box = self.world_from_box();
        let h = self.size * 0.5;
        std::array::from_fn(|i| {
            let local = Vec3::new(
                if i & 1 == 0 { -h.x } else { h.x },
                if i & 2 == 0 { -h.y } else { h.y },
                if i & 4 == 0 { -h.z } else { h.z },
            );
            world_from_box.transform_point3(local)
        })
    }

    pub fn bottom_z(&self) -> f32 {
        self.center.z - 0.5 * self.size.z
    }

    pub fn top_z(&self) -> f32 {
        self.center.z + 0.5 * self.size.z
    }

    pub fn volume(&self) -> f32 {
        self.size.x * self.size.y * self.size.z
    }

    /// Whether `point_in_world` is inside the box grown by `margin` on every side.
    pub fn contains(&self, point_in_world: Vec3, margin: f32) -> bool {
        let local = self
            .world_from_box()
            .inverse()
            .transform_point3(point_in_world);
        let h = self.size * 0.5 + Vec3::splat(margin);
        local.x.abs() <= h.x && local.y.abs() <= h.y && local.z.abs() <= h.z
    }

    /// The gravity-aligned box with yaw `yaw` that encloses `points_in_world` tightly.
    pub fn enclosing(points_in_world: &[Vec3], yaw: f32) -> Option<GravityBox> {
        let box_from_world = Quat::from_rotation_z(-yaw);
        let first = box_from_world * *points_in_world.first()?;
        let (lo, hi) = points_in_world
            .iter()
            .map(|p| box_from_world * *p)
            .fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let center_in_box = (lo + hi) * 0.5;
        Some(GravityBox {
            center: Quat::from_rotation_z(yaw) * center_in_box,
            yaw,
            size: hi - lo,
        })
    }

    /// The gravity-aligned box of least volume around `points_in_world`: the minimum-area
    /// rectangle of their footprint on the floor, z from their extremes. `None` without a finite
    /// point.
    pub fn minimal(points_in_world: &[Vec3]) -> Option<GravityBox> {
        let footprint: Vec<glam::Vec2> = points_in_world.iter().map(|p| p.truncate()).collect();
        let rect = min_area_rect(&footprint)?;
        let (lo, hi) = points_in_world
            .iter()
            .filter(|p| p.is_finite())
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.z), hi.max(p.z))
            });
        Some(GravityBox {
            center: rect.center.extend(0.5 * (lo + hi)),
            yaw: rect.angle,
            size: rect.size.extend(hi - lo),
        })
    }

    /// The box with its sides across `axis` (a box axis, 0 for x or 1 for y) drawn in to leave
    /// out the outermost `share` of `points` past each side: the surface the map bleeds past an
    /// object's side (a centimetre or two of label and depth noise at its edge) widens a box
    /// fitted to the extremes, where nearly all the side's points lie within half a centimetre.
    /// Only ever narrower; the box as it is with too few points.
    pub fn trimmed_along(&self, axis: usize, points: &[Vec3], share: f32) -> GravityBox {
        let box_from_world = self.world_from_box().inverse();
        let mut along: Vec<f32> = points
            .iter()
            .map(|p| box_from_world.transform_point3(*p)[axis])
            .filter(|u| u.is_finite())
            .collect();
        let skip = (share * along.len() as f32).floor() as usize;
        if skip == 0 || along.len() < 2 * skip + 2 {
            return *self;
        }
        along.sort_by(f32::total_cmp);
        let half = 0.5 * self.size[axis];
        let (lo, hi) = (
            along[skip].max(-half),
            along[along.len() - 1 - skip].min(half),
        );
        if hi <= lo {
            return *self;
        }
        let mut trimmed = *self;
        trimmed.size[axis] = hi - lo;
        let mut shift = Vec3::ZERO;
        shift[axis] = 0.5 * (lo + hi);
        trimmed.center = self.world_from_box().transform_point3(shift);
        trimmed
    }

    /// The footprint's corners, counter-clockwise.
    pub fn footprint(&self) -> [glam::Vec2; 4] {
        let axis = glam::Vec2::from_angle(self.yaw);
        let (u, v) = (axis * 0.5 * self.size.x, axis.perp() * 0.5 * self.size.y);
        let c = self.center.truncate();
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }

    /// Intersection over union of the two boxes' volumes: the footprints' intersection (convex
    /// polygon clipping) times the overlap of the z intervals.
    pub fn iou(&self, other: &GravityBox) -> f32 {
        let dz = self.top_z().min(other.top_z()) - self.bottom_z().max(other.bottom_z());
        if dz <= 0.0 {
            return 0.0;
        }
        let inter = polygon_area(&clip_convex(&self.footprint(), &other.footprint())) * dz;
        let union = self.volume() + other.volume() - inter;
        if union <= 0.0 {
            0.0
        } else {
            (inter / union).clamp(0.0, 1.0)
        }
    }

    /// Whether two boxes overlap once each is grown by `margin` (separating axes in the floor plane
    /// plus the z interval: both boxes share the z axis, so four axes decide).
    pub fn overlaps(&self, other: &GravityBox, margin: f32) -> bool {
        if self.bottom_z() - margin > other.top_z() || other.bottom_z() - margin > self.top_z() {
            return false;
        }
        let axes = |b: &GravityBox| {
            let (s, c) = b.yaw.sin_cos();
            [glam::Vec2::new(c, s), glam::Vec2::new(-s, c)]
        };
        let project = |b: &GravityBox, axis: glam::Vec2| {
            let [ax, ay] = axes(b);
            let centre = b.center.truncate().dot(axis);
            let radius = 0.5 * (b.size.x * ax.dot(axis).abs() + b.size.y * ay.dot(axis).abs());
            (centre - radius, centre + radius)
        };
        axes(self).into_iter().chain(axes(other)).all(|axis| {
            let (a0, a1) = project(self, axis);
            let (b0, b1) = project(other, axis);
            a0 - margin <= b1 && b0 - margin <= a1
        })
    }

    /// Where `plane` cuts the box grown by `margin`: a convex polygon, its corners in order
    /// around the plane's normal (counter-clockwise seen from the side it points to); empty when
    /// the plane misses the box. This is how a node's surface plane is drawn within its extent.
    pub fn section(&self, plane: &Plane, margin: f32) -> Vec<Vec3> {
        let grown = GravityBox {
            size: self.size + Vec3::splat(2.0 * margin),
            ..*self
        };
        let corners = grown.corners();
        let distance = corners.map(|c| plane.signed_distance(c));
        let mut points: Vec<Vec3> = Vec::new();
        // The twelve edges join corners that differ in one bit.
        for a in 0..8 {
            for bit in [1, 2, 4] {
                let b = a | bit;
                if b == a {
                    continue;
                }
                let (da, db) = (distance[a], distance[b]);
                if (da > 0.0) == (db > 0.0) && da != 0.0 && db != 0.0 {
                    continue;
                }
                let t = if da == db { 0.0 } else { da / (da - db) };
                let p = corners[a] + (corners[b] - corners[a]) * t.clamp(0.0, 1.0);
                if points.iter().all(|q| q.distance(p) > 1e-5) {
                    points.push(p);
                }
            }
        }
        if points.len() < 3 {
            return Vec::new();
        }
        let centre = points.iter().copied().sum::<Vec3>() / points.len() as f32;
        let u = (points[0] - centre).normalize_or_zero();
        let v = plane.normal.cross(u);
        points.sort_by(|p, q| {
            let angle = |x: &Vec3| (*x - centre).dot(v).atan2((*x - centre).dot(u));
            angle(p).total_cmp(&angle(q))
        });
        points
    }
}

/// Area of the intersection of two convex, counter-clockwise polygons.
pub fn convex_overlap_area(a: &[glam::Vec2], b: &[glam::Vec2]) -> f32 {
    if a.len() < 3 || b.len() < 3 {
        return 0.0;
    }
    polygon_area(&clip_convex(a, b)).max(0.0)
}

/// `subject` clipped by the convex, counter-clockwise polygon `clip` (Sutherland-Hodgman).
fn clip_convex(subject: &[glam::Vec2], clip: &[glam::Vec2]) -> Vec<glam::Vec2> {
    let mut out = subject.to_vec();
    for k in 0..clip.len() {
        let (a, b) = (clip[k], clip[(k + 1) % clip.len()]);
        let inside = |p: glam::Vec2| (b - a).perp_dot(p - a) >= 0.0;
        let input = std::mem::take(&mut out);
        for i in 0..input.len() {
            let (p, q) = (input[i], input[(i + 1) % input.len()]);
            let crossing = || {
                let (dp, dq) = ((b - a).perp_dot(p - a), (b - a).perp_dot(q - a));
                p + (q - p) * (dp / (dp - dq))
            };
            match (inside(p), inside(q)) {
                (true, true) => out.push(q),
                (true, false) => out.push(crossing()),
                (false, true) => {
                    out.push(crossing());
                    out.push(q);
                }
                (false, false) => {}
            }
        }
        if out.is_empty() {
            break;
        }
    }
    out
}

/// Area of a simple polygon (shoelace), counter-clockwise positive.
fn polygon_area(polygon: &[glam::Vec2]) -> f32 {
    let n = polygon.len();
    (0..n)
        .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
        .sum::<f32>()
        * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn enclosing_box_contains_its_corners(
            cx in -5.0f32..5.0, cy in -5.0f32..5.0, cz in 0.0f32..2.0,
            sx in 0.05f32..3.0, sy in 0.05f32..3.0, sz in 0.05f32..3.0, yaw in -3.1f32..3.1,
        ) {
            let b = GravityBox { center: Vec3::new(cx, cy, cz), yaw, size: Vec3::new(sx, sy, sz) };
            let corners = b.corners();
            for c in corners {
                prop_assert!(b.contains(c, 1e-4));
            }
            let again = GravityBox::enclosing(&corners, yaw).expect("corners");
            prop_assert!((again.center - b.center).length() < 1e-3);
            prop_assert!((again.size - b.size).abs().max_element() < 1e-3);
            prop_assert!(b.overlaps(&again, 0.0));
        }

        /// The minimal box of a turned box's corners (plus points inside) is that box.
        #[test]
        fn the_minimal_box_of_a_box_is_itself(
            cx in -5.0f32..5.0, cy in -5.0f32..5.0, cz in 0.0f32..2.0,
            sx in 0.05f32..3.0, sy in 0.05f32..3.0, sz in 0.05f32..3.0, yaw in -3.1f32..3.1,
        ) {
            let b = GravityBox { center: Vec3::new(cx, cy, cz), yaw, size: Vec3::new(sx, sy, sz) };
            let mut points = b.corners().to_vec();
            points.push(b.center);
            let m = GravityBox::minimal(&points).expect("points");
            prop_assert!((m.volume() - b.volume()).abs() < 1e-3 * (1.0 + b.volume()));
            prop_assert!((m.center - b.center).length() < 1e-3);
            for c in b.corners() {
                prop_assert!(m.contains(c, 1e-3));
            }
        }

        /// IoU is 1 with itself, symmetric, in [0, 1], and matches the closed form for a box
        /// shifted along its own x axis.
        #[test]
        fn iou_behaves(
            sx in 0.1f32..3.0, sy in 0.1f32..3.0, sz in 0.1f32..3.0, yaw in -3.1f32..3.1,
            shift in 0.0f32..1.0, other_yaw in -3.1f32..3.1,
        ) {
            let a = GravityBox { center: Vec3::new(0.5, -0.2, 1.0), yaw, size: Vec3::new(sx, sy, sz) };
            prop_assert!((a.iou(&a) - 1.0).abs() < 1e-4);
            let axis = Vec3::new(yaw.cos(), yaw.sin(), 0.0);
            let moved = GravityBox { center: a.center + axis * shift * sx, ..a };
            let expected = (1.0 - shift) / (1.0 + shift);
            prop_assert!((a.iou(&moved) - expected).abs() < 1e-3, "{} vs {}", a.iou(&moved), expected);
            let b = GravityBox { yaw: other_yaw, ..moved };
            let (ab, ba) = (a.iou(&b), b.iou(&a));
            prop_assert!((ab - ba).abs() < 1e-4 && (0.0..=1.0).contains(&ab));
        }

        /// A plane's section of a box lies on the plane and in the box, is convex and turns
        /// counter-clockwise about the normal; a level plane through a box is its footprint.
        #[test]
        fn a_section_is_the_convex_cut_of_the_box(
            sx in 0.1f32..3.0, sy in 0.1f32..3.0, sz in 0.1f32..3.0, yaw in -3.1f32..3.1,
            nx in -1.0f32..1.0, ny in -1.0f32..1.0, nz in -1.0f32..1.0, along in -0.45f32..0.45,
        ) {
            let b = GravityBox { center: Vec3::new(0.3, -0.7, 1.2), yaw, size: Vec3::new(sx, sy, sz) };
            let normal = Vec3::new(nx, ny, nz);
            prop_assume!(normal.length() > 0.1);
            let through = b.center + b.world_from_box().transform_vector3(b.size * along);
            let plane = Plane::from_point_normal(through, normal);
            let section = b.section(&plane, 0.0);
            prop_assert!(section.len() >= 3 && section.len() <= 6, "{} corners", section.len());
            let n = section.len();
            for (i, p) in section.iter().enumerate() {
                prop_assert!(plane.signed_distance(*p).abs() < 1e-3);
                prop_assert!(b.contains(*p, 1e-3));
                let (q, r) = (section[(i + 1) % n], section[(i + 2) % n]);
                prop_assert!((q - *p).cross(r - q).dot(plane.normal) > -1e-5, "not convex");
            }
            let level = Plane::from_point_normal(b.center, Vec3::Z);
            let footprint = b.section(&level, 0.0);
            prop_assert_eq!(footprint.len(), 4);
            let area = 0.5 * (footprint[2] - footprint[0]).cross(footprint[3] - footprint[1]).length();
            prop_assert!((area - sx * sy).abs() < 1e-3 * (1.0 + sx * sy));
            let above = Plane::from_point_normal(b.center + Vec3::Z * sz, Vec3::Z);
            prop_assert!(b.section(&above, 0.0).is_empty());
        }

        #[test]
        fn boxes_apart_do_not_overlap(gap in 0.01f32..2.0, yaw in -3.1f32..3.1) {
            let a = GravityBox { center: Vec3::ZERO, yaw, size: Vec3::ONE };
            // The enclosing circle of a unit square has radius sqrt(0.5); beyond it nothing touches.
            let b = GravityBox { center: Vec3::new(2.0 * 0.7072 + gap, 0.0, 0.0), yaw: -yaw, size: Vec3::ONE };
            prop_assert!(!a.overlaps(&b, 0.0));
        }
    }

    #[test]
    fn a_trimmed_box_leaves_out_the_outermost_points_past_each_side_of_one_axis() {
        // 200 points across a 0.6 m width (x of the box, turned 30 degrees), two strays 2 cm
        // past each side; the depth has strays too, and keeps them.
        let b = GravityBox {
            center: Vec3::new(1.0, 2.0, 0.5),
            yaw: std::f32::consts::FRAC_PI_6,
            size: Vec3::new(0.64, 0.4, 1.0),
        };
        let mut local: Vec<Vec3> = (0..200)
            .map(|i| Vec3::new(-0.3 + 0.6 * i as f32 / 199.0, 0.1, 0.0))
            .collect();
        local.extend([-0.32, -0.32, 0.32, 0.32].map(|x| Vec3::new(x, 0.2, 0.0)));
        let world: Vec<Vec3> = local
            .iter()
            .map(|p| b.world_from_box().transform_point3(*p))
            .collect();
        let t = b.trimmed_along(0, &world, 0.01);
        assert!((t.size.x - 0.6).abs() < 1e-2, "{t:?}");
        assert_eq!((t.size.y, t.size.z, t.yaw), (b.size.y, b.size.z, b.yaw));
        assert!(t.center.distance(b.center) < 1e-4, "{t:?}");
        // Never wider, and as it is with too few points to leave any out.
        assert_eq!(b.trimmed_along(0, &world[..50], 0.01), b);
        let narrow = GravityBox {
            size: Vec3::new(0.5, 0.4, 1.0),
            ..b
        };
        assert!(narrow.trimmed_along(0, &world, 0.01).size.x <= 0.5 + 1e-6);
    }
}
