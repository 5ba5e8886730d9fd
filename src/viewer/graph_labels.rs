//! The contact graph layer's labels: each node's id on a tag above its box, kept over the box as
//! the camera moves and as the object is moved, shown only with the graph layer.

use bevy::prelude::*;

use crate::components::{OrientedBox, Panoptic, SceneEntity};
use crate::viewer::camera::OrbitCamera;
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::HIDDEN_CLASSES;

const LABEL_FONT_PX: f32 = 11.0;
const LABEL_TEXT: Color = Color::srgb(0.05, 0.05, 0.1);
const LABEL_BACKGROUND: Color = Color::srgba(1.0, 0.85, 0.6, 0.8);
/// The tag floats this high (metres) over the box's top.
const LABEL_LIFT_M: f32 = 0.05;

/// A tag naming the scene node `0`.
#[derive(Component)]
pub struct NodeLabel(pub Entity);

/// Scene nodes with a box, as they first appear.
type NewNode<'a> = (Entity, &'a SceneEntity, Option<&'a Panoptic>);
type NewNodeFilter = (Added<SceneEntity>, With<OrientedBox>);

/// One tag per node that has a box and is not hidden, spawned once the node exists.
fn spawn_labels(mut commands: Commands, nodes: Query<NewNode, NewNodeFilter>) {
    for (entity, id, panoptic) in &nodes {
        if panoptic.is_some_and(|p| HIDDEN_CLASSES.contains(&p.class.as_str())) {
            continue;
        }
        commands.spawn((
            Text::new(id.0.clone()),
            TextFont {
                font_size: FontSize::Px(LABEL_FONT_PX),
                ..default()
            },
            TextColor(LABEL_TEXT),
            Node {
                position_type: PositionType::Absolute,
                padding: UiRect::axes(Val::Px(2.0), Val::Px(0.0)),
                ..default()
            },
            BackgroundColor(LABEL_BACKGROUND),
            Visibility::Hidden,
            NodeLabel(entity),
        ));
    }
}

/// Puts each tag over its node's box as the camera sees it; hides it when the graph layer is off
/// or the box is behind the camera.
fn place_labels(
    layers: Res<ActiveLayers>,
    camera: Query<(&Camera, &GlobalTransform), With<OrbitCamera>>,
    boxes: Query<&OrientedBox>,
    mut labels: Query<(&NodeLabel, &ComputedNode, &mut Node, &mut Visibility)>,
) {
    let Ok((camera, eye)) = camera.single() else {
        return;
    };
    for (label, computed, mut node, mut visibility) in &mut labels {
        let at = boxes.get(label.0).ok().and_then(|b| {
            let top = b.0.center.with_z(b.0.top_z() + LABEL_LIFT_M);
            camera.world_to_viewport(eye, top).ok()
        });
        match at.filter(|_| layers.is_on(Layer::Graph)) {
            Some(p) => {
                // Centred over the point: half the tag's own size, in logical pixels.
                let half = computed.size() * computed.inverse_scale_factor() / 2.0;
                node.left = Val::Px(p.x - half.x);
                node.top = Val::Px(p.y - half.y);
                visibility.set_if_neq(Visibility::Inherited);
            }
            None => {
                visibility.set_if_neq(Visibility::Hidden);
            }
        }
    }
}

pub struct GraphLabelsPlugin;

impl Plugin for GraphLabelsPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (spawn_labels, place_labels).chain());
    }
}
