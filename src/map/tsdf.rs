//! A voxel-hashed truncated signed distance field with a segment label per voxel: blocks of 8^3
//! voxels in an arena indexed by a hash map, projective integration of depth frames in parallel
//! over the blocks a frame touches (`integrator.rs`), weights that drop off behind the surface,
//! colour, and Voxblox++'s label confidence vote. Blocks out of view are packed (`block.rs`),
//! losslessly.
//!
//! Signs: `sdf` is positive in front of the surface (free space, towards the camera), negative
//! behind it, in metres, clamped to `[-truncation, truncation]`.

use std::collections::{HashMap, HashSet};

use foldhash::fast::FixedState;
use glam::{Affine3A, IVec3, Vec3};
use rayon::prelude::*;

pub use super::block::{BLOCK_SIDE, BLOCK_VOXELS, Block, voxel_index, voxel_local};
use super::integrator::Integrator;
use super::voxel::weight_steps;
pub use super::voxel::{SegmentLabel, Voxel};
use crate::geometry::Pinhole;

/// One frame to fuse: depth in metres along the optical axis (0 = none), optional row-major RGB
/// (empty = none) and optional per-pixel global segment labels.
pub struct TsdfFrame<'a> {
    pub depth: &'a [f32],
    pub color: &'a [u8],
    pub labels: Option<&'a [SegmentLabel]>,
    /// Per pixel, how many times its weight the label's vote counts (`None`: once). The mapper
    /// raises it where semantics overrules geometry.
    pub label_gains: Option<&'a [u8]>,
    pub camera: &'a Pinhole,
    pub world_from_camera: &'a Affine3A,
}

/// Deterministic hashing: block order never depends on a per-process random seed.
type BlockIndex = HashMap<IVec3, u32, FixedState>;
type BlockSet = HashSet<IVec3, FixedState>;

/// `floor` per coordinate without a libm call (baseline x86-64 has no rounding instruction).
fn floor_ivec3(p: Vec3) -> IVec3 {
    let t = p.as_ivec3();
    t - IVec3::new(
        i32::from(t.x as f32 > p.x),
        i32::from(t.y as f32 > p.y),
        i32::from(t.z as f32 > p.z),
    )
}

#[derive(Clone)]
pub struct TsdfMap {
    pub voxel_size: f32,
    pub truncation: f32,
    /// Measurements farther than this from the camera are not integrated.
    pub max_ray_length: f32,
    /// Running averages stop growing their weight here, so the map can still change (at most
    /// 1023: weights are 16-bit fixed point).
    pub max_weight: f32,
    /// Once the map holds more than `pack_above_blocks` blocks, a block no frame has touched for
    /// this many integrations is packed ([`Block::pack`]: lossless, a fraction of the memory);
    /// 0 = never. The map's memory then grows with the surface seen, at the packed blocks' size,
    /// and only the blocks in view take 8 KB each.
    pub pack_after_frames: u32,
    /// A map of at most this many blocks packs none: a room at 2 cm fits whole, and packing,
    /// unpacking and reading packed blocks cost a little time.
    pub pack_above_blocks: usize,
    /// Blocks in the order they were first touched.
    pub blocks: Vec<Block>,
    /// Per block, the integration that last touched it (see `integrations`).
    last_touched: Vec<u32>,
    /// Frames integrated so far.
    integrations: u32,
    index: BlockIndex,
}

/// One second of a Kinect's 30 frames per second.
pub const PACK_AFTER_FRAMES: u32 = 30;
/// 32 MB of whole blocks.
pub const PACK_ABOVE_BLOCKS: usize = 4096;

impl TsdfMap {
    /// A map with `voxel_size` metres voxels and a truncation band of four voxels.
    pub fn new(voxel_size: f32) -> Self {
        Self {
            voxel_size,
            truncation: 4.0 * voxel_size,
            max_ray_length: 5.0,
            max_weight: 1000.0,
            pack_after_frames: PACK_AFTER_FRAMES,
            pack_above_blocks: PACK_ABOVE_BLOCKS,
            blocks: Vec::new(),
            last_touched: Vec::new(),
            integrations: 0,
            index: BlockIndex::default(),
        }
    }

