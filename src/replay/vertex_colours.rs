//! The reconstruction in colour. The map keeps geometry and labels, not colour, so each vertex
//! of the final map takes the colour that a frame seeing it shows where it projects. At most
//! `MAX_COLOUR_FRAMES` frames, spread evenly over the sequence, are read; a vertex takes the
//! first of them that sees it (the depth test of first_seen.rs), so occluded and free-space
//! views never colour it.

use glam::Vec3;
use rayon::prelude::*;

use crate::error::InputError;
use crate::io::Sequence;
use crate::replay::first_seen::pixel_seen;

/// Frames read to colour the map: enough to see every side of a room, few enough to open a
/// 1000-frame 7-Scenes folder in seconds.
pub const MAX_COLOUR_FRAMES: usize = 24;

/// For each point, its colour (8-bit sRGB) in the first of the chosen frames that sees it within
/// `tolerance_m` of its measured depth; `None` where none does.
pub fn vertex_colours(
    points_in_world: &[Vec3],
    sequence: &Sequence,
    tolerance_m: f32,
) -> Result<Vec<Option<[u8; 3]>>, InputError> {
    let n = sequence.frames.len();
    let chosen: Vec<usize> = if n <= MAX_COLOUR_FRAMES {
        (0..n).collect()
    } else {
        (0..MAX_COLOUR_FRAMES)
            .map(|k| k * (n - 1) / (MAX_COLOUR_FRAMES - 1))
            .collect()
    };
    let mut colours: Vec<Option<[u8; 3]>> = vec![None; points_in_world.len()];
    // A few frames at a time in parallel, folded in frame order: the earliest frame wins.
    let batch = 2 * rayon::current_num_threads().max(1);
    for frames in chosen.chunks(batch) {
        let seen: Vec<Vec<Option<[u8; 3]>>> = frames
            .par_iter()
            .map(|&i| {
                let frame = sequence.load_frame(i)?;
                let camera_from_world = frame.world_from_camera.inverse();
                let width = frame.camera.width as usize;
                Ok(points_in_world
                    .iter()
                    .map(|p| {
                        let (u, v) = pixel_seen(
                            *p,
                            &frame.camera,
                            &camera_from_world,
                            &frame.depth,
                            tolerance_m,
                        )?;
                        let at = 3 * (v * width + u);
                        frame.color.get(at..at + 3).map(|c| [c[0], c[1], c[2]])
                    })
                    .collect())
            })
            .collect::<Result<_, InputError>>()?;
        for in_frame in &seen {
            for (slot, colour) in colours.iter_mut().zip(in_frame) {
                if slot.is_none() {
                    *slot = *colour;
                }
            }
        }
    }
    Ok(colours)
}
