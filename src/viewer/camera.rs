//! The orbit camera: it looks at the middle of the floor from inside the room (the ceiling is
//! not drawn), turns with a drag, zooms with the wheel and flies with WASD/QE. z is up, as
//! everywhere in iscene.

use bevy::input::mouse::{AccumulatedMouseMotion, AccumulatedMouseScroll};
use bevy::prelude::*;

use crate::components::{OrientedBox, Panoptic};

/// Where the camera looks from: spherical coordinates about `target`.
#[derive(Component, Clone, Copy, Debug)]
pub struct OrbitCamera {
    pub target: Vec3,
    /// Radians about z, from +x.
    pub yaw: f32,
    /// Radians above the horizontal.
    pub pitch: f32,
    pub distance: f32,
}

impl OrbitCamera {
    /// Frames a floor of `size` (metres) centred at `centre`: from its -x, -y corner, high up.
    pub fn framing(centre: Vec3, size: Vec2) -> Self {
        let half_diagonal = size.length() / 2.0;
        Self {
            target: centre + Vec3::Z * 0.6,
            yaw: (-size.y).atan2(-size.x),
            pitch: 0.95,
            distance: (1.25 * half_diagonal).max(1.5),
        }
    }

    pub fn transform(&self) -> Transform {
        let direction = Vec3::new(
            self.pitch.cos() * self.yaw.cos(),
            self.pitch.cos() * self.yaw.sin(),
            self.pitch.sin(),
        );
        Transform::from_translation(self.target + direction * self.distance)
            .looking_at(self.target, Vec3::Z)
    }
}

/// Spawns the camera once the floor's box is known (the room's size and middle).
fn spawn_camera(
    mut commands: Commands,
    cameras: Query<(), With<OrbitCamera>>,
    floors: Query<(&Panoptic, &OrientedBox)>,
) {
    if !cameras.is_empty() {
        return;
    }
    let (centre, size) = floors
        .iter()
        .find(|(p, _)| p.class == "floor")
        .map_or((Vec3::ZERO, Vec2::splat(4.0)), |(_, b)| {
            (b.0.center.with_z(0.0), b.0.size.truncate())
        });
    spawn_orbit_camera(&mut commands, centre, size);
}

/// The camera framing a floor of `size` centred at `centre`. MSAA and tonemapping are off: on
/// a software renderer they cost a quarter of the frame time.
pub fn spawn_orbit_camera(commands: &mut Commands, centre: Vec3, size: Vec2) {
    let orbit = OrbitCamera::framing(centre, size);
    commands.spawn((
        Camera3d::default(),
        Msaa::Off,
        bevy::core_pipeline::tonemapping::Tonemapping::None,
        orbit.transform(),
        orbit,
        // The panel is drawn by this camera, also off screen, where no window picks it.
        IsDefaultUiCamera,
    ));
}

/// Radians per pixel of drag, and the zoom per wheel line.
const TURN_PER_PIXEL: f32 = 0.005;
const ZOOM_PER_LINE: f32 = 0.1;

/// Flying speed in orbit distances per second.
const FLY_PER_S: f32 = 0.6;

fn orbit(
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    time: Res<Time>,
    motion: Res<AccumulatedMouseMotion>,
    scroll: Res<AccumulatedMouseScroll>,
    mut cameras: Query<(&mut OrbitCamera, &mut Transform)>,
) {
    // W/S fly forward and back over the floor, A/D to the sides, Q/E down and up: the point
    // looked at moves, the view turns about it as before.
    let pressed = |k: KeyCode| if keys.pressed(k) { 1.0 } else { 0.0 };
    let forward = pressed(KeyCode::KeyW) - pressed(KeyCode::KeyS);
    let right = pressed(KeyCode::KeyD) - pressed(KeyCode::KeyA);
    let up = pressed(KeyCode::KeyE) - pressed(KeyCode::KeyQ);
    for (mut orbit, mut transform) in &mut cameras {
        if forward != 0.0 || right != 0.0 || up != 0.0 {
            let ahead = -Vec2::from_angle(orbit.yaw);
            let step = FLY_PER_S * orbit.distance * time.delta_secs();
            let flat = (ahead * forward + ahead.perp() * -right) * step;
            orbit.target += flat.extend(up * step);
        }
        if buttons.pressed(MouseButton::Right) || buttons.pressed(MouseButton::Middle) {
            orbit.yaw -= motion.delta.x * TURN_PER_PIXEL;
            orbit.pitch = (orbit.pitch + motion.delta.y * TURN_PER_PIXEL).clamp(0.05, 1.5);
        }
        if scroll.delta.y != 0.0 {
            orbit.distance = (orbit.distance * (1.0 - ZOOM_PER_LINE * scroll.delta.y)).max(0.3);
        }
        let now = orbit.transform();
        if *transform != now {
            *transform = now;
        }
    }
}

pub struct OrbitCameraPlugin;

impl Plugin for OrbitCameraPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (spawn_camera, orbit).chain());
    }
}
