//! The replay's timeline: a clock over the sequence's frames that plays, pauses, steps and
//! scrubs, driven from the keyboard and the bar along the bottom of the window, and the panel
//! that says where it stands.

use bevy::prelude::*;

use crate::viewer::layers::{ActiveLayers, Layer, PanelCorner, panel};

/// Where the replay stands: a frame position (fractional while playing) and how it moves.
#[derive(Resource, Clone, Copy, Debug)]
pub struct ReplayClock {
    pub frame: f32,
    /// Frames of the sequence: positions run over 0..frames.
    pub frames: u32,
    pub playing: bool,
    /// Sequence frames per second of wall time while playing.
    pub speed: f32,
}

impl ReplayClock {
    pub fn new(frames: u32) -> Self {
        Self {
            frame: 0.0,
            frames,
            playing: false,
            speed: DEFAULT_SPEED,
        }
    }

    /// The frame shown.
    pub fn shown(&self) -> u32 {
        (self.frame.max(0.0) as u32).min(self.frames.saturating_sub(1))
    }

    fn last(&self) -> f32 {
        self.frames.saturating_sub(1) as f32
    }

    /// Moves the clock to `frame` (clamped to the sequence).
    pub fn seek(&mut self, frame: f32) {
        self.frame = frame.clamp(0.0, self.last());
    }
}

const DEFAULT_SPEED: f32 = 15.0;
const SPEEDS: [f32; 6] = [2.0, 5.0, 15.0, 30.0, 60.0, 120.0];
/// Height of the scrub bar and of the strip above it that still grabs it, pixels.
const BAR_HEIGHT_PX: f32 = 10.0;
const BAR_GRAB_PX: f32 = 30.0;

/// Space plays or pauses, the arrows step a frame (Shift: ten), Home and End jump, Up and Down
/// change the speed; 3, 4, 5 switch boxes, graph and planes.
fn keyboard(
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    mut clock: ResMut<ReplayClock>,
    mut layers: ResMut<ActiveLayers>,
) {
    let step = if keys.pressed(KeyCode::ShiftLeft) || keys.pressed(KeyCode::ShiftRight) {
        10.0
    } else {
        1.0
    };
    if keys.just_pressed(KeyCode::Space) {
        if clock.shown() + 1 >= clock.frames {
            clock.frame = 0.0;
        }
        clock.playing = !clock.playing;
    }
    if keys.just_pressed(KeyCode::ArrowRight) {
        clock.playing = false;
        let to = clock.frame.floor() + step;
        clock.seek(to);
    }
    if keys.just_pressed(KeyCode::ArrowLeft) {
        clock.playing = false;
        let to = clock.frame.floor() - step;
        clock.seek(to);
    }
    if keys.just_pressed(KeyCode::Home) {
        clock.seek(0.0);
    }
    if keys.just_pressed(KeyCode::End) {
        let last = clock.last();
        clock.seek(last);
    }
    let at = SPEEDS.iter().position(|s| *s >= clock.speed).unwrap_or(0);
    if keys.just_pressed(KeyCode::ArrowUp) {
        clock.speed = SPEEDS[(at + 1).min(SPEEDS.len() - 1)];
    }
    if keys.just_pressed(KeyCode::ArrowDown) {
        clock.speed = SPEEDS[at.saturating_sub(1)];
    }
    for (key, layer) in [
        (KeyCode::Digit3, Layer::Boxes),
        (KeyCode::Digit4, Layer::Graph),
        (KeyCode::Digit5, Layer::Planes),
    ] {
        if keys.just_pressed(key) {
            let on = layers.is_on(layer);
            layers.set(layer, !on);
        }
    }
    if clock.playing {
        let to = clock.frame + clock.speed * time.delta_secs();
        clock.seek(to);
        if to >= clock.last() {
            clock.playing = false;
        }
    }
}

/// A press or drag near the bottom of the window scrubs: the pointer's x is the position.
fn scrub(
    buttons: Res<ButtonInput<MouseButton>>,
    windows: Query<&Window>,
    mut clock: ResMut<ReplayClock>,
) {
    if !buttons.pressed(MouseButton::Left) {
        return;
    }
    for window in &windows {
        let Some(at) = window.cursor_position() else {
            continue;
        };
        if at.y < window.height() - BAR_GRAB_PX {
            continue;
        }
        clock.playing = false;
        let share = (at.x / window.width().max(1.0)).clamp(0.0, 1.0);
        let to = share * clock.last();
        clock.seek(to.round());
    }
}

#[derive(Component)]
struct BarFill;

#[derive(Component)]
struct TimelineText;

fn spawn_timeline(mut commands: Commands) {
    commands.spawn((panel(PanelCorner::TopLeft), TimelineText));
    commands
        .spawn((
            Node {
                position_type: PositionType::Absolute,
                bottom: Val::Px(8.0),
                left: Val::Px(8.0),
                right: Val::Px(8.0),
                height: Val::Px(BAR_HEIGHT_PX),
                ..default()
            },
            BackgroundColor(Color::srgb(0.75, 0.77, 0.8)),
        ))
        .with_children(|bar| {
            bar.spawn((
                Node {
                    width: Val::Percent(0.0),
                    height: Val::Percent(100.0),
                    ..default()
                },
                BackgroundColor(Color::srgb(0.15, 0.3, 0.7)),
                BarFill,
            ));
        });
}

/// What the panel says beside the clock: counts of what has appeared so far.
#[derive(Resource, Clone, Debug, Default)]
pub struct ReplayCounts(pub String);

fn update_timeline(
    clock: Res<ReplayClock>,
    counts: Res<ReplayCounts>,
    mut fill: Query<&mut Node, With<BarFill>>,
    mut text: Query<&mut Text, With<TimelineText>>,
) {
    if !clock.is_changed() && !counts.is_changed() {
        return;
    }
    let share = clock.shown() as f32 / clock.frames.saturating_sub(1).max(1) as f32;
    for mut node in &mut fill {
        node.width = Val::Percent(100.0 * share);
    }
    let state = if clock.playing { "playing" } else { "paused" };
    let lines = [
        format!(
            "frame {} / {}  {state} at {} frames/s",
            clock.shown() + 1,
            clock.frames,
            clock.speed
        ),
        counts.0.clone(),
        "space play, left/right step, up/down speed, home/end, drag the bar".into(),
        "3 boxes 4 graph 5 planes; right-drag orbit, wheel zoom, WASD/QE fly".into(),
    ];
    for mut t in &mut text {
        t.0 = lines.join("\n");
    }
}

/// Where the clock moves; what shows the replay at the clock runs after it.
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub struct ClockUpdate;

pub struct TimelinePlugin;

impl Plugin for TimelinePlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ReplayCounts>()
            .add_systems(Startup, spawn_timeline)
            .add_systems(
                Update,
                (keyboard, scrub, update_timeline)
                    .chain()
                    .in_set(ClockUpdate),
            );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_clock_stays_on_the_sequence() {
        let mut clock = ReplayClock::new(10);
        clock.seek(-3.0);
        assert_eq!(clock.shown(), 0);
        clock.seek(42.0);
        assert_eq!(clock.shown(), 9);
        clock.seek(4.7);
        assert_eq!(clock.shown(), 4);
        assert_eq!(ReplayClock::new(0).shown(), 0);
    }
}
