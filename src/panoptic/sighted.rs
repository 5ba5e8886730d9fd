//! What the frames themselves measured of each object's outline. A map's mesh has a vertex per
//! voxel column across a horizontal surface, so the unseen back edge of a top is known to a voxel
//! at best, and the labels blur there (the wall behind claims the top's last voxels): with 2 cm
//! voxels, cabinets 0.8, 1.8 and 3.8 cm off their wall all came out 2.9 cm off. Depth precise
//! to well under a millimetre (rendered depth, structured-light scanners at close range) places
//! the edge itself: the points on each object's silhouette, frame by frame, go to the contact
//! graph, which fits the object's box to the extent several frames measured
//! (`graph::sighted_extent`). Noisier depth would grow boxes by its noise, so only points whose
//! estimated noise is a small fraction of a voxel count; a Kinect's contribute nothing.

use std::collections::HashSet;

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use crate::classes::EntityKind;
use crate::error::InputError;
use crate::io::Sequence;
use crate::map::depth_precision::noise_scale;
use crate::map::free_space::axial_sigma;
use crate::map::median;
use crate::panoptic::carve::entity_of_frame_label;
use crate::panoptic::{PanopticEntity, PanopticMapper};

#[derive(Clone, Copy, Debug)]
pub struct SightedParams {
    /// Only depth this many times less noisy than a Kinect's (`depth_precision`) measures
    /// outlines: 7-Scenes' Kinect reads 0.85, noise-free renderings 0.03.
    pub max_noise_scale: f32,
    /// Of that, only points whose depth noise (one sigma, metres) is estimated below this count.
    pub max_sigma: f32,
    /// Pixels are sampled every this many in each direction.
    pub stride: usize,
    /// A point counts for an object within about this distance (metres) of its mesh: a few
    /// pixels of a mask's boundary fall on the surface behind it.
    pub near_mesh: f32,
    /// A neighbouring pixel this much deeper (metres) shows what lies behind the object: the
    /// object's silhouette.
    pub silhouette_step: f32,
    /// Frames sampled to estimate the sequence's depth noise.
    pub noise_frames: usize,
}

impl SightedParams {
    /// For a map of `voxel` metres: points to a twentieth of a voxel (1 mm at 2 cm).
    pub fn for_voxel(voxel: f32) -> Self {
        Self {
            max_noise_scale: 0.25,
            max_sigma: voxel / 20.0,
            stride: 2,
            near_mesh: 2.0 * voxel,
            silhouette_step: voxel / 4.0,
            noise_frames: 8,
        }
    }
}

/// The depth noise of `sequence` relative to `axial_sigma`: the median over `frames` frames
/// spread over it (`depth_precision::noise_scale`); `None` when none shows a surface.
pub fn sequence_noise_scale(sequence: &Sequence, frames: usize) -> Result<Option<f32>, InputError> {
    let n = sequence.frames.len();
    let picked: Vec<usize> = (0..frames.min(n)).map(|k| k * n / frames.min(n)).collect();
    let scales: Vec<Option<f32>> = picked
        .par_iter()
        .map(|&i| {
            let depth = sequence.load_depth(i)?;
            Ok(noise_scale(&depth, sequence.camera.width as usize, 4))
        })
        .collect::<Result<_, InputError>>()?;
    let mut scales: Vec<f32> = scales.into_iter().flatten().collect();
    Ok((!scales.is_empty()).then(|| median(&mut scales)))
}

/// The noise scale of `sequence`'s depth (`sequence_noise_scale`) when it is precise enough to
/// measure outlines, `None` otherwise.
pub fn precise_depth(
    sequence: &Sequence,
    params: &SightedParams,
) -> Result<Option<f32>, InputError> {
    Ok(sequence_noise_scale(sequence, params.noise_frames)?
        .filter(|&scale| scale <= params.max_noise_scale))
}

