//! Doors standing open in front of a front (issue 36, section 1). A door turned about its hinge
//! shows its panel as a vertical plane through a line at one side edge of the front, running out
//! of it at the door's angle; seen from above, a straight run of points from the hinge outwards,
//! as long as the door is wide. Found there:
//! - its handle (on the panel's outer face) is carried back onto the closed front by turning it
//!   about the hinge, where a model's handle is with its door shut, so the hinge side is read
//!   as on a shut door (a wall cabinet open 62 degrees had no handle on its front, and its
//!   open door's points made its box 0.86 m deep: it was given a chest of drawers);
//! - its points are neither part of the closed carcass the models are fitted to nor handles of
//!   the closed front;
//! - its angle opens the placed model's door as far as seen.
//!
//! A drawer pulled out is a plane parallel to the front (`open_drawers`, looked for first; its
//! sides are its own). A flap turned down (ovens, dishwashers) turns about a horizontal line:
//! its edge seen from above runs out of the front too, but slants in height, and the classes
//! with flaps are not searched. Bevy-free.

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::geometry::principal_axis::principal_axis;
use crate::graph::parts::{PartJointType, PartJson};
use crate::perception::handles::{Front, Handle, find_handles};
use crate::perception::parts::{Side, quantile_range};

/// Angles looked at, radians: from this far open ...
const MIN_ANGLE: f32 = 20.0 * std::f32::consts::PI / 180.0;
/// ... to this far (past square the door leaves the box's side, where the hinge is looked for) ...
const MAX_ANGLE: f32 = 120.0 * std::f32::consts::PI / 180.0;
/// ... in steps of this much.
const ANGLE_STEP: f32 = 1.0 * std::f32::consts::PI / 180.0;
/// The hinge is looked for this far (metres) either way of the box's side edge and of the front
/// plane, in steps of [`HINGE_STEP_M`]: the box is a voxel or two off.
const HINGE_SEARCH_M: f32 = 0.03;
const HINGE_STEP_M: f32 = 0.01;
/// A panel's points lie within this distance (metres) of its plane: the map's surface is a
/// voxel or so thick, a door a board.
const PANEL_HALF_THICKNESS_M: f32 = 0.02;
/// Points at least this far out of the front (metres) are looked at: a handle on the shut front
/// stands out 1 to 8 cm, but a short run there is no door's length.
const MIN_OUT_M: f32 = 0.03;
/// The run along the panel is measured in cells this long (metres), and may skip this many
/// empty ones (what stands in front hides some of it) ...
const CELL_M: f32 = 0.02;
const MAX_GAP_CELLS: usize = 2;
/// ... starts within this distance of the hinge (metres), beyond where it first stands
/// [`MIN_OUT_M`] out ...
const NEAR_HINGE_M: f32 = 0.06;
/// ... and is at least this long and high (metres; a drawer's sides, 10 to 20 cm high, are
/// taken with their drawer first) ...
const MIN_WIDTH_M: f32 = 0.2;
const MIN_HEIGHT_M: f32 = 0.25;
/// ... at most the front's width and this much more (a door covers the front at most) ...
const WIDTH_SLACK_M: f32 = 0.04;
/// (A run still going this many cells past that runs on into something else: the carcass's
/// side, behind a hinge looked for too deep.)
const RUN_ON_CELLS: usize = 3;
/// ... filling at least this share of its cells along it, and this share of its 2 cm cells
/// across its rectangle (a chair's back bleeding into the segment fills a strip).
const MIN_RUN_FILL: f32 = 0.6;
const MIN_PANEL_FILL: f32 = 0.4;
/// The fitted line may turn the panel by at most this much (radians) from the search's.
const MAX_FIT_TURN: f32 = 5.0 * std::f32::consts::PI / 180.0;
/// The panel's height is taken between these quantiles of its points.
const EDGE_QUANTILE: f32 = 0.03;
/// Points within this distance (metres) of a door's panel, out of the front by more than
/// [`ON_FRONT_M`], are the door's.
const FOOTPRINT_MARGIN_M: f32 = 0.04;
const ON_FRONT_M: f32 = 0.015;
/// A handle on a door's panel is looked for among the points from this far behind its plane to
/// this far in front (metres), as on the closed front.
const BEHIND_M: f32 = 0.08;
const IN_FRONT_M: f32 = 0.1;

