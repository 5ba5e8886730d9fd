//! The doors, drawers and flaps of a front, laid out from the handles perceived on it (issue 36,
//! section 1). Rusu et al. (2008) tell a part's type by its handle: a vertical bar (or a knob
//! near a side) opens a door hinged on the edge away from it, a horizontal bar (or a knob in
//! the middle) pulls out a drawer. The grooves between fronts (4 mm here, a few millimetres in
//! real kitchens) are below the map's 2 cm surface spacing, so the handles also give the layout:
//! each handle opens one part, handles at one height are a row of parts side by side, and the
//! rows stack up the front between its perceived bottom and top edges.
//!
//! Bevy-free: works in the front's frame (`Front::local`: along the front to the right, world
//! height, out of the front).

use glam::Vec3;
use serde::Serialize;

use crate::perception::handles::{Front, Handle, HandleKind};

/// Which side of a part its hinge runs along, seen from the room.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Left,
    Right,
}

/// How a perceived part moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum PartKind {
    /// Turns about a vertical hinge along its `hinge` edge.
    Door { hinge: Side },
    /// Slides out along the front's normal.
    Drawer,
    /// Turns down about a horizontal hinge along its bottom edge (an oven's or a dishwasher's
    /// door).
    Flap,
}

/// The rectangle the parts of a front cover, in the front's frame: `right` along it (0 at the
/// front's origin), `z` in world height.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrontExtent {
    pub right: [f32; 2],
    pub z: [f32; 2],
}

impl FrontExtent {
    fn width(&self) -> f32 {
        self.right[1] - self.right[0]
    }
}

/// One door, drawer or flap: its kind, its front's rectangle (as [`FrontExtent`]) and the
/// handle that opens it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PerceivedPart {
    #[serde(flatten)]
    pub kind: PartKind,
    pub right: [f32; 2],
    pub z: [f32; 2],
    pub handle: Handle,
}

/// Classes whose doors open down as flaps where a horizontal bar runs along their top.
pub fn opens_as_flap(class: &str) -> bool {
    matches!(class, "oven" | "dishwasher")
}

/// Points this close to the front plane (metres) are the front itself.
const ON_FRONT_M: f32 = 0.015;
/// The extent is taken between these quantiles of the front's points, so that a few stray
/// points do not widen it.
const EXTENT_QUANTILE: f32 = 0.02;
/// With fewer points on the front than this, its extent is the box's face.
const MIN_FRONT_POINTS: usize = 30;

/// Where the fronts of the parts end: the extent of the points lying on the front plane, within
/// `face` (the box's face in the front's frame, the fallback). A plinth set back under the
/// fronts and a worktop standing out over them are not on the plane.
pub fn front_extent(front: &Front, face: FrontExtent, points: &[Vec3]) -> FrontExtent {
    let on: Vec<Vec3> = points
        .iter()
        .map(|p| front.local(*p))
        .filter(|l| l.z.abs() <= ON_FRONT_M)
        .filter(|l| (face.right[0]..=face.right[1]).contains(&l.x))
        .filter(|l| (face.z[0]..=face.z[1]).contains(&(l.y + front.origin.z)))
        .collect();
    if on.len() < MIN_FRONT_POINTS {
        return face;
    }
    let range = |v: Vec<f32>| quantile_range(v, EXTENT_QUANTILE);
    FrontExtent {
        right: range(on.iter().map(|l| l.x).collect()),
        z: range(on.iter().map(|l| l.y + front.origin.z).collect()),
    }
}

/// The `q` and `1 - q` quantiles of `values` (not empty): where a surface's points end, a few
/// stray ones left out.
pub fn quantile_range(mut values: Vec<f32>, q: f32) -> [f32; 2] {
    values.sort_by(f32::total_cmp);
    let at = |q: f32| values[((values.len() - 1) as f32 * q).round() as usize];
    [at(q), at(1.0 - q)]
}

