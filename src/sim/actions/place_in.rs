//! An arm's place of the object it holds into a container: from the first spot (on the lowest
//! level), else from the first spot of each other level, the hand carrying the object level
//! through the front, the base trying poses straight out from the spot too.

use glam::Affine3A;

use crate::arm::rig::ArmRig;
use crate::sim::actions::{ActionError, Change, RobotInTree, arm_bases, arm_motion, arm_scene};
use crate::sim::robot::RobotSpec;
use crate::sim::scene_view::SceneView;

/// Spots of a container less than this apart in height (metres) are on the same level.
const SAME_LEVEL_M: f32 = 0.02;

/// The arm's place of the held `object` (node id and link) into `container` at `spot`, after
/// the base's approach `first` (its drive and the robot after it); when no motion sets it
/// there, at the first of `others` on each other level. The reason is the first spot's.
#[allow(clippy::too_many_arguments, reason = "one action's whole problem")]
pub(super) fn by_arm(
    view: &SceneView,
    robot: &RobotSpec,
    rig: &ArmRig,
    state: &RobotInTree,
    first: (Vec<Change>, RobotInTree),
    (object, link): (&str, usize),
    container: &str,
    spot: Affine3A,
    others: impl Iterator<Item = Affine3A>,
) -> Result<Vec<Change>, ActionError> {
    let gripper = view.link(crate::sim::robot::GRIPPER_LINK).unwrap_or(0);
    let around = arm_scene::AroundObject::new(view, link);
    let place_at = |spot: Affine3A| {
        // Into the container through its front, not down through its top.
        let inward = view
            .node_link(container)
            .and_then(|c| arm_motion::way_in(view, c, link, &spot));
        let front = inward.map(|(d, _)| -d.truncate().normalize_or_zero());
        arm_bases::from_some_base(
            view,
            robot,
            state,
            first.clone(),
            (spot.translation.truncate(), front),
            &|at| {
                arm_motion::place_motion(
                    view,
                    rig,
                    at,
                    (object, link),
                    &around,
                    (container, &spot),
                    inward,
                    &[gripper],
                )
            },
        )
    };
    let at_first = place_at(spot);
    if at_first.is_ok() {
        return at_first;
    }
    // A Panda on its base does not reach down into a floor cabinet's bottom level, where the
    // first spot is.
    let mut levels = vec![spot.translation.z];
    for other in others {
        let z = other.translation.z;
        if levels.iter().any(|l| (l - z).abs() < SAME_LEVEL_M) {
            continue;
        }
        levels.push(z);
        if let Ok(changes) = place_at(other) {
            return Ok(changes);
        }
    }
    at_first
}
