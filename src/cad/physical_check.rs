//! The global physical check of CAD placements (Han et al., Sect. 4.3): placed models must not
//! interpenetrate each other or the layout, and every object resting on another must stand on
//! enough of its supporting surface. A min-conflict search over each object's aligned candidates
//! (start from the best, move the most conflicted object to its least conflicting candidate,
//! bounded) picks the final models; then every model is snapped onto its supporting plane.

use glam::{Affine3A, Vec2, Vec3};
use parry3d::math::Pose;
use parry3d::shape::ConvexPolyhedron;

use crate::cad::database::DatabaseModel;
use crate::geometry::Plane;

/// Deeper interpenetration than this (metres) is a conflict (the bar).
pub const MAX_PENETRATION_M: f32 = 0.01;
/// A child must stand on at least this share of its bottom rectangle (the contact graph's
/// stable-support bar).
pub const MIN_SUPPORT_AREA: f32 = 0.5;
/// How far (metres) below or above a child's bottom the parent's upward surface may be found.
const SUPPORT_HEIGHT_BAND_M: f32 = 0.03;
/// Samples per side of the child's bottom rectangle in the support-area test.
const SUPPORT_SAMPLES: usize = 8;

/// A model placed in the world as solid convex pieces (the primitives it is built from).
pub struct PlacedSolid {
    pieces: Vec<(ConvexPolyhedron, Vec3, Vec3)>,
    /// Bounds of the whole model.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Upward-facing triangles of the posed mesh (support surfaces), world frame.
    upward: Vec<[Vec3; 3]>,
    /// The bottom rectangle of the model's box, world frame (corners in order).
    pub footprint: [Vec3; 4],
}

impl PlacedSolid {
    pub fn new(model: &DatabaseModel, world_from_model: &Affine3A) -> Self {
        let pieces: Vec<(ConvexPolyhedron, Vec3, Vec3)> = model
            .pieces
            .iter()
            .filter_map(|piece| {
                let points: Vec<Vec3> = piece
                    .iter()
                    .map(|p| world_from_model.transform_point3(*p))
                    .collect();
                let (lo, hi) = bounds(&points)?;
                Some((ConvexPolyhedron::from_convex_hull(&points)?, lo, hi))
            })
            .collect();
        let (lo, hi) = pieces.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), (_, a, b)| (lo.min(*a), hi.max(*b)),
        );
        let posed = model.mesh.transformed(world_from_model);
        let upward = (0..posed.triangles.len())
            .filter(|&t| posed.face_normal(t).z > 0.9)
            .map(|t| posed.triangle(t))
            .collect();
        let (mlo, mhi) = model
            .mesh
            .bounds()
            .unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let footprint = [
            Vec3::new(mlo.x, mlo.y, mlo.z),
            Vec3::new(mhi.x, mlo.y, mlo.z),
            Vec3::new(mhi.x, mhi.y, mlo.z),
            Vec3::new(mlo.x, mhi.y, mlo.z),
        ]
        .map(|c| world_from_model.transform_point3(c));
        Self {
            pieces,
            lo,
            hi,
            upward,
            footprint,
        }
    }

    /// The lowest point of the model.
    pub fn bottom_z(&self) -> f32 {
        self.lo.z
    }

    /// The height of this model's upward surface at `xy` nearest to `z` within the band, if any.
    pub fn surface_height_at(&self, xy: Vec2, z: f32) -> Option<f32> {
        self.upward
            .iter()
            .filter_map(|t| height_in_triangle(t, xy))
            .filter(|h| (h - z).abs() <= SUPPORT_HEIGHT_BAND_M)
            .min_by(|a, b| (a - z).abs().total_cmp(&(b - z).abs()))
    }
}

fn bounds(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = *points.first()?;
    Some(
        points
            .iter()
            .fold((first, first), |(lo, hi), p| (lo.min(*p), hi.max(*p))),
    )
}