/// What a handle says of the part it opens.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    /// Near a door's free edge: a vertical bar, or a knob near a side of the front.
    Edge,
    /// In the middle of a drawer, or along a flap's top: a horizontal bar, a knob.
    Pull,
}

/// Handles whose centres are this far apart in height (metres) or more open parts in different
/// rows.
const ROW_GAP_M: f32 = 0.1;
/// A knob this close to a side of the front (share of its width) opens a door.
const KNOB_EDGE_SHARE: f32 = 0.15;
/// Two knobs this close across the middle (share of the width) are the free edges of two doors
/// meeting there.
const MEETING_KNOBS_SHARE: f32 = 0.2;
/// A part's edge stays this far (metres) from the handles of its neighbours.
const HANDLE_CLEARANCE_M: f32 = 0.02;
/// A pulled part this high or more on a class with flaps is a flap; lower, a drawer (an oven's
/// drawer under its door).
const MIN_FLAP_HEIGHT_M: f32 = 0.25;
/// On any class, a part higher than wide pulled by a bar in the top quarter is a flap (Rusu et
/// al.'s rule) ...
const FLAP_TOP_SHARE: f32 = 0.25;
/// ... unless it starts this low (metres above the floor) or lower: a base unit's door.
const FLOOR_LEVEL_M: f32 = 0.25;
/// Handles stand 2 to 5 cm out of a front: a cluster reaching farther (to the end of the
/// handles' band, 8 cm) is more likely the edge of an open door or drawer crossing the band, and
/// lays out no part.
const MAX_PART_HANDLE_OUT_M: f32 = 0.06;
/// Handles sit on their parts, a few centimetres in from the edges: one centred within this
/// distance (metres) of the extent's edge, or beyond it, is more likely the edge of the carcass
/// or of a worktop (a wall unit seen from below shows its top edge as a knob) and lays out
/// nothing.
const EDGE_MARGIN_M: f32 = 0.02;

struct Placed {
    handle: Handle,
    right: f32,
    role: Role,
}

impl Placed {
    /// The handle's reach up and down from its centre, metres.
    fn half_height(&self) -> f32 {
        match self.handle.kind {
            HandleKind::Bar => 0.5 * self.handle.length * self.handle.axis.z.abs(),
            HandleKind::Knob => 0.5 * self.handle.length,
        }
    }
}

/// The parts `handles` open on `front`, covering `extent` in rows (bottom to top) of parts side
/// by side (left to right); a pulled part is a flap where `flaps` and it is high enough.
pub fn lay_out_parts(
    front: &Front,
    extent: FrontExtent,
    handles: &[Handle],
    flaps: bool,
) -> Vec<PerceivedPart> {
    lay_out_parts_between(front, extent, handles, flaps, &Gaps::default())
}

/// The gaps seen between a front's parts: vertical ones as distances along it (as
/// `Front::local`'s x), horizontal ones as heights, each in increasing order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Gaps {
    pub vertical: Vec<f32>,
    pub horizontal: Vec<f32>,
}

