//! The entity's surface planes, world frame, largest first.

use bevy::prelude::*;

use crate::geometry::Plane;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct SurfacePlanes(pub Vec<Plane>);
