//! The objects CAD replacement works on, read off a contact graph: each with its observed
//! points, its box cut back to its front, and the way it faces (its back to a wall, its front
//! where the camera saw handles and open parts, a chair towards its table, else the room's
//! middle), the priors the ranking and alignment weigh.

use std::collections::HashMap;

use glam::Vec3;

use crate::cad::replace::matching::{Facing, ObservedObject};
use crate::classes::{ClassTable, EntityKind};
use crate::geometry::{GravityBox, Plane};
use crate::graph::ContactGraph;
use crate::perception::front_marks::FrontMarks;
use crate::perception::fronts::{PerceivedFront, fitted_to_front, perceive_front, with_marks};
use crate::perception::handles::HandleKind;
use crate::perception::parts::opens_as_flap;

/// Objects with fewer segment points than this keep their segment mesh: too little was seen to
/// align anything to.
pub const MIN_OBJECT_POINTS: usize = 30;

/// An object whose box comes this close (metres) to a wall has its back to it.
const BACK_TO_WALL_M: f32 = 0.15;
/// Walls whose normals are closer than this cosine (about 60 degrees) are on the same side of an
/// object, not a corner.
const CORNER_COS: f32 = 0.5;
/// A box whose long side is at least this many times its short one has long sides to tell (a
/// microwave's are 1.25-1.35 times its depth; the boxes seen of free-standing ones 1.1-1.35).
const LONG_SIDE_RATIO: f32 = 1.1;
/// The objects an object holds define its top when they rest at most this far (metres) under
/// its box's top.
const TOP_FROM_CHILDREN_M: f32 = 0.1;

/// Far longer than wide (or deep): the ratio of the sides at which a footprint's long side is
/// told from its short one without doubt (a bookcase's 0.8 by 0.35 m, a sofa's 2 by 0.9 m; not
/// a cabinet's 0.8 by 0.55 m, built narrower than deep as often).
const ELONGATED: f32 = 1.5;

/// The share of an object's points past each side of its width left out of its box.
const WIDTH_TRIM_SHARE: f32 = 0.01;

/// A wall is behind a face when its normal is within about 15 degrees of the face's.
const PARALLEL_WALL_COS: f32 = 0.966;
/// A face may stand this far (metres) into its wall's fitted plane (noise of both) and still have
/// it behind.
const WALL_SLACK_M: f32 = 0.03;

/// Confidence of the weaker prior that an object away from walls faces the room's middle (the
/// side that was seen): enough to choose between shapes that fit alike, not against the shape.
const FACES_ROOM_CONFIDENCE: f32 = 0.5;

/// Classes that stand at a table facing it (ProcTHOR's rule for chairs, which real dining and
/// office rooms keep), and how near (metres, box to box) a table must be for it to count.
const FACES_ITS_TABLE: [&str; 1] = ["chair"];
const AT_TABLE_M: f32 = 0.5;

