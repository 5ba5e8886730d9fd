//! The viewer's layers, switched with the number keys and listed in the on-screen panel: the
//! models' own colours, panoptic segment colours, gravity-aligned boxes, and the contact graph
//! (support edges from parent to child, proximal pairs).

use bevy::prelude::*;

use crate::components::{OrientedBox, ProximalTo, SceneEntity};
use crate::viewer::interaction::ViewerStatus;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Layer {
    /// The models' own colours.
    Colour,
    /// Each object in its panoptic instance colour.
    Segments,
    /// Gravity-aligned boxes of the contact graph's nodes.
    Boxes,
    /// Support edges (orange, parent to child) and proximal pairs (blue).
    Graph,
}

impl Layer {
    pub const ALL: [Layer; 4] = [Layer::Colour, Layer::Segments, Layer::Boxes, Layer::Graph];

    fn key(self) -> KeyCode {
        match self {
            Layer::Colour => KeyCode::Digit1,
            Layer::Segments => KeyCode::Digit2,
            Layer::Boxes => KeyCode::Digit3,
            Layer::Graph => KeyCode::Digit4,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Layer::Colour => "colour",
            Layer::Segments => "segments",
            Layer::Boxes => "boxes",
            Layer::Graph => "graph",
        }
    }
}

/// The layers shown. Colour and segments are the two looks of the meshes: one of them is on.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct ActiveLayers(Vec<Layer>);

impl ActiveLayers {
    pub fn new(layers: &[Layer]) -> Self {
        let mut on = Self(Vec::new());
        for &layer in layers {
            on.set(layer, true);
        }
        if !on.is_on(Layer::Segments) {
            on.set(Layer::Colour, true);
        }
        on
    }

    pub fn is_on(&self, layer: Layer) -> bool {
        self.0.contains(&layer)
    }

    pub fn set(&mut self, layer: Layer, on: bool) {
        self.0.retain(|l| *l != layer);
        if on {
            self.0.push(layer);
        }
        // The meshes show exactly one of their looks.
        match (layer, on) {
            (Layer::Colour, true) => self.0.retain(|l| *l != Layer::Segments),
            (Layer::Segments, true) => self.0.retain(|l| *l != Layer::Colour),
            (Layer::Segments, false) if !self.is_on(Layer::Colour) => self.0.push(Layer::Colour),
            _ => {}
        }
    }
}

fn toggle_layers(keys: Res<ButtonInput<KeyCode>>, mut layers: ResMut<ActiveLayers>) {
    for layer in Layer::ALL {
        if keys.just_pressed(layer.key()) {
            let on = layers.is_on(layer);
            layers.set(layer, !on);
        }
    }
}

const SUPPORT_COLOUR: Color = Color::srgb(1.0, 0.45, 0.0);
const PROXIMAL_COLOUR: Color = Color::srgb(0.1, 0.35, 1.0);
const BOX_COLOUR: Color = Color::srgb(0.1, 0.1, 0.1);

fn draw_boxes(
    layers: Res<ActiveLayers>,
    boxes: Query<&OrientedBox, With<SceneEntity>>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Boxes) {
        return;
    }
    for b in &boxes {
        let b = b.0;
        gizmos.cube(
            Transform::from_translation(b.center)
                .with_rotation(Quat::from_rotation_z(b.yaw))
                .with_scale(b.size),
            BOX_COLOUR,
        );
    }
}

/// A node as the graph layer draws it: its box, support parent and proximal partners.
type GraphNodeView<'a> = (
    Entity,
    &'a OrientedBox,
    Option<&'a ChildOf>,
    Option<&'a ProximalTo>,
);

fn draw_graph(
    layers: Res<ActiveLayers>,
    nodes: Query<GraphNodeView, With<SceneEntity>>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Graph) {
        return;
    }
    for (entity, b, parent, proximal) in &nodes {
        // The edge runs from the parent's top centre to the child's bottom centre.
        let bottom = b.0.center - Vec3::Z * b.0.size.z / 2.0;
        if let Some((_, pb, _, _)) = parent.and_then(|p| nodes.get(p.parent()).ok()) {
            let top = pb.0.center + Vec3::Z * pb.0.size.z / 2.0;
            gizmos.line(top, bottom, SUPPORT_COLOUR);
            gizmos.sphere(Isometry3d::from_translation(bottom), 0.03, SUPPORT_COLOUR);
        }
        for &other in proximal.map(|p| p.0.as_slice()).unwrap_or_default() {
            // Each pair once.
            if other < entity {
                continue;
            }
            if let Ok((_, ob, _, _)) = nodes.get(other) {
                gizmos.line(b.0.center, ob.0.center, PROXIMAL_COLOUR);
            }
        }
    }
}

/// The panel's text: the layers with their keys, then the last interaction.
#[derive(Component)]
struct PanelText;

fn spawn_panel(mut commands: Commands) {
    commands.spawn((
        Text::new(""),
        TextFont {
            font_size: FontSize::Px(16.0),
            ..default()
        },
        TextColor(Color::srgb(0.05, 0.05, 0.1)),
        Node {
            position_type: PositionType::Absolute,
            top: Val::Px(8.0),
            left: Val::Px(8.0),
            ..default()
        },
        PanelText,
    ));
}

fn update_panel(
    layers: Res<ActiveLayers>,
    status: Res<ViewerStatus>,
    mut text: Query<&mut Text, With<PanelText>>,
) {
    if !layers.is_changed() && !status.is_changed() {
        return;
    }
    let mut lines: Vec<String> = Layer::ALL
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let mark = if layers.is_on(*l) { "x" } else { " " };
            format!("[{mark}] {} {}", i + 1, l.name())
        })
        .collect();
    lines.push(
        "click a door or drawer to open or close it; right-drag to orbit, wheel to zoom".into(),
    );
    lines.extend(status.0.iter().cloned());
    for mut t in &mut text {
        t.0 = lines.join("\n");
    }
}

pub struct LayersPlugin;

impl Plugin for LayersPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_panel).add_systems(
            Update,
            (toggle_layers, draw_boxes, draw_graph, update_panel).chain(),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_meshes_show_one_look_at_a_time() {
        let mut on = ActiveLayers::new(&[Layer::Boxes]);
        assert!(on.is_on(Layer::Colour) && on.is_on(Layer::Boxes));
        on.set(Layer::Segments, true);
        assert!(on.is_on(Layer::Segments) && !on.is_on(Layer::Colour));
        on.set(Layer::Segments, false);
        assert!(on.is_on(Layer::Colour));
        assert!(ActiveLayers::new(&[Layer::Segments]).is_on(Layer::Segments));
        assert!(!ActiveLayers::new(&[Layer::Segments]).is_on(Layer::Colour));
    }
}