    pub fn block_size(&self) -> f32 {
        self.voxel_size * BLOCK_SIDE as f32
    }

    /// Bytes held by voxel blocks and their index.
    pub fn memory_bytes(&self) -> usize {
        self.blocks.iter().map(Block::memory_bytes).sum::<usize>()
            + self.last_touched.capacity() * 4
            + self.index.capacity() * 24
    }

    /// Blocks held packed.
    pub fn packed_blocks(&self) -> usize {
        self.blocks.iter().filter(|b| b.is_packed()).count()
    }

    /// Keys of the blocks the truncation band of `frame` passes through, sorted. Rays are sampled
    /// every few pixels: neighbouring rays are far closer together than a block is wide.
    fn touched_blocks(&self, frame: &TsdfFrame) -> Vec<IVec3> {
        let camera = frame.camera;
        let (w, h) = (camera.width as usize, camera.height as usize);
        let footprint_at_max_range = self.max_ray_length / camera.fx;
        let stride = ((self.block_size() / (2.0 * footprint_at_max_range)) as usize).clamp(1, 8);
        let inv_block = 1.0 / self.block_size();
        let step = 0.5 * self.block_size();
        let (truncation, max_ray_length) = (self.truncation, self.max_ray_length);
        let pose = frame.world_from_camera;
        let keys: BlockSet = (0..h)
            .into_par_iter()
            .step_by(stride)
            .fold(BlockSet::default, |mut keys, v| {
                let mut last = IVec3::MAX;
                let eye = Vec3::from(pose.translation);
                for u in (0..w).step_by(stride) {
                    let d = frame.depth[v * w + u];
                    if d <= 0.0 || d > max_ray_length {
                        continue;
                    }
                    let ray = pose.matrix3 * camera.unproject(u as f32, v as f32, 1.0);
                    let mut t = (d - truncation).max(0.0);
                    loop {
                        let key = floor_ivec3((eye + ray * t) * inv_block);
                        // Neighbouring samples mostly share a block: skip the hash then.
                        if key != last {
                            keys.insert(key);
                            last = key;
                        }
                        if t >= d + truncation {
                            break;
                        }
                        t = (t + step).min(d + truncation);
                    }
                }
                keys
            })
            .reduce(BlockSet::default, |mut a, b| {
                a.extend(b);
                a
            });
        let mut keys: Vec<IVec3> = keys.into_iter().collect();
        keys.sort_unstable_by_key(|k| (k.x, k.y, k.z));
        keys
    }

    /// Fuses one frame: depth, colour when given, labels when given.
    pub fn integrate(&mut self, frame: &TsdfFrame) {
        let keys = self.touched_blocks(frame);
        let mut touched = vec![false; self.blocks.len() + keys.len()];
        self.integrations += 1;
        for key in keys {
            let slot = self.ensure_block(key);
            touched[slot] = true;
            self.last_touched[slot] = self.integrations;
        }
        let integrator = Integrator {
            camera: *frame.camera,
            camera_from_world: frame.world_from_camera.inverse(),
            depth: frame.depth,
            // A colour image of another size than the depth's is not used.
            color: if frame.color.len() == frame.depth.len() * 3 {
                frame.color
            } else {
                &[]
            },
            labels: frame.labels,
            label_gains: frame.label_gains,
            voxel_size: self.voxel_size,
            truncation: self.truncation,
            max_ray_length: self.max_ray_length,
            max_weight: weight_steps(self.max_weight),
        };
        let mut work: Vec<&mut Block> = self
            .blocks
            .iter_mut()
            .zip(&touched)
            .filter_map(|(b, &t)| t.then_some(b))
            .collect();
        work.par_iter_mut()
            .with_min_len(4)
            .for_each(|block| integrator.block(block.key, block.voxels_mut()));
        self.pack_blocks_out_of_view();
    }

