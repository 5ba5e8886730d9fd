//! The front of a piece of furniture and the handles on it, perceived in the map (issue 36,
//! section 1) and predicted from a CAD model, and how far a model's handles disagree with the
//! perceived ones: a chest of drawers shows three horizontal bars one above another, a
//! two-door cabinet two vertical bars meeting in the middle, and a model whose handles are
//! elsewhere has its doors and drawers elsewhere.

use std::collections::BTreeMap;

use glam::{Affine3A, Vec3};

use crate::geometry::surface_points::surface_points;
use crate::geometry::{GravityBox, TriMesh};
use crate::perception::front_marks::FrontMarks;
use crate::perception::handles::{Front, Handle, HandleKind, find_handles};
use crate::perception::open_doors::{OpenDoor, open_doors};
use crate::perception::open_drawers::{OpenDrawer, open_drawers};
use crate::perception::parts::{
    FrontExtent, PerceivedPart, front_extent, lay_out_parts, lay_out_parts_between,
};

/// The front's points are those within its rectangle grown by this much sideways, metres (a
/// handle near the edge, the box a little tight).
const SIDE_MARGIN_M: f32 = 0.02;
/// ... and not within this distance of the box's top: a worktop overhanging the front by a few
/// centimetres stands out of it like a long bar.
const TOP_MARGIN_M: f32 = 0.03;
/// ... and from this far behind the front plane to this far in front of it, metres.
const BEHIND_M: f32 = 0.08;
const IN_FRONT_M: f32 = 0.1;

/// A predicted handle stands for a perceived one of its kind when their centres are this close,
/// metres ...
pub const SAME_HANDLE_M: f32 = 0.1;
/// ... and, for bars, their directions within this angle (cos of 30 degrees).
const SAME_BAR_COS: f32 = 0.866;

/// Where surface points are sampled on a model to find its handles, metres apart.
const MODEL_SAMPLE_SPACING_M: f32 = 0.01;

/// What the camera saw of an object's front: the plane facing the room, the handles on it (an
/// open drawer's or door's carried back onto it), the rectangle its doors and drawers cover, the
/// parts the handles open there and the drawers and doors standing open.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PerceivedFront {
    pub front: Front,
    pub handles: Vec<Handle>,
    pub open_drawers: Vec<OpenDrawer>,
    pub open_doors: Vec<OpenDoor>,
    pub extent: FrontExtent,
    pub parts: Vec<PerceivedPart>,
    /// Nothing stands out in front of it beyond its handles: no door or drawer is open, nothing
    /// stands before it. An open part hides what is behind it and shows its own edges, so
    /// handles and parts are then less sure.
    pub clear: bool,
}

/// The vertical face of `bbox` that faces most nearly along `facing` (horizontal), as a
/// [`Front`] through its centre, with the face's half width and half height.
pub fn box_front(bbox: &GravityBox, facing: Vec3) -> Option<(Front, f32, f32)> {
    let (sin, cos) = bbox.yaw.sin_cos();
    let x = Vec3::new(cos, sin, 0.0);
    let y = Vec3::new(-sin, cos, 0.0);
    let half = 0.5 * bbox.size;
    let (normal, depth, width) = [(x, half.x, half.y), (-x, half.x, half.y)]
        .into_iter()
        .chain([(y, half.y, half.x), (-y, half.y, half.x)])
        .max_by(|a, b| a.0.dot(facing).total_cmp(&b.0.dot(facing)))?;
    let front = Front::new(bbox.center + normal * depth, normal)?;
    Some((front, width, half.z))
}

