//! The default camera path: a loop around the room at eye height, looking across the room and
//! down at furniture, swaying left and right so that objects along every wall are seen.

use glam::{Affine3A, Mat3, Vec3};

/// Distance kept from the walls, metres.
const MARGIN: f32 = 0.8;
/// How far the view turns left and right of the room centre, radians.
const SWAY: f32 = 0.5;
/// Height the camera looks at on average, and how far the view nods up and down from it, metres.
const TARGET_HEIGHT: f32 = 0.8;
const TARGET_NOD: f32 = 0.6;

/// `world_from_camera` for a camera at `eye` looking at `target` with the world's +z up
/// (OpenCV axes: x right, y down, z forward).
pub fn look_at(eye: Vec3, target: Vec3) -> Affine3A {
    let forward = (target - eye).normalize();
    let right = forward.cross(Vec3::Z).normalize();
    let down = forward.cross(right);
    Affine3A::from_mat3_translation(Mat3::from_cols(right, down, forward), eye)
}

/// `frames` poses along one loop around a room of `room` size at `height`.
pub fn room_loop(room: Vec3, frames: usize, height: f32) -> Vec<Affine3A> {
    let centre = Vec3::new(0.5 * room.x, 0.5 * room.y, 0.0);
    let a = (0.5 * room.x - MARGIN).max(0.25 * room.x);
    let b = (0.5 * room.y - MARGIN).max(0.25 * room.y);
    (0..frames)
        .map(|k| {
            let phase = std::f32::consts::TAU * k as f32 / frames.max(1) as f32;
            let eye = centre
                + Vec3::new(
                    a * phase.cos(),
                    b * phase.sin(),
                    height + 0.05 * (2.0 * phase).sin(),
                );
            let to_centre = (centre - eye).truncate();
            let look = glam::Vec2::from_angle(SWAY * (3.0 * phase).sin())
                .rotate(to_centre.normalize_or_zero());
            // Aim across the room, mostly down at furniture and table tops, sometimes up at wall
            // cabinets and shelves.
            let reach = to_centre.length().max(1.0) * 1.1;
            let target_height = TARGET_HEIGHT + TARGET_NOD * (5.0 * phase).sin();
            let target = Vec3::new(
                eye.x + look.x * reach,
                eye.y + look.y * reach,
                target_height,
            );
            look_at(eye, target)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_points_the_optical_axis_at_the_target() {
        let eye = Vec3::new(1.0, 2.0, 1.5);
        let target = Vec3::new(3.0, 2.5, 0.5);
        let pose = look_at(eye, target);
        let forward = pose.transform_vector3(Vec3::Z);
        assert!((forward - (target - eye).normalize()).length() < 1e-5);
        // Image "down" points down in the world.
        assert!(pose.transform_vector3(Vec3::Y).z < 0.0);
        assert!((Mat3::from(pose.matrix3).determinant() - 1.0).abs() < 1e-5);
    }

    #[test]
    fn the_loop_stays_inside_the_room() {
        let room = Vec3::new(5.0, 4.0, 2.6);
        for pose in room_loop(room, 100, 1.45) {
            let eye = Vec3::from(pose.translation);
            assert!(
                eye.x > 0.5
                    && eye.x < 4.5
                    && eye.y > 0.5
                    && eye.y < 3.5
                    && eye.z > 1.3
                    && eye.z < 1.6,
                "{eye}"
            );
        }
    }
}
