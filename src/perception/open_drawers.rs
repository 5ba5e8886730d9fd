//! Drawers standing open in front of a front (issue 36, section 1). A drawer pulled out shows
//! its front as a plane parallel to the closed front, centimetres to decimetres out of it, with
//! its handle on it and its box's sides and rim between the two. Found there:
//! - its handles are carried back onto the closed front, where a model's are with its drawers
//!   shut, so a chest whose top drawer is open still reads as three drawers (on held-out rooms
//!   the open drawer's handle was missing and its box's rim, 6 to 7 cm out, read as four
//!   handles: the chest was given a model with a door);
//! - its points are neither handles of the closed front nor part of the closed carcass the
//!   models are fitted to.
//!
//! An open door is no plane parallel to the front (it turns about its hinge), and a handle
//! covers too little of one: neither is taken for a drawer. Bevy-free.

use glam::Vec3;
use serde::Serialize;

use crate::graph::parts::{PartJointType, PartJson};
use crate::perception::handles::{Front, Handle, find_handles};
use crate::perception::parts::quantile_range;

/// A plane this far out of the closed front (metres) or farther may be an open drawer's front:
/// handles stand 2 to 6 cm out, and cover too little to pass for one.
const MIN_OUT_M: f32 = 0.05;
/// Depths are binned this finely (metres); a plane's points lie within this distance of it.
const DEPTH_BIN_M: f32 = 0.01;
const PLANE_HALF_THICKNESS_M: f32 = 0.015;
/// A drawer's front is at least this wide and high (metres) ...
const MIN_WIDTH_M: f32 = 0.15;
const MIN_HEIGHT_M: f32 = 0.08;
/// ... parallel to the front: its points' distance out of the front changes by at most this
/// much per metre across it or up it (about 8 degrees). An oven's flap turned down part way
/// crosses the slab of each depth bin as a strip 7 to 12 cm high that slopes (seed 30 read one
/// as three drawers).
const MAX_TILT: f32 = 0.15;
/// ... and its points fill at least this share of the map's 2 cm cells over its rectangle: the
/// sides of an open drawer, an open door seen edge-on and a row of handles fill a thin strip.
const MIN_FILL: f32 = 0.4;
const CELL_M: f32 = 0.02;
/// A plane with fewer points is not looked at.
const MIN_PLANE_POINTS: usize = 20;
/// Its rectangle is taken between these quantiles of its points.
const EDGE_QUANTILE: f32 = 0.03;
/// Points within this distance of a drawer's rectangle (metres), standing out of the closed
/// front by more than [`ON_FRONT_M`], are the drawer's: its box behind its front, its rim.
const FOOTPRINT_MARGIN_M: f32 = 0.04;
const ON_FRONT_M: f32 = 0.015;
/// Planes looked at per front, open drawers found at most.
const MAX_PLANES: usize = 8;
const MAX_DRAWERS: usize = 4;
/// A handle on a drawer's front is looked for among the points from this far behind it to
/// this far in front (metres), as on the closed front.
const BEHIND_M: f32 = 0.08;
const IN_FRONT_M: f32 = 0.1;

/// A drawer standing open: its front's rectangle in the closed front's frame (`right` along it,
/// `z` world height), how far it stands out, and the handles on it carried back onto the closed
/// front (`Handle::depth` is still how far each stands out of the drawer's own front).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OpenDrawer {
    pub right: [f32; 2],
    pub z: [f32; 2],
    pub out: f32,
    pub handles: Vec<Handle>,
}

impl OpenDrawer {
    /// Whether world point `p` belongs to this drawer rather than to the closed front or the
    /// carcass: across its rectangle (grown by [`FOOTPRINT_MARGIN_M`]) and out of the front.
    pub fn holds(&self, front: &Front, p: Vec3) -> bool {
        let l = front.local(p);
        l.z > ON_FRONT_M && in_footprint(self.right, self.z, l.x, p.z)
    }
}

/// Whether `right` along a front and height `z` lie across the rectangle `rect_right` by
/// `rect_z` grown by [`FOOTPRINT_MARGIN_M`].
fn in_footprint(rect_right: [f32; 2], rect_z: [f32; 2], right: f32, z: f32) -> bool {
    (rect_right[0] - FOOTPRINT_MARGIN_M..=rect_right[1] + FOOTPRINT_MARGIN_M).contains(&right)
        && (rect_z[0] - FOOTPRINT_MARGIN_M..=rect_z[1] + FOOTPRINT_MARGIN_M).contains(&z)
}

