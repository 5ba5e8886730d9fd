//! The entity's own surface points as the contact graph kept them: its segment mesh's vertices
//! without what the walls, the floor or its supporting plane claimed, and without stray pieces.
//! CAD alignment fits models to these.

use bevy::prelude::*;
use glam::Vec3;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct ObservedSurface(pub Vec<Vec3>);