    /// Packs the whole blocks whose last touch is at least `pack_after_frames` integrations old,
    /// once the map is over `pack_above_blocks` (touched again, a block is unpacked and ages from
    /// then).
    fn pack_blocks_out_of_view(&mut self) {
        if self.pack_after_frames == 0 || self.blocks.len() <= self.pack_above_blocks {
            return;
        }
        let Some(aged) = self.integrations.checked_sub(self.pack_after_frames) else {
            return;
        };
        let truncation = self.truncation;
        self.blocks
            .par_iter_mut()
            .zip(&self.last_touched)
            .filter(|(block, last)| **last <= aged && !block.is_packed())
            .for_each(|(block, _)| block.pack(truncation));
    }

    /// The arena slot of block `key`, allocating an unobserved block when it is new.
    pub fn ensure_block(&mut self, key: IVec3) -> usize {
        let next = self.blocks.len() as u32;
        let slot = *self.index.entry(key).or_insert(next);
        if slot == next {
            self.blocks.push(Block::new(key));
            self.last_touched.push(self.integrations);
        }
        slot as usize
    }

    /// Replaces voxel labels: `relabel[l]` is the new label of `l` (labels past its end stay).
    pub fn relabel(&mut self, relabel: &[SegmentLabel]) {
        self.blocks
            .par_iter_mut()
            .for_each(|block| block.relabel(relabel));
    }

    /// The block holding voxel `index` (integer voxel coordinates), and the voxel's slot in it.
    fn locate(&self, voxel: IVec3) -> Option<(&Block, usize)> {
        let key = voxel.div_euclid(IVec3::splat(BLOCK_SIDE as i32));
        let local = voxel.rem_euclid(IVec3::splat(BLOCK_SIDE as i32));
        let slot = *self.index.get(&key)?;
        Some((&self.blocks[slot as usize], voxel_index(local)))
    }

    /// Integer coordinates of the voxel containing `point`.
    pub fn voxel_coords(&self, point: Vec3) -> IVec3 {
        (point / self.voxel_size).floor().as_ivec3()
    }

    /// Centre of the voxel with integer coordinates `voxel`.
    pub fn voxel_center(&self, voxel: IVec3) -> Vec3 {
        (voxel.as_vec3() + Vec3::splat(0.5)) * self.voxel_size
    }

    /// The voxel with integer coordinates `voxel`, if its block exists.
    pub fn voxel(&self, voxel: IVec3) -> Option<Voxel> {
        self.locate(voxel).map(|(b, i)| b.voxel(i))
    }

    /// The voxel containing `point`, if its block exists.
    pub fn voxel_at(&self, point: Vec3) -> Option<Voxel> {
        self.voxel(self.voxel_coords(point))
    }

    /// Trilinear signed distance at `point` from observed voxels; `None` where any corner is unobserved.
    pub fn sdf_at(&self, point: Vec3) -> Option<f32> {
        let base = point / self.voxel_size - Vec3::splat(0.5);
        let corner = base.floor();
        let f = base - corner;
        let corner = corner.as_ivec3();
        let mut value = 0.0;
        for c in 0..8 {
            let offset = IVec3::new(c & 1, (c >> 1) & 1, (c >> 2) & 1);
            let v = self.voxel(corner + offset).filter(|v| v.is_observed())?;
            let wx = if c & 1 == 1 { f.x } else { 1.0 - f.x };
            let wy = if c & 2 == 2 { f.y } else { 1.0 - f.y };
            let wz = if c & 4 == 4 { f.z } else { 1.0 - f.z };
            value += wx * wy * wz * v.sdf;
        }
        Some(value)
    }