/// The drawers standing open in front of `front` among `points` (the object's surface across its
/// front, world frame): planes parallel to the front at least [`MIN_OUT_M`] out whose points
/// cover a drawer-sized rectangle, the plane holding most points looked at first, then the next
/// among what is left.
pub fn open_drawers(front: &Front, points: &[Vec3]) -> Vec<OpenDrawer> {
    let mut left: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| front.local(*p).z >= MIN_OUT_M - PLANE_HALF_THICKNESS_M)
        .collect();
    let mut drawers = Vec::new();
    for _ in 0..MAX_PLANES {
        if drawers.len() == MAX_DRAWERS {
            break;
        }
        let Some(out) = densest_depth(front, &left) else {
            break;
        };
        let on: Vec<Vec3> = left
            .iter()
            .copied()
            .filter(|p| (front.local(*p).z - out).abs() <= PLANE_HALF_THICKNESS_M)
            .collect();
        match drawer_front(front, out, &on, points) {
            Some(drawer) => {
                left.retain(|p| !drawer.holds(front, *p));
                drawers.push(drawer);
            }
            None => left.retain(|p| (front.local(*p).z - out).abs() > PLANE_HALF_THICKNESS_M),
        }
    }
    drawers
}

/// The depth out of `front` (at least [`MIN_OUT_M`]) where most of `points` lie, each bin
/// counted with its two neighbours; `None` when no bin holds [`MIN_PLANE_POINTS`].
fn densest_depth(front: &Front, points: &[Vec3]) -> Option<f32> {
    let bin_of = |z: f32| ((z - MIN_OUT_M) / DEPTH_BIN_M).round();
    let mut counts: Vec<usize> = Vec::new();
    for p in points {
        let b = bin_of(front.local(*p).z);
        if b >= 0.0 {
            let b = b as usize;
            if counts.len() <= b + 1 {
                counts.resize(b + 2, 0);
            }
            counts[b] += 1;
        }
    }
    let (bin, count) = (0..counts.len())
        .map(|b| {
            let before = if b > 0 { counts[b - 1] } else { 0 };
            let after = counts.get(b + 1).copied().unwrap_or(0);
            (b, before + counts[b] + after)
        })
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))?;
    (count >= MIN_PLANE_POINTS).then_some(MIN_OUT_M + bin as f32 * DEPTH_BIN_M)
}

/// The open drawer whose front is the plane `out` metres out of `front` holding `on`, when they
/// cover a drawer-sized rectangle well enough; its handles are looked for among `all`.
fn drawer_front(front: &Front, out: f32, on: &[Vec3], all: &[Vec3]) -> Option<OpenDrawer> {
    if on.len() < MIN_PLANE_POINTS {
        return None;
    }
    let range = |v: Vec<f32>| quantile_range(v, EDGE_QUANTILE);
    let right = range(on.iter().map(|p| front.local(*p).x).collect());
    let z = range(on.iter().map(|p| p.z).collect());
    let (width, height) = (right[1] - right[0], z[1] - z[0]);
    if width < MIN_WIDTH_M || height < MIN_HEIGHT_M || tilted(front, on) {
        return None;
    }
    let mut cells: Vec<(i32, i32)> = on
        .iter()
        .filter(|p| {
            let x = front.local(**p).x;
            (right[0]..=right[1]).contains(&x) && (z[0]..=z[1]).contains(&p.z)
        })
        .map(|p| {
            let x = front.local(*p).x - right[0];
            (
                (x / CELL_M).floor() as i32,
                ((p.z - z[0]) / CELL_M).floor() as i32,
            )
        })
        .collect();
    cells.sort_unstable();
    cells.dedup();
    let total = ((width / CELL_M).ceil() * (height / CELL_M).ceil()).max(1.0);
    if (cells.len() as f32) < MIN_FILL * total {
        return None;
    }
    let plane = Front::new(front.origin + front.normal * out, front.normal)?;
    let near: Vec<Vec3> = all
        .iter()
        .copied()
        .filter(|p| {
            let l = plane.local(*p);
            (-BEHIND_M..=IN_FRONT_M).contains(&l.z) && in_footprint(right, z, l.x, p.z)
        })
        .collect();
    let handles = find_handles(&plane, &near)
        .into_iter()
        .filter(|h| {
            let x = plane.local(h.center).x;
            (right[0]..=right[1]).contains(&x) && (z[0]..=z[1]).contains(&h.center.z)
        })
        .map(|h| Handle {
            center: h.center - front.normal * out,
            ..h
        })
        .collect();
    Some(OpenDrawer {
        right,
        z,
        out,
        handles,
    })
}

/// A model's drawer stands for an open drawer when its closed front's centre is this close to
/// the open drawer's rectangle's centre carried back onto the front, metres ...
const SAME_DRAWER_M: f32 = 0.12;
/// ... and it slides out along the front's normal within this angle (cos of 30 degrees).
const SAME_SLIDE_COS: f32 = 0.866;

