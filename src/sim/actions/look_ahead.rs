//! A pick looking ahead to its place: the task's next drives, doors and the place of the same
//! object, planned on a copy of the tree with the pick made.

use crate::arm::rig::ArmRig;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::{Action, ActionError, Change, RobotInTree, attempt};
use crate::sim::motion_path::apply_to_tree;
use crate::sim::robot::RobotSpec;

/// A pick looks ahead through at most this many of its grasps: planning the place that follows
/// costs as much as the pick.
pub(super) const MAX_LOOKS_AHEAD: usize = 4;

/// The actions of `then` up to the place of `object` (what a pick of it looks ahead through):
/// drives and doors, then the place; none when no place of it follows before another pick.
pub(super) fn pick_ahead<'a>(object: &str, then: &'a [Action]) -> &'a [Action] {
    for (k, action) in then.iter().enumerate() {
        match action {
            Action::PlaceOn { object: o, .. } | Action::PlaceIn { object: o, .. }
                if o == object =>
            {
                return &then[..=k];
            }
            Action::Navigate { .. } | Action::Open { .. } | Action::Close { .. } => {}
            _ => break,
        }
    }
    &[]
}

/// An action after a pick that does not plan once the pick is made.
#[derive(Debug, thiserror::Error)]
#[error("then {action}: {source}")]
pub(super) struct LookAheadError {
    /// The action, in words.
    action: String,
    source: ActionError,
}

/// Whether `ahead` plans, in turn, from `tree` after the robot went from `from` to `at` and
/// made the changes `picked`; else why not, naming the action that does not.
pub(super) fn plans_after(
    tree: &KinematicTree,
    robot: &RobotSpec,
    rig: &ArmRig,
    (from, at): (&RobotInTree, &RobotInTree),
    picked: &[Change],
    ahead: &[Action],
) -> Result<(), LookAheadError> {
    let mut after = tree.clone();
    let drive = Change::MoveBase {
        from: from.base,
        to: at.base,
        path_length_m: 0.0,
        path: Vec::new(),
    };
    for change in std::iter::once(&drive).chain(picked) {
        apply_to_tree(&mut after, change);
    }
    for action in ahead {
        let changes =
            attempt(&after, robot, Some(rig), action).map_err(|source| LookAheadError {
                action: action.in_words(),
                source,
            })?;
        for change in &changes {
            apply_to_tree(&mut after, change);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pick_looks_ahead_through_drives_and_doors_to_its_own_place_only() {
        let go = |to: &str| Action::Navigate { to: to.into() };
        let place_in = |object: &str| Action::PlaceIn {
            object: object.into(),
            container: "cabinet_1".into(),
        };
        let then = [
            go("cabinet_1"),
            Action::Open {
                object: "cabinet_1".into(),
                part: None,
                value: None,
            },
            place_in("cup_1"),
            go("table_1"),
        ];
        assert_eq!(pick_ahead("cup_1", &then), &then[..3]);
        // Another object's place, or another pick first: nothing to look ahead to.
        assert!(pick_ahead("cup_2", &then).is_empty());
        let picks_first = [
            Action::Pick {
                object: "bowl_1".into(),
            },
            place_in("cup_1"),
        ];
        assert!(pick_ahead("cup_1", &picks_first).is_empty());
    }
}
