//! The viewer's layers, switched with the number keys 1-8 and listed in the on-screen panel with
//! what the last interaction did. Each layer is drawn by its own module (graph_overlays,
//! collision, occupancy, physics_layer; link_meshes for the two looks of the meshes).

use bevy::prelude::*;

use crate::viewer::physics_layer::RestVerdicts;
use crate::viewer::state::ViewerStatus;
use crate::viewer::task_player::TaskPlayer;

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
    /// The nodes' surface planes within their boxes: up-facing green, down-facing red, upright
    /// blue, each with its normal.
    Planes,
    /// The convex collision pieces of every link, as wireframes.
    Collision,
    /// The robot's occupancy grid on the floor: occupied dark, free shaded by clearance (amber
    /// where the base does not fit).
    Occupancy,
    /// The rest test's verdicts: stable objects' boxes green, unstable orange, penetrating red.
    Physics,
    /// The reconstructed map in place of the models: each panoptic segment's mesh in its
    /// instance colour (a reconstruction's folder only).
    Map,
}

impl Layer {
    pub const ALL: [Layer; 9] = [
        Layer::Colour,
        Layer::Segments,
        Layer::Boxes,
        Layer::Graph,
        Layer::Planes,
        Layer::Collision,
        Layer::Occupancy,
        Layer::Physics,
        Layer::Map,
    ];

    /// The number key that switches the layer: its place in `ALL`, from 1.
    fn key(self) -> KeyCode {
        const KEYS: [KeyCode; 9] = [
            KeyCode::Digit1,
            KeyCode::Digit2,
            KeyCode::Digit3,
            KeyCode::Digit4,
            KeyCode::Digit5,
            KeyCode::Digit6,
            KeyCode::Digit7,
            KeyCode::Digit8,
            KeyCode::Digit9,
        ];
        KEYS[Self::ALL.iter().position(|l| *l == self).unwrap_or(0)]
    }

    pub fn name(self) -> &'static str {
        match self {
            Layer::Colour => "colour",
            Layer::Segments => "segments",
            Layer::Boxes => "boxes",
            Layer::Graph => "graph",
            Layer::Planes => "planes",
            Layer::Collision => "collision",
            Layer::Occupancy => "occupancy",
            Layer::Physics => "physics",
            Layer::Map => "map",
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

/// The panels' look (this one's and the replay's).
const PANEL_FONT_PX: f32 = 12.0;
const PANEL_TEXT: Color = Color::srgb(0.05, 0.05, 0.1);
const PANEL_BACKGROUND: Color = Color::srgba(1.0, 1.0, 1.0, 0.7);

/// The panel's text: the layers with their keys, then the last interaction.
#[derive(Component)]
struct PanelText;

fn spawn_panel(mut commands: Commands) {
    // Bottom left: the camera looks across the room from its -x, -y corner, so the top of the
    // picture holds the far wall's appliances and the bottom the open floor.
    commands.spawn((panel(PanelCorner::BottomLeft), PanelText));
}

/// Which corner of the view a panel sits in.
pub enum PanelCorner {
    TopLeft,
    BottomLeft,
}

/// An empty panel in `corner`: small type on a veil that keeps it legible over the scene.
pub fn panel(corner: PanelCorner) -> impl Bundle {
    let margin = Val::Px(6.0);
    let mut node = Node {
        position_type: PositionType::Absolute,
        left: margin,
        padding: UiRect::all(Val::Px(4.0)),
        ..default()
    };
    match corner {
        PanelCorner::TopLeft => node.top = margin,
        PanelCorner::BottomLeft => node.bottom = margin,
    }
    (
        Text::new(""),
        TextFont {
            font_size: FontSize::Px(PANEL_FONT_PX),
            ..default()
        },
        TextColor(PANEL_TEXT),
        node,
        BackgroundColor(PANEL_BACKGROUND),
    )
}

fn update_panel(
    layers: Res<ActiveLayers>,
    status: Res<ViewerStatus>,
    verdicts: Res<RestVerdicts>,
    player: Res<TaskPlayer>,
    mut text: Query<&mut Text, With<PanelText>>,
) {
    if !layers.is_changed()
        && !status.is_changed()
        && !verdicts.is_changed()
        && !player.is_changed()
    {
        return;
    }
    // Rows of four layers, the ones shown in brackets: short enough to leave the scene be.
    let names: Vec<String> = Layer::ALL
        .iter()
        .enumerate()
        .map(|(i, l)| {
            let name = format!("{} {}", i + 1, l.name());
            if layers.is_on(*l) {
                format!("[{name}]")
            } else {
                format!(" {name} ")
            }
        })
        .collect();
    let mut lines: Vec<String> = names.chunks(4).map(|row| row.join(" ")).collect();
    lines.push("click: open/close, drag: move; right-drag orbit, wheel zoom, WASD/QE fly".into());
    if !player.actions.is_empty() {
        let done = player.next.min(player.actions.len());
        lines.push(format!(
            "task: {done} of {} actions done; N next, P {}",
            player.actions.len(),
            if player.playing { "pause" } else { "play" }
        ));
    }
    lines.extend(status.0.iter().cloned());
    // The rest test's verdicts, once asked for or once the scene changed from here.
    lines.extend(verdicts.summary());
    for mut t in &mut text {
        t.0 = lines.join("\n");
    }
}

pub struct LayersPlugin;

impl Plugin for LayersPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_panel)
            .add_systems(Update, (toggle_layers, update_panel).chain());
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
