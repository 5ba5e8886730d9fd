//! A moving part of an articulated CAD model (a door, a drawer) as its own entity: a child of the
//! object's entity (or of another part) joined by its revolute or prismatic `Joint`.

use bevy::prelude::*;

#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub struct ModelPart {
    /// The contact-graph id of the object the part belongs to.
    pub object: String,
    /// The part's name in the model (`door`, `drawer_1`).
    pub part: String,
}
