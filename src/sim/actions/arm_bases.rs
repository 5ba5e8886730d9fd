//! Where an arm's pick or place is tried from: the free spots of a surface in turn, and for
//! each the base pose the approach chose, then poses closer to the target and straight out
//! from a container's opening.

use glam::Affine3A;

use crate::arm::rig::ArmRig;
use crate::sim::actions::arm_motion::place_motion;
use crate::sim::actions::arm_scene::AroundObject;
use crate::sim::actions::error::ArmTries;
use crate::sim::actions::reach::{APPROACH_M, approach_point, drive};
use crate::sim::actions::{ActionError, Change, RobotInTree};
use crate::sim::navigation::NavGoal;
use crate::sim::robot::RobotSpec;
use crate::sim::scene_view::SceneView;

/// Distances (metres, base centre to the target) of the base poses tried after the one the
/// base's own approach chose, nearest last: the arm reaches farther down and in from closer.
pub(super) const CLOSER_BASES_M: [f32; 2] = [0.7, 0.55];
/// How far (metres) a base straight out from a container's spot may stand from the point
/// straight out.
const IN_FRONT_M: f32 = 0.2;
/// Base poses closer than this (metres) to one already tried are not tried again.
pub(super) const SAME_BASE_M: f32 = 0.05;
/// Free spots closer than this (metres) to one already listed are not listed again.
const SAME_SPOT_M: f32 = 0.05;

/// The arm's placing of the held `object` (node id and link) on `surface`: from the free spot
/// `first` (with the base's drive to it), or when the arm finds no motion there, from the other
/// free spots ([`free_spots`], `ignore` left out of their checks). The drive, the arm's motion
/// and the object's attachment to the surface.
#[allow(clippy::too_many_arguments, reason = "one action's whole problem")]
pub(super) fn place_on_some_spot(
    view: &SceneView,
    robot: &RobotSpec,
    rig: &ArmRig,
    state: &RobotInTree,
    (object, link): (&str, usize),
    surface: &str,
    first: Affine3A,
    ignore: &[usize],
) -> Result<Vec<Change>, ActionError> {
    let around = AroundObject::new(view, link);
    let mut tries = ArmTries::default();
    for spot in free_spots(view, link, surface, first, ignore) {
        let target = spot.translation.truncate();
        let (changes, moved) = match approach_point(view, robot, state, target, surface) {
            Ok(found) => found,
            Err(e) => {
                tries.unreached(e);
                continue;
            }
        };
        let place = |at: &RobotInTree| {
            place_motion(
                view,
                rig,
                at,
                (object, link),
                &around,
                (surface, &spot),
                None,
                ignore,
            )
        };
        match from_some_base(view, robot, state, (changes, moved), (target, None), &place) {
            Ok(changes) => return Ok(changes),
            Err(e) => tries.failed(&format!("spot ({:.2}, {:.2})", target.x, target.y), e)?,
        }
    }
    // When the base reached no spot, that is the reason, not the arm.
    Err(tries.error(Some(format!("place {object} on {surface}"))))
}

/// Free spots for `link` on `surface`: `first`, then the ones nearest the surface's middle and
/// the middles of its four quarters, each once.
pub(super) fn free_spots(
    view: &SceneView,
    link: usize,
    surface: &str,
    first: Affine3A,
    ignore: &[usize],
) -> Vec<Affine3A> {
    let mut spots = vec![first];
    let Some((lo, hi)) = view.node_bounds(surface) else {
        return spots;
    };
    let (lo, hi) = (lo.truncate(), hi.truncate());
    let centre = 0.5 * (lo + hi);
    let corners = [
        lo,
        glam::Vec2::new(lo.x, hi.y),
        glam::Vec2::new(hi.x, lo.y),
        hi,
    ];
    let nears = std::iter::once(centre).chain(corners.map(|c| 0.5 * (centre + c)));
    for near in nears {
        if let Some(spot) = view.spot_on(link, surface, near, ignore)
            && spots
                .iter()
                .all(|s| s.translation.distance(spot.translation) > SAME_SPOT_M)
        {
            spots.push(spot);
        }
    }
    spots
}

/// The arm's `motion` from the base pose the approach chose (`first`: its drive and the robot
/// after it) or, when the arm finds none there, from base poses closer to `target` (x, y) that
/// the base drives to from `start`, then (given the way a container's opening faces, `front`)
/// from those straight out from `target` through the opening: the drive and the motion, or
/// every attempt's reason.
pub(super) fn from_some_base(
    view: &SceneView,
    robot: &RobotSpec,
    start: &RobotInTree,
    first: (Vec<Change>, RobotInTree),
    (target, front): (glam::Vec2, Option<glam::Vec2>),
    motion: &dyn Fn(&RobotInTree) -> Result<Vec<Change>, ActionError>,
) -> Result<Vec<Change>, ActionError> {
    let mut bases = vec![first];
    let near = CLOSER_BASES_M.map(|reach| NavGoal {
        target,
        reach,
        facing: None,
        keep_out: Vec::new(),
    });
    // The nearest free place to the target can be beside a cabinet, not in front of the door
    // the arm must reach through.
    let in_front = front.into_iter().flat_map(|out| {
        CLOSER_BASES_M.map(|d| NavGoal {
            target: target + out * d,
            reach: IN_FRONT_M,
            facing: None,
            keep_out: Vec::new(),
        })
    });
    for goal in near.into_iter().chain(in_front) {
        if let Ok(Some((change, moved))) = drive(view, robot, start, &goal, APPROACH_M)
            && bases
                .iter()
                .all(|(_, b)| b.base.position.distance(moved.base.position) > SAME_BASE_M)
        {
            bases.push((vec![change], moved));
        }
    }
    let mut tries = ArmTries::default();
    for (mut changes, moved) in bases {
        match motion(&moved) {
            Ok(motion) => {
                changes.extend(motion);
                return Ok(changes);
            }
            Err(e) => tries.failed(&base_words(&moved), e)?,
        }
    }
    Err(tries.error(None))
}

/// Where the base of `robot` stands, in words for a failure's reason.
pub(super) fn base_words(robot: &RobotInTree) -> String {
    let p = robot.base.position;
    format!("base at ({:.2}, {:.2})", p.x, p.y)
}
