//! The plane of a layout piece (floor, ceiling, wall) from its points: levelled or stood upright
//! where what is left of a tilt is the fit's noise, and facing into the room.

use glam::Vec3;

use crate::geometry::Plane;
use crate::geometry::plane::fit_plane;

/// A wall's plane within this angle (degrees) of upright is made upright (more, and it is no
/// wall: a sloping ceiling, a wrong label).
const WALL_UPRIGHT_MAX_DEG: f32 = 5.0;

/// The layout piece's plane, facing into the room: the floor's up, the ceiling's down, a wall's
/// towards the room's centre.
pub fn layout_plane(class: &str, points: &[Vec3], room_center: Vec3) -> Option<Plane> {
    let plane = fit_plane(points)?;
    let centroid = points.iter().copied().sum::<Vec3>() / points.len() as f32;
    // The aligned frame was levelled to the floor where they disagreed by more than the fit's
    // noise; what is left is noise, and a simulator's floor tilted by it makes everything on it
    // creep (0.17 degrees on 7-Scenes redkitchen: every chair moved 2 mm in 2 s).
    let level = class == "floor"
        && plane.normal.z.abs() >= crate::graph::gravity::LEVEL_MIN_DEG.to_radians().cos();
    if level {
        return Some(Plane::from_point_normal(Vec3::Z * centroid.z, Vec3::Z));
    }
    // A wall stands upright. A plane fitted to a wall seen 1.6 m high from one side leans by
    // noise (half a degree on 7-Scenes redkitchen), and the upright slab enclosing it then
    // reaches 1.4 cm into the room at one end: the monitors in front of it started inside it in
    // MuJoCo while the physical check, which has the plane, saw them clear.
    let upright =
        class == "wall" && plane.normal.z.abs() <= WALL_UPRIGHT_MAX_DEG.to_radians().sin();
    let plane = match plane.normal.with_z(0.0).try_normalize() {
        Some(normal) if upright => Plane::from_point_normal(centroid, normal),
        _ => plane,
    };
    let facing = match class {
        "floor" => Vec3::Z,
        "ceiling" => -Vec3::Z,
        _ => (room_center - centroid).with_z(0.0),
    };
    Some(if plane.normal.dot(facing) < 0.0 {
        Plane {
            normal: -plane.normal,
            offset: -plane.offset,
        }
    } else {
        plane
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_floor_within_half_a_degree_of_level_is_level_and_a_steeper_one_keeps_its_tilt() {
        let floor_at = |tilt_deg: f32| -> Vec<Vec3> {
            let tilt = glam::Quat::from_rotation_x(tilt_deg.to_radians());
            (0..30)
                .flat_map(|i| (0..30).map(move |j| Vec3::new(i as f32 * 0.1, j as f32 * 0.1, 0.0)))
                .map(|p| tilt * p + Vec3::Z * 0.01)
                .collect()
        };
        let room = Vec3::new(1.5, 1.5, 1.0);
        let plane = layout_plane("floor", &floor_at(0.2), room).expect("plane");
        assert_eq!(plane.normal, Vec3::Z);
        // At the points' mean height: 1 cm, plus the tilt's rise to the middle of 2.9 m.
        let mid = 0.01 + 1.45 * 0.2f32.to_radians().sin();
        assert!(
            (plane.signed_distance(Vec3::ZERO) + mid).abs() < 1e-4,
            "{plane:?}"
        );
        let steep = layout_plane("floor", &floor_at(1.0), room).expect("plane");
        assert!((steep.normal.angle_between(Vec3::Z).to_degrees() - 1.0).abs() < 0.01);
    }

    #[test]
    fn a_wall_leaning_by_noise_stands_upright_through_its_points() {
        // A wall at x = 0, 3 m long and 1.6 m high, leaning 0.5 degrees into the room.
        let lean = glam::Quat::from_rotation_y(-0.5f32.to_radians());
        let points: Vec<Vec3> = (0..30)
            .flat_map(|i| (0..16).map(move |j| Vec3::new(0.0, i as f32 * 0.1, j as f32 * 0.1)))
            .map(|p| lean * p)
            .collect();
        let room = Vec3::new(2.0, 1.5, 1.0);
        let plane = layout_plane("wall", &points, room).expect("plane");
        assert_eq!(plane.normal.z, 0.0);
        assert!(plane.normal.angle_between(Vec3::X) < 1e-4, "{plane:?}");
        let mean = points.iter().sum::<Vec3>() / points.len() as f32;
        assert!(plane.signed_distance(mean).abs() < 1e-5);
        // 10 degrees is no noise: that plane keeps its slope.
        let slope = glam::Quat::from_rotation_y(-10f32.to_radians());
        let sloped: Vec<Vec3> = points
            .iter()
            .map(|p| slope * (lean.inverse() * *p))
            .collect();
        let kept = layout_plane("wall", &sloped, room).expect("plane");
        assert!((kept.normal.angle_between(Vec3::X).to_degrees() - 10.0).abs() < 0.01);
    }
}
