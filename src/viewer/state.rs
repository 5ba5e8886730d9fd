//! The viewer's state that several of its parts share: where the pointer is, how often the scene
//! has changed, and what the panel says. Each layer's own state stays in its file.

use bevy::prelude::*;

/// The pointer's last position over the view, in pixels from its top-left corner.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct PointerPosition(pub Option<Vec2>);

/// Counts the changes made to the scene from the viewer: layers that depend on the scene as it
/// stands (occupancy, physics) rebuild when it moves on.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct SceneRevision(pub u64);

/// Lines the panel shows about the last interaction.
#[derive(Resource, Clone, Debug, Default)]
pub struct ViewerStatus(pub Vec<String>);
