//! A moving part of an articulated CAD model (a door, a drawer) as its own entity: a child of the
//! object's entity (or of another part) joined by its revolute or prismatic `Joint`.

use bevy::prelude::*;

#[derive(Component, Clone, Debug, PartialEq, Eq)]
pub struct ModelPart {
    /// The object's entity the part belongs to (its `SceneEntity` names it in exports).
    pub object: Entity,
    /// The part's name in the model (`door`, `drawer_1`).
    pub part: String,
}