/// The front of `bbox` facing along `facing` and the handles on it among `points` (the object's
/// observed surface, world frame). The front plane is where most of the points across the
/// face lie (the mode of their depth in the box, [`FRONT_BIN_M`] bins), not the box's face
/// itself: a box also holds what stands out in front of the front (an open door, a chair's
/// bleeding). The back, against a wall, is not seen; the inside's back, seen through a wide-open
/// door, is told by where the carcass's top ends. The parts are laid out from the handles
/// (`perception::parts`), pulled ones as flaps where `flaps`.
pub fn perceive_front(
    bbox: &GravityBox,
    facing: Vec3,
    points: &[Vec3],
    flaps: bool,
) -> Option<PerceivedFront> {
    let (face, half_width, half_height) = box_front(bbox, facing)?;
    let depth_of_box = 2.0 * face.origin.distance(bbox.center.with_z(face.origin.z));
    let across: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| {
            let l = face.local(*p);
            l.x.abs() <= half_width + SIDE_MARGIN_M && l.y <= half_height - TOP_MARGIN_M
        })
        .collect();
    let plane = front_depth(&face, depth_of_box, &across).unwrap_or(0.0);
    let face_right = [-half_width, half_width];
    let look = |depth: f32| -> Option<(Front, Vec<OpenDrawer>, Vec<OpenDoor>)> {
        let front = Front::new(face.origin + face.normal * depth, face.normal)?;
        let drawers = open_drawers(&front, &across);
        let doors = if flaps {
            Vec::new()
        } else {
            let free: Vec<Vec3> = across
                .iter()
                .copied()
                .filter(|p| !drawers.iter().any(|d| d.holds(&front, *p)))
                .collect();
            open_doors(&front, face_right, &free)
        };
        Some((front, drawers, doors))
    };
    // Behind an open door the inside's back is the largest plane facing the room, at the back
    // of the box: the carcass's front is then where its top (or, above the eye, its bottom)
    // ends. (A plane farther out is a front, an open drawer's included.)
    let at_back = -plane > depth_of_box - BACK_BAND_M;
    let edges = carcass_edges(&face, half_width, half_height, points);
    let edge = edges
        .chosen
        .filter(|edge| at_back && edge - plane > OPEN_FRONT_M);
    // A door standing open turns about the carcass's front edge, wherever the plane is (a door
    // open square showed the shelves inside, 13 cm behind the edge, as the largest plane): of
    // the plane (unless it is the inside's back) and the edges of the top and the bottom, the
    // front is where a door stands open best (its panel running from a hinge there as far as a
    // door reaches, not on into the carcass's side behind it; then the longest).
    let with_door = [edge.is_none().then_some(plane), edges.top, edges.bottom]
        .into_iter()
        .flatten()
        .filter(|d| *d == plane || d - plane > OPEN_FRONT_M)
        .filter_map(look)
        .filter(|(_, _, doors)| !doors.is_empty())
        .max_by_key(|(_, _, doors)| {
            doors
                .iter()
                .map(|d| (usize::from(!d.reaches_cap), d.cells))
                .fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1))
        });
    let (front, open, doors) = match with_door {
        Some(seen) => seen,
        None => look(edge.unwrap_or(plane))?,
    };
    tracing::debug!(
        "front at {:.2} (plane {plane:.2}, carcass edges {edges:?}, box depth {depth_of_box:.2}): \
         {} open drawers, open doors {doors:?}",
        front.local(face.origin).z,
        open.len()
    );
    let opened = |p: &Vec3| {
        open.iter().any(|d| d.holds(&front, *p)) || doors.iter().any(|d| d.holds(&front, *p))
    };
    let on_front: Vec<Vec3> = across
        .iter()
        .copied()
        .filter(|p| (-BEHIND_M..=IN_FRONT_M).contains(&front.local(*p).z))
        .filter(|p| !opened(p))
        .collect();
    let mut handles = find_handles(&front, &on_front);
    // Measured from the closed front, an open drawer's handle stands out by its drawer's travel.
    let shut_handles_out = handles.iter().map(|h| h.depth).fold(0.0, f32::max);
    handles.extend(open.iter().flat_map(|d| d.handles.iter().copied()));
    handles.extend(doors.iter().flat_map(|d| d.handles.iter().copied()));
    let beyond = shut_handles_out + BEYOND_HANDLES_M;
    let in_front = across
        .iter()
        .filter(|p| front.local(**p).z > beyond && !opened(p))
        .count();
    let clear = in_front as f32 <= MAX_IN_FRONT_SHARE * across.len() as f32;
    let face = FrontExtent {
        right: face_right,
        z: [bbox.bottom_z(), bbox.top_z()],
    };
    let extent = with_open_parts(front_extent(&front, face, &on_front), face, &open, &doors);
    let parts = lay_out_parts(&front, extent, &handles, flaps);
    Some(PerceivedFront {
        front,
        handles,
        open_drawers: open,
        open_doors: doors,
        extent,
        parts,
        clear,
    })
}

