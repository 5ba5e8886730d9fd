//! A face of an object that instance fusion kept as an instance of its own: a vertical slab a
//! few centimetres thick lying over a face of a deeper instance of the same class (a cabinet's
//! front cut off from its carcass, a drawer's front, a dishwasher's door). Left apart, such a
//! slab becomes an object of its own in front of its object: a CAD model is placed on it, it
//! stands in the way of the doors and drawers it is the front of, and it counts as an extra
//! instance. A separate object seen only from the front is a slab too, but it stands beside
//! the other, not over its face.

use glam::{IVec3, Vec2};

/// The thickest (metres) a slab may be across its plane: the narrowest band holding
/// [`SLAB_SHARE`] of its voxels (a front, with the depth noise of a camera a few metres away, not
/// a body).
pub const MAX_SLAB_THICKNESS_M: f32 = 0.06;
/// The share of a slab's voxels that must lie within [`MAX_SLAB_THICKNESS_M`] of its plane. The
/// rest may trail off behind it (an open drawer's sides running back into its cabinet) or be the
/// map's strays.
const SLAB_SHARE: f32 = 0.8;
/// How far either way of the principal axes of a piece's voxels its plane is searched, in
/// steps of [`NORMAL_STEP_DEG`] degrees.
const NORMAL_SEARCH_STEPS: i32 = 20;
const NORMAL_STEP_DEG: f32 = 0.5;
/// A piece whose voxels spread more than this (metres) across its principal axes is a body,
/// not a slab a few degrees turned from them (not searched).
const SEARCH_BAND_M: f32 = 0.3;
/// The least extent (metres) of a slab along its plane and up: a front, not a book or a board.
pub const MIN_SLAB_SIDE_M: f32 = 0.15;
/// How deep (metres) the other instance must reach behind the slab: a body, not another face.
pub const MIN_DEPTH_BEHIND_M: f32 = 0.10;
/// How far (metres) the slab's outer side may lie from the other's face, and the slab beyond
/// its sides, top or bottom (the map's bleeding at the edges).
const OVERHANG_M: f32 = 0.06;
/// The share of the slab's voxels that must lie within the other's extent across and up.
const MIN_SHARE_OVER_FACE: f32 = 0.8;
/// The share of voxels left out at either end of every extent measured here: stray voxels of
/// the map's noise.
const STRAY_SHARE: f32 = 0.05;

/// A piece of voxels thin along a horizontal direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slab {
    /// Horizontal unit normal of its plane (voxel axes).
    normal: Vec2,
    /// The band along the normal that holds [`SLAB_SHARE`] of its voxels, in voxel indices.
    across: (f32, f32),
    /// The extent of all its voxels along the normal, strays left out: a front pulled out
    /// reaches back to its body through its sides.
    reach: (f32, f32),
}

impl Slab {
    /// `piece` as a vertical slab, if it is one at `voxel_size` metres: [`SLAB_SHARE`] of its
    /// voxels lie within [`MAX_SLAB_THICKNESS_M`] of a vertical plane (the thinnest within 10
    /// degrees of their principal axes), over at least [`MIN_SLAB_SIDE_M`] along it and up.
    pub fn of(piece: &[IVec3], voxel_size: f32) -> Option<Self> {
        // A few stray voxels spread over a front's size are no front.
        let side = MIN_SLAB_SIDE_M / voxel_size;
        if (piece.len() as f32) < side * side {
            return None;
        }
        // The principal axes of all its voxels are tilted by a tail behind the front (an open
        // drawer's sides), so the plane is the one near them across which the voxels lie
        // thinnest.
        let first = major_axis(piece.iter().map(flat)).perp();
        let band_along =
            |normal: Vec2| narrowest_band(piece.iter().map(|v| flat(v).dot(normal)), SLAB_SHARE);
        let width = |(lo, hi): (f32, f32)| hi - lo;
        // A body is no slab whichever way it is turned.
        let first_band = band_along(first);
        if width(first_band) * voxel_size > SEARCH_BAND_M {
            return None;
        }
        let (normal, across) = (-NORMAL_SEARCH_STEPS..=NORMAL_SEARCH_STEPS)
            .map(|k| {
                if k == 0 {
                    return (k, first, first_band);
                }
                let normal =
                    Vec2::from_angle((k as f32 * NORMAL_STEP_DEG).to_radians()).rotate(first);
                (k, normal, band_along(normal))
            })
            .min_by(|a, b| {
                width(a.2)
                    .total_cmp(&width(b.2))
                    .then(a.0.abs().cmp(&b.0.abs()))
            })
            .map(|(_, normal, band)| (normal, band))
            .expect("the search has steps");
        let major = normal.perp();
        let along = extent(piece, |v| flat(v).dot(major));
        let up = extent(piece, |v| v.z as f32);
        // In whole voxels: a front a little turned to the grid spreads by a fraction of one.
        let size = |(lo, hi): (f32, f32)| ((hi - lo).round() + 1.0) * voxel_size;
        // A hundredth of a millimetre of slack: 3 voxels of 2 cm are 6 cm.
        (size(across) <= MAX_SLAB_THICKNESS_M + 1e-5
            && size(along) >= MIN_SLAB_SIDE_M - 1e-5
            && size(up) >= MIN_SLAB_SIDE_M - 1e-5)
            .then(|| Self {
                normal,
                across,
                reach: extent(piece, |v| flat(v).dot(normal)),
            })
    }

