//! Grasps of an object from its box: where the tool goes and from which way the hand comes in.
//!
//! The tool frame is the gripper's: +z points out of the hand between the fingertips, the
//! fingers close along +-y (the Panda's `panda_grasptarget`). A top grasp comes down with the
//! fingers across a horizontal side of the box that fits between them; a side grasp comes in
//! horizontally at the box's middle height, across the other horizontal side or across the
//! height (a book lying flat). Grasps facing the robot come first. No grasp takes the tool so
//! deep into the object that the palm behind the fingers would meet it.

use glam::{Affine3A, Mat3, Vec2, Vec3};
use parry3d::query::{Ray, RayCast};
use parry3d::shape::ConvexPolyhedron;

use crate::geometry::mesh::points_bounds;

/// How far the fingertips reach below an object's top in a top grasp, metres (less for a
/// low object: half its height).
const TOP_GRASP_DEPTH_M: f32 = 0.03;
/// How far the finger pads reach past the grasp point towards the palm, metres: the band of
/// the object the fingers close on.
const FINGER_PAD_M: f32 = 0.02;
/// Room left between the object and each open finger, metres (the Panda's 8 cm hand takes the
/// kitchen's 7.5 cm cup from the side).
const FINGER_CLEARANCE_M: f32 = 0.002;
/// A vessel's wall as the fingers take it: its thickness, and how far in from the box's side
/// the fingers close on it, metres.
const RIM_WIDTH_M: f32 = 0.01;
const RIM_INSET_M: f32 = 0.006;
/// The rim is the object's outline within this much (metres) of its top: a mug's handle, which
/// ends lower, is no rim (at the box's side a finger went 15 mm into a mug in rapier).
const RIM_BAND_M: f32 = 0.01;
/// Room left between the object and the palm, metres: more than the planner's clearance on
/// the last stretch (`reach::STRETCH_MARGIN_M`, 4 mm).
const PALM_CLEARANCE_M: f32 = 0.006;
/// How far a pitched side grasp's approach dips below the horizontal, radians (30 degrees).
const SIDE_PITCH: f32 = std::f32::consts::FRAC_PI_6;
/// How far a leaning rim grasp's approach leans from the vertical, radians (30 degrees): at 45
/// the hand's far end, tilted with it, met the table under a bowl.
const RIM_LEAN: f32 = std::f32::consts::FRAC_PI_6;
/// How far below the rim a leaning rim grasp's tool goes, metres (less than an upright one's
/// `TOP_GRASP_DEPTH_M`: the finger outside, tilted, met the table under a bowl).
const LEANING_RIM_DEPTH_M: f32 = 0.015;
/// How far back along its approach the hand starts its straight last stretch, metres.
pub const PREGRASP_M: f32 = 0.1;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GraspKind {
    Top,
    Rim,
    Side,
    /// The grasp an object is already held by (set down as it was picked).
    Held,
}

/// What of the hand decides a grasp, metres.
#[derive(Clone, Copy, Debug)]
pub struct Hand {
    /// How wide the fingers open.
    pub opening: f32,
    /// How far the palm lies behind the tool point (`Arm::palm_depth`).
    pub palm_depth: f32,
}

impl Hand {
    /// How far past the object's near face the tool may go.
    fn reach_in(&self) -> f32 {
        (self.palm_depth - PALM_CLEARANCE_M).max(0.0)
    }
}

/// The gap the fingers close to on `pieces` (convex, in the tool's frame; the fingers close
/// along the tool's y through its point): each finger stops `FINGER_CLEARANCE_M` short of the
/// farther of the surfaces it meets, so the closed hand stands round what it holds without
/// going into it (the held object rides in the hand as attached, not by friction). The whole
/// opening when something fills the space between the open fingers; `None` when nothing lies
/// between them.
pub fn finger_gap(pieces: &[ConvexPolyhedron], opening: f32) -> Option<f32> {
    let half = 0.5 * opening;
    let mut reach: Option<f32> = None;
    for piece in pieces {
        for towards in [Vec3::Y, Vec3::NEG_Y] {
            // From the open finger on one side towards the other (a start inside is a hit at 0).
            let ray = Ray::new(-towards * half, towards);
            if let Some(t) = piece.cast_local_ray(&ray, opening, true) {
                let from_middle = half - t;
                reach = Some(reach.map_or(from_middle, |r| r.max(from_middle)));
            }
        }
    }
    reach.map(|r| (2.0 * (r.abs() + FINGER_CLEARANCE_M)).min(opening))
}