/// `seen` with what the frames show of its front (`perception::front_marks`): where the map's
/// handles open no part on it (none found, or only the front's edges standing out of a real
/// camera's noisy depth), the handles of its image lay out its parts, split at the gaps the
/// image shows. Where the map's handles open parts they stand: they are measured, the image's
/// are a colour.
pub fn with_marks(seen: PerceivedFront, marks: &FrontMarks, flaps: bool) -> PerceivedFront {
    if !seen.parts.is_empty() || marks.handles.is_empty() {
        return seen;
    }
    let parts = lay_out_parts_between(&seen.front, seen.extent, &marks.handles, flaps, &marks.gaps);
    PerceivedFront {
        handles: marks.handles.clone(),
        parts,
        ..seen
    }
}

/// `extent` grown over the rectangles of the `open` drawers (whose fronts are not on the front
/// plane) and the shut rectangles of the open `doors`, within `face`.
fn with_open_parts(
    extent: FrontExtent,
    face: FrontExtent,
    open: &[OpenDrawer],
    doors: &[OpenDoor],
) -> FrontExtent {
    let rectangles = open
        .iter()
        .map(|d| (d.right, d.z))
        .chain(doors.iter().map(|d| (d.shut_right(), d.z)));
    rectangles.fold(extent, |e, (right, z)| FrontExtent {
        right: [
            e.right[0].min(right[0]).max(face.right[0]),
            e.right[1].max(right[1]).min(face.right[1]),
        ],
        z: [
            e.z[0].min(z[0]).max(face.z[0]),
            e.z[1].max(z[1]).min(face.z[1]),
        ],
    })
}

/// A front is clear when at most this share of the points across it stand out beyond its
/// handles.
const MAX_IN_FRONT_SHARE: f32 = 0.03;

/// A carcass edge this far (metres) in front of the largest plane across the face means the
/// plane is the back of an open inside, not the front: doors stand at most a board in front
/// of the carcass's edge.
const OPEN_FRONT_M: f32 = 0.05;
/// A plane within this distance (metres) of the box's back is the back of its inside.
const BACK_BAND_M: f32 = 0.1;
/// The top and bottom bands are this high, metres ...
const EDGE_BAND_M: f32 = 0.04;
/// ... and tell where the carcass ends with at least this many points.
const MIN_EDGE_POINTS: usize = 20;
/// The edge is the outermost bin ([`EDGE_BIN_M`]) of a band holding at least this share of
/// its fullest bin: a top surface fills its bins alike (a row of points across the whole width
/// in each), the rows of a vertical face in the band (the inside's back, a front) fill one bin
/// a few times over, and the top edge of an open door (a strip a board wide running out of the
/// front) fills its bins with a point or two.
const EDGE_BIN_SHARE: f32 = 0.2;
/// Bins of the edge's search, metres: the map's surface points are about 2 cm apart.
const EDGE_BIN_M: f32 = 0.02;

/// Where the carcass's top and bottom surfaces end towards the front (offsets along
/// `face.normal`, negative inwards), and the one to trust without other evidence.
#[derive(Clone, Copy, Debug)]
struct CarcassEdges {
    top: Option<f32>,
    bottom: Option<f32>,
    /// The top's, or the bottom's where more of that was seen (a wall cabinet above the eye).
    chosen: Option<f32>,
}

/// The edges of the carcass's top surface, seen in the band of points under the box's top, and
/// of its bottom, in the band above the box's bottom; each `None` with too few points.
fn carcass_edges(face: &Front, half_width: f32, half_height: f32, points: &[Vec3]) -> CarcassEdges {
    let band = |top: bool| -> Vec<f32> {
        points
            .iter()
            .map(|p| face.local(*p))
            .filter(|l| l.x.abs() <= half_width)
            .filter(|l| {
                if top {
                    l.y >= half_height - EDGE_BAND_M
                } else {
                    l.y <= EDGE_BAND_M - half_height
                }
            })
            .map(|l| -l.z)
            .collect()
    };
    let (top, bottom) = (band(true), band(false));
    let (top_edge, bottom_edge) = (band_edge(&top), band_edge(&bottom));
    CarcassEdges {
        top: top_edge,
        bottom: bottom_edge,
        chosen: if top.len() >= bottom.len() {
            top_edge
        } else {
            bottom_edge
        },
    }
}

