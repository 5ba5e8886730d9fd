//! Joints between links of a kinematic tree, shared by CAD models, the contact graph and the ECS.

pub mod contact_pieces;
pub mod inertial;
pub mod joint_sweep;
pub mod link;
pub mod motion_bounds;
pub mod ray_pick;
pub mod rest_test;
pub mod tree;

// The joint types live in the base layer (the CAD models carry them too); named here as well
// because a joint is the kinematic tree's vocabulary.
pub use crate::base::joint;
pub use crate::base::{JointKind, JointSpec};
