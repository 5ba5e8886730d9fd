//! A CAD model placed in the world as solid convex pieces, and what the physical check asks of
//! it: how deep two interpenetrate, how far one reaches behind the layout, how much of a child's
//! bottom its parent holds, and whether it stands by itself.

use glam::{Affine3A, Vec2, Vec3};
use parry3d::shape::ConvexPolyhedron;

use crate::cad::db::database::DatabaseModel;
use crate::geometry::convex_depth::convex_penetration;
use crate::geometry::mesh::points_bounds;
use crate::geometry::{Plane, TriMesh};

/// How far (metres) below or above a child's bottom the parent's upward surface may be found.
const SUPPORT_HEIGHT_BAND_M: f32 = 0.03;
/// Points of a model this close above its lowest are what it stands on: this share of its
/// height, within these bounds (metres). Tight, or a mug laid on its side stands on the rows of
/// its round body a few millimetres up, and rolls over in a simulator.
const STANDING_BAND_SHARE: f32 = 0.005;
const STANDING_BAND_M: std::ops::RangeInclusive<f32> = 0.001..=0.005;
/// Samples per side of the child's bottom rectangle in the support-area test.
const SUPPORT_SAMPLES: usize = 8;

/// A model placed in the world as solid convex pieces (the primitives it is built from).
#[derive(Clone)]
pub struct PlacedSolid {
    pub(crate) pieces: Vec<(ConvexPolyhedron, Vec3, Vec3)>,
    /// Bounds of the whole model.
    pub lo: Vec3,
    pub hi: Vec3,
    /// Upward-facing triangles of the posed mesh (support surfaces), world frame.
    pub(crate) upward: Vec<[Vec3; 3]>,
    /// The bottom rectangle of the model's box, world frame (corners in order).
    pub footprint: [Vec3; 4],
}

impl PlacedSolid {
    pub fn new(model: &DatabaseModel, world_from_model: &Affine3A) -> Self {
        let pieces = model.pieces.iter().map(|piece| {
            piece
                .iter()
                .map(|p| world_from_model.transform_point3(*p))
                .collect()
        });
        let (mlo, mhi) = model.mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let footprint = [
            Vec3::new(mlo.x, mlo.y, mlo.z),
            Vec3::new(mhi.x, mlo.y, mlo.z),
            Vec3::new(mhi.x, mhi.y, mlo.z),
            Vec3::new(mlo.x, mhi.y, mlo.z),
        ]
        .map(|c| world_from_model.transform_point3(c));
        Self::from_pieces(pieces, &model.mesh.transformed(world_from_model), footprint)
    }

    /// A mesh already placed in the world (doors and drawers where they stand) as the hulls of
    /// its connected components; its footprint is the bottom of its axis-aligned bounds.
    pub fn from_world_mesh(mesh: &TriMesh) -> Self {
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let footprint = [
            lo,
            Vec3::new(hi.x, lo.y, lo.z),
            Vec3::new(hi.x, hi.y, lo.z),
            Vec3::new(lo.x, hi.y, lo.z),
        ];
        let pieces = mesh.connected_components().into_iter().map(|c| c.positions);
        Self::from_pieces(pieces, mesh, footprint)
    }

