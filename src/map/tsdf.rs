//! A voxel-hashed truncated signed distance field: blocks of 8^3 voxels in a hash map, projective
//! integration of depth frames in parallel over blocks, weights that drop off behind the surface.
//!
//! Signs: `sdf` is positive in front of the surface (free space, towards the camera), negative
//! behind it, in metres, clamped to `[-truncation, truncation]`.

use std::collections::{HashMap, HashSet};

use glam::{Affine3A, IVec3, Vec3};
use rayon::prelude::*;

use crate::geometry::Pinhole;

/// Voxels along one side of a block.
pub const BLOCK_SIDE: usize = 8;
const BLOCK_VOXELS: usize = BLOCK_SIDE * BLOCK_SIDE * BLOCK_SIDE;

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Voxel {
    /// Signed distance in metres (see the module docs for the sign).
    pub sdf: f32,
    /// Accumulated integration weight; 0 = never observed.
    pub weight: f32,
    pub color: [u8; 3],
}

/// Centre of voxel `index` of block `key`, world frame.
fn voxel_center(voxel_size: f32, key: IVec3, index: usize) -> Vec3 {
    let local = IVec3::new(
        (index % BLOCK_SIDE) as i32,
        ((index / BLOCK_SIDE) % BLOCK_SIDE) as i32,
        (index / (BLOCK_SIDE * BLOCK_SIDE)) as i32,
    );
    (key * BLOCK_SIDE as i32 + local).as_vec3() * voxel_size + Vec3::splat(0.5 * voxel_size)
}

pub struct Block {
    pub voxels: Box<[Voxel; BLOCK_VOXELS]>,
}

pub struct TsdfMap {
    pub voxel_size: f32,
    pub truncation: f32,
    /// Measurements farther than this from the camera are not integrated.
    pub max_ray_length: f32,
    /// Running averages stop growing their weight here, so the map can still change.
    pub max_weight: f32,
    pub blocks: HashMap<IVec3, Block>,
}

impl TsdfMap {
    /// A map with `voxel_size` metres voxels and a truncation band of four voxels.
    pub fn new(voxel_size: f32) -> Self {
        Self {
            voxel_size,
            truncation: 4.0 * voxel_size,
            max_ray_length: 5.0,
            max_weight: 1000.0,
            blocks: HashMap::new(),
        }
    }

    fn block_size(&self) -> f32 {
        self.voxel_size * BLOCK_SIDE as f32
    }

    fn block_of(&self, point: Vec3) -> IVec3 {
        (point / self.block_size()).floor().as_ivec3()
    }

    /// Fuses one depth frame (metres, 0 = none) with its colour (row-major RGB, may be empty).
    pub fn integrate(
        &mut self,
        depth: &[f32],
        color: &[u8],
        camera: &Pinhole,
        world_from_camera: &Affine3A,
    ) {
        let w = camera.width as usize;
        // Blocks the truncation band around every measurement passes through.
        let mut touched: HashSet<IVec3> = HashSet::new();
        let eye = Vec3::from(world_from_camera.translation);
        let step = (self.block_size() * 0.5).max(self.voxel_size);
        for (i, &d) in depth.iter().enumerate() {
            if d <= 0.0 || d > self.max_ray_length {
                continue;
            }
            let point = world_from_camera.transform_point3(camera.unproject(
                (i % w) as f32,
                (i / w) as f32,
                d,
            ));
            let ray = (point - eye).normalize_or_zero();
            let mut t = -self.truncation;
            while t <= self.truncation {
                touched.insert(self.block_of(point + ray * t));
                t += step;
            }
            touched.insert(self.block_of(point + ray * self.truncation));
        }
        for key in &touched {
            self.blocks.entry(*key).or_insert_with(|| Block {
                voxels: Box::new([Voxel::default(); BLOCK_VOXELS]),
            });
        }
        let camera_from_world = world_from_camera.inverse();
        let (truncation, max_weight, voxel_size) =
            (self.truncation, self.max_weight, self.voxel_size);
        let max_ray_length = self.max_ray_length;
        self.blocks
            .par_iter_mut()
            .filter(|(k, _)| touched.contains(k))
            .for_each(|(key, block)| {
                for (index, voxel) in block.voxels.iter_mut().enumerate() {
                    let p =
                        camera_from_world.transform_point3(voxel_center(voxel_size, *key, index));
                    if p.z <= 0.0 {
                        continue;
                    }
                    let uv = camera.project(p);
                    let (u, v) = (uv.x.round(), uv.y.round());
                    if u < 0.0 || v < 0.0 || u >= camera.width as f32 || v >= camera.height as f32 {
                        continue;
                    }
                    let i = v as usize * w + u as usize;
                    let d = depth[i];
                    if d <= 0.0 || d > max_ray_length {
                        continue;
                    }
                    let sdf = d - p.z;
                    if sdf < -truncation {
                        continue;
                    }
                    // Full weight in front of and at the surface, falling linearly to zero at the back
                    // of the truncation band (Voxblox's drop-off).
                    let weight = if sdf >= -voxel_size {
                        1.0
                    } else {
                        (truncation + sdf) / (truncation - voxel_size)
                    };
                    let total = voxel.weight + weight;
                    voxel.sdf = (voxel.sdf * voxel.weight + sdf.min(truncation) * weight) / total;
                    if let Some(c) = color.get(3 * i..3 * i + 3) {
                        for (old, new) in voxel.color.iter_mut().zip(c) {
                            *old = ((f32::from(*old) * voxel.weight + f32::from(*new) * weight)
                                / total)
                                .round() as u8;
                        }
                    }
                    voxel.weight = total.min(max_weight);
                }
            });
    }