/// A door standing open: the side its hinge runs along and where that line is in the closed
/// front's frame (`hinge_at`: right along the front, out of it), how far it is turned (radians,
/// 0 shut), its panel's width and height range (world z), and the handles on it carried back
/// onto the closed front.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OpenDoor {
    pub hinge: Side,
    pub hinge_at: [f32; 2],
    pub angle: f32,
    pub width: f32,
    pub z: [f32; 2],
    pub handles: Vec<Handle>,
    /// How many cells of the panel's run held points, and whether the run reached as far as a
    /// door of the front may: then it may run on into the carcass's side behind its hinge.
    #[serde(skip)]
    pub cells: usize,
    #[serde(skip)]
    pub reaches_cap: bool,
}

/// Where a door's panel runs from its hinge, in the front's (right, out) plane, and the panel's
/// outward normal there: a door hinged on the right edge lies to the left of its hinge when shut.
fn panel_frame(hinge: Side, angle: f32) -> (Vec2, Vec2) {
    let s = match hinge {
        Side::Left => 1.0,
        Side::Right => -1.0,
    };
    let (sin, cos) = angle.sin_cos();
    (Vec2::new(s * cos, sin), Vec2::new(-s * sin, cos))
}

impl OpenDoor {
    /// `p`'s distance along the panel from the hinge and out of the panel (towards its outer
    /// face), in metres.
    fn panel_local(&self, front: &Front, p: Vec3) -> (f32, f32) {
        let l = front.local(p);
        let d = Vec2::new(l.x, l.z) - Vec2::from_array(self.hinge_at);
        let (along, normal) = panel_frame(self.hinge, self.angle);
        (d.dot(along), d.dot(normal))
    }

    /// Whether world point `p` belongs to this door rather than to the closed front or the
    /// carcass: near its panel (grown by [`FOOTPRINT_MARGIN_M`]) and out of the front.
    pub fn holds(&self, front: &Front, p: Vec3) -> bool {
        let (along, across) = self.panel_local(front, p);
        front.local(p).z > ON_FRONT_M
            && across.abs() <= FOOTPRINT_MARGIN_M
            && (-FOOTPRINT_MARGIN_M..=self.width + FOOTPRINT_MARGIN_M).contains(&along)
            && (self.z[0] - FOOTPRINT_MARGIN_M..=self.z[1] + FOOTPRINT_MARGIN_M).contains(&p.z)
    }

    /// The door's shut rectangle along the front (right, from the hinge towards its free edge).
    pub fn shut_right(&self) -> [f32; 2] {
        match self.hinge {
            Side::Left => [self.hinge_at[0], self.hinge_at[0] + self.width],
            Side::Right => [self.hinge_at[0] - self.width, self.hinge_at[0]],
        }
    }

    /// World point `p` on the open door moved to where it is with the door shut.
    fn shut(&self, front: &Front, p: Vec3) -> Vec3 {
        let (along, across) = self.panel_local(front, p);
        let (shut_along, shut_normal) = panel_frame(self.hinge, 0.0);
        let at = Vec2::from_array(self.hinge_at) + shut_along * along + shut_normal * across;
        front.origin + front.right * at.x + front.normal * at.y + Vec3::Z * (p.z - front.origin.z)
    }
}

/// The doors standing open in front of `front` among `points` (the object's surface across its
/// front, world frame, less what open drawers hold): at most one hinged on each side edge of
/// `face_right` (the box's face along the front), each a panel running out of the front at its
/// angle through a hinge line within [`HINGE_SEARCH_M`] of that edge and of the front plane.
pub fn open_doors(front: &Front, face_right: [f32; 2], points: &[Vec3]) -> Vec<OpenDoor> {
    // Seen from above: (right, out) of the points standing out of the front.
    let standing: Vec<Vec2> = points
        .iter()
        .map(|p| {
            let l = front.local(*p);
            Vec2::new(l.x, l.z)
        })
        .filter(|l| l.y >= MIN_OUT_M)
        .collect();
    let max_width = face_right[1] - face_right[0] + WIDTH_SLACK_M;
    if standing.is_empty() || max_width < MIN_WIDTH_M {
        return Vec::new();
    }
    [(Side::Left, face_right[0]), (Side::Right, face_right[1])]
        .into_iter()
        .filter_map(|(side, edge)| {
            let panel = best_panel(&standing, side, edge, max_width)?;
            let fitted = fit_panel(panel, &standing);
            let door = finish_door(front, fitted, points);
            tracing::trace!("door panel {panel:?}, fitted {fitted:?}: {door:?}");
            door
        })
        .collect()
}