/// Where a band's top (or bottom) surface ends towards the front: the offset (negative inwards)
/// of the outermost bin holding at least [`EDGE_BIN_SHARE`] of the fullest one; `None` with
/// fewer than [`MIN_EDGE_POINTS`].
fn band_edge(inward: &[f32]) -> Option<f32> {
    if inward.len() < MIN_EDGE_POINTS {
        return None;
    }
    let outermost = inward.iter().copied().fold(f32::MAX, f32::min);
    let mut counts: Vec<u32> = Vec::new();
    for d in inward {
        let bin = ((d - outermost) / EDGE_BIN_M) as usize;
        if counts.len() <= bin {
            counts.resize(bin + 1, 0);
        }
        counts[bin] += 1;
    }
    let full = counts.iter().copied().max()? as f32;
    let edge = counts
        .iter()
        .position(|&c| c as f32 >= EDGE_BIN_SHARE * full)?;
    Some(-(outermost + (edge as f32 + 0.5) * EDGE_BIN_M))
}

/// Bins of the front plane's search, metres.
const FRONT_BIN_M: f32 = 0.01;

/// The offset along `face.normal` (from the face, negative inwards) where most of `points`
/// lie, over the box's `depth`; each bin counts with its two neighbours, so a front a little
/// rough or slanted stays one peak. `None` without points.
fn front_depth(face: &Front, depth: f32, points: &[Vec3]) -> Option<f32> {
    let bins = (depth / FRONT_BIN_M).ceil() as usize + 1;
    let mut counts = vec![0u32; bins + 2];
    for p in points {
        let inward = -face.local(*p).z;
        if (-0.5 * FRONT_BIN_M..depth + FRONT_BIN_M).contains(&inward) {
            counts[1 + ((inward / FRONT_BIN_M).round() as usize).min(bins - 1)] += 1;
        }
    }
    let (bin, count) = (1..=bins)
        .map(|b| (b, counts[b - 1] + counts[b] + counts[b + 1]))
        .max_by(|a, b| a.1.cmp(&b.1).then(b.0.cmp(&a.0)))?;
    (count > 0).then(|| -((bin - 1) as f32) * FRONT_BIN_M)
}

/// Points standing out this far beyond the front plane's handles (metres) are no part of the
/// closed object: an open door or drawer, or something in front of it.
const BEYOND_HANDLES_M: f32 = 0.02;
/// The box is cut back to the front only when that moves its face at least this far (metres) ...
const MIN_CUT_M: f32 = 0.03;
/// ... and leaves at least this share of the points no open part holds: a front plane found
/// deep inside the box (the back of an open cabinet's inside) must not cut off the real front.
const MIN_KEPT_SHARE: f32 = 0.6;

/// `bbox` cut back to the perceived `front` (the front plane, its handles and a margin in front
/// of it), and the `points` left within it, less what belongs to an open drawer; `None` when
/// there is nothing to cut, or too much.
pub fn cut_to_front(
    bbox: &GravityBox,
    seen: &PerceivedFront,
    points: &[Vec3],
) -> Option<(GravityBox, Vec<Vec3>)> {
    let handles_out = seen.handles.iter().map(|h| h.depth).fold(0.0, f32::max);
    let limit = handles_out + BEYOND_HANDLES_M;
    let face_out = bbox
        .corners()
        .iter()
        .map(|c| seen.front.local(*c).z)
        .fold(f32::MIN, f32::max);
    if face_out - limit < MIN_CUT_M {
        return None;
    }
    let opened = |p: &Vec3| {
        seen.open_drawers.iter().any(|d| d.holds(&seen.front, *p))
            || seen.open_doors.iter().any(|d| d.holds(&seen.front, *p))
    };
    let closed: Vec<Vec3> = points.iter().copied().filter(|p| !opened(p)).collect();
    let kept: Vec<Vec3> = closed
        .iter()
        .copied()
        .filter(|p| seen.front.local(*p).z <= limit)
        .collect();
    if (kept.len() as f32) < MIN_KEPT_SHARE * closed.len() as f32 {
        return None;
    }
    let cut = face_out - limit;
    let world_from_box = bbox.world_from_box();
    let along = world_from_box
        .inverse()
        .transform_vector3(seen.front.normal);
    let mut cut_box = *bbox;
    cut_box.size -= (along * cut).abs();
    cut_box.center -= seen.front.normal * (0.5 * cut);
    Some((cut_box, kept))
}