    /// The voxel containing `point`, if its block exists.
    pub fn voxel_at(&self, point: Vec3) -> Option<&Voxel> {
        let index = (point / self.voxel_size).floor().as_ivec3();
        let key = index.div_euclid(IVec3::splat(BLOCK_SIDE as i32));
        let local = index.rem_euclid(IVec3::splat(BLOCK_SIDE as i32));
        let i = local.x as usize + BLOCK_SIDE * (local.y as usize + BLOCK_SIDE * local.z as usize);
        self.blocks.get(&key).map(|b| &b.voxels[i])
    }

    /// Trilinear signed distance at `point` from observed voxels; `None` where any corner is unobserved.
    pub fn sdf_at(&self, point: Vec3) -> Option<f32> {
        let base = point / self.voxel_size - Vec3::splat(0.5);
        let corner = base.floor();
        let f = base - corner;
        let mut value = 0.0;
        for c in 0..8 {
            let offset = Vec3::new((c & 1) as f32, ((c >> 1) & 1) as f32, ((c >> 2) & 1) as f32);
            let center = (corner + offset + Vec3::splat(0.5)) * self.voxel_size;
            let v = self.voxel_at(center).filter(|v| v.weight > 0.0)?;
            let wx = if c & 1 == 1 { f.x } else { 1.0 - f.x };
            let wy = if c & 2 == 2 { f.y } else { 1.0 - f.y };
            let wz = if c & 4 == 4 { f.z } else { 1.0 - f.z };
            value += wx * wy * wz * v.sdf;
        }
        Some(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::render_scene::RenderScene;
    use crate::render::sequence::render_frame;
    use crate::render::trajectory::room_loop;
    use crate::scene::{SceneSpec, SceneWorld};

    #[test]
    fn fused_clean_depth_has_its_zero_crossing_on_the_true_surface() {
        let spec = SceneSpec::parse(crate::BUILTIN_KITCHEN, std::path::Path::new("kitchen.json"))
            .expect("spec");
        let world =
            SceneWorld::from_spec(&spec, std::path::Path::new("kitchen.json")).expect("world");
        let scene = RenderScene::from_world(&world);
        let camera = Pinhole::KINECT;
        let poses = room_loop(world.room_size, 60, 1.45);
        let mut map = TsdfMap::new(0.02);
        for (k, pose) in poses.iter().enumerate().step_by(2) {
            let f = render_frame(&scene, &camera, pose, None, 1, k);
            map.integrate(&f.depth, &f.color, &camera, pose);
        }
        // A held-out frame: its measured surface points should sit at sdf ~ 0 in the map.
        let pose = poses[31];
        let f = render_frame(&scene, &camera, &pose, None, 1, 31);
        let mut errors: Vec<f32> = (0..f.depth.len())
            .step_by(53)
            .filter(|&i| f.depth[i] > 0.0)
            .filter_map(|i| {
                let p = pose.transform_point3(camera.unproject(
                    (i % 640) as f32,
                    (i / 640) as f32,
                    f.depth[i],
                ));
                map.sdf_at(p).map(f32::abs)
            })
            .collect();
        assert!(errors.len() > 3000, "{} observed samples", errors.len());
        errors.sort_by(f32::total_cmp);
        let median = errors[errors.len() / 2];
        assert!(
            median < 0.005,
            "median |sdf| on held-out surface points: {median} m"
        );
    }
}
