//! The entities this one is proximal to: close without either supporting the other, so their
//! meshes must not interpenetrate (the CAD stage's constraint). Both ends of a pair list each
//! other, in the contact graph's edge order.

use bevy::prelude::*;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct ProximalTo(pub Vec<Entity>);