/// As [`lay_out_parts`], with the `gaps` seen: each handle's part runs between the nearest
/// vertical gaps beyond its handle's ends (a door whose handle was missed stays a panel of its
/// own instead of widening its neighbour), and rows meet at the horizontal gap nearest halfway
/// between them.
pub fn lay_out_parts_between(
    front: &Front,
    extent: FrontExtent,
    handles: &[Handle],
    flaps: bool,
    gaps: &Gaps,
) -> Vec<PerceivedPart> {
    let width = extent.width();
    if width <= 0.0 || extent.z[1] <= extent.z[0] {
        return Vec::new();
    }
    let middle = 0.5 * (extent.right[0] + extent.right[1]);
    let mut placed: Vec<Placed> = handles
        .iter()
        .filter(|h| h.depth <= MAX_PART_HANDLE_OUT_M)
        .filter(|h| {
            let (right, z) = (front.local(h.center).x, h.center.z);
            right >= extent.right[0] + EDGE_MARGIN_M
                && right <= extent.right[1] - EDGE_MARGIN_M
                && z >= extent.z[0] + EDGE_MARGIN_M
                && z <= extent.z[1] - EDGE_MARGIN_M
        })
        .map(|h| {
            let right = front.local(h.center).x;
            let role = match h.kind {
                HandleKind::Bar if h.axis.z.abs() >= std::f32::consts::FRAC_1_SQRT_2 => Role::Edge,
                HandleKind::Bar => Role::Pull,
                HandleKind::Knob => {
                    let to_side = (right - extent.right[0]).min(extent.right[1] - right);
                    if to_side <= KNOB_EDGE_SHARE * width {
                        Role::Edge
                    } else {
                        Role::Pull
                    }
                }
            };
            Placed {
                handle: *h,
                right,
                role,
            }
        })
        .collect();
    placed.sort_by(|a, b| a.handle.center.z.total_cmp(&b.handle.center.z));
    let mut rows: Vec<Vec<Placed>> = Vec::new();
    for p in placed {
        match rows.last_mut() {
            Some(row)
                if p.handle.center.z - row.last().map_or(f32::MIN, |q| q.handle.center.z)
                    < ROW_GAP_M =>
            {
                row.push(p)
            }
            _ => rows.push(vec![p]),
        }
    }
    for row in &mut rows {
        row.sort_by(|a, b| a.right.total_cmp(&b.right));
        meet_in_the_middle(row, middle, width);
    }
    let bounds = row_bounds(&rows, extent, flaps, &gaps.horizontal);
    rows.iter()
        .zip(bounds.windows(2))
        .flat_map(|(row, z)| {
            let z = [z[0], z[1]];
            // Doors pulled at their top pair up to meet in the middle: the first of a row hinges
            // on its left, the next on its right, and so on.
            let mut pulled_doors = 0;
            column_bounds(row, extent, &gaps.vertical)
                .into_iter()
                .zip(row)
                .map(|(right, p)| {
                    let kind = match p.role {
                        Role::Edge if p.right - right[0] > right[1] - p.right => {
                            PartKind::Door { hinge: Side::Left }
                        }
                        Role::Edge => PartKind::Door { hinge: Side::Right },
                        Role::Pull => match pulled_kind(p, right, z, flaps) {
                            Pulled::Flap => PartKind::Flap,
                            Pulled::Drawer => PartKind::Drawer,
                            Pulled::Door => {
                                pulled_doors += 1;
                                let hinge = if pulled_doors % 2 == 1 {
                                    Side::Left
                                } else {
                                    Side::Right
                                };
                                PartKind::Door { hinge }
                            }
                        },
                    };
                    PerceivedPart {
                        kind,
                        right,
                        z,
                        handle: p.handle,
                    }
                })
                .collect::<Vec<_>>()
        })
        .collect()
}

/// How a part pulled by its handle opens.
enum Pulled {
    Flap,
    Drawer,
    /// A tall part at floor level with its bar along its top: a base unit's door (a flap there
    /// would open onto the floor). Its hinge side is not seen: a centred handle says nothing.
    Door,
}

/// How the pulled part `right` by `z` opens: as a flap on a class with `flaps` when it is high
/// enough, on any other when it is higher than wide with its bar along its top quarter (Rusu et
/// al.'s rule) unless it reaches down to the floor, where it is a door; else as a drawer.
fn pulled_kind(p: &Placed, right: [f32; 2], z: [f32; 2], flaps: bool) -> Pulled {
    let (width, height) = (right[1] - right[0], z[1] - z[0]);
    let near_top = p.handle.center.z >= z[1] - FLAP_TOP_SHARE * height;
    let tall_with_top_bar = p.handle.kind == HandleKind::Bar && height > width && near_top;
    if flaps && height >= MIN_FLAP_HEIGHT_M {
        Pulled::Flap
    } else if tall_with_top_bar && z[0] <= FLOOR_LEVEL_M {
        Pulled::Door
    } else if tall_with_top_bar {
        Pulled::Flap
    } else {
        Pulled::Drawer
    }
}

