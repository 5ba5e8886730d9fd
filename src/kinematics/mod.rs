//! Joints between links of a kinematic tree, shared by CAD models, the contact graph and the ECS.

pub mod contact_pieces;
pub mod inertial;
pub mod joint_sweep;
pub mod link;
pub mod motion_bounds;
pub mod observed;
pub mod ray_pick;
pub mod rest_test;
pub mod tree;

// The joint types live in the base layer (the CAD models carry them too); named here as well
// because a joint is the kinematic tree's vocabulary.
pub use crate::base::joint;
pub use crate::base::{JointKind, JointSpec};

use crate::classes::ClassTable;

/// The joint an object gets to its support: floating for a movable class with a model, fixed
/// otherwise. An object no model replaced keeps its segment mesh, the surface seen from one side:
/// it has no inside to weigh, its hull stands on nothing in particular, and the worst such
/// segments are the ones the shape filters rejected (a 1.1 m "book" of label bleeding), so it
/// stays where it was seen.
pub fn support_joint(class: &str, has_model: bool) -> JointSpec {
    match ClassTable::builtin().get(class) {
        Some(info) if info.movable && has_model => JointSpec::FLOATING,
        _ => JointSpec::FIXED,
    }
}
