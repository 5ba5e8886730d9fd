//! Joints between links of a kinematic tree, shared by CAD models, the contact graph and the ECS.

pub mod contact_pieces;
pub mod inertial;
pub mod joint;
pub mod joint_sweep;
pub mod link;
pub mod ray_pick;
pub mod rest_test;
pub mod tree;

pub use joint::{JointKind, JointSpec};
