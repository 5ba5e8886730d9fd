//! What a generated room must pass beyond a specification's own checks: every door and drawer
//! free to open, every object seen along the default camera path.

use crate::cad::placed_solid::{PlacedSolid, layout_penetration, penetration_depth};
use crate::geometry::Pinhole;
use crate::render::raster::{NO_TRIANGLE, rasterize};
use crate::render::trajectory::room_loop;
use crate::scene::overlap::MAX_OVERLAP_M;
use crate::scene::render_sequence::DEFAULT_CAMERA_HEIGHT;
use crate::scene::world::SceneWorld;

use super::{MIN_VISIBLE_PIXELS, VISIBILITY_FRAMES};

/// Indices of the objects of `world` that no frame of the default path of `frames` frames sees
/// with `MIN_VISIBLE_PIXELS` at a quarter of the resolution.
pub fn unseen_objects(world: &SceneWorld, frames: usize) -> Vec<usize> {
    use rayon::prelude::*;
    let scene = world.render_scene();
    let k = Pinhole::KINECT;
    let camera = Pinhole {
        width: k.width / 4,
        height: k.height / 4,
        fx: k.fx / 4.0,
        fy: k.fy / 4.0,
        cx: (k.cx + 0.5) / 4.0 - 0.5,
        cy: (k.cy + 0.5) / 4.0 - 0.5,
    };
    let poses = room_loop(world.room_size, frames, DEFAULT_CAMERA_HEIGHT);
    let step = (frames / VISIBILITY_FRAMES).max(1);
    let counts: Vec<Vec<usize>> = poses
        .par_iter()
        .step_by(step)
        .map(|pose| {
            let raster = rasterize(&scene, &camera, &pose.inverse());
            let mut count = vec![0usize; world.objects.len()];
            for &t in &raster.triangle {
                if t != NO_TRIANGLE {
                    let instance = scene.instances[t as usize];
                    if let Some(i) = world.objects.iter().position(|o| o.instance == instance) {
                        count[i] += 1;
                    }
                }
            }
            count
        })
        .collect();
    (0..world.objects.len())
        .filter(|&i| counts.iter().all(|c| c[i] < MIN_VISIBLE_PIXELS))
        .collect()
}

/// Whether every door and drawer of object `new` opens all the way without meeting another
/// object or the room, and every other object's doors and drawers still open past `new`.
pub fn doors_open_freely(world: &SceneWorld, new: usize) -> bool {
    let planes: Vec<_> = world.layout.iter().map(|l| l.plane).collect();
    let opened = |i: usize| {
        let o = &world.objects[i];
        let values: Vec<(String, f32)> = o
            .model
            .movable_parts()
            .filter_map(|p| p.joint.limits.map(|(_, upper)| (p.name.clone(), upper)))
            .collect();
        let mesh = o
            .model
            .merged_mesh(&values)
            .transformed(&o.world_from_model);
        PlacedSolid::from_world_mesh(&mesh)
    };
    let closed = |i: usize| PlacedSolid::from_world_mesh(&world.objects[i].world_mesh());
    let parent_of = |i: usize| match world.objects[i].support {
        crate::scene::Support::OnObject(p) | crate::scene::Support::InObject(p) => Some(p),
        _ => None,
    };
    let related = |a: usize, b: usize| parent_of(a) == Some(b) || parent_of(b) == Some(a);
    let new_closed = closed(new);
    if world.objects[new].model.is_articulated() {
        let new_open = opened(new);
        if layout_penetration(&new_open, &planes) > MAX_OVERLAP_M {
            return false;
        }
        for i in 0..world.objects.len() {
            if i != new
                && !related(i, new)
                && penetration_depth(&new_open, &closed(i)) > MAX_OVERLAP_M
            {
                return false;
            }
        }
    }
    (0..world.objects.len()).all(|i| {
        i == new
            || related(i, new)
            || !world.objects[i].model.is_articulated()
            || penetration_depth(&opened(i), &new_closed) <= MAX_OVERLAP_M
    })
}
