//! Handles and knobs on the front of a piece of furniture, and what they say about the part they
//! open (after Rusu et al. 2008, "Towards 3D Point Cloud Based Object Maps for Household
//! Environments", Sect. V): the front is a plane; a handle is a cluster of points standing 1 to
//! 8 cm out of it; a cluster long and thin across the front is a bar (a line fitted to it), a
//! small round one a knob. What each opens is `perception::parts`'s.
//!
//! Bevy-free: the pipeline gives it an object's observed surface points and the front's frame.

use glam::{Vec2, Vec3};

use crate::geometry::clusters::cluster_roots;
use crate::geometry::principal_axis::principal_axis;
pub use crate::graph::parts::HandleKind;
use crate::map::median;

/// How far out of the front plane a handle stands, metres: closer is the front's own relief (a
/// groove, a frame), farther is something standing in front of the furniture.
pub const HANDLE_DEPTH_M: std::ops::RangeInclusive<f32> = 0.01..=0.08;
/// A handle has at least this many points (at the map's 2 cm surface spacing, a 10 cm bar has
/// about 5 to 15): fewer is noise.
pub const MIN_HANDLE_POINTS: usize = 4;
/// Points of a handle lie within this distance (metres) of each other.
const HANDLE_CELL_M: f32 = 0.025;
/// A bar is at least this long (metres) and this many times longer than wide; a knob at most
/// this wide.
const MIN_BAR_LENGTH_M: f32 = 0.06;
const MIN_BAR_ELONGATION: f32 = 2.5;
const MAX_KNOB_WIDTH_M: f32 = 0.06;
/// A knob is at least this wide across the front (metres): points standing out in one spot
/// are the edge of a side panel seen edge-on, not a knob (real knobs are 2 to 5 cm).
const MIN_KNOB_WIDTH_M: f32 = 0.015;
/// Anything wider than this across the front (metres) is not a handle (a towel, a cup).
const MAX_HANDLE_LENGTH_M: f32 = 0.6;

/// The front of an object: a vertical plane through `origin` whose `normal` (horizontal, unit)
/// points out of the object into the room, with `right` (horizontal, unit) along it as seen
/// from the room and +z up.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Front {
    pub origin: Vec3,
    pub normal: Vec3,
    pub right: Vec3,
}

impl Front {
    /// A front facing `normal` (made horizontal) through `origin`.
    pub fn new(origin: Vec3, normal: Vec3) -> Option<Self> {
        let normal = normal.with_z(0.0).try_normalize()?;
        Some(Self {
            origin,
            normal,
            right: Vec3::Z.cross(normal),
        })
    }

    /// `p` in the front's frame: along the front (right), up, and out of it.
    pub fn local(&self, p: Vec3) -> Vec3 {
        let d = p - self.origin;
        Vec3::new(d.dot(self.right), d.z, d.dot(self.normal))
    }
}

/// A handle found on a front, in the world frame.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Handle {
    pub kind: HandleKind,
    pub center: Vec3,
    /// A bar's direction (unit, in the front plane); a knob's is the front's normal.
    pub axis: Vec3,
    /// A bar's length, a knob's width, metres.
    pub length: f32,
    /// How far it stands out of the front plane, metres.
    pub depth: f32,
}

/// The front plane's offset along its normal: the median offset of the points within 5 cm of
/// `front.origin`'s plane (most of a front is the front itself, its handles are few).
pub fn front_plane_offset(front: &Front, points: &[Vec3]) -> Option<f32> {
    let mut offsets: Vec<f32> = points
        .iter()
        .map(|p| front.local(*p).z)
        .filter(|d| d.abs() <= 0.05)
        .collect();
    (!offsets.is_empty()).then(|| median(&mut offsets))
}