    /// Depth (along the optical axis) of the first zero crossing of the map along the ray through
    /// pixel `(u, v)`, or `None` when the ray leaves the map's observed space without a crossing.
    pub fn raycast_depth(
        &self,
        camera: &Pinhole,
        world_from_camera: &Affine3A,
        u: f32,
        v: f32,
    ) -> Option<f32> {
        let dir = world_from_camera.matrix3 * camera.unproject(u, v, 1.0);
        let eye = Vec3::from(world_from_camera.translation);
        let scale = dir.length();
        let mut t = 0.1;
        let mut previous: Option<(f32, f32)> = None;
        while t < self.max_ray_length {
            let p = eye + dir * t;
            match self.sdf_at(p) {
                Some(sdf) => {
                    if let Some((t0, sdf0)) = previous
                        && sdf0 > 0.0
                        && sdf <= 0.0
                    {
                        return Some(t0 + (t - t0) * sdf0 / (sdf0 - sdf));
                    }
                    previous = Some((t, sdf));
                    // Never step past the surface: at most the distance left, at least half a voxel.
                    t += (sdf.abs() * 0.8).max(0.5 * self.voxel_size) / scale;
                }
                None => {
                    previous = None;
                    t += self.voxel_size / scale;
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::trajectory::room_loop;
    use crate::scene::render_sequence::render_frame;
    use crate::scene::{SceneSpec, SceneWorld};

    /// The built-in kitchen's world and the scene its frames are rendered from.
    fn kitchen() -> (SceneWorld, crate::render::render_scene::RenderScene) {
        let spec = SceneSpec::parse(crate::BUILTIN_KITCHEN, std::path::Path::new("kitchen.json"))
            .expect("spec");
        let world =
            SceneWorld::from_spec(&spec, std::path::Path::new("kitchen.json")).expect("world");
        let scene = world.render_scene();
        (world, scene)
    }

    #[test]
    fn fused_clean_depth_has_its_zero_crossing_on_the_true_surface() {
        let (world, scene) = kitchen();
        let camera = Pinhole::KINECT;
        let poses = room_loop(world.room_size, 60, 1.45);
        let mut map = TsdfMap::new(0.02);
        for (k, pose) in poses.iter().enumerate().step_by(2) {
            let f = render_frame(&scene, &camera, pose, None, 1, k);
            map.integrate(&TsdfFrame {
                depth: &f.depth,
                color: &f.color,
                labels: None,
                label_gains: None,
                camera: &camera,
                world_from_camera: pose,
            });
        }
        // A held-out frame: its measured surface points should sit at sdf ~ 0 in the map, and
        // rays cast into the map should find the measured depth.
        let pose = poses[31];
        let f = render_frame(&scene, &camera, &pose, None, 1, 31);
        let samples: Vec<usize> = (0..f.depth.len())
            .step_by(53)
            .filter(|&i| f.depth[i] > 0.0)
            .collect();
        let mut sdf_errors: Vec<f32> = samples
            .iter()
            .filter_map(|&i| {
                let p = pose.transform_point3(camera.unproject(
                    (i % 640) as f32,
                    (i / 640) as f32,
                    f.depth[i],
                ));
                map.sdf_at(p).map(f32::abs)
            })
            .collect();
        assert!(
            sdf_errors.len() > 3000,
            "{} observed samples",
            sdf_errors.len()
        );
        let median = crate::map::median(&mut sdf_errors);
        assert!(
            median < 0.005,
            "median |sdf| on held-out surface points: {median} m"
        );
        let mut depth_errors: Vec<f32> = samples
            .iter()
            .filter_map(|&i| {
                map.raycast_depth(&camera, &pose, (i % 640) as f32, (i / 640) as f32)
                    .map(|d| (d - f.depth[i]).abs())
            })
            .collect();
        assert!(depth_errors.len() as f32 > 0.9 * samples.len() as f32);
        let median = crate::map::median(&mut depth_errors);
        assert!(
            median < 0.005,
            "median |raycast - measured depth|: {median} m"
        );
    }

    #[test]
    fn packing_blocks_out_of_view_changes_no_voxel() {
        let (world, scene) = kitchen();
        let camera = Pinhole::KINECT;
        // Half the loop, then its start again: blocks go out of view, are packed, and are
        // touched (unpacked) again.
        let poses = room_loop(world.room_size, 40, 1.45);
        let order: Vec<usize> = (0..20).chain(0..8).collect();
        let frames: Vec<_> = order
            .iter()
            .map(|&k| render_frame(&scene, &camera, &poses[k], None, 1, k))
            .collect();
        let labels: Vec<Vec<SegmentLabel>> = frames
            .iter()
            .map(|f| {
                (0..f.depth.len())
                    .map(|i| (i % 7) as SegmentLabel)
                    .collect()
            })
            .collect();
        let map_packing_after = |frames_out_of_view: u32, above_blocks: usize| {
            let mut map = TsdfMap::new(0.04);
            map.pack_after_frames = frames_out_of_view;
            map.pack_above_blocks = above_blocks;
            for ((f, l), &k) in frames.iter().zip(&labels).zip(&order) {
                map.integrate(&TsdfFrame {
                    depth: &f.depth,
                    color: &f.color,
                    labels: Some(l),
                    label_gains: None,
                    camera: &camera,
                    world_from_camera: &poses[k],
                });
            }
            map.relabel(&[0, 2, 1]);
            map
        };
        let whole = map_packing_after(0, 0);
        let packed = map_packing_after(3, 0);
        assert_eq!(whole.packed_blocks(), 0);
        // A map within `pack_above_blocks` packs nothing.
        let small = map_packing_after(3, whole.blocks.len());
        assert_eq!(small.packed_blocks(), 0);
        assert!(
            packed.packed_blocks() * 4 > packed.blocks.len(),
            "{} of {} blocks packed",
            packed.packed_blocks(),
            packed.blocks.len()
        );
        assert!(packed.memory_bytes() < whole.memory_bytes());
        assert_eq!(whole.blocks.len(), packed.blocks.len());
        for (a, b) in whole.blocks.iter().zip(&packed.blocks) {
            assert_eq!(a.key, b.key);
            for (i, (va, vb)) in a.voxels().zip(b.voxels()).enumerate() {
                assert!(
                    va.sdf.to_bits() == vb.sdf.to_bits() && va == vb,
                    "block {} slot {i}: {va:?} against {vb:?}",
                    a.key
                );
            }
        }
    }

    /// An 8 x 8 camera looking down +z (the label-vote tests).
    fn eight_pixel_camera() -> Pinhole {
        Pinhole {
            width: 8,
            height: 8,
            fx: 8.0,
            fy: 8.0,
            cx: 3.5,
            cy: 3.5,
        }
    }

    #[test]
    fn the_label_vote_follows_the_majority_and_relabel_renames() {
        let camera = eight_pixel_camera();
        let depth = vec![1.0f32; 64];
        let pose = Affine3A::IDENTITY;
        let mut map = TsdfMap::new(0.05);
        for label in [3, 3, 5, 3, 5, 5, 5, 5] {
            let labels = vec![label; 64];
            map.integrate(&TsdfFrame {
                depth: &depth,
                color: &[],
                labels: Some(&labels),
                label_gains: None,
                camera: &camera,
                world_from_camera: &pose,
            });
        }
        let surface = map.voxel_at(Vec3::new(0.0, 0.0, 1.01)).expect("observed");
        assert_eq!(surface.label, 5);
        map.relabel(&[0, 1, 2, 3, 4, 9]);
        let surface = map.voxel_at(Vec3::new(0.0, 0.0, 1.01)).expect("observed");
        assert_eq!(surface.label, 9);
    }

    #[test]
    fn a_cut_out_label_voting_twice_overturns_a_label_seen_in_more_frames() {
        let camera = eight_pixel_camera();
        let depth = vec![1.0f32; 64];
        let pose = Affine3A::IDENTITY;
        let label_after = |votes: &[(SegmentLabel, u8)]| {
            let mut map = TsdfMap::new(0.05);
            for &(label, gain) in votes {
                map.integrate(&TsdfFrame {
                    depth: &depth,
                    color: &[],
                    labels: Some(&[label; 64]),
                    label_gains: Some(&[gain; 64]),
                    camera: &camera,
                    world_from_camera: &pose,
                });
            }
            map.voxel_at(Vec3::new(0.0, 0.0, 1.01))
                .expect("observed")
                .label
        };
        // The table's label three times, the mug's (cut out, gain 2) twice: 4 against 3.
        assert_eq!(label_after(&[(3, 1), (3, 1), (7, 2), (3, 1), (7, 2)]), 7);
        assert_eq!(label_after(&[(3, 1), (3, 1), (7, 1), (3, 1), (7, 1)]), 3);
    }
}