/// How far each of `parts` (a placed model's, world frame) is pulled out as `drawers` were
/// seen standing open on `front`: `(part name, joint value)`, the value clamped to the part's
/// range and signed the way its range opens. A drawer no part stands for is left out.
pub fn drawer_openings(
    front: &Front,
    drawers: &[OpenDrawer],
    parts: &[PartJson],
) -> Vec<(String, f32)> {
    let mut taken = vec![false; parts.len()];
    let mut openings = Vec::new();
    for d in drawers {
        let centre = front.origin
            + front.right * (0.5 * (d.right[0] + d.right[1]))
            + Vec3::Z * (0.5 * (d.z[0] + d.z[1]) - front.origin.z);
        let nearest = parts
            .iter()
            .enumerate()
            .filter(|(k, p)| {
                !taken[*k]
                    && p.joint.kind == PartJointType::Prismatic
                    && p.opening_direction().dot(front.normal) >= SAME_SLIDE_COS
            })
            .map(|(k, p)| {
                let off = p.front_center() - centre;
                (k, (off - front.normal * off.dot(front.normal)).length())
            })
            .filter(|(_, distance)| *distance <= SAME_DRAWER_M)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, _)) = nearest {
            taken[k] = true;
            let joint = &parts[k].joint;
            let value = if joint.upper.abs() >= joint.lower.abs() {
                d.out.min(joint.upper)
            } else {
                (-d.out).max(joint.lower)
            };
            openings.push((parts[k].name.clone(), value));
        }
    }
    openings
}