/// The height of triangle `t`'s plane at `xy` when `xy` lies inside its projection.
fn height_in_triangle(t: &[Vec3; 3], xy: Vec2) -> Option<f32> {
    let [a, b, c] = *t;
    let (a2, b2, c2) = (a.truncate(), b.truncate(), c.truncate());
    let area = (b2 - a2).perp_dot(c2 - a2);
    if area.abs() < 1e-12 {
        return None;
    }
    let u = (c2 - b2).perp_dot(xy - b2) / area;
    let v = (a2 - c2).perp_dot(xy - c2) / area;
    let w = 1.0 - u - v;
    (u >= -1e-6 && v >= -1e-6 && w >= -1e-6).then(|| u * a.z + v * b.z + w * c.z)
}

/// How deep (metres, 0 when apart) two placed models interpenetrate: the deepest contact of
/// any two of their convex pieces.
pub fn penetration_depth(a: &PlacedSolid, b: &PlacedSolid) -> f32 {
    if !overlap(a.lo, a.hi, b.lo, b.hi) {
        return 0.0;
    }
    let mut deepest = 0.0f32;
    for (pa, alo, ahi) in &a.pieces {
        if !overlap(*alo, *ahi, b.lo, b.hi) {
            continue;
        }
        for (pb, blo, bhi) in &b.pieces {
            if !overlap(*alo, *ahi, *blo, *bhi) {
                continue;
            }
            if let Ok(Some(contact)) =
                parry3d::query::contact(&Pose::IDENTITY, pa, &Pose::IDENTITY, pb, 0.0)
            {
                deepest = deepest.max(-contact.dist);
            }
        }
    }
    deepest
}

fn overlap(alo: Vec3, ahi: Vec3, blo: Vec3, bhi: Vec3) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

/// How far (metres, 0 when not) the model reaches behind any of the layout `planes` (facing
/// into the room: the floor's up, walls' inwards).
pub fn layout_penetration(solid: &PlacedSolid, planes: &[Plane]) -> f32 {
    solid
        .pieces
        .iter()
        .flat_map(|(p, _, _)| p.points().iter())
        .flat_map(|v| planes.iter().map(move |plane| -plane.signed_distance(*v)))
        .fold(0.0f32, f32::max)
}

/// The share of the child's bottom rectangle over the parent's upward surface at the child's
/// bottom height.
pub fn support_area(child: &PlacedSolid, parent: &PlacedSolid) -> f32 {
    let [c0, c1, _, c3] = child.footprint;
    let z = child.bottom_z();
    let n = SUPPORT_SAMPLES;
    let mut held = 0;
    for i in 0..n {
        for j in 0..n {
            let (u, v) = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let p = c0 + (c1 - c0) * u + (c3 - c0) * v;
            if parent.surface_height_at(p.truncate(), z).is_some() {
                held += 1;
            }
        }
    }
    held as f32 / (n * n) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::database::CadDatabase;

    fn placed(db: &CadDatabase, id: &str, at: Vec3) -> PlacedSolid {
        let m = db.models().iter().find(|m| m.model.id == id).expect("model");
        PlacedSolid::new(m, &Affine3A::from_translation(at))
    }

    #[test]
    fn a_cup_on_a_table_is_supported_and_one_sunk_into_it_penetrates() {
        let db = CadDatabase::parametric();
        let table = placed(&db, "table_01", Vec3::ZERO);
        let top = table.hi.z;
        let cup = placed(&db, "cup_01", Vec3::new(0.2, 0.1, top));
        assert!(support_area(&cup, &table) > 0.99);
        assert!(penetration_depth(&cup, &table) < 1e-3);
        let sunk = placed(&db, "cup_01", Vec3::new(0.2, 0.1, top - 0.03));
        let depth = penetration_depth(&sunk, &table);
        assert!((depth - 0.03).abs() < 0.005, "depth {depth}");
        // Half over the edge: about half supported.
        let edge_x = table.hi.x;
        let half = placed(&db, "cup_01", Vec3::new(edge_x, 0.0, top));
        let area = support_area(&half, &table);
        assert!((0.3..0.7).contains(&area), "area {area}");
        // Through the floor.
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let low = placed(&db, "table_01", Vec3::new(0.0, 0.0, -0.02));
        assert!((layout_penetration(&low, &[floor]) - 0.02).abs() < 1e-3);
        assert!(layout_penetration(&table, &[floor]) < 1e-4);
    }
}
