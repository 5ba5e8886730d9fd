//! The collision layer: every link's convex collision pieces (what rapier and the exports
//! collide) as wireframes over the meshes, so a user sees where the simulated shape differs
//! from the drawn one (a hull closing over a shelf's opening, say).

use bevy::prelude::*;

use crate::components::LinkBody;
use crate::viewer::layers::{ActiveLayers, Layer};

const COLLISION_COLOUR: Color = Color::srgb(0.85, 0.0, 0.85);
/// Edges between faces turned less than this (degrees) are a face's triangulation, not shape.
const CREASE_DEG: f32 = 5.0;

/// The feature edges of a link's collision pieces, in the link's frame.
#[derive(Component, Clone, Debug)]
pub struct CollisionEdges(pub Vec<[Vec3; 2]>);

/// Works out the edges of links that have none yet, once the layer is first shown.
fn find_collision_edges(
    layers: Res<ActiveLayers>,
    mut commands: Commands,
    links: Query<(Entity, &LinkBody), Without<CollisionEdges>>,
) {
    if !layers.is_on(Layer::Collision) {
        return;
    }
    for (entity, body) in &links {
        let edges = body
            .0
            .collision
            .iter()
            .flat_map(|piece| piece.feature_edges(CREASE_DEG))
            .collect();
        commands.entity(entity).insert(CollisionEdges(edges));
    }
}

fn draw_collision_edges(
    layers: Res<ActiveLayers>,
    links: Query<(&CollisionEdges, &GlobalTransform, &InheritedVisibility)>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Collision) {
        return;
    }
    for (edges, at, visible) in &links {
        if !visible.get() {
            continue;
        }
        for [a, b] in &edges.0 {
            gizmos.line(
                at.transform_point(*a),
                at.transform_point(*b),
                COLLISION_COLOUR,
            );
        }
    }
}

pub struct CollisionLayerPlugin;

impl Plugin for CollisionLayerPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (find_collision_edges, draw_collision_edges).chain());
    }
}
