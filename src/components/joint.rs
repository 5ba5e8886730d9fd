//! How a child entity may move relative to the parent that supports it (its `ChildOf`).

use bevy::prelude::*;

use crate::kinematics::JointSpec;

/// The joint to the parent and its current value (radians or metres; 0 for fixed and floating).
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct Joint {
    pub spec: JointSpec,
    pub value: f32,
}