    /// Whether this slab (of the voxels `piece`) lies over a face of `body`: `body` reaches at
    /// least [`MIN_DEPTH_BEHIND_M`] behind it, the slab's outer side is where `body`'s face is
    /// (or further out when the slab's own voxels run back to that face: a drawer pulled out,
    /// with its sides), and most of its voxels lie within `body`'s extent across and up.
    pub fn lies_on_face_of(&self, piece: &[IVec3], body: &[IVec3], voxel_size: f32) -> bool {
        let overhang = OVERHANG_M / voxel_size;
        let depth = MIN_DEPTH_BEHIND_M / voxel_size;
        let (lo, hi) = extent(body, |v| flat(v).dot(self.normal));
        let (s_lo, s_hi) = self.across;
        // The body behind the slab on one side, its face at the slab's other side.
        let (r_lo, r_hi) = self.reach;
        let behind_plus =
            hi - s_hi >= depth && s_lo <= lo + overhang && (s_lo >= lo - overhang || r_hi >= lo);
        let behind_minus =
            s_lo - lo >= depth && s_hi >= hi - overhang && (s_hi <= hi + overhang || r_lo <= hi);
        if !(behind_plus || behind_minus) {
            return false;
        }
        let side = self.normal.perp();
        let (t_lo, t_hi) = extent(body, |v| flat(v).dot(side));
        let (z_lo, z_hi) = extent(body, |v| v.z as f32);
        let over = piece
            .iter()
            .filter(|v| {
                let t = flat(v).dot(side);
                let z = v.z as f32;
                (t_lo - overhang..=t_hi + overhang).contains(&t)
                    && (z_lo - overhang..=z_hi + overhang).contains(&z)
            })
            .count();
        over as f32 >= MIN_SHARE_OVER_FACE * piece.len() as f32
    }
}

/// The horizontal direction along which `points` spread most: the major axis of their 2x2
/// covariance.
fn major_axis(points: impl Iterator<Item = Vec2> + Clone) -> Vec2 {
    let n = points.clone().count().max(1) as f32;
    let mean = points.clone().sum::<Vec2>() / n;
    let (mut xx, mut xy, mut yy) = (0.0f32, 0.0f32, 0.0f32);
    for d in points.map(|p| p - mean) {
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
    }
    Vec2::from_angle(0.5 * (2.0 * xy).atan2(xx - yy))
}

/// The narrowest interval of `values` holding `share` of them.
fn narrowest_band(values: impl Iterator<Item = f32>, share: f32) -> (f32, f32) {
    let mut values: Vec<f32> = values.collect();
    values.sort_by(f32::total_cmp);
    let Some(span) = ((share * values.len() as f32).ceil() as usize).checked_sub(1) else {
        return (f32::MAX, f32::MIN);
    };
    (0..values.len().saturating_sub(span))
        .map(|i| (values[i], values[i + span]))
        .min_by(|a, b| (a.1 - a.0).total_cmp(&(b.1 - b.0)))
        .unwrap_or((f32::MAX, f32::MIN))
}

/// A voxel's horizontal position.
fn flat(v: &IVec3) -> Vec2 {
    v.truncate().as_vec2()
}