/// Whether `points` slope out of `front`'s plane by more than [`MAX_TILT`] across it or up it:
/// the least-squares plane `out = a + b right + c up` through them.
fn tilted(front: &Front, points: &[Vec3]) -> bool {
    let local: Vec<Vec3> = points.iter().map(|p| front.local(*p)).collect();
    let n = local.len() as f32;
    let mean = local.iter().copied().sum::<Vec3>() / n;
    let (mut xx, mut xy, mut yy, mut xo, mut yo) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for l in &local {
        let d = *l - mean;
        xx += d.x * d.x;
        xy += d.x * d.y;
        yy += d.y * d.y;
        xo += d.x * d.z;
        yo += d.y * d.z;
    }
    let det = xx * yy - xy * xy;
    if det <= f32::EPSILON {
        return true;
    }
    let across = (yy * xo - xy * yo) / det;
    let up = (xx * yo - xy * xo) / det;
    across.abs() > MAX_TILT || up.abs() > MAX_TILT
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points every 2 cm over a rectangle of the plane `out` metres in front of the y = 0 front
    /// (facing -y, so out is -y): x from `x0` to `x1`, z from `z0` to `z1`.
    fn panel(out: f32, [x0, x1]: [f32; 2], [z0, z1]: [f32; 2]) -> Vec<Vec3> {
        let (nx, nz) = (
            ((x1 - x0) / 0.02).round() as usize,
            ((z1 - z0) / 0.02).round() as usize,
        );
        (0..=nx)
            .flat_map(|i| {
                (0..=nz).map(move |j| Vec3::new(x0 + 0.02 * i as f32, -out, z0 + 0.02 * j as f32))
            })
            .collect()
    }

    /// A horizontal bar `out` metres in front of the y = 0 plane, centred at `x`, `z`, 20 cm long.
    fn bar(out: f32, x: f32, z: f32) -> Vec<Vec3> {
        (0..=10)
            .flat_map(|i| {
                let p = Vec3::new(x - 0.1 + 0.02 * i as f32, -out, z);
                [p, p - Vec3::Y * 0.01]
            })
            .collect()
    }

    fn front() -> Front {
        Front::new(Vec3::new(0.3, 0.0, 0.4), Vec3::NEG_Y).expect("front")
    }

    /// A chest 0.6 wide, its fronts at y = 0 from z = 0.1 to 0.7, its top drawer (z 0.5 to 0.7)
    /// pulled out `out` metres: its front there with its bar, its two sides running back to the
    /// carcass, and the closed drawers' bars below.
    fn chest_with_open_top_drawer(out: f32) -> Vec<Vec3> {
        let mut points = panel(0.0, [0.0, 0.6], [0.1, 0.5]);
        points.extend(panel(out, [0.02, 0.58], [0.5, 0.7]));
        points.extend(bar(out + 0.025, 0.3, 0.6));
        points.extend(bar(0.025, 0.3, 0.2));
        points.extend(bar(0.025, 0.3, 0.4));
        for x in [0.02, 0.58] {
            for k in 0..(out / 0.02) as usize {
                for j in 0..8 {
                    points.push(Vec3::new(x, -0.02 * k as f32, 0.52 + 0.02 * j as f32));
                }
            }
        }
        points
    }

    #[test]
    fn a_drawer_pulled_out_is_found_with_its_handle_carried_back_onto_the_front() {
        let points = chest_with_open_top_drawer(0.16);
        let drawers = open_drawers(&front(), &points);
        assert_eq!(drawers.len(), 1, "{drawers:?}");
        let d = &drawers[0];
        assert!((d.out - 0.16).abs() <= 0.011, "{d:?}");
        assert!(d.z[0] > 0.48 && d.z[1] < 0.72, "{d:?}");
        assert_eq!(d.handles.len(), 1, "{d:?}");
        let h = d.handles[0];
        // Back on the closed front: 2.5 cm out of it, where the model's is.
        assert!((h.center.y + 0.03).abs() < 0.015, "{h:?}");
        assert!(
            (h.center.z - 0.6).abs() < 0.01 && h.axis.x.abs() > 0.99,
            "{h:?}"
        );
        // The drawer's box is its own; the closed fronts' bars below are not.
        let f = front();
        assert!(d.holds(&f, Vec3::new(0.02, -0.08, 0.6)));
        assert!(!d.holds(&f, Vec3::new(0.3, -0.025, 0.4)));
        assert!(!d.holds(&f, Vec3::new(0.3, 0.0, 0.6)));
    }

    #[test]
    fn an_open_drawer_opens_the_models_drawer_behind_it_as_far_as_it_was_pulled() {
        use crate::cad::library::storage::cabinet_drawers;
        use crate::cad::model_parts::model_parts;
        // A chest 0.6 x 0.45 x 0.8 turned to face +x, its front at x = 0.225.
        let model = cabinet_drawers("chest", Vec3::new(0.6, 0.45, 0.8));
        let frame = glam::Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_2);
        let parts = model_parts(&model, &frame);
        let top = parts
            .iter()
            .max_by(|a, b| a.front_center().z.total_cmp(&b.front_center().z))
            .expect("drawers");
        let front = Front::new(Vec3::new(0.225, 0.0, 0.4), Vec3::X).expect("front");
        let at = front.local(top.front_center());
        let drawer = |out: f32| OpenDrawer {
            right: [at.x - 0.25, at.x + 0.25],
            z: [top.front_center().z - 0.08, top.front_center().z + 0.08],
            out,
            handles: Vec::new(),
        };
        let opened = drawer_openings(&front, &[drawer(0.16)], &parts);
        assert_eq!(opened.len(), 1, "{opened:?}");
        assert_eq!(opened[0].0, top.name);
        assert!((opened[0].1 - 0.16).abs() < 1e-6, "{opened:?}");
        // Seen pulled out farther than the model's drawer slides, it is open to its end.
        let far = drawer_openings(&front, &[drawer(2.0)], &parts);
        assert_eq!(far[0].1, top.joint.upper);
        // A drawer seen on another face stands for none of them.
        let side = Front::new(Vec3::new(0.0, 0.3, 0.4), Vec3::Y).expect("side");
        assert!(drawer_openings(&side, &[drawer(0.16)], &parts).is_empty());
    }

    #[test]
    fn handles_a_shut_front_and_an_open_door_are_no_open_drawers() {
        let f = front();
        let mut shut = panel(0.0, [0.0, 0.6], [0.1, 0.7]);
        shut.extend(bar(0.05, 0.3, 0.6));
        shut.extend(bar(0.06, 0.3, 0.4));
        assert!(open_drawers(&f, &shut).is_empty());
        // A door 0.6 high hinged at x = 0, open 90 degrees: a panel running out of the front.
        let mut door = panel(0.0, [0.0, 0.6], [0.1, 0.7]);
        for k in 0..=20 {
            for j in 0..=30 {
                door.push(Vec3::new(0.0, -0.02 * k as f32, 0.1 + 0.02 * j as f32));
            }
        }
        assert!(open_drawers(&f, &door).is_empty());
        // An oven's flap 0.6 wide and 0.6 high, hinged along its bottom at z = 0.1 and turned
        // down 15 degrees: each depth bin's slab crosses it as a strip 11 cm high.
        let mut flap = Vec::new();
        for k in 0..=60 {
            let up = 0.01 * k as f32;
            for i in 0..=30 {
                let out = up * 15f32.to_radians().tan();
                flap.push(Vec3::new(0.02 * i as f32, -out, 0.1 + up));
            }
        }
        assert!(
            open_drawers(&f, &flap).is_empty(),
            "{:?}",
            open_drawers(&f, &flap)
        );
    }
}