/// A panel hypothesis: hinge side, hinge line and angle, the run of cells along it, how
/// closely the points within its slab follow it, and whether the run goes on past the widest
/// door.
#[derive(Clone, Copy, Debug)]
struct Panel {
    hinge: Side,
    hinge_at: Vec2,
    angle: f32,
    width: f32,
    cells: usize,
    closeness: f32,
    capped: bool,
}

/// The hinge line near `edge` and angle whose ray holds the longest run of `standing` points
/// (right, out), when that run makes a door.
fn best_panel(standing: &[Vec2], hinge: Side, edge: f32, max_width: f32) -> Option<Panel> {
    let inward = match hinge {
        Side::Left => 1.0,
        Side::Right => -1.0,
    };
    let steps = (HINGE_SEARCH_M / HINGE_STEP_M).round() as i32;
    let angles = ((MAX_ANGLE - MIN_ANGLE) / ANGLE_STEP).round() as usize;
    let cell_count = (max_width / CELL_M).ceil() as usize;
    // The run is followed a little past the widest door, to tell a panel that ends from one
    // that runs on.
    let followed = cell_count + RUN_ON_CELLS;
    let mut best: Option<Panel> = None;
    let mut occupied = vec![false; followed];
    for along_edge in -steps..=steps {
        for out in -steps..=steps {
            let hinge_at = Vec2::new(
                edge + inward * along_edge as f32 * HINGE_STEP_M,
                out as f32 * HINGE_STEP_M,
            );
            for k in 0..=angles {
                let angle = MIN_ANGLE + k as f32 * ANGLE_STEP;
                let (along, normal) = panel_frame(hinge, angle);
                occupied.iter_mut().for_each(|c| *c = false);
                // How well the line runs through the points: each point within the slab
                // counts the more the nearer it lies to the line (a handle standing beside the
                // panel must not pull the line off it).
                let mut closeness = 0.0;
                for l in standing {
                    let d = *l - hinge_at;
                    let (a, n) = (d.dot(along), d.dot(normal));
                    if n.abs() <= PANEL_HALF_THICKNESS_M && a >= 0.0 {
                        let cell = (a / CELL_M) as usize;
                        if cell < followed {
                            occupied[cell] = true;
                        }
                        if cell < cell_count {
                            closeness += 1.0 - (n / PANEL_HALF_THICKNESS_M).powi(2);
                        }
                    }
                }
                let Some((first, last)) = longest_run(&occupied) else {
                    continue;
                };
                let capped = last >= cell_count;
                let last = last.min(cell_count - 1);
                if first > last {
                    continue;
                }
                let cells = occupied[first..=last].iter().filter(|o| **o).count();
                // Where the panel first stands MIN_OUT_M out of the front.
                let first_out = (MIN_OUT_M - hinge_at.y).max(0.0) / angle.sin();
                let width = (last + 1) as f32 * CELL_M;
                let starts_at_hinge = first as f32 * CELL_M <= first_out + NEAR_HINGE_M;
                let filled = cells as f32 >= MIN_RUN_FILL * (last + 1 - first) as f32;
                if !starts_at_hinge || !filled || width < MIN_WIDTH_M {
                    continue;
                }
                // The longest run; of runs as long, the one holding the most points (the
                // panel's own angle, not one that grazes it); then the hinge nearest the edge.
                let to_edge = (hinge_at - Vec2::new(edge, 0.0)).length();
                let better = |p: &Panel| {
                    cells > p.cells
                        || (cells == p.cells && closeness > p.closeness)
                        || (cells == p.cells
                            && closeness == p.closeness
                            && to_edge < (p.hinge_at - Vec2::new(edge, 0.0)).length())
                };
                if best.as_ref().is_none_or(better) {
                    best = Some(Panel {
                        hinge,
                        hinge_at,
                        angle,
                        width,
                        cells,
                        closeness,
                        capped,
                    });
                }
            }
        }
    }
    best
}