/// The box and points a model is fitted to: `bbox` and `points` cut back to the perceived
/// `front` where it calls for a cut ([`cut_to_front`]), else as they are.
pub fn fitted_to_front<'a>(
    bbox: &GravityBox,
    front: Option<&PerceivedFront>,
    points: &'a [Vec3],
) -> (GravityBox, std::borrow::Cow<'a, [Vec3]>) {
    match front.and_then(|f| cut_to_front(bbox, f, points)) {
        Some((cut, kept)) => (cut, std::borrow::Cow::Owned(kept)),
        None => (*bbox, std::borrow::Cow::Borrowed(points)),
    }
}

/// The handles on the front of a model in the canonical frame (front facing -y, the origin at
/// the bottom centre of its box `size`), found as the perception finds them on what a camera
/// straight in front of the model sees of `visual` (its look with doors and drawers closed):
/// the frontmost surface point in each cell of a grid across the front.
pub fn model_handles(visual: &TriMesh, size: Vec3) -> Vec<Handle> {
    let bbox = GravityBox {
        center: Vec3::new(0.0, 0.0, 0.5 * size.z),
        yaw: 0.0,
        size,
    };
    let facing = visual.filtered(|[a, b, c]| (b - a).cross(c - a).normalize_or_zero().y < 0.0);
    let mut frontmost: BTreeMap<(i32, i32), Vec3> = BTreeMap::new();
    for p in surface_points(&facing, MODEL_SAMPLE_SPACING_M).points {
        let cell = (
            (p.x / MODEL_SAMPLE_SPACING_M).floor() as i32,
            (p.z / MODEL_SAMPLE_SPACING_M).floor() as i32,
        );
        frontmost
            .entry(cell)
            .and_modify(|q| {
                if p.y < q.y {
                    *q = p;
                }
            })
            .or_insert(p);
    }
    let seen: Vec<Vec3> = frontmost.into_values().collect();
    perceive_front(&bbox, Vec3::NEG_Y, &seen, false).map_or_else(Vec::new, |f| f.handles)
}

/// `handle` carried by `frame` (a placed model's world-from-model, scale included).
pub fn placed_handle(frame: &Affine3A, handle: &Handle) -> Handle {
    Handle {
        center: frame.transform_point3(handle.center),
        axis: frame
            .transform_vector3(handle.axis)
            .try_normalize()
            .unwrap_or(handle.axis),
        ..*handle
    }
}

