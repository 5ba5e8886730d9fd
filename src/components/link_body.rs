//! What a link of the kinematic tree is made of: visual mesh, convex collision pieces, mass
//! properties and friction, in the entity's own frame.

use std::sync::Arc;

use bevy::prelude::*;

use crate::kinematics::link::LinkGeometry;

#[derive(Component, Clone, Debug)]
pub struct LinkBody(pub Arc<LinkGeometry>);
