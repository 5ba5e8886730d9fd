//! The entity's gravity-aligned oriented box, world frame.

use bevy::prelude::*;

use crate::geometry::GravityBox;

#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct OrientedBox(pub GravityBox);