/// How far `predicted` handles (a placed model's) disagree with the `perceived` ones, in [0, 1]:
/// one minus the share of both lists that pair up (a perceived and a predicted handle of the
/// same kind, bars along the same direction, centres within [`SAME_HANDLE_M`]; closest pairs
/// first). 0 when nothing was perceived: handles the camera did not make out say nothing.
pub fn layout_error(perceived: &[Handle], predicted: &[Handle]) -> f32 {
    if perceived.is_empty() {
        return 0.0;
    }
    let mut pairs: Vec<(f32, usize, usize)> = Vec::new();
    for (i, p) in perceived.iter().enumerate() {
        for (j, q) in predicted.iter().enumerate() {
            let alike = p.kind == q.kind
                && (p.kind == HandleKind::Knob || p.axis.dot(q.axis).abs() >= SAME_BAR_COS);
            let distance = p.center.distance(q.center);
            if alike && distance <= SAME_HANDLE_M {
                pairs.push((distance, i, j));
            }
        }
    }
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let (mut used_p, mut used_q) = (vec![false; perceived.len()], vec![false; predicted.len()]);
    let mut matched = 0;
    for (_, i, j) in pairs {
        if !used_p[i] && !used_q[j] {
            used_p[i] = true;
            used_q[j] = true;
            matched += 1;
        }
    }
    1.0 - 2.0 * matched as f32 / (perceived.len() + predicted.len()) as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::library::storage::{cabinet_drawers, cabinet_two_doors};
    use crate::perception::parts::{PartKind, Side};

    fn size() -> Vec3 {
        Vec3::new(0.6, 0.45, 0.8)
    }

    /// A flat panel sampled every 2 cm: `corner + 0.02 (i u + j v)` for i up to `n_u` and j up
    /// to `n_v`.
    fn panel(corner: Vec3, u: Vec3, n_u: usize, v: Vec3, n_v: usize) -> Vec<Vec3> {
        (0..=n_u)
            .flat_map(|i| (0..=n_v).map(move |j| corner + 0.02 * (i as f32 * u + j as f32 * v)))
            .collect()
    }

    #[test]
    fn the_front_is_the_box_face_along_the_facing() {
        let bbox = GravityBox {
            center: Vec3::new(1.0, 2.0, 0.4),
            yaw: 0.3,
            size: size(),
        };
        let facing = Vec3::new(-(0.3f32).sin(), 0.3f32.cos(), 0.0);
        let (front, half_width, half_height) = box_front(&bbox, facing).expect("front");
        assert!(front.normal.dot(facing) > 0.999);
        assert!((front.origin.distance(bbox.center) - 0.225).abs() < 1e-5);
        assert!((half_width - 0.3).abs() < 1e-6 && (half_height - 0.4).abs() < 1e-6);
    }

    /// A front at y = 0 (facing -y), 0.6 x 0.8 m, with a door standing 30 cm out of it at its
    /// right edge.
    fn front_with_open_door() -> Vec<Vec3> {
        let mut points = panel(Vec3::new(-0.3, 0.0, 0.0), Vec3::X, 30, Vec3::Z, 40);
        points.extend(panel(
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::NEG_Y,
            15,
            Vec3::Z,
            40,
        ));
        points
    }

    #[test]
    fn the_front_plane_is_where_the_points_are_not_where_an_open_door_ends_the_box() {
        // A front at y = 0 (facing -y), sampled every 2 cm over 0.6 x 0.8 m, with a panel
        // standing 30 cm out of it at its right edge (an open door): the box reaches y = -0.3.
        let mut points = front_with_open_door();
        let bar = (0..=10).map(|i| Vec3::new(0.2, -0.025, 0.3 + 0.02 * i as f32));
        points.extend(bar.clone().chain(bar.map(|p| p + Vec3::Y * 0.01)));
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        let seen = perceive_front(&bbox, Vec3::NEG_Y, &points, false).expect("front");
        assert!(seen.front.origin.y.abs() < 0.011, "{:?}", seen.front);
        assert_eq!(seen.handles.len(), 1, "{:?}", seen.handles);
        assert!(seen.handles[0].axis.z.abs() > 0.99);
    }

    #[test]
    fn behind_a_wide_open_door_the_front_is_where_the_top_ends() {
        // A cabinet 0.6 wide, 0.45 deep and 0.8 high facing -y with its front at y = 0: its
        // top, its back inside (at y = 0.43) seen through the open doorway, and its door open
        // 90 degrees, standing out 0.6 m from the left edge.
        let mut points = panel(Vec3::new(-0.3, 0.43, 0.0), Vec3::X, 30, Vec3::Z, 40);
        points.extend(panel(Vec3::new(-0.3, 0.0, 0.8), Vec3::X, 30, Vec3::Y, 22));
        points.extend(panel(
            Vec3::new(-0.3, 0.0, 0.0),
            Vec3::NEG_Y,
            30,
            Vec3::Z,
            40,
        ));
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        let seen = perceive_front(&bbox, Vec3::NEG_Y, &points, false).expect("front");
        assert!(seen.front.origin.y.abs() < 0.021, "{:?}", seen.front);
    }

    #[test]
    fn a_box_reaching_over_an_open_door_is_cut_back_to_the_front() {
        // The front with its door open 30 cm out, and its back 0.45 m behind it.
        let mut points = front_with_open_door();
        points.extend(panel(Vec3::new(-0.3, 0.45, 0.0), Vec3::X, 30, Vec3::Z, 40));
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        assert!((bbox.size.y - 0.75).abs() < 1e-4);
        let seen = perceive_front(&bbox, Vec3::NEG_Y, &points, false).expect("front");
        let (cut, kept) = cut_to_front(&bbox, &seen, &points).expect("a cut");
        // Cut back to 2 cm in front of the front (no handles here).
        assert!((cut.size.y - 0.47).abs() < 0.011, "{cut:?}");
        assert!((cut.center.y - 0.215).abs() < 0.006, "{cut:?}");
        assert!(kept.iter().all(|p| p.y >= -0.021));
        assert!(kept.len() >= 2 * 31 * 41);
        // Cut once, it needs no second cut.
        assert!(cut_to_front(&cut, &seen, &kept).is_none());
    }

    #[test]
    fn a_door_open_square_stands_on_the_top_s_edge_and_is_no_part_of_the_carcass() {
        // A cupboard 0.6 wide, 0.34 deep and 0.7 high facing -y, its front at y = 0: its top,
        // its inside's back (the largest plane across the face), its right side seen along
        // its length, an inside floor recessed 14 cm (a bottom band holding more points than
        // the top, whose edge lies inside), and its door hinged on the right (+x, seen from the
        // room) open 90 degrees with a vertical bar on its outer face near its free edge.
        let mut points = panel(Vec3::new(-0.3, 0.34, 0.0), Vec3::X, 30, Vec3::Z, 35);
        points.extend(panel(Vec3::new(-0.3, 0.0, 0.7), Vec3::X, 30, Vec3::Y, 17));
        points.extend(panel(Vec3::new(0.3, 0.0, 0.0), Vec3::Y, 17, Vec3::Z, 35));
        for layer in 0..3 {
            let z = 0.005 * layer as f32;
            points.extend(panel(Vec3::new(-0.3, 0.14, z), Vec3::X, 30, Vec3::Y, 10));
        }
        points.extend(panel(
            Vec3::new(0.3, -0.02, 0.0),
            Vec3::NEG_Y,
            29,
            Vec3::Z,
            35,
        ));
        for j in 0..=8 {
            points.push(Vec3::new(0.33, -0.56, 0.3 + 0.02 * j as f32));
            points.push(Vec3::new(0.335, -0.56, 0.3 + 0.02 * j as f32));
        }
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        let seen = perceive_front(&bbox, Vec3::NEG_Y, &points, false).expect("front");
        assert!(seen.front.origin.y.abs() < 0.021, "{:?}", seen.front);
        assert_eq!(seen.open_doors.len(), 1, "{:?}", seen.open_doors);
        let door = &seen.open_doors[0];
        assert_eq!(door.hinge, Side::Right, "{door:?}");
        assert!((door.angle.to_degrees() - 90.0).abs() < 3.0, "{door:?}");
        assert!((door.width - 0.6).abs() < 0.05, "{door:?}");
        // The bar turned back onto the shut front opens a door hinged on the right.
        assert!(
            seen.parts
                .iter()
                .any(|p| p.kind == PartKind::Door { hinge: Side::Right }),
            "{:?} {:?}",
            seen.parts,
            seen.handles
        );
        // The box (0.94 deep) is cut back to the front and its handles' depth, the door's
        // points (0.6 out) left out.
        let (cut, kept) = cut_to_front(&bbox, &seen, &points).expect("a cut");
        assert!(cut.size.y < 0.42, "{cut:?}");
        assert!(kept.iter().all(|p| p.y >= -0.07), "{cut:?}");
    }

    #[test]
    fn a_single_door_fridge_shows_the_bar_of_its_door() {
        let db = crate::cad::db::database::CadDatabase::parametric();
        let fridge = db.get("fridge_01").expect("fridge");
        assert_eq!(fridge.handles.len(), 1, "{:?}", fridge.handles);
        let bar = fridge.handles[0];
        assert!(
            bar.kind == HandleKind::Bar && bar.axis.z.abs() > 0.99,
            "{bar:?}"
        );
        // Hinged on the right (seen from the room, +x is right): the bar is on the left.
        assert!(bar.center.x < 0.0, "{bar:?}");
    }

    #[test]
    fn a_chest_shows_three_horizontal_bars_and_two_doors_two_vertical_ones() {
        let drawers = cabinet_drawers("d", size());
        let handles = model_handles(&drawers.merged_visual_mesh(&[]), drawers.size);
        assert_eq!(handles.len(), 3, "{handles:?}");
        assert!(
            handles
                .iter()
                .all(|h| h.kind == HandleKind::Bar && h.axis.x.abs() > 0.99),
            "{handles:?}"
        );
        let doors = cabinet_two_doors("t", size());
        let door_handles = model_handles(&doors.merged_visual_mesh(&[]), doors.size);
        assert_eq!(door_handles.len(), 2, "{door_handles:?}");
        assert!(door_handles.iter().all(|h| h.axis.z.abs() > 0.99));
        // The chest's handles say nothing like the doors' do, and agree with themselves.
        assert_eq!(layout_error(&handles, &handles), 0.0);
        assert_eq!(layout_error(&handles, &door_handles), 1.0);
        assert_eq!(layout_error(&[], &door_handles), 0.0);
        // A model carried into the world keeps its handles where they are on it.
        let frame = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(1.0),
            Vec3::new(2.0, 1.0, 0.0),
        );
        let placed: Vec<Handle> = handles.iter().map(|h| placed_handle(&frame, h)).collect();
        assert_eq!(layout_error(&placed, &placed), 0.0);
        assert_eq!(layout_error(&placed, &handles), 1.0);
    }
}