/// Two knobs of a row straddling the front's middle close to it are the free edges of two doors
/// meeting there.
fn meet_in_the_middle(row: &mut [Placed], middle: f32, width: f32) {
    if let [a, b] = row
        && a.handle.kind == HandleKind::Knob
        && b.handle.kind == HandleKind::Knob
        && a.right < middle
        && b.right > middle
        && b.right - a.right <= MEETING_KNOBS_SHARE * width
    {
        a.role = Role::Edge;
        b.role = Role::Edge;
    }
}

/// The heights where the rows meet, with the extent's bottom and top at the ends. A row of pulls
/// at the bottom or (without flaps) the top holds drawers with their pulls in the middle, so it
/// reaches as far past its pulls as the extent's edge lies on their other side; rows in between
/// meet halfway between their handles. Each bound keeps clear of both rows' handles.
fn row_bounds(rows: &[Vec<Placed>], extent: FrontExtent, flaps: bool, gaps: &[f32]) -> Vec<f32> {
    let mean_z =
        |row: &[Placed]| row.iter().map(|p| p.handle.center.z).sum::<f32>() / row.len() as f32;
    let pulls = |row: &[Placed]| row.iter().all(|p| p.role == Role::Pull);
    let last = rows.len().saturating_sub(1);
    let mut bounds = vec![extent.z[0]];
    for (k, pair) in rows.windows(2).enumerate() {
        let (lower, upper) = (&pair[0], &pair[1]);
        let (zl, zu) = (mean_z(lower), mean_z(upper));
        let reflected = if k == 0 && pulls(lower) {
            Some(2.0 * zl - extent.z[0])
        } else if k + 1 == last && pulls(upper) && !flaps {
            Some(2.0 * zu - extent.z[1])
        } else {
            None
        };
        let lowest = lower
            .iter()
            .map(|p| p.handle.center.z + p.half_height())
            .fold(f32::MIN, f32::max)
            + HANDLE_CLEARANCE_M;
        let highest = upper
            .iter()
            .map(|p| p.handle.center.z - p.half_height())
            .fold(f32::MAX, f32::min)
            - HANDLE_CLEARANCE_M;
        let halfway = 0.5 * (zl + zu);
        let bound = match (nearest_between(gaps, lowest, highest, halfway), reflected) {
            (Some(gap), _) => gap,
            (None, Some(b)) if (lowest..=highest).contains(&b) => b,
            _ if lowest <= highest => halfway.clamp(lowest, highest),
            _ => halfway,
        };
        bounds.push(bound);
    }
    bounds.push(extent.z[1]);
    bounds
}

/// Where the parts of a row (sorted left to right) lie, each as [left, right]: between the
/// `gaps` seen, where there are any ([`columns_at_gaps`]); else side by side across the extent,
/// of equal widths, as units are built, when each handle then lies on its own part, or meeting
/// halfway between neighbouring handles.
fn column_bounds(row: &[Placed], extent: FrontExtent, gaps: &[f32]) -> Vec<[f32; 2]> {
    if !gaps.is_empty() {
        return columns_at_gaps(row, extent, gaps);
    }
    let n = row.len();
    let step = extent.width() / n as f32;
    let equal: Vec<f32> = (0..=n).map(|k| extent.right[0] + step * k as f32).collect();
    let each_on_its_own = row
        .iter()
        .enumerate()
        .all(|(k, p)| (equal[k]..=equal[k + 1]).contains(&p.right));
    if each_on_its_own {
        return equal.windows(2).map(|w| [w[0], w[1]]).collect();
    }
    let mut bounds = vec![extent.right[0]];
    bounds.extend(row.windows(2).map(|w| 0.5 * (w[0].right + w[1].right)));
    bounds.push(extent.right[1]);
    bounds.windows(2).map(|w| [w[0], w[1]]).collect()
}

