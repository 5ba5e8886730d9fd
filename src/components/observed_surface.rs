//! The entity's own surface points as the contact graph kept them: its segment mesh's vertices
//! without what the walls, the floor or its supporting plane claimed, and without stray pieces.
//! CAD alignment fits models to these.

use bevy::prelude::*;
use glam::Vec3;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct ObservedSurface(pub Vec<Vec3>);

/// What the map saw of a counter under its top (aligned world): its front of doors and drawers
/// and its ends (`graph::counters::counter_body`). It joins the counter's [`ObservedSurface`],
/// where its front is perceived, but not its segment mesh: the contact graph takes a counter's
/// box from its top and stands it on the floor.
#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct CounterBody(pub Vec<Vec3>);