/// The run of occupied cells that skips at most [`MAX_GAP_CELLS`] empty ones at a time holding
/// the most occupied cells: its first and last cell.
fn longest_run(occupied: &[bool]) -> Option<(usize, usize)> {
    let mut best: Option<(usize, usize, usize)> = None;
    let mut current: Option<(usize, usize, usize)> = None;
    let mut gap = 0;
    for (i, &o) in occupied.iter().enumerate() {
        if o {
            current = Some(match current {
                Some((first, _, n)) => (first, i, n + 1),
                None => (i, i, 1),
            });
            gap = 0;
        } else if current.is_some() {
            gap += 1;
            if gap > MAX_GAP_CELLS {
                current = None;
                gap = 0;
            }
        }
        if let Some(c) = current
            && best.is_none_or(|b| c.2 > b.2)
        {
            best = Some(c);
        }
    }
    best.map(|(first, last, _)| (first, last))
}

/// `panel` with its line fitted to the points in its slab (their principal direction, through
/// their mean): the search's 1 degree steps leave the far edge of a 60 cm door up to 3 cm off
/// its line, and the hinge it found may lie a little in or out of the front.
fn fit_panel(panel: Panel, standing: &[Vec2]) -> Panel {
    let (along, normal) = panel_frame(panel.hinge, panel.angle);
    let on: Vec<Vec2> = standing
        .iter()
        .copied()
        .filter(|l| {
            let d = *l - panel.hinge_at;
            d.dot(normal).abs() <= PANEL_HALF_THICKNESS_M
                && (0.0..=panel.width).contains(&d.dot(along))
        })
        .collect();
    if on.len() < 2 {
        return panel;
    }
    let Some((mean, mut direction)) = principal_axis(&on) else {
        return panel;
    };
    // Turned to run out of the front like the panel.
    if direction.dot(along) < 0.0 {
        direction = -direction;
    }
    let s = match panel.hinge {
        Side::Left => 1.0,
        Side::Right => -1.0,
    };
    let angle = direction.y.atan2(s * direction.x);
    if !(MIN_ANGLE..=MAX_ANGLE).contains(&angle) || (angle - panel.angle).abs() > MAX_FIT_TURN {
        return panel;
    }
    // The hinge is where the fitted line meets the front plane (the door turns about the
    // carcass's front edge; the search's hinge may lie on the line a little in or out of it).
    let hinge_at = mean - direction * (mean.y / direction.y);
    Panel {
        hinge_at,
        angle,
        ..panel
    }
}