/// The extent of `f` over `voxels`, [`STRAY_SHARE`] of them left out at either end.
fn extent(voxels: &[IVec3], f: impl Fn(&IVec3) -> f32) -> (f32, f32) {
    let mut values: Vec<f32> = voxels.iter().map(f).collect();
    values.sort_by(f32::total_cmp);
    let stray = (STRAY_SHARE * values.len() as f32) as usize;
    match values.get(stray..values.len().saturating_sub(stray)) {
        Some([first, .., last]) => (*first, *last),
        Some([only]) => (*only, *only),
        _ => (f32::MAX, f32::MIN),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The voxels of a box's surface from `lo` to `hi` (inclusive), less the face at y = `lo.y`
    /// when `open_front`.
    fn shell(lo: IVec3, hi: IVec3, open_front: bool) -> Vec<IVec3> {
        let mut voxels = Vec::new();
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    let on = [x == lo.x, x == hi.x, y == hi.y, z == lo.z, z == hi.z]
                        .into_iter()
                        .any(|b| b)
                        || (y == lo.y && !open_front);
                    if on && !(open_front && y == lo.y && x > lo.x && x < hi.x && z > lo.z) {
                        voxels.push(IVec3::new(x, y, z));
                    }
                }
            }
        }
        voxels
    }

    fn slab(x: (i32, i32), y: (i32, i32), z: (i32, i32)) -> Vec<IVec3> {
        let mut voxels = Vec::new();
        for a in x.0..=x.1 {
            for b in y.0..=y.1 {
                for c in z.0..=z.1 {
                    voxels.push(IVec3::new(a, b, c));
                }
            }
        }
        voxels
    }

    #[test]
    fn a_cabinet_s_front_cut_off_from_its_carcass_lies_on_its_face() {
        // 2 cm voxels: a carcass 60 cm wide, 56 cm deep, 86 cm high, its front (y = 0) missing;
        // the front is a slab 2 voxels thick at y = -1..0.
        let carcass = shell(IVec3::new(0, 0, 0), IVec3::new(30, 28, 43), true);
        let front = slab((1, 29), (-1, 0), (1, 42));
        let s = Slab::of(&front, 0.02).expect("a slab");
        assert!(s.lies_on_face_of(&front, &carcass, 0.02));
        // The same front turned: a slab across x.
        let turned: Vec<IVec3> = front.iter().map(|v| IVec3::new(v.y, v.x, v.z)).collect();
        let carcass_turned: Vec<IVec3> =
            carcass.iter().map(|v| IVec3::new(v.y, v.x, v.z)).collect();
        let s = Slab::of(&turned, 0.02).expect("a slab");
        assert!(s.lies_on_face_of(&turned, &carcass_turned, 0.02));
        // A few stray voxels of the depth noise, 10 cm out, leave it a slab on the face.
        let mut noisy = front.clone();
        noisy.extend((0..20).map(|k| IVec3::new(1 + k, -6, 20)));
        let s = Slab::of(&noisy, 0.02).expect("a slab with strays");
        assert!(s.lies_on_face_of(&noisy, &carcass, 0.02));
    }

    #[test]
    fn an_open_drawer_s_front_with_its_sides_trailing_into_the_carcass_lies_on_its_face() {
        // 2 cm voxels: the carcass as above; a drawer 56 x 24 cm pulled 4 cm out, its front two
        // voxels thick and its sides' top edges seen running 24 cm back into the carcass, a
        // little turned (the tail that tilted a normal fitted to all its voxels).
        let carcass = shell(IVec3::new(0, 0, 0), IVec3::new(30, 28, 43), true);
        let mut drawer = slab((2, 28), (-3, -2), (30, 41));
        for y in -1..=12 {
            for z in 38..=41 {
                drawer.push(IVec3::new(2 + y / 5, y, z));
                drawer.push(IVec3::new(28 + y / 5, y, z));
            }
        }
        let s = Slab::of(&drawer, 0.02).expect("a slab with a tail");
        assert!(s.normal.y.abs() > 0.999, "the normal is the front's: {s:?}");
        assert!(s.lies_on_face_of(&drawer, &carcass, 0.02));
    }

    #[test]
    fn a_body_a_neighbour_seen_from_the_front_and_a_slab_off_the_face_are_not_face_pieces() {
        let carcass = shell(IVec3::new(0, 0, 0), IVec3::new(30, 28, 43), true);
        // A 10 cm deep piece is a body.
        assert!(Slab::of(&slab((1, 29), (-4, 0), (1, 42)), 0.02).is_none());
        // A cabinet next to it, seen only from the front: a slab beside it, not over its face.
        let beside = slab((31, 60), (-1, 0), (1, 42));
        let s = Slab::of(&beside, 0.02).expect("a slab");
        assert!(!s.lies_on_face_of(&beside, &carcass, 0.02));
        // A wall cabinet's front above it.
        let above = slab((1, 29), (-1, 0), (70, 100));
        let s = Slab::of(&above, 0.02).expect("a slab");
        assert!(!s.lies_on_face_of(&above, &carcass, 0.02));
        // A slab standing 20 cm in front of it (a door standing open, another thing).
        let off = slab((1, 29), (-11, -10), (1, 42));
        let s = Slab::of(&off, 0.02).expect("a slab");
        assert!(!s.lies_on_face_of(&off, &carcass, 0.02));
        // A board inside it, halfway back, is no face of it.
        let inside = slab((1, 29), (10, 11), (1, 42));
        let s = Slab::of(&inside, 0.02).expect("a slab");
        assert!(!s.lies_on_face_of(&inside, &carcass, 0.02));
        // A piece 10 cm wide is no front (a book standing, a strip of a board).
        assert!(Slab::of(&slab((1, 5), (-1, 0), (1, 42)), 0.02).is_none());
        // Another slab is no body to lie on.
        let front = slab((1, 29), (-1, 0), (1, 42));
        let other = slab((1, 29), (2, 3), (1, 42));
        let s = Slab::of(&front, 0.02).expect("a slab");
        assert!(!s.lies_on_face_of(&front, &other, 0.02));
    }
}