    fn from_pieces(
        pieces: impl Iterator<Item = Vec<Vec3>>,
        posed: &TriMesh,
        footprint: [Vec3; 4],
    ) -> Self {
        let pieces: Vec<(ConvexPolyhedron, Vec3, Vec3)> = pieces
            .filter_map(|points| {
                let (lo, hi) = points_bounds(&points)?;
                Some((ConvexPolyhedron::from_convex_hull(&points)?, lo, hi))
            })
            .collect();
        let (lo, hi) = pieces.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), (_, a, b)| (lo.min(*a), hi.max(*b)),
        );
        let upward = (0..posed.triangles.len())
            .filter(|&t| posed.face_normal(t).z > 0.9)
            .map(|t| posed.triangle(t))
            .collect();
        Self {
            pieces,
            lo,
            hi,
            upward,
            footprint,
        }
    }

    /// An object that keeps its segment mesh, as a fixed solid: the convex hull of what the map
    /// saw of it (simulators collide such a mesh as its hull too). `None` when the points span
    /// no volume.
    pub fn from_hull(points: &[Vec3]) -> Option<Self> {
        let hull = TriMesh {
            positions: points.to_vec(),
            triangles: Vec::new(),
        }
        .convex_hull()?;
        let (lo, hi) = points_bounds(&hull.positions)?;
        let piece = ConvexPolyhedron::from_convex_hull(&hull.positions)?;
        let upward = (0..hull.triangles.len())
            .filter(|&t| hull.face_normal(t).z > 0.9)
            .map(|t| hull.triangle(t))
            .collect();
        Some(Self {
            pieces: vec![(piece, lo, hi)],
            lo,
            hi,
            upward,
            footprint: [
                lo,
                Vec3::new(hi.x, lo.y, lo.z),
                Vec3::new(hi.x, hi.y, lo.z),
                Vec3::new(lo.x, hi.y, lo.z),
            ],
        })
    }

    /// Whether it stands by itself where it rests: its centre of mass (of its convex pieces,
    /// uniformly dense) over the hull of its lowest points. A chair laid on its back by the
    /// orientation search, its seat sticking out, tips over in any simulator.
    pub fn stands(&self) -> bool {
        use parry3d::shape::Shape;
        let (mut mass, mut moment) = (0.0f32, Vec3::ZERO);
        for (piece, _, _) in &self.pieces {
            let props = piece.mass_properties(1.0);
            mass += props.mass();
            moment += props.local_com * props.mass();
        }
        if mass <= 0.0 {
            return true;
        }
        let com = (moment / mass).truncate();
        let band = (STANDING_BAND_SHARE * (self.hi.z - self.lo.z))
            .clamp(*STANDING_BAND_M.start(), *STANDING_BAND_M.end());
        let feet: Vec<Vec2> = self
            .pieces
            .iter()
            .flat_map(|(p, _, _)| p.points().iter())
            .filter(|v| v.z <= self.lo.z + band)
            .map(|v| v.truncate())
            .collect();
        let hull = crate::geometry::min_area_rect::convex_hull(&feet);
        if hull.len() < 3 {
            return false;
        }
        (0..hull.len()).all(|k| {
            let (a, b) = (hull[k], hull[(k + 1) % hull.len()]);
            (b - a).perp_dot(com - a) >= 0.0
        })
    }

    /// The centre of its bounds.
    pub fn centre(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// The lowest point of the model.
    pub fn bottom_z(&self) -> f32 {
        self.lo.z
    }

    /// The height of this model's upward surface at `xy` nearest to `z` within the support
    /// band, if any.
    pub fn surface_height_at(&self, xy: Vec2, z: f32) -> Option<f32> {
        self.surface_height_within(xy, z, SUPPORT_HEIGHT_BAND_M)
    }

    /// The height of this model's upward surface at `xy` nearest to `z` within `band` metres.
    pub(crate) fn surface_height_within(&self, xy: Vec2, z: f32, band: f32) -> Option<f32> {
        self.upward
            .iter()
            .filter_map(|t| height_in_triangle(t, xy))
            .filter(|h| (h - z).abs() <= band)
            .min_by(|a, b| (a - z).abs().total_cmp(&(b - z).abs()))
    }
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
    (u >= -1e-6 && v >= -1e-6 && w >= -1e-6).then_some(u * a.z + v * b.z + w * c.z)
}

/// How deep (metres, 0 when apart) two placed models interpenetrate: the deepest contact of
/// any two of their convex pieces.
pub fn penetration_depth(a: &PlacedSolid, b: &PlacedSolid) -> f32 {
    deepest_contact(a, b).map_or(0.0, |(depth, _)| depth)
}

/// The deepest interpenetration of two placed models and its normal (out of `a`, towards `b`);
/// `None` when they do not interpenetrate.
pub fn deepest_contact(a: &PlacedSolid, b: &PlacedSolid) -> Option<(f32, Vec3)> {
    if !overlap(a.lo, a.hi, b.lo, b.hi) {
        return None;
    }
    let mut deepest: Option<(f32, Vec3)> = None;
    for (pa, alo, ahi) in &a.pieces {
        if !overlap(*alo, *ahi, b.lo, b.hi) {
            continue;
        }
        for (pb, blo, bhi) in &b.pieces {
            if !overlap(*alo, *ahi, *blo, *bhi) {
                continue;
            }
            if let Some((depth, normal)) =
                convex_penetration(pa, &Affine3A::IDENTITY, pb, &Affine3A::IDENTITY)
                && deepest.is_none_or(|(d, _)| depth > d)
            {
                deepest = Some((depth, normal));
            }
        }
    }
    deepest
}

/// How far (metres, 0 when apart) `b` must move along unit `direction` for every convex piece of
/// it to clear every piece of `a` it interpenetrates: the overlap of their projections on it.
/// The contact depth is the shallowest way out, which may be up (two thin books lying half on
/// each other); this is the way out along a chosen line.
pub fn overlap_along(a: &PlacedSolid, b: &PlacedSolid, direction: Vec3) -> f32 {
    let extent = |piece: &ConvexPolyhedron| {
        piece
            .points()
            .iter()
            .map(|p| p.dot(direction))
            .fold((f32::MAX, f32::MIN), |(lo, hi), t| (lo.min(t), hi.max(t)))
    };
    let mut most = 0.0f32;
    for (pa, _, _) in &a.pieces {
        for (pb, _, _) in &b.pieces {
            if convex_penetration(pa, &Affine3A::IDENTITY, pb, &Affine3A::IDENTITY).is_some() {
                most = most.max(extent(pa).1 - extent(pb).0);
            }
        }
    }
    most
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