/// The objects of `graph` that replacement works on (not layout, enough points), in node order.
/// `points` gives each node id its observed surface points (aligned world), `marks` what the
/// frames show of the fronts of some (`perception::front_marks`, read off the fronts perceived
/// without them).
pub fn observed_objects<'a>(
    graph: &'a ContactGraph,
    points: &'a HashMap<String, Vec<Vec3>>,
    marks: &HashMap<String, FrontMarks>,
) -> Vec<ObservedObject<'a>> {
    // Wall planes face into the room.
    let walls: Vec<Plane> = graph
        .nodes
        .iter()
        .filter(|n| n.class == "wall")
        .filter_map(|n| n.planes.first().map(|p| Plane::from_array(*p)))
        .collect();
    let room_middle = graph
        .node("floor")
        .map(|f| Vec3::from_array(f.bbox.center))
        .or_else(|| {
            let centres: Vec<Vec3> = graph
                .nodes
                .iter()
                .filter(|n| n.class == "wall")
                .map(|n| Vec3::from_array(n.bbox.center))
                .collect();
            (!centres.is_empty()).then(|| centres.iter().sum::<Vec3>() / centres.len() as f32)
        });
    let tables: Vec<GravityBox> = graph
        .nodes
        .iter()
        .filter(|n| n.class == "table")
        .map(|n| GravityBox::from(&n.bbox))
        .collect();
    let table = ClassTable::builtin();
    graph
        .nodes
        .iter()
        .filter(|n| n.kind != EntityKind::Layout)
        .filter_map(|n| {
            let p = points.get(&n.id)?;
            let class = table.get(&n.class);
            let articulated = class.is_some_and(|c| c.kind == EntityKind::Articulated);
            let bbox = match class.filter(|_| articulated) {
                Some(c) => reaching_back_to_wall(
                    GravityBox::from(&n.bbox),
                    &walls,
                    c.size_min.y..=c.size_max.y,
                ),
                None => GravityBox::from(&n.bbox),
            };
            let has_front = table.get(&n.class).is_some_and(|c| c.yaw_symmetry == 1);
            let top_z = graph
                .support_edges()
                .filter(|(parent, _)| *parent == n.id)
                .filter_map(|(_, child)| graph.node(child))
                .map(|c| GravityBox::from(&c.bbox).bottom_z())
                .filter(|z| (bbox.top_z() - TOP_FROM_CHILDREN_M..=bbox.top_z()).contains(z))
                .fold(None, |top: Option<f32>, z| {
                    Some(top.map_or(z, |t| t.max(z)))
                })
                .unwrap_or(bbox.top_z());
            if p.len() < MIN_OBJECT_POINTS {
                return None;
            }
            let flaps = opens_as_flap(&n.class);
            let long_side = table.get(&n.class).is_some_and(|c| c.front_on_long_side);
            let behind = if has_front {
                let wide = table.get(&n.class).is_some_and(|c| c.size.x >= ELONGATED * c.size.y);
                long_side_first(walls_behind(&bbox, &walls), &bbox, wide)
            } else {
                Vec::new()
            };
            let faces_room = || {
                let to_middle = room_middle? - bbox.center;
                Some(Facing {
                    direction: to_middle.with_z(0.0).try_normalize()?,
                    confidence: FACES_ROOM_CONFIDENCE,
                    against_wall: false,
                })
            };
            let (facing, front) = if !has_front {
                (None, None)
            } else if articulated && !behind.is_empty() {
                let (facing, front) =
                    front_among_faces(&behind, |d| perceive_front(&bbox, d, p, flaps));
                if facing.direction != behind[0].direction {
                    tracing::debug!(
                        "{}: in a corner, faces {} (its front's evidence), not away from the nearer wall",
                        n.id,
                        facing.direction
                    );
                }
                (Some(facing), front)
            } else if let Some(long) = (articulated && behind.is_empty() && long_side)
                .then(|| long_faces(&bbox, faces_room().map(|f| f.direction)))
                .flatten()
            {
                let (facing, front) =
                    front_among_faces(&long, |d| perceive_front(&bbox, d, p, flaps));
                (Some(facing), front)
            } else if let Some(facing) = FACES_ITS_TABLE
                .contains(&n.class.as_str())
                .then(|| facing_its_table(&bbox, &tables))
                .flatten()
            {
                // A chair at a table faces it, whatever wall is behind it (at a desk against
                // a wall the room is behind the chair).
                (Some(facing), None)
            } else {
                let facing = behind.first().copied().or_else(faces_room);
                let front = facing
                    .filter(|_| articulated)
                    .and_then(|f| perceive_front(&bbox, f.direction, p, flaps));
                (facing, front)
            };
            let front = match (front, marks.get(&n.id)) {
                (Some(front), Some(marks)) => Some(with_marks(front, marks, flaps)),
                (front, _) => front,
            };
            // An open door or drawer (or what stands in front) is no part of the closed object
            // the models are fitted as.
            let (bbox, points) = fitted_to_front(&bbox, front.as_ref(), p);
            let bbox = match facing {
                Some(f) => across_its_front(&bbox, f.direction, &points),
                None => bbox,
            };
            Some(ObservedObject {
                id: &n.id,
                class: &n.class,
                top_z,
                bbox,
                planes: n.planes.iter().map(|p| Plane::from_array(*p)).collect(),
                points,
                facing,
                front,
            })
        })
        .collect()
}