/// The handle's reach along the front either way from its centre, metres.
fn half_width(p: &Placed) -> f32 {
    match p.handle.kind {
        HandleKind::Bar => 0.5 * p.handle.length * p.handle.axis.truncate().length(),
        HandleKind::Knob => 0.5 * p.handle.length,
    }
}

/// Where the parts of a row lie with `gaps` seen (increasing): each handle's part runs between
/// the nearest gaps beyond its handle's ends, or to the extent's sides; neighbours with no gap
/// between them meet halfway between their handles.
fn columns_at_gaps(row: &[Placed], extent: FrontExtent, gaps: &[f32]) -> Vec<[f32; 2]> {
    let beside = |p: &Placed| {
        let reach = half_width(p) + HANDLE_CLEARANCE_M;
        let left = gaps
            .iter()
            .copied()
            .filter(|g| *g > extent.right[0] && *g < p.right - reach)
            .fold(extent.right[0], f32::max);
        let right = gaps
            .iter()
            .copied()
            .filter(|g| *g > p.right + reach && *g < extent.right[1])
            .fold(extent.right[1], f32::min);
        [left, right]
    };
    let mut columns: Vec<[f32; 2]> = row.iter().map(beside).collect();
    for k in 1..row.len() {
        if columns[k][0] < columns[k - 1][1] {
            let halfway = 0.5 * (row[k - 1].right + row[k].right);
            columns[k - 1][1] = halfway;
            columns[k][0] = halfway;
        }
    }
    columns
}

