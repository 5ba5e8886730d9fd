//! Who an entity is: its contact-graph id, and its panoptic identity (instance, class, kind).

use bevy::prelude::*;

use crate::base::ClassId;
use crate::classes::EntityKind;

/// The entity's id in the contact graph and every export (`table_1`, `floor`, `wall_2`).
#[derive(Component, Clone, Debug, PartialEq, Eq, Hash)]
pub struct SceneEntity(pub String);

/// Panoptic identity: instance id in the panoptic map, semantic class and kind.
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Panoptic {
    pub instance: u32,
    pub class: ClassId,
    pub kind: EntityKind,
}