/// The handles on `front` among `points` (an object's observed surface, world frame): clusters
/// of the points standing [`HANDLE_DEPTH_M`] out of the front plane, each a bar or a knob by
/// its shape across the front; anything else standing out (too big, too long and wide) is not
/// a handle. In the order of their first point.
pub fn find_handles(front: &Front, points: &[Vec3]) -> Vec<Handle> {
    let Some(plane) = front_plane_offset(front, points) else {
        return Vec::new();
    };
    let standing: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| HANDLE_DEPTH_M.contains(&(front.local(*p).z - plane)))
        .collect();
    let roots = cluster_roots(&standing, HANDLE_CELL_M);
    let mut clusters: Vec<(usize, Vec<Vec3>)> = Vec::new();
    for (p, root) in standing.iter().zip(&roots) {
        let Some(root) = root else { continue };
        match clusters.iter_mut().find(|(r, _)| r == root) {
            Some((_, members)) => members.push(*p),
            None => clusters.push((*root, vec![*p])),
        }
    }
    clusters
        .into_iter()
        .filter(|(_, members)| members.len() >= MIN_HANDLE_POINTS)
        .filter_map(|(_, members)| handle_of(front, plane, &members))
        .collect()
}

/// A cluster as a bar or a knob, or `None` when it is neither: the principal direction of its
/// points across the front gives its length and width.
fn handle_of(front: &Front, plane: f32, members: &[Vec3]) -> Option<Handle> {
    let across: Vec<Vec2> = members.iter().map(|p| front.local(*p).truncate()).collect();
    let n = across.len() as f32;
    let (mean, major) = principal_axis(&across)?;
    let minor = major.perp();
    let extent = |axis: Vec2| {
        let (lo, hi) = across.iter().fold((f32::MAX, f32::MIN), |(lo, hi), q| {
            let t = (*q - mean).dot(axis);
            (lo.min(t), hi.max(t))
        });
        hi - lo
    };
    let (length, width) = (extent(major), extent(minor));
    let out: Vec<f32> = members.iter().map(|p| front.local(*p).z - plane).collect();
    let depth = out.iter().copied().fold(0.0, f32::max);
    let mean_out = out.iter().sum::<f32>() / n;
    let center =
        front.origin + front.right * mean.x + Vec3::Z * mean.y + front.normal * (plane + mean_out);
    let kind = if length > MAX_HANDLE_LENGTH_M {
        return None;
    } else if length >= MIN_BAR_LENGTH_M && length >= MIN_BAR_ELONGATION * width {
        HandleKind::Bar
    } else if (MIN_KNOB_WIDTH_M..=MAX_KNOB_WIDTH_M).contains(&length) {
        HandleKind::Knob
    } else {
        return None;
    };
    let axis = match kind {
        HandleKind::Bar => (front.right * major.x + Vec3::Z * major.y).normalize(),
        HandleKind::Knob => front.normal,
    };
    Some(Handle {
        kind,
        center,
        axis,
        length,
        depth,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::parts::{FrontExtent, PartKind, Side, lay_out_parts};

    /// A cabinet front facing -y at y = 0 (so the room is at y < 0), 0.6 m wide from x = 0 and
    /// 0.8 m high from z = 0.1, sampled every 2 cm with `noise` metres of depth noise.
    fn front_points(noise: f32) -> (Front, Vec<Vec3>) {
        let front = Front::new(Vec3::new(0.3, 0.0, 0.5), Vec3::NEG_Y).expect("front");
        let mut points = Vec::new();
        let mut k = 0u32;
        for i in 0..=30 {
            for j in 0..=40 {
                // A fixed pseudo-random offset, the same every run.
                k = k.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let jitter = ((k >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 2.0 * noise;
                points.push(Vec3::new(0.02 * i as f32, jitter, 0.1 + 0.02 * j as f32));
            }
        }
        (front, points)
    }

    /// Points of a bar from `a` to `b` standing `out` metres in front of the y = 0 front.
    fn bar(a: Vec3, b: Vec3, out: f32) -> Vec<Vec3> {
        (0..=12)
            .flat_map(|i| {
                let p = a.lerp(b, i as f32 / 12.0);
                [p - Vec3::Y * out, p - Vec3::Y * (out - 0.01)]
            })
            .collect()
    }

    /// The handles found on the test front (3 mm of depth noise) with `extra` points added.
    fn handles_with(extra: Vec<Vec3>) -> (Front, Vec<Handle>) {
        let (front, mut points) = front_points(0.003);
        points.extend(extra);
        let handles = find_handles(&front, &points);
        (front, handles)
    }

    /// How the part covering the whole test front opens, by `handle` (`perception::parts`).
    fn motion(front: &Front, handle: &Handle) -> PartKind {
        let extent = FrontExtent {
            right: [-0.3, 0.3],
            z: [0.1, 0.9],
        };
        lay_out_parts(front, extent, &[*handle], false)[0].kind
    }

    #[test]
    fn a_vertical_bar_near_the_right_edge_is_a_door_hinged_on_the_left() {
        let (front, handles) = handles_with(bar(
            Vec3::new(0.52, 0.0, 0.45),
            Vec3::new(0.52, 0.0, 0.65),
            0.035,
        ));
        assert_eq!(handles.len(), 1, "{handles:?}");
        let h = handles[0];
        assert_eq!(h.kind, HandleKind::Bar);
        assert!(h.axis.z.abs() > 0.99, "{h:?}");
        assert!((h.length - 0.2).abs() < 0.02, "{h:?}");
        assert!((h.depth - 0.035).abs() < 0.006, "{h:?}");
        assert!(
            h.center.distance(Vec3::new(0.52, -0.03, 0.55)) < 0.005,
            "{h:?}"
        );
        // Seen from the room (looking along +y), +x is on the right: the handle is at the
        // right edge, the hinge at the left.
        assert!(front.right.x > 0.99);
        assert_eq!(motion(&front, &h), PartKind::Door { hinge: Side::Left });
    }

    #[test]
    fn a_centred_horizontal_bar_is_a_drawer_and_a_high_one_on_a_tall_base_part_a_door() {
        let (front, handles) = handles_with(bar(
            Vec3::new(0.2, 0.0, 0.5),
            Vec3::new(0.4, 0.0, 0.5),
            0.03,
        ));
        let h = handles[0];
        assert_eq!(h.kind, HandleKind::Bar);
        assert!(h.axis.x.abs() > 0.99, "{h:?}");
        assert_eq!(motion(&front, &h), PartKind::Drawer);
        let (front, handles) = handles_with(bar(
            Vec3::new(0.2, 0.0, 0.83),
            Vec3::new(0.4, 0.0, 0.83),
            0.03,
        ));
        // The part stands on the plinth: a flap would open onto the floor (`perception::parts`).
        assert_eq!(
            motion(&front, &handles[0]),
            PartKind::Door { hinge: Side::Left }
        );
    }

    #[test]
    fn a_small_round_knob_is_a_knob_and_opens_a_door_when_off_centre() {
        let ring = (0..12)
            .map(|i| {
                let a = i as f32 / 12.0 * std::f32::consts::TAU;
                Vec3::new(0.08 + 0.015 * a.cos(), -0.03, 0.5 + 0.015 * a.sin())
            })
            .collect();
        let (front, handles) = handles_with(ring);
        assert_eq!(handles.len(), 1, "{handles:?}");
        assert_eq!(handles[0].kind, HandleKind::Knob);
        assert!(handles[0].length < MAX_KNOB_WIDTH_M);
        // x = 0.08 is at the left as seen from the room: hinged on the right.
        assert_eq!(
            motion(&front, &handles[0]),
            PartKind::Door { hinge: Side::Right }
        );
    }

    #[test]
    fn a_noisy_bare_front_and_things_standing_far_in_front_have_no_handles() {
        let (front, mut points) = front_points(0.004);
        assert!(find_handles(&front, &points).is_empty());
        // A cup 15 cm in front of the doors, and a towel hanging 2 cm out over half the front.
        for i in 0..10 {
            for j in 0..10 {
                points.push(Vec3::new(
                    0.3 + 0.01 * i as f32,
                    -0.15 - 0.005 * j as f32,
                    0.6,
                ));
            }
        }
        for i in 0..20 {
            for j in 0..10 {
                points.push(Vec3::new(0.02 * i as f32, -0.02, 0.3 + 0.02 * j as f32));
            }
        }
        assert!(find_handles(&front, &points).is_empty());
    }
}
