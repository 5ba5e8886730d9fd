//! The contact graph layer's labels: each node's id on a tag above its box, kept over the box as
//! the camera moves and as the object is moved, shown only with the graph layer. The replay tags
//! its nodes too, each from the frame it appears in.

use bevy::prelude::*;

use crate::components::{OrientedBox, Panoptic, SceneEntity};
use crate::viewer::camera::OrbitCamera;
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::HIDDEN_CLASSES;
use crate::viewer::replay_scene::ReplayData;
use crate::viewer::timeline::{ClockUpdate, ReplayClock};

const LABEL_FONT_PX: f32 = 11.0;
const LABEL_TEXT: Color = Color::srgb(0.05, 0.05, 0.1);
const LABEL_BACKGROUND: Color = Color::srgba(1.0, 0.85, 0.6, 0.8);
/// The tag floats this high (metres) over the box's top.
const LABEL_LIFT_M: f32 = 0.05;

/// A tag naming the scene node `0`.
#[derive(Component)]
pub struct NodeLabel(pub Entity);

/// A tag naming the replay's node `0` (its index in the replay's nodes).
#[derive(Component)]
pub struct ReplayLabel(pub usize);

/// A hidden tag reading `text`.
fn tag(text: String) -> impl Bundle {
    (
        Text::new(text),
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
    )
}

/// Where the tag of a node with the box `gravity_box` goes: a little over its top.
fn tag_point(gravity_box: &crate::geometry::GravityBox) -> Vec3 {
    gravity_box
        .center
        .with_z(gravity_box.top_z() + LABEL_LIFT_M)
}

/// Puts a tag centred over the pixel `at`, or hides it when there is none.
fn place_tag(
    at: Option<Vec2>,
    computed: &ComputedNode,
    mut node: Mut<Node>,
    mut visibility: Mut<Visibility>,
) {
    match at {
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

/// Scene nodes with a box, as they first appear.
type NewNode<'a> = (Entity, &'a SceneEntity, Option<&'a Panoptic>);
type NewNodeFilter = (Added<SceneEntity>, With<OrientedBox>);

/// One tag per node that has a box and is not hidden, spawned once the node exists.
fn spawn_labels(mut commands: Commands, nodes: Query<NewNode, NewNodeFilter>) {
    for (entity, id, panoptic) in &nodes {
        if panoptic.is_some_and(|p| HIDDEN_CLASSES.contains(&p.class.as_str())) {
            continue;
        }
        commands.spawn((tag(id.0.clone()), NodeLabel(entity)));
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
    for (label, computed, node, visibility) in &mut labels {
        let at = boxes
            .get(label.0)
            .ok()
            .filter(|_| layers.is_on(Layer::Graph))
            .and_then(|b| camera.world_to_viewport(eye, tag_point(&b.0)).ok());
        place_tag(at, computed, node, visibility);
    }
}

/// One tag per replayed node that is not hidden.
fn spawn_replay_labels(mut commands: Commands, replay: Res<ReplayData>) {
    for (i, node) in replay.0.nodes.iter().enumerate() {
        if !HIDDEN_CLASSES.contains(&node.class.as_str()) {
            commands.spawn((tag(node.id.clone()), ReplayLabel(i)));
        }
    }
}

/// Puts each replayed node's tag over its box once the node has appeared, with the graph layer.
fn place_replay_labels(
    layers: Res<ActiveLayers>,
    clock: Res<ReplayClock>,
    replay: Res<ReplayData>,
    camera: Query<(&Camera, &GlobalTransform), With<OrbitCamera>>,
    mut labels: Query<(&ReplayLabel, &ComputedNode, &mut Node, &mut Visibility)>,
) {
    let Ok((camera, eye)) = camera.single() else {
        return;
    };
    let frame = clock.shown();
    for (label, computed, node, visibility) in &mut labels {
        let at = replay
            .0
            .nodes
            .get(label.0)
            .filter(|n| n.appears_at <= frame && layers.is_on(Layer::Graph))
            .and_then(|n| {
                camera
                    .world_to_viewport(eye, tag_point(&n.gravity_box))
                    .ok()
            });
        place_tag(at, computed, node, visibility);
    }
}

pub struct GraphLabelsPlugin;

impl Plugin for GraphLabelsPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (spawn_labels, place_labels).chain());
    }
}

pub struct ReplayLabelsPlugin;

impl Plugin for ReplayLabelsPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_replay_labels)
            .add_systems(Update, place_replay_labels.after(ClockUpdate));
    }
}
