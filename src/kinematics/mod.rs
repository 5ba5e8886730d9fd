//! Joints between links of a kinematic tree, shared by CAD models, the contact graph and the ECS.

pub mod joint;

pub use joint::{JointKind, JointSpec};