/// One way to hold an object.
#[derive(Clone, Copy, Debug)]
pub struct Grasp {
    pub kind: GraspKind,
    /// The tool's pose when holding it.
    pub world_from_tool: Affine3A,
    /// Unit direction (world) the hand moves along its last stretch: the tool's +z.
    pub approach: Vec3,
    /// The object's width between the fingers, metres.
    pub width: f32,
}

impl Grasp {
    /// The tool's pose at the start of the last stretch.
    pub fn pregrasp(&self) -> Affine3A {
        Affine3A::from_translation(-self.approach * PREGRASP_M) * self.world_from_tool
    }
}

/// The grasps of an object whose collision vertices are `points` (its frame, z up) placed at
/// `world_from_object`, for `hand`, best first for a robot standing at `robot` (x, y). A top grasp
/// measures the object where the fingers close (a bottle's neck, not its body). An open vessel
/// (`rim`: a cup, a bowl) too wide for the fingers is also held by its rim, the fingers across the
/// wall at the middle of each side of its top.
pub fn grasps(
    world_from_object: &Affine3A,
    points: &[Vec3],
    hand: Hand,
    robot: Vec2,
    rim: bool,
) -> Vec<Grasp> {
    let Some((lo, hi)) = points_bounds(points) else {
        return Vec::new();
    };
    let size = hi - lo;
    let centre = world_from_object.transform_point3(0.5 * (lo + hi));
    let axis_x = world_from_object.transform_vector3(Vec3::X).normalize();
    let axis_y = world_from_object.transform_vector3(Vec3::Y).normalize();
    // A tenth of a millimetre for rounding: 7.6 cm fits the 8 cm hand.
    let fits = |width: f32| width + 2.0 * FINGER_CLEARANCE_M <= hand.opening + 1e-4;
    let to_robot = (robot - centre.truncate()).normalize_or_zero().extend(0.0);
    let mut out = Vec::new();
    // Top grasps: down onto the top, the fingers closing across x or y.
    let depth = TOP_GRASP_DEPTH_M.min(0.5 * size.z).min(hand.reach_in());
    let top = centre + Vec3::Z * (0.5 * size.z - depth);
    let band: Vec<Vec3> = points
        .iter()
        .copied()
        .filter(|p| p.z >= hi.z - depth - FINGER_PAD_M)
        .collect();
    let band_size = points_bounds(&band).map_or(size, |(l, h)| h - l);
    for (closing, width) in [(axis_x, band_size.x), (axis_y, band_size.y)] {
        if fits(width) {
            out.push(Grasp {
                kind: GraspKind::Top,
                world_from_tool: tool_pose(top, -Vec3::Z, closing),
                approach: -Vec3::Z,
                width,
            });
        }
    }
    if rim {
        // Around the middle of the rim, at each side of its outline.
        let ring: Vec<Vec3> = points
            .iter()
            .copied()
            .filter(|p| p.z >= hi.z - RIM_BAND_M)
            .collect();
        let (ring_lo, ring_hi) = points_bounds(&ring).unwrap_or((lo, hi));
        let ring_size = ring_hi - ring_lo;
        let off_middle = (0.5 * (ring_lo + ring_hi) - 0.5 * (lo + hi)).with_z(0.0);
        let rim_top = top + world_from_object.transform_vector3(off_middle);
        let (mut rims, mut leaning_rims) = (Vec::new(), Vec::new());
        for (outward, half) in [
            (axis_x, 0.5 * ring_size.x),
            (-axis_x, 0.5 * ring_size.x),
            (axis_y, 0.5 * ring_size.y),
            (-axis_y, 0.5 * ring_size.y),
        ] {
            let at = rim_top + outward * (half - RIM_INSET_M);
            rims.push(Grasp {
                kind: GraspKind::Rim,
                world_from_tool: tool_pose(at, -Vec3::Z, outward),
                approach: -Vec3::Z,
                width: RIM_WIDTH_M,
            });
            // The same with the hand leaning out over the side (a bowl carried into a
            // microwave leaves the wrist low and outside the cavity, not over the bowl), less
            // deep: the finger outside, tilted, comes lower than the tool.
            let at = at + Vec3::Z * (depth - LEANING_RIM_DEPTH_M).max(0.0);
            let approach = -(Vec3::Z * RIM_LEAN.cos() + outward * RIM_LEAN.sin()).normalize();
            leaning_rims.push(Grasp {
                kind: GraspKind::Rim,
                world_from_tool: tool_pose(at, approach, outward),
                approach,
                width: RIM_WIDTH_M,
            });
        }
        // The rim nearest the robot first; leaning after upright.
        let d = |g: &Grasp| g.world_from_tool.translation.truncate().distance(robot);
        rims.sort_by(|a, b| d(a).total_cmp(&d(b)));
        leaning_rims.sort_by(|a, b| d(a).total_cmp(&d(b)));
        out.extend(rims);
        out.extend(leaning_rims);
    }
    // Side grasps: in from each horizontal side, across the other horizontal side or the height.
    let mut sides = Vec::new();
    for (inward, across, across_width, deep) in [
        (axis_x, axis_y, size.y, size.x),
        (-axis_x, axis_y, size.y, size.x),
        (axis_y, axis_x, size.x, size.y),
        (-axis_y, axis_x, size.x, size.y),
    ] {
        // At the middle, or as far in as the palm allows.
        let at = centre - inward * (0.5 * deep - hand.reach_in()).max(0.0);
        for (closing, width) in [(across, across_width), (Vec3::Z, size.z)] {
            if fits(width) {
                sides.push(Grasp {
                    kind: GraspKind::Side,
                    world_from_tool: tool_pose(at, inward, closing),
                    approach: inward,
                    width,
                });
            }
        }
        // The same across the other side with the hand pitched down: its wrist rides higher,
        // clear of the surface the object stands on (level at a cup's middle, 6 cm over a
        // table, the Panda's sixth link met the table) and of a low shelf's top it is carried
        // under.
        if fits(across_width) {
            let approach = (inward * SIDE_PITCH.cos() - Vec3::Z * SIDE_PITCH.sin()).normalize();
            let nearest = points
                .iter()
                .map(|p| (world_from_object.transform_point3(*p) - centre).dot(approach))
                .fold(f32::INFINITY, f32::min);
            let at = centre + approach * (nearest + hand.reach_in()).min(0.0);
            sides.push(Grasp {
                kind: GraspKind::Side,
                world_from_tool: tool_pose(at, approach, across),
                approach,
                width: across_width,
            });
        }
    }
    // Facing the robot: coming in away from it first.
    sides.sort_by(|a, b| {
        a.approach
            .dot(to_robot)
            .total_cmp(&b.approach.dot(to_robot))
    });
    out.extend(sides);
    out
}