/// Facing the nearest of `tables` within [`AT_TABLE_M`] of `bbox`: towards the point of the
/// table's footprint nearest the box's centre. `None` when no table is that near, or the
/// centre stands over a table (nothing tells which way then).
fn facing_its_table(bbox: &GravityBox, tables: &[GravityBox]) -> Option<Facing> {
    let centre = bbox.center.truncate();
    let corners = bbox.footprint();
    let (gap, nearest) = tables
        .iter()
        .map(|t| {
            let local = t.world_from_box().inverse();
            let half = 0.5 * t.size.truncate();
            let clamp = |p: glam::Vec2| {
                let l = local.transform_point3(p.extend(t.center.z)).truncate();
                l.clamp(-half, half)
            };
            let to_world = |l: glam::Vec2| {
                t.world_from_box()
                    .transform_point3(l.extend(0.0))
                    .truncate()
            };
            // Box to box: the nearest of the chair's corners and centre to the table.
            let gap = corners
                .iter()
                .chain(std::iter::once(&centre))
                .map(|c| to_world(clamp(*c)).distance(*c))
                .fold(f32::MAX, f32::min);
            (gap, to_world(clamp(centre)))
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    if gap > AT_TABLE_M {
        return None;
    }
    let direction = (nearest - centre).try_normalize()?.extend(0.0);
    Some(Facing {
        direction,
        confidence: 1.0,
        against_wall: false,
    })
}

/// `bbox` of a unit seen only as its front, reaching back to the wall behind it. When its short
/// side is shallower than its class's `depth` range allows, the camera saw a slab of its front
/// (a dishwasher as its 9 cm door, 50 cm from the wall: room 16 of `iscene benchmark`), and the
/// carcass stands behind it, its back to the wall, as units are built. The box then grows along
/// its short axis to the nearest wall parallel to its long side behind either face, no deeper
/// than the class is; it stays as it is when no such wall is near enough. Fitted to the slab,
/// a model sat 7 cm off and what stood on it tipped.
fn reaching_back_to_wall(
    bbox: GravityBox,
    walls: &[Plane],
    depth: std::ops::RangeInclusive<f32>,
) -> GravityBox {
    let short = bbox.size.x.min(bbox.size.y);
    if short >= *depth.start() {
        return bbox;
    }
    let short_axis = short_axis(&bbox);
    let most = *depth.end() - short;
    // Over both faces across the short axis: the gap from the face to a wall whose normal points
    // the face's way back into the room, the nearest.
    let behind = [short_axis, -short_axis]
        .into_iter()
        .flat_map(|front| {
            let back = bbox.center - front * (0.5 * short);
            walls.iter().filter_map(move |w| {
                let normal = w.normal.with_z(0.0).try_normalize()?;
                let gap = w.signed_distance(back);
                (normal.dot(front) >= PARALLEL_WALL_COS && (-WALL_SLACK_M..=most).contains(&gap))
                    .then_some((gap, front))
            })
        })
        .min_by(|a, b| a.0.total_cmp(&b.0));
    let Some((gap, front)) = behind else {
        return bbox;
    };
    let grown = gap.max(0.0);
    let mut reached = bbox;
    reached.size[short_axis_index(&bbox)] += grown;
    reached.center -= front * (0.5 * grown);
    reached
}

/// Which of `bbox`'s horizontal axes is its short one: 0 for x, 1 for y.
fn short_axis_index(bbox: &GravityBox) -> usize {
    usize::from(bbox.size.x >= bbox.size.y)
}

/// The world direction of `bbox`'s short horizontal axis.
fn short_axis(bbox: &GravityBox) -> Vec3 {
    let (sin, cos) = bbox.yaw.sin_cos();
    if short_axis_index(bbox) == 0 {
        Vec3::new(cos, sin, 0.0)
    } else {
        Vec3::new(-sin, cos, 0.0)
    }
}

/// `bbox` with the sides across its front (those of its width, seen from where it `faces`) drawn
/// in past the outermost [`WIDTH_TRIM_SHARE`] of `points` on each: the map bleeds a centimetre or
/// two past an object's side, and a model fitted to the extremes puts its hinge there (furniture
/// boxes of `iscene benchmark` were 2.8 cm too wide, median over 146 units, where 99 % of a
/// side's points lie within 0.5 cm of it).
fn across_its_front(bbox: &GravityBox, faces: Vec3, points: &[Vec3]) -> GravityBox {
    let (sin, cos) = bbox.yaw.sin_cos();
    let x_axis = Vec3::new(cos, sin, 0.0);
    // The width runs along the box axis farther from the facing.
    let width = if x_axis.dot(faces).abs() < std::f32::consts::FRAC_1_SQRT_2 {
        0
    } else {
        1
    };
    bbox.trimmed_along(width, points, WIDTH_TRIM_SHARE)
}

/// Facing away from each wall within `BACK_TO_WALL_M` of the box (its inward normal made
/// horizontal), the nearest first.
fn walls_behind(bbox: &GravityBox, walls: &[Plane]) -> Vec<Facing> {
    let mut behind: Vec<(f32, Vec3)> = walls
        .iter()
        .filter_map(|w| {
            let gap = bbox
                .corners()
                .iter()
                .map(|c| w.signed_distance(*c))
                .fold(f32::MAX, f32::min);
            let direction = w.normal.with_z(0.0).try_normalize()?;
            (gap <= BACK_TO_WALL_M).then_some((gap, direction))
        })
        .collect();
    behind.sort_by(|a, b| a.0.total_cmp(&b.0));
    behind
        .into_iter()
        .map(|(_, direction)| Facing {
            direction,
            confidence: 1.0,
            against_wall: true,
        })
        .collect()
}

/// `behind` (facings away from the walls behind an object, nearest first) with, in a corner, the
/// wall along the box's long side first when the object is `wide` (its class is far wider than
/// deep, a bookcase, a sofa) and its box is far longer than deep: such a thing stands with its
/// back to a wall, not its side, however near the other wall is (room 14 of `iscene benchmark`:
/// a bookcase 4 cm from the wall at its side, 1 cm from the one behind, faced along it).
fn long_side_first(mut behind: Vec<Facing>, bbox: &GravityBox, wide: bool) -> Vec<Facing> {
    let (long, short) = (bbox.size.x.max(bbox.size.y), bbox.size.x.min(bbox.size.y));
    if !wide || long < ELONGATED * short || behind.len() < 2 {
        return behind;
    }
    // The facing along the box's short axis: its back then runs along the long side.
    let short_axis = short_axis(bbox);
    if let Some(k) = behind
        .iter()
        .position(|f| f.direction.dot(short_axis).abs() > CORNER_COS)
        .filter(|&k| behind[0].direction.dot(behind[k].direction) < CORNER_COS)
    {
        behind.swap(0, k);
    }
    behind
}

/// Which of the `faces` (facings, the prior's first, at least one) an articulated object's front
/// is, with the front perceived that way: the face where bar handles, open doors or open drawers
/// are seen, the first when no other face shows more. The faces are those away from the walls
/// within `BACK_TO_WALL_M` (in a corner, a side is as near a wall as the back), or the two long
/// faces of a class whose front is on a long side.
///
/// Knobs are no evidence here: a side panel seen at a glancing angle, a few centimetres from its
/// wall, shows bumps of depth noise that read as knobs (the kitchen's fridge: four on its side
/// against its front's two bars), while a bar is a line of points over 8 cm or more.
fn front_among_faces(
    faces: &[Facing],
    perceive: impl Fn(Vec3) -> Option<PerceivedFront>,
) -> (Facing, Option<PerceivedFront>) {
    let evidence = |front: &Option<PerceivedFront>| {
        front.as_ref().map_or(0, |f| {
            let bars = f.handles.iter().filter(|h| h.kind == HandleKind::Bar);
            bars.count() + f.open_drawers.len() + f.open_doors.len()
        })
    };
    let first = faces[0];
    let mut best = (first, perceive(first.direction));
    for &other in &faces[1..] {
        // A face along the first (a wall split in two behind the same side) is no other face.
        if other.direction.dot(first.direction) > CORNER_COS {
            continue;
        }
        let front = perceive(other.direction);
        if evidence(&front) > evidence(&best.1) {
            best = (other, front);
        }
    }
    best
}

/// The outward normals of `bbox`'s two long vertical faces, the one nearer `toward` (the room's
/// middle) first, as facings of a free-standing object; `None` when the box is too near square
/// (sides within `LONG_SIDE_RATIO`) to tell its long sides.
fn long_faces(bbox: &GravityBox, toward: Option<Vec3>) -> Option<[Facing; 2]> {
    let (sin, cos) = bbox.yaw.sin_cos();
    let normal = if bbox.size.x >= LONG_SIDE_RATIO * bbox.size.y {
        Vec3::new(-sin, cos, 0.0)
    } else if bbox.size.y >= LONG_SIDE_RATIO * bbox.size.x {
        Vec3::new(cos, sin, 0.0)
    } else {
        return None;
    };
    let normal = if toward.is_some_and(|t| t.dot(normal) < 0.0) {
        -normal
    } else {
        normal
    };
    Some([normal, -normal].map(|direction| Facing {
        direction,
        confidence: FACES_ROOM_CONFIDENCE,
        against_wall: false,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chair_at_a_table_faces_it_and_one_far_from_any_table_does_not_care() {
        // A 1.4 x 0.8 table turned 30 degrees, and chairs seen as their backs (8 cm deep).
        let table = GravityBox {
            center: Vec3::new(0.0, 0.0, 0.37),
            yaw: std::f32::consts::FRAC_PI_6,
            size: Vec3::new(1.4, 0.8, 0.75),
        };
        let chair = |x: f32, y: f32| GravityBox {
            center: Vec3::new(x, y, 0.45),
            yaw: std::f32::consts::FRAC_PI_6,
            size: Vec3::new(0.45, 0.08, 0.9),
        };
        // On the table's long side, 30 cm out: faces across the table's width.
        let side = table
            .world_from_box()
            .transform_point3(Vec3::new(0.2, 0.75, 0.0));
        let facing = facing_its_table(&chair(side.x, side.y), std::slice::from_ref(&table))
            .expect("at the table");
        let inward = table.world_from_box().transform_vector3(-Vec3::Y);
        assert!(facing.direction.dot(inward) > 0.999, "{facing:?}");
        assert_eq!(facing.confidence, 1.0);
        // At its end: faces along its length.
        let end = table
            .world_from_box()
            .transform_point3(Vec3::new(-1.0, 0.1, 0.0));
        let facing = facing_its_table(&chair(end.x, end.y), std::slice::from_ref(&table))
            .expect("at the table");
        let along = table.world_from_box().transform_vector3(Vec3::X);
        assert!(facing.direction.dot(along) > 0.999, "{facing:?}");
        // 1.5 m away, or with no table: no opinion.
        let far = table
            .world_from_box()
            .transform_point3(Vec3::new(0.0, 1.9, 0.0));
        assert!(facing_its_table(&chair(far.x, far.y), std::slice::from_ref(&table)).is_none());
        assert!(facing_its_table(&chair(side.x, side.y), &[]).is_none());
    }

    /// Points every 2 cm over `corner + i u + j v`, `i` up to `a` and `j` up to `b` metres.
    fn panel(corner: Vec3, u: Vec3, a: f32, v: Vec3, b: f32) -> Vec<Vec3> {
        let (n_u, n_v) = ((a / 0.02).round() as usize, (b / 0.02).round() as usize);
        (0..=n_u)
            .flat_map(|i| (0..=n_v).map(move |j| corner + 0.02 * (i as f32 * u + j as f32 * v)))
            .collect()
    }

    #[test]
    fn a_bookcase_in_a_corner_has_its_back_to_the_wall_along_its_long_side() {
        let wall = |direction: Vec3| Facing {
            direction,
            confidence: 1.0,
            against_wall: true,
        };
        // Seen 0.32 m deep along x and 0.7 m wide along y; the wall across its end (facing +y)
        // is nearer than the one along its long side (facing +x).
        let bbox = GravityBox {
            center: Vec3::new(0.17, 0.34, 0.65),
            yaw: 0.0,
            size: Vec3::new(0.32, 0.7, 1.3),
        };
        let behind = vec![wall(Vec3::Y), wall(Vec3::X)];
        let first = |b: Vec<Facing>| b[0].direction;
        assert_eq!(first(long_side_first(behind.clone(), &bbox, true)), Vec3::X);
        // A class built as deep as wide (a cabinet) keeps the nearer wall, and so does a box
        // too near square to tell its long side.
        assert_eq!(
            first(long_side_first(behind.clone(), &bbox, false)),
            Vec3::Y
        );
        let squarish = GravityBox {
            size: Vec3::new(0.5, 0.7, 1.3),
            ..bbox
        };
        assert_eq!(
            first(long_side_first(behind.clone(), &squarish, true)),
            Vec3::Y
        );
        // Already with its back along the long side: unchanged.
        let turned = GravityBox {
            size: Vec3::new(0.7, 0.32, 1.3),
            ..bbox
        };
        assert_eq!(first(long_side_first(behind, &turned, true)), Vec3::Y);
    }

    #[test]
    fn a_cabinet_in_a_corner_faces_where_its_handles_are_not_away_from_the_nearer_wall() {
        // A cabinet 0.6 wide, 0.56 deep and 0.86 high, its front at y = 0 facing -y with two
        // bar handles standing 3 cm out; its back 4 cm from a wall at y = 0.6 and its left side
        // 1 cm from a wall at x = -0.31. Seen: the front, the top and the right side.
        let mut points = panel(Vec3::new(-0.3, 0.0, 0.0), Vec3::X, 0.6, Vec3::Z, 0.86);
        points.extend(panel(
            Vec3::new(-0.3, 0.0, 0.86),
            Vec3::X,
            0.6,
            Vec3::Y,
            0.56,
        ));
        points.extend(panel(
            Vec3::new(0.3, 0.0, 0.0),
            Vec3::Y,
            0.56,
            Vec3::Z,
            0.86,
        ));
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        let bar = |x: f32| {
            (0..=12).flat_map(move |i| {
                let p = Vec3::new(x, -0.03, 0.3 + 0.02 * i as f32);
                [p, p + 0.01 * Vec3::Y]
            })
        };
        let walls = [
            Plane::from_point_normal(Vec3::new(0.0, 0.6, 0.0), Vec3::NEG_Y),
            Plane::from_point_normal(Vec3::new(-0.31, 0.0, 0.0), Vec3::X),
        ];
        let behind = walls_behind(&bbox, &walls);
        assert_eq!(behind.len(), 2);
        assert!(
            behind[0].direction.x > 0.99,
            "the side's wall is the nearer"
        );
        let perceive = |points: &[Vec3]| {
            front_among_faces(&behind, |d| perceive_front(&bbox, d, points, false))
        };
        // Without handles the nearer wall decides, as for an object against one wall.
        let (facing, _) = perceive(&points);
        assert!(facing.direction.x > 0.99, "{facing:?}");
        // Knobs are no evidence: noise on a glancing side panel reads as knobs.
        let knob = |x: f32| {
            (0..12).map(move |i| {
                let a = i as f32 / 12.0 * std::f32::consts::TAU;
                Vec3::new(x + 0.015 * a.cos(), -0.03, 0.6 + 0.015 * a.sin())
            })
        };
        points.extend(knob(-0.2).chain(knob(0.2)));
        let seen_knobs = perceive_front(&bbox, Vec3::NEG_Y, &points, false).expect("a front");
        assert_eq!(seen_knobs.handles.len(), 2, "{:?}", seen_knobs.handles);
        assert!(
            seen_knobs
                .handles
                .iter()
                .all(|h| h.kind == HandleKind::Knob)
        );
        let (facing, _) = perceive(&points);
        assert!(facing.direction.x > 0.99, "{facing:?}");
        points.extend(bar(-0.25).chain(bar(0.25)));
        let (facing, front) = perceive(&points);
        assert!(facing.direction.y < -0.99, "{facing:?}");
        let bars = front.expect("a front").handles;
        let bars = bars.iter().filter(|h| h.kind == HandleKind::Bar);
        assert_eq!(bars.count(), 2);
    }

    #[test]
    fn a_free_standing_microwave_faces_along_its_short_axis_where_its_handle_is() {
        // A microwave 0.5 wide (x) and 0.38 deep (y), 0.3 high, on a table in the room's middle,
        // seen all round; the room's middle lies off its short side (+x, a little -y).
        let mut points = Vec::new();
        for (corner, u, a, v, b) in [
            (Vec3::new(-0.25, -0.19, 0.75), Vec3::X, 0.5, Vec3::Z, 0.3),
            (Vec3::new(-0.25, 0.19, 0.75), Vec3::X, 0.5, Vec3::Z, 0.3),
            (Vec3::new(-0.25, -0.19, 0.75), Vec3::Y, 0.38, Vec3::Z, 0.3),
            (Vec3::new(0.25, -0.19, 0.75), Vec3::Y, 0.38, Vec3::Z, 0.3),
            (Vec3::new(-0.25, -0.19, 1.05), Vec3::X, 0.5, Vec3::Y, 0.38),
        ] {
            points.extend(panel(corner, u, a, v, b));
        }
        let bbox = GravityBox::enclosing(&points, 0.0).expect("box");
        let toward = Vec3::new(1.0, -0.3, 0.0).normalize();
        let faces = long_faces(&bbox, Some(toward)).expect("long sides");
        // The short face (+x) is nearest the room's middle; the long face on its side comes first.
        assert!(faces[0].direction.y < -0.99, "{:?}", faces[0]);
        assert!(faces[1].direction.y > 0.99, "{:?}", faces[1]);
        let perceive = |points: &[Vec3]| {
            front_among_faces(&faces, |d| perceive_front(&bbox, d, points, false))
        };
        let (facing, _) = perceive(&points);
        assert!(
            facing.direction.y < -0.99,
            "no evidence: the prior's long face, {facing:?}"
        );
        // A bar handle on the far long face (+y) turns it.
        points.extend((0..=10).flat_map(|i| {
            let p = Vec3::new(0.18, 0.22, 0.8 + 0.02 * i as f32);
            [p, p - 0.01 * Vec3::Y]
        }));
        let (facing, front) = perceive(&points);
        assert!(facing.direction.y > 0.99, "{facing:?}");
        assert!(
            front
                .expect("a front")
                .handles
                .iter()
                .any(|h| h.kind == HandleKind::Bar)
        );
        // A box near square has no long sides to tell.
        let square =
            GravityBox::enclosing(&[Vec3::ZERO, Vec3::new(0.5, 0.48, 0.3)], 0.0).expect("box");
        assert!(long_faces(&square, Some(toward)).is_none());
    }

    #[test]
    fn a_unit_seen_as_its_front_reaches_back_to_the_wall_behind_it() {
        // A dishwasher's door seen as a 9 cm slab, 0.6 m wide along x, its front facing +y; the
        // wall behind faces +y at y = 0, the slab's back 0.5 m out; a side wall faces +x.
        let walls = [
            Plane::from_point_normal(Vec3::ZERO, Vec3::Y),
            Plane::from_point_normal(Vec3::new(-0.5, 0.0, 0.0), Vec3::X),
        ];
        let slab = GravityBox {
            center: Vec3::new(0.4, 0.545, 0.42),
            yaw: 0.0,
            size: Vec3::new(0.6, 0.09, 0.84),
        };
        let depth = 0.5..=0.7;
        let reached = reaching_back_to_wall(slab, &walls, depth.clone());
        let near = |a: Vec3, b: Vec3| (a - b).abs().max_element() < 1e-5;
        assert!(
            near(reached.size, Vec3::new(0.6, 0.59, 0.84)),
            "{reached:?}"
        );
        assert!(
            near(reached.center, Vec3::new(0.4, 0.295, 0.42)),
            "{reached:?}"
        );
        // The same slab with its box turned a quarter (its short side the box's x): the same.
        let turned = GravityBox {
            yaw: std::f32::consts::FRAC_PI_2,
            size: Vec3::new(0.09, 0.6, 0.84),
            ..slab
        };
        let reached = reaching_back_to_wall(turned, &walls, depth.clone());
        assert!(
            near(reached.center, Vec3::new(0.4, 0.295, 0.42)),
            "{reached:?}"
        );
        assert!((reached.size.x - 0.59).abs() < 1e-5, "{reached:?}");
        // A wall farther than the class is deep, or none, leaves the box; so does a box as deep
        // as the class, or one whose only wall is at its side.
        let far = GravityBox {
            center: Vec3::new(0.4, 0.745, 0.42),
            ..slab
        };
        assert_eq!(reaching_back_to_wall(far, &walls, depth.clone()), far);
        assert_eq!(reaching_back_to_wall(slab, &[], depth.clone()), slab);
        let deep = GravityBox {
            size: Vec3::new(0.6, 0.55, 0.84),
            ..slab
        };
        assert_eq!(reaching_back_to_wall(deep, &walls, depth.clone()), deep);
        assert_eq!(reaching_back_to_wall(slab, &walls[1..], depth), slab);
    }
}