/// `panel` as an open door when its points cover a door-sized rectangle in height well enough,
/// with the handles on its outer face carried back onto the shut front; `None` otherwise.
fn finish_door(front: &Front, panel: Panel, points: &[Vec3]) -> Option<OpenDoor> {
    let mut door = OpenDoor {
        hinge: panel.hinge,
        hinge_at: panel.hinge_at.to_array(),
        angle: panel.angle,
        width: panel.width,
        z: [f32::MIN, f32::MAX],
        handles: Vec::new(),
        cells: panel.cells,
        reaches_cap: panel.capped,
    };
    let on: Vec<(f32, f32)> = points
        .iter()
        .filter(|p| front.local(**p).z >= MIN_OUT_M)
        .filter_map(|p| {
            let (along, across) = door.panel_local(front, *p);
            (across.abs() <= PANEL_HALF_THICKNESS_M && (0.0..=door.width).contains(&along))
                .then_some((along, p.z))
        })
        .collect();
    let z = quantile_range(on.iter().map(|(_, z)| *z).collect(), EDGE_QUANTILE);
    let height = z[1] - z[0];
    if height < MIN_HEIGHT_M {
        return None;
    }
    let mut cells: Vec<(i32, i32)> = on
        .iter()
        .filter(|(_, h)| (z[0]..=z[1]).contains(h))
        .map(|(a, h)| {
            (
                (a / CELL_M).floor() as i32,
                ((h - z[0]) / CELL_M).floor() as i32,
            )
        })
        .collect();
    cells.sort_unstable();
    cells.dedup();
    // Along the panel its points start where it stands MIN_OUT_M out of the front.
    let first_out = (MIN_OUT_M - door.hinge_at[1]).max(0.0) / door.angle.sin();
    let seen_width = (door.width - first_out).max(CELL_M);
    let total = ((seen_width / CELL_M).ceil() * (height / CELL_M).ceil()).max(1.0);
    if (cells.len() as f32) < MIN_PANEL_FILL * total {
        return None;
    }
    door.z = z;
    // The panel as a front of its own: its outer face towards its normal.
    let (along, normal) = panel_frame(door.hinge, door.angle);
    let middle = Vec2::from_array(door.hinge_at) + along * (0.5 * door.width);
    let to_world = |v: Vec2| front.right * v.x + front.normal * v.y;
    let origin = front.origin + to_world(middle) + Vec3::Z * (0.5 * (z[0] + z[1]) - front.origin.z);
    let panel_front = Front::new(origin, to_world(normal))?;
    let near: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| front.local(*p).z > ON_FRONT_M)
        .filter(|p| {
            let (a, n) = door.panel_local(front, *p);
            (-BEHIND_M..=IN_FRONT_M).contains(&n)
                && (0.0..=door.width).contains(&a)
                && (z[0]..=z[1]).contains(&p.z)
        })
        .collect();
    door.handles = find_handles(&panel_front, &near)
        .into_iter()
        .map(|h| {
            let centre = door.shut(front, h.center);
            let tip = door.shut(front, h.center + h.axis);
            Handle {
                center: centre,
                axis: (tip - centre).try_normalize().unwrap_or(h.axis),
                ..h
            }
        })
        .collect();
    Some(door)
}

/// A model's door stands for an open door when its hinge line is this close to the open door's
/// (metres) ...
const SAME_HINGE_M: f32 = 0.1;
/// ... its front's centre this close to the open door's shut rectangle's centre ...
const SAME_DOOR_M: f32 = 0.15;
/// ... it turns about a vertical axis (cos of 30 degrees) and its front starts to move out of
/// the front.
const VERTICAL_COS: f32 = 0.866;
const OPENS_OUT_COS: f32 = 0.866;