/// `grasps` with the most level approaches first (from the side, then pitched, then from
/// above), each group in its own order. A caller tries only the first few: a cup's two top and
/// four rim grasps came before every side grasp, and into a container the hand carries the
/// object in level through its front (from above, a forearm over a cup in a cabinet's level
/// met the cabinet).
pub fn most_level_first(mut grasps: Vec<Grasp>) -> Vec<Grasp> {
    grasps.sort_by_key(|g| std::cmp::Reverse((g.approach.z * 10.0).round() as i32));
    grasps
}

/// The tool pose at `at` pointing along `approach` with the fingers closing along `closing`.
fn tool_pose(at: Vec3, approach: Vec3, closing: Vec3) -> Affine3A {
    let z = approach.normalize();
    let y = (closing - z * closing.dot(z)).normalize();
    let x = y.cross(z);
    Affine3A::from_mat3_translation(Mat3::from_cols(x, y, z), at)
}

#[cfg(test)]
mod tests {
    use glam::Vec3A;

    use super::*;

    /// A hand opening to `opening` whose palm lies far behind the tool point.
    fn hand(opening: f32) -> Hand {
        Hand {
            opening,
            palm_depth: 0.2,
        }
    }

    /// The fingers close to 2 mm off each side of what lies between them, to the farther side
    /// of an object off the middle, stay open on one that fills the opening, and have nothing to
    /// close on beside an object out of their line.
    #[test]
    fn fingers_close_round_what_lies_between_them() {
        let block = |lo: Vec3, hi: Vec3| {
            ConvexPolyhedron::from_convex_hull(&crate::geometry::mesh::box_corners(lo, hi))
                .expect("a box")
        };
        let centred = block(Vec3::new(-0.01, -0.03, -0.05), Vec3::new(0.01, 0.03, 0.01));
        let gap = finger_gap(&[centred], 0.08).expect("between the fingers");
        assert!((gap - 0.064).abs() < 1e-5, "{gap}");
        let off_middle = block(Vec3::new(-0.01, -0.01, -0.05), Vec3::new(0.01, 0.025, 0.01));
        let gap = finger_gap(&[off_middle], 0.08).expect("between the fingers");
        assert!((gap - 0.054).abs() < 1e-5, "{gap}");
        let wide = block(Vec3::new(-0.01, -0.06, -0.05), Vec3::new(0.01, 0.06, 0.01));
        assert_eq!(finger_gap(&[wide], 0.08), Some(0.08));
        let beside = block(Vec3::new(0.05, -0.01, -0.05), Vec3::new(0.07, 0.01, 0.01));
        assert_eq!(finger_gap(&[beside], 0.08), None);
    }