/// Per entity of `entities` (layout and entities no frame saw precisely get none): for each
/// frame that saw it, the points on its silhouette there, world frame; none unless the
/// depth is precise, with a noise of `noise_scale` times `axial_sigma` (`precise_depth`).
/// `entities` are the ones extracted from `mapper`'s map, whose frames are `sequence`'s.
pub fn sighted_outlines(
    entities: &[PanopticEntity],
    sequence: &Sequence,
    mapper: &PanopticMapper,
    noise_scale: Option<f32>,
    params: &SightedParams,
) -> Result<Vec<Vec<Vec<Vec3>>>, InputError> {
    let mut outlines = vec![Vec::new(); entities.len()];
    let Some(scale) = noise_scale else {
        return Ok(outlines);
    };
    if mapper.frame_labels().len() != sequence.frames.len() {
        return Ok(outlines);
    }
    let entity_of_label = entity_of_frame_label(entities, mapper);
    let is_object: Vec<bool> = std::iter::once(false)
        .chain(entities.iter().map(|e| e.kind != EntityKind::Layout))
        .collect();
    let cell = |p: Vec3| (p / params.near_mesh).floor().as_ivec3();
    let near: HashSet<(u32, IVec3)> = entities
        .iter()
        .enumerate()
        .filter(|(_, e)| e.kind != EntityKind::Layout)
        .flat_map(|(k, e)| {
            e.mesh
                .positions
                .iter()
                .map(move |&p| (k as u32 + 1, cell(p)))
        })
        .collect();
    let near_mesh = |entity: u32, p: Vec3| {
        let c = cell(p);
        (-1..=1).any(|x| {
            (-1..=1).any(|y| (-1..=1).any(|z| near.contains(&(entity, c + IVec3::new(x, y, z)))))
        })
    };
    let camera = &sequence.camera;
    let (w, h) = (camera.width as i64, camera.height as i64);
    let s = params.stride.max(1) as i64;
    let per_frame: Vec<Vec<(u32, Vec<Vec3>)>> = (0..sequence.frames.len())
        .into_par_iter()
        .map(|i| {
            let labels = &mapper.frame_labels()[i];
            // A frame whose labels were dropped (a long sequence's) shows no entity.
            if labels.is_dropped() {
                return Ok(Vec::new());
            }
            let depth = sequence.load_depth(i)?;
            let world_from_camera = sequence.frames[i].world_from_camera;
            let entity_at = |u: i64, v: i64| {
                if u < 0 || v < 0 || u >= w || v >= h || depth[(v * w + u) as usize] <= 0.0 {
                    return 0;
                }
                let label = labels.at(u as u32, v as u32);
                entity_of_label.get(label as usize).copied().unwrap_or(0)
            };
            let mut found: Vec<(u32, Vec<Vec3>)> = Vec::new();
            for v in (0..h).step_by(s as usize) {
                for u in (0..w).step_by(s as usize) {
                    let e = entity_at(u, v);
                    if !is_object[e as usize] {
                        continue;
                    }
                    let d = depth[(v * w + u) as usize];
                    if scale * axial_sigma(d) > params.max_sigma {
                        continue;
                    }
                    // On the silhouette: a neighbour shows what lies behind the object, or
                    // nothing. Not where the image ends or something in front hides it: there
                    // the mask ends short of the object.
                    let silhouette = [(s, 0), (-s, 0), (0, s), (0, -s)].iter().any(|&(du, dv)| {
                        let (x, y) = (u + du, v + dv);
                        if x < 0 || y < 0 || x >= w || y >= h {
                            return false;
                        }
                        let behind = depth[(y * w + x) as usize];
                        behind <= 0.0
                            || (entity_at(x, y) != e && behind > d + params.silhouette_step)
                    });
                    if !silhouette {
                        continue;
                    }
                    let p =
                        world_from_camera.transform_point3(camera.unproject(u as f32, v as f32, d));
                    // Near its own mesh, and not where the map holds another object: a
                    // frame's labels bleed a pixel or two onto the neighbour at its boundary.
                    let mapped = mapper.tsdf.voxel_at(p).map_or(0, |voxel| {
                        entity_of_label
                            .get(voxel.label as usize)
                            .copied()
                            .unwrap_or(0)
                    });
                    if !near_mesh(e, p) || (mapped != e && is_object[mapped as usize]) {
                        continue;
                    }
                    match found.iter_mut().find(|(k, _)| *k == e) {
                        Some((_, points)) => points.push(p),
                        None => found.push((e, vec![p])),
                    }
                }
            }
            Ok(found)
        })
        .collect::<Result<_, InputError>>()?;
    for frame in per_frame {
        for (e, points) in frame {
            outlines[e as usize - 1].push(points);
        }
    }
    Ok(outlines)
}
