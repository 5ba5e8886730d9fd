//! The front of an object of an articulated class as the camera saw it: the plane facing the
//! room and the handles and knobs on it (`perception::fronts`). CadMatch puts it on the entity;
//! CAD selection weighs models by it and report.json lists it.

use bevy::prelude::*;

#[derive(Component, Clone, Debug, PartialEq)]
pub struct PerceivedFront(pub crate::perception::fronts::PerceivedFront);