    #[test]
    fn a_cup_gets_top_and_side_grasps_and_a_tray_none() {
        let cuboid = |lo: Vec3, hi: Vec3| crate::geometry::mesh::box_corners(lo, hi).to_vec();
        let cup = grasps(
            &Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.75)),
            &cuboid(Vec3::new(-0.04, -0.04, 0.0), Vec3::new(0.04, 0.04, 0.1)),
            hand(0.1),
            Vec2::ZERO,
            false,
        );
        assert_eq!(cup[0].kind, GraspKind::Top);
        let top = cup[0].world_from_tool;
        assert!((top.translation.z - (0.75 + 0.07)).abs() < 1e-5);
        // The hand points down, its axes a rotation.
        assert!((Vec3::from(top.matrix3.z_axis) + Vec3::Z).length() < 1e-5);
        assert!((top.matrix3.determinant() - 1.0).abs() < 1e-5);
        // The first side grasp comes in from the robot's side (it stands at -x).
        let side = cup
            .iter()
            .find(|g| g.kind == GraspKind::Side)
            .expect("side");
        assert!(side.approach.x > 0.9, "{:?}", side.approach);
        assert!((side.pregrasp().translation.x - 0.9).abs() < 1e-5);
        let tray = grasps(
            &Affine3A::IDENTITY,
            &cuboid(Vec3::new(-0.2, -0.2, 0.0), Vec3::new(0.2, 0.2, 0.2)),
            hand(0.08),
            Vec2::ZERO,
            false,
        );
        assert!(tray.is_empty());
        // A bowl is held by its rim, the nearest side first.
        let bowl = grasps(
            &Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.75)),
            &cuboid(Vec3::new(-0.07, -0.07, 0.0), Vec3::new(0.07, 0.07, 0.07)),
            hand(0.08),
            Vec2::ZERO,
            true,
        );
        assert_eq!(bowl[0].kind, GraspKind::Rim);
        assert!((bowl[0].world_from_tool.translation.x - (1.0 - 0.064)).abs() < 1e-5);
        // A 10 cm mug whose handle (on +x, 2 cm out) ends 1.2 cm under its rim: the rim grasp
        // on the handle's side is at the body's wall, not at the handle's outer bar.
        let mut mug = cuboid(Vec3::new(-0.04, -0.04, 0.0), Vec3::new(0.04, 0.04, 0.1));
        mug.extend(cuboid(
            Vec3::new(0.04, -0.006, 0.025),
            Vec3::new(0.06, 0.006, 0.088),
        ));
        let mug = grasps(
            &Affine3A::IDENTITY,
            &mug,
            hand(0.08),
            Vec2::new(1.0, 0.0),
            true,
        );
        let on_the_handle_side = mug
            .iter()
            .filter(|g| g.kind == GraspKind::Rim && g.approach.z < -0.99)
            .map(|g| g.world_from_tool.translation.x)
            .fold(f32::MIN, f32::max);
        assert!(
            (on_the_handle_side - (0.04 - RIM_INSET_M)).abs() < 1e-5,
            "{on_the_handle_side}"
        );
        // A bottle too wide for the hand is taken by its neck from above.
        let mut bottle = cuboid(Vec3::new(-0.045, -0.045, 0.0), Vec3::new(0.045, 0.045, 0.2));
        bottle.extend(cuboid(
            Vec3::new(-0.015, -0.015, 0.2),
            Vec3::new(0.015, 0.015, 0.3),
        ));
        let taken = grasps(&Affine3A::IDENTITY, &bottle, hand(0.08), Vec2::X, false);
        assert_eq!(taken[0].kind, GraspKind::Top);
        assert!((taken[0].width - 0.03).abs() < 1e-5);
    }

    #[test]
    fn pitched_and_leaning_grasps_come_first_into_a_container_and_keep_the_hand_outside() {
        let cuboid = |lo: Vec3, hi: Vec3| crate::geometry::mesh::box_corners(lo, hi).to_vec();
        let panda = Hand {
            opening: 0.08,
            palm_depth: 0.039,
        };
        // A 7 cm cup: top, rim, level side and side grasps pitched 30 degrees down.
        let cup = grasps(
            &Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.75)),
            &cuboid(
                Vec3::new(-0.035, -0.035, 0.0),
                Vec3::new(0.035, 0.035, 0.11),
            ),
            panda,
            Vec2::ZERO,
            true,
        );
        let pitched: Vec<&Grasp> = cup
            .iter()
            .filter(|g| g.kind == GraspKind::Side && g.approach.z < -0.1)
            .collect();
        assert_eq!(pitched.len(), 4);
        for g in &pitched {
            assert!((g.approach.z + SIDE_PITCH.sin()).abs() < 1e-5, "{g:?}");
            // The fingers still close level, across the cup.
            assert!(g.world_from_tool.matrix3.y_axis.z.abs() < 1e-5, "{g:?}");
        }
        // Into a container the most level come first: level sides, then pitched sides, then
        // leaning rims, then those from straight above.
        let ordered = most_level_first(cup);
        let order: Vec<i32> = ordered
            .iter()
            .map(|g| (g.approach.z * 10.0).round() as i32)
            .collect();
        assert!(order.windows(2).all(|w| w[0] >= w[1]), "{order:?}");
        assert_eq!(ordered[0].kind, GraspKind::Side);
        assert_eq!(ordered.last().map(|g| g.approach.z), Some(-1.0));
        // A 14 cm bowl: rims only; the leaning ones come down towards its middle, so the hand
        // behind the tool leans out over the side, outside the bowl.
        let bowl = grasps(
            &Affine3A::from_translation(Vec3::new(1.0, 0.0, 0.75)),
            &cuboid(Vec3::new(-0.07, -0.07, 0.0), Vec3::new(0.07, 0.07, 0.07)),
            panda,
            Vec2::ZERO,
            true,
        );
        let leaning: Vec<&Grasp> = bowl
            .iter()
            .filter(|g| g.kind == GraspKind::Rim && g.approach.z > -0.99)
            .collect();
        assert_eq!(leaning.len(), 4);
        for g in leaning {
            let tool = Vec3::from(g.world_from_tool.translation);
            let palm = tool - g.approach * 0.1;
            let out = (palm - Vec3::new(1.0, 0.0, 0.75))
                .truncate()
                .abs()
                .max_element();
            assert!(out > 0.07, "{g:?}: the hand 10 cm back is {out} m out");
            // Shallower than an upright rim grasp: 1.5 cm under the rim.
            assert!(
                (tool.z - (0.75 + 0.07 - LEANING_RIM_DEPTH_M)).abs() < 1e-5,
                "{g:?}"
            );
        }
    }

    #[test]
    fn the_palm_stays_clear_of_the_object() {
        // The Panda's palm lies 3.9 cm behind its tool point: 3.3 cm with the clearance.
        let panda = Hand {
            opening: 0.08,
            palm_depth: 0.039,
        };
        let reach_in = 0.039 - PALM_CLEARANCE_M;
        // A box 6 cm across and 16 cm long, 5 cm high: taken from the side across its 6 cm,
        // the tool stops 3.3 cm in from the end it comes in at, not at the middle 8 cm in.
        let long = crate::geometry::mesh::box_corners(
            Vec3::new(-0.08, -0.03, 0.0),
            Vec3::new(0.08, 0.03, 0.05),
        );
        let found = grasps(
            &Affine3A::IDENTITY,
            &long,
            panda,
            Vec2::new(-1.0, 0.0),
            false,
        );
        let side = found
            .iter()
            .find(|g| g.kind == GraspKind::Side && g.approach.x > 0.9)
            .expect("a side grasp along x");
        assert!((side.world_from_tool.translation.x - (-0.08 + reach_in)).abs() < 1e-5);
        // Across its 16 cm it does not fit; from its long side the middle is 3 cm in: as asked.
        let across = found
            .iter()
            .find(|g| g.kind == GraspKind::Side && g.approach.y > 0.9)
            .expect("a side grasp along y");
        assert!(across.world_from_tool.translation.y.abs() < 1e-5);
        // A palm 2 cm behind the tool: a top grasp goes 1.4 cm below the top, not 3 cm.
        let short = Hand {
            opening: 0.08,
            palm_depth: 0.02,
        };
        let top = grasps(&Affine3A::IDENTITY, &long, short, Vec2::ZERO, false)
            .into_iter()
            .find(|g| g.kind == GraspKind::Top)
            .expect("a top grasp");
        assert!((top.world_from_tool.translation.z - (0.05 - 0.014)).abs() < 1e-5);
        // The palm clears every corner of the box, at each grasp.
        for grasp in grasps(&Affine3A::IDENTITY, &long, panda, Vec2::ZERO, false) {
            let deepest = long
                .iter()
                .map(|p| {
                    (grasp.world_from_tool.translation - Vec3A::from(*p)).dot(grasp.approach.into())
                })
                .fold(f32::NEG_INFINITY, f32::max);
            assert!(deepest <= reach_in + 1e-5, "{grasp:?}: {deepest}");
        }
    }
}