/// How far each of `parts` (a placed model's, world frame) is turned as `doors` were seen
/// standing open on `front`: `(part name, joint value)`, the value clamped to the part's range
/// and signed the way its range opens. A door no part stands for is left out.
pub fn door_openings(front: &Front, doors: &[OpenDoor], parts: &[PartJson]) -> Vec<(String, f32)> {
    let mut taken = vec![false; parts.len()];
    let mut openings = Vec::new();
    for d in doors {
        let right = d.shut_right();
        let centre = front.origin
            + front.right * (0.5 * (right[0] + right[1]))
            + Vec3::Z * (0.5 * (d.z[0] + d.z[1]) - front.origin.z);
        let hinge = front.origin + front.right * d.hinge_at[0];
        let nearest = parts
            .iter()
            .enumerate()
            .filter(|(k, p)| {
                !taken[*k]
                    && p.joint.kind == PartJointType::Revolute
                    && p.axis().z.abs() >= VERTICAL_COS
                    && p.opening_direction().dot(front.normal) >= OPENS_OUT_COS
            })
            .filter(|(_, p)| {
                let off = Vec3::from_array(p.joint.origin) - hinge;
                off.dot(front.right).abs() <= SAME_HINGE_M
            })
            .map(|(k, p)| {
                let off = p.front_center() - centre;
                (
                    k,
                    (off - front.normal * off.dot(front.normal))
                        .with_z(0.0)
                        .length(),
                )
            })
            .filter(|(_, distance)| *distance <= SAME_DOOR_M)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, _)) = nearest {
            taken[k] = true;
            let joint = &parts[k].joint;
            let value = if joint.upper.abs() >= joint.lower.abs() {
                d.angle.min(joint.upper)
            } else {
                (-d.angle).max(joint.lower)
            };
            openings.push((parts[k].name.clone(), value));
        }
    }
    openings
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points every 2 cm over the y = 0 front (facing -y, so out is -y) from x0 to x1, z0 to z1.
    fn shut_panel([x0, x1]: [f32; 2], [z0, z1]: [f32; 2]) -> Vec<Vec3> {
        let (nx, nz) = (
            ((x1 - x0) / 0.02).round() as usize,
            ((z1 - z0) / 0.02).round() as usize,
        );
        (0..=nx)
            .flat_map(|i| {
                (0..=nz).map(move |j| Vec3::new(x0 + 0.02 * i as f32, 0.0, z0 + 0.02 * j as f32))
            })
            .collect()
    }

    fn front() -> Front {
        Front::new(Vec3::new(0.3, 0.0, 0.4), Vec3::NEG_Y).expect("front")
    }

    /// A cabinet 0.6 wide (x 0 to 0.6; seen from the room, right is +x), its front at
    /// y = 0 from z = 0.1 to 0.7, its one door hinged at x = `hinge_x` turned `angle` out, with
    /// a vertical bar 2.5 cm out of its outer face 4 cm from its free edge; the inside's back
    /// 0.3 m behind the front.
    fn cabinet_with_open_door(hinge_x: f32, angle: f32) -> Vec<Vec3> {
        let mut points = shut_panel([0.0, 0.6], [0.1, 0.7])
            .into_iter()
            .map(|p| p + Vec3::Y * 0.3)
            .collect::<Vec<_>>();
        // The door shut would run from the hinge to the other side: x grows away from a hinge
        // at 0, falls from one at 0.6.
        let towards = if hinge_x < 0.3 { 1.0 } else { -1.0 };
        let (sin, cos) = angle.sin_cos();
        let along = Vec3::new(towards * cos, -sin, 0.0);
        // The outer face's normal: out of the front when shut (-y), turned with the door.
        let outer = Vec3::new(-towards * sin, -cos, 0.0);
        let hinge = Vec3::new(hinge_x, 0.0, 0.0);
        for i in 0..=30 {
            for j in 0..=30 {
                points.push(hinge + along * (0.02 * i as f32) + Vec3::Z * (0.1 + 0.02 * j as f32));
            }
        }
        for j in 0..=8 {
            for k in 0..2 {
                points.push(
                    hinge
                        + along * 0.56
                        + outer * (0.025 + 0.01 * k as f32)
                        + Vec3::Z * (0.32 + 0.02 * j as f32),
                );
            }
        }
        points
    }

    #[test]
    fn a_door_open_at_any_angle_is_found_with_its_hinge_side_and_its_handle_carried_back() {
        let f = front();
        // Seen from the room (looking along +y), right is +x: x = 0 is the left edge.
        for (hinge_x, side) in [(0.0, Side::Left), (0.6, Side::Right)] {
            for degrees in [30.0f32, 62.0, 90.0, 110.0] {
                let points = cabinet_with_open_door(hinge_x, degrees.to_radians());
                let doors = open_doors(&f, [-0.3, 0.3], &points);
                assert_eq!(doors.len(), 1, "{side:?} {degrees}: {doors:?}");
                let d = &doors[0];
                assert_eq!(d.hinge, side, "{degrees}: {d:?}");
                assert!(
                    (d.angle.to_degrees() - degrees).abs() <= 3.0,
                    "{degrees}: {d:?}"
                );
                assert!((d.width - 0.6).abs() <= 0.04, "{degrees}: {d:?}");
                assert!(d.z[0] < 0.14 && d.z[1] > 0.66, "{degrees}: {d:?}");
                assert_eq!(d.handles.len(), 1, "{degrees}: {d:?}");
                let h = d.handles[0];
                // Back on the shut front: 4 cm from the free edge, standing out of the front.
                let shut_x = hinge_x + if hinge_x < 0.3 { 0.56 } else { -0.56 };
                assert!((h.center.x - shut_x).abs() < 0.02, "{degrees}: {h:?}");
                assert!(
                    h.center.y < -0.015 && h.center.y > -0.05,
                    "{degrees}: {h:?} {d:?}"
                );
                assert!(h.axis.z.abs() > 0.95, "{degrees}: {h:?}");
                // The panel is the door's; the inside's back and the front are not.
                let hinge = Vec3::new(hinge_x, 0.0, 0.0);
                assert!(d.holds(&f, hinge + along_of(hinge_x, degrees) * 0.3 + Vec3::Z * 0.4));
                assert!(!d.holds(&f, Vec3::new(0.3, 0.3, 0.4)));
            }
        }
    }

    fn along_of(hinge_x: f32, degrees: f32) -> Vec3 {
        let towards = if hinge_x < 0.3 { 1.0 } else { -1.0 };
        let (sin, cos) = degrees.to_radians().sin_cos();
        Vec3::new(towards * cos, -sin, 0.0)
    }

    #[test]
    fn a_shut_front_its_handles_and_a_drawer_pulled_out_are_no_open_doors() {
        let f = front();
        let mut shut = shut_panel([0.0, 0.6], [0.1, 0.7]);
        for j in 0..=8 {
            shut.push(Vec3::new(0.04, -0.03, 0.3 + 0.02 * j as f32));
        }
        assert!(open_doors(&f, [-0.3, 0.3], &shut).is_empty());
        // A drawer's sides run straight out along the side edges, but only 16 cm high.
        let mut drawer = shut_panel([0.0, 0.6], [0.1, 0.5]);
        for x in [0.01, 0.59] {
            for k in 0..=15 {
                for j in 0..8 {
                    drawer.push(Vec3::new(x, -0.02 * k as f32, 0.52 + 0.02 * j as f32));
                }
            }
        }
        assert!(open_doors(&f, [-0.3, 0.3], &drawer).is_empty());
        // A chair's back 30 cm in front, parallel to the front: no run from a hinge.
        let mut chair = shut_panel([0.0, 0.6], [0.1, 0.7]);
        chair.extend(
            shut_panel([0.1, 0.5], [0.4, 0.9])
                .into_iter()
                .map(|p| p - Vec3::Y * 0.3),
        );
        assert!(open_doors(&f, [-0.3, 0.3], &chair).is_empty());
    }

    #[test]
    fn an_open_door_turns_the_models_door_behind_it_as_far_as_it_was_opened() {
        use crate::cad::library::storage::cabinet_wall;
        use crate::cad::model_parts::model_parts;
        let model = cabinet_wall("cupboard", Vec3::new(0.6, 0.35, 0.7));
        let parts = model_parts(&model, &glam::Affine3A::IDENTITY);
        let door = parts
            .iter()
            .find(|p| p.joint.kind == PartJointType::Revolute)
            .expect("a door");
        // The model faces -y with its front at y = -0.175.
        let f = Front::new(Vec3::new(0.0, -0.175, 0.35), Vec3::NEG_Y).expect("front");
        let hinge_right = f.local(Vec3::from_array(door.joint.origin)).x;
        let side = if f.local(door.front_center()).x < hinge_right {
            Side::Right
        } else {
            Side::Left
        };
        let open = |angle: f32| OpenDoor {
            hinge: side,
            hinge_at: [hinge_right, 0.0],
            angle,
            width: 0.6,
            z: [0.05, 0.65],
            handles: Vec::new(),
            cells: 30,
            reaches_cap: false,
        };
        let opened = door_openings(&f, &[open(1.0)], &parts);
        assert_eq!(opened.len(), 1, "{opened:?}");
        assert_eq!(opened[0].0, door.name);
        let upper_opens = door.joint.upper.abs() >= door.joint.lower.abs();
        assert!((opened[0].1.abs() - 1.0).abs() < 1e-6 && (opened[0].1 > 0.0) == upper_opens);
        // A door seen hinged on the other side stands for none of them.
        let other = OpenDoor {
            hinge: if side == Side::Left {
                Side::Right
            } else {
                Side::Left
            },
            hinge_at: [-hinge_right, 0.0],
            ..open(1.0)
        };
        assert!(door_openings(&f, &[other], &parts).is_empty());
    }
}