/// The one of `gaps` within `lowest..=highest` nearest to `target`.
fn nearest_between(gaps: &[f32], lowest: f32, highest: f32, target: f32) -> Option<f32> {
    gaps.iter()
        .copied()
        .filter(|g| (lowest..=highest).contains(g))
        .min_by(|a, b| (a - target).abs().total_cmp(&(b - target).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A front facing -y through the origin (right is +x), 1 m wide, from 0.1 m to 0.9 m high.
    fn front() -> (Front, FrontExtent) {
        let front = Front::new(Vec3::new(0.0, 0.0, 0.5), -Vec3::Y).expect("front");
        (
            front,
            FrontExtent {
                right: [-0.5, 0.5],
                z: [0.1, 0.9],
            },
        )
    }

    fn bar(x: f32, z: f32, vertical: bool) -> Handle {
        Handle {
            kind: HandleKind::Bar,
            center: Vec3::new(x, -0.02, z),
            axis: if vertical { Vec3::Z } else { Vec3::X },
            length: 0.2,
            depth: 0.025,
        }
    }

    fn knob(x: f32, z: f32) -> Handle {
        Handle {
            kind: HandleKind::Knob,
            center: Vec3::new(x, -0.02, z),
            axis: Vec3::NEG_Y,
            length: 0.03,
            depth: 0.025,
        }
    }

    #[test]
    fn a_base_run_pulled_at_the_top_is_doors_in_pairs_split_at_the_gaps_seen() {
        // Four 0.45 m doors from x = -0.9 to 0.9, from the plinth (0.1 m) to 0.85 m, with
        // horizontal bars along their tops; the third's bar was missed. The gaps are seen
        // (the third door's edges included) and the middle of two handles is not a gap.
        let front = Front::new(Vec3::new(0.0, 0.0, 0.5), -Vec3::Y).expect("front");
        let extent = FrontExtent {
            right: [-0.9, 0.9],
            z: [0.1, 0.85],
        };
        let bars = [
            bar(-0.675, 0.8, false),
            bar(-0.225, 0.8, false),
            bar(0.675, 0.8, false),
        ];
        let gaps = Gaps {
            vertical: vec![-0.45, 0.0, 0.45],
            horizontal: Vec::new(),
        };
        let parts = lay_out_parts_between(&front, extent, &bars, false, &gaps);
        let laid: Vec<(PartKind, [f32; 2])> = parts.iter().map(|p| (p.kind, p.right)).collect();
        assert_eq!(
            laid,
            [
                (PartKind::Door { hinge: Side::Left }, [-0.9, -0.45]),
                (PartKind::Door { hinge: Side::Right }, [-0.45, 0.0]),
                (PartKind::Door { hinge: Side::Left }, [0.45, 0.9]),
            ]
        );
        assert!(parts.iter().all(|p| p.z == [0.1, 0.85]));
        // Without the gaps the third door's width goes to its neighbours (equal widths).
        let parts = lay_out_parts(&front, extent, &bars, false);
        assert_eq!(parts.len(), 3);
        assert!((parts[1].right[1] - 0.3).abs() < 1e-4, "{parts:?}");
        // Lifted off the floor (a wall unit), the same front opens as flaps (Rusu et al.).
        let high = FrontExtent {
            right: extent.right,
            z: [1.4, 2.15],
        };
        let lifted: Vec<Handle> = bars
            .iter()
            .map(|h| Handle {
                center: h.center + Vec3::Z * 1.3,
                ..*h
            })
            .collect();
        let parts = lay_out_parts_between(&front, high, &lifted, false, &gaps);
        assert!(parts.iter().all(|p| p.kind == PartKind::Flap), "{parts:?}");
    }

    #[test]
    fn two_vertical_bars_meeting_in_the_middle_are_two_doors_hinged_outside() {
        let (front, extent) = front();
        let parts = lay_out_parts(
            &front,
            extent,
            &[bar(0.06, 0.5, true), bar(-0.06, 0.5, true)],
            false,
        );
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].kind, PartKind::Door { hinge: Side::Left });
        assert_eq!(parts[1].kind, PartKind::Door { hinge: Side::Right });
        assert_eq!(parts[0].right, [-0.5, 0.0]);
        assert_eq!(parts[1].right, [0.0, 0.5]);
        assert!(parts.iter().all(|p| p.z == [0.1, 0.9]));
    }

    #[test]
    fn three_horizontal_bars_stacked_are_three_drawers_of_the_full_width() {
        let (front, extent) = front();
        let third = 0.8 / 3.0;
        let bars: Vec<Handle> = (0..3)
            .map(|k| bar(0.0, 0.1 + third * (k as f32 + 0.5), false))
            .collect();
        let parts = lay_out_parts(&front, extent, &bars, false);
        assert_eq!(parts.len(), 3);
        for (k, p) in parts.iter().enumerate() {
            assert_eq!(p.kind, PartKind::Drawer);
            assert_eq!(p.right, [-0.5, 0.5]);
            assert!((p.z[0] - (0.1 + third * k as f32)).abs() < 1e-4, "{p:?}");
            assert!(
                (p.z[1] - (0.1 + third * (k + 1) as f32)).abs() < 1e-4,
                "{p:?}"
            );
        }
    }

    #[test]
    fn a_drawer_above_a_door_ends_as_far_under_its_bar_as_the_top_is_above_it() {
        let (front, extent) = front();
        // A drawer 0.8..0.9 (bar at 0.85) over a door with its bar near the left: hinged right.
        let parts = lay_out_parts(
            &front,
            extent,
            &[bar(0.0, 0.85, false), bar(-0.42, 0.5, true)],
            false,
        );
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].kind, PartKind::Door { hinge: Side::Right });
        assert_eq!(parts[1].kind, PartKind::Drawer);
        assert!((parts[0].z[1] - 0.8).abs() < 1e-4 && (parts[1].z[0] - 0.8).abs() < 1e-4);
    }

    #[test]
    fn a_bar_along_an_ovens_top_opens_a_flap_and_a_low_one_a_drawer_under_it() {
        let (front, extent) = front();
        let parts = lay_out_parts(
            &front,
            extent,
            &[bar(0.0, 0.84, false), bar(0.0, 0.175, false)],
            true,
        );
        assert_eq!(parts.len(), 2);
        assert_eq!(parts[0].kind, PartKind::Drawer);
        assert!((parts[0].z[1] - 0.25).abs() < 1e-4, "{:?}", parts[0]);
        assert_eq!(parts[1].kind, PartKind::Flap);
        // The same bars on a cabinet: two drawers.
        let parts = lay_out_parts(
            &front,
            extent,
            &[bar(0.0, 0.84, false), bar(0.0, 0.175, false)],
            false,
        );
        assert!(parts.iter().all(|p| p.kind == PartKind::Drawer));
    }

    #[test]
    fn knobs_tell_doors_at_the_sides_and_in_the_middle_from_drawers() {
        let (front, extent) = front();
        // One knob near the right side: a door hinged left.
        let parts = lay_out_parts(&front, extent, &[knob(0.44, 0.7)], false);
        assert_eq!(parts[0].kind, PartKind::Door { hinge: Side::Left });
        // Two knobs close across the middle: doors meeting there.
        let parts = lay_out_parts(&front, extent, &[knob(-0.04, 0.7), knob(0.04, 0.7)], false);
        assert_eq!(parts[0].kind, PartKind::Door { hinge: Side::Left });
        assert_eq!(parts[1].kind, PartKind::Door { hinge: Side::Right });
        // Two knobs in the middles of two halves: drawers side by side.
        let parts = lay_out_parts(&front, extent, &[knob(-0.25, 0.8), knob(0.25, 0.8)], false);
        assert!(parts.iter().all(|p| p.kind == PartKind::Drawer));
        assert_eq!(parts[0].right, [-0.5, 0.0]);
    }

    #[test]
    fn two_doors_hinged_alike_split_the_front_equally() {
        let (front, extent) = front();
        // Both handles near the right edge of their doors: each hinged left.
        let parts = lay_out_parts(
            &front,
            extent,
            &[bar(-0.06, 0.5, true), bar(0.44, 0.5, true)],
            false,
        );
        assert_eq!(parts[0].right, [-0.5, 0.0]);
        assert!(
            parts
                .iter()
                .all(|p| p.kind == PartKind::Door { hinge: Side::Left })
        );
    }

    #[test]
    fn a_bar_standing_to_the_end_of_the_band_is_an_open_doors_edge_and_opens_nothing() {
        let (front, extent) = front();
        let edge = Handle {
            depth: 0.079,
            ..bar(0.0, 0.12, false)
        };
        assert!(lay_out_parts(&front, extent, &[edge], false).is_empty());
        assert_eq!(
            lay_out_parts(&front, extent, &[edge, bar(0.0, 0.5, false)], false).len(),
            1
        );
    }

    #[test]
    fn the_extent_is_where_the_front_plane_has_points() {
        let (front, face) = front();
        // A front 0.9 m wide from 0.15 m up; a plinth set 5 cm back below it.
        let mut points = Vec::new();
        for i in 0..=45 {
            for k in 0..=37 {
                points.push(Vec3::new(
                    -0.45 + 0.02 * i as f32,
                    0.0,
                    0.15 + 0.02 * k as f32,
                ));
            }
            points.push(Vec3::new(-0.45 + 0.02 * i as f32, 0.05, 0.11));
        }
        let extent = front_extent(&front, face, &points);
        assert!((extent.right[0] + 0.43).abs() < 0.02, "{extent:?}");
        assert!((extent.z[0] - 0.16).abs() < 0.02, "{extent:?}");
        assert!((extent.z[1] - 0.88).abs() < 0.02, "{extent:?}");
        // Too few points: the box's face.
        assert_eq!(front_extent(&front, face, &points[..10]), face);
    }
}
