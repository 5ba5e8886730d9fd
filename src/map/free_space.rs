//! Free-space evidence for surface points: a point that frames saw clearly past (the depth at its
//! pixel lies well beyond it) is in free space, whatever the TSDF's average says. The projective
//! TSDF marks the band behind a grazing hit as inside, so an object's top or side runs on over a
//! few centimetres of gap to its wall or neighbour; steeper views see through that run-on, and
//! counting them removes it (space carving, Kutulakos and Seitz, applied to the fused surface).
//! The frames' label images say whose surface they saw at a point as well: a wall seen through
//! the gap behind a shelf, in the frames, carries the shelf's label in the map when the band
//! behind the shelf's hits outvoted the few frames that saw the wall there.

use glam::{Affine3A, Vec3};
use rayon::prelude::*;

use crate::error::InputError;
use crate::geometry::Pinhole;
use crate::io::sequence::Sequence;
use crate::map::FrameLabels;

/// When a point counts as in free space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeSpaceParams {
    /// Frames whose depth at a point is nearer than this (metres) or `occlusion_sigmas` of noise
    /// are occluders: they neither see the point nor past it.
    pub occlusion_margin: f32,
    pub occlusion_sigmas: f32,
    /// Residuals (measured depth minus the point's) are clipped to this (metres): a point seen
    /// past by 2 m counts like one seen past by this much.
    pub max_residual: f32,
    /// A point is in free space when at least `min_frames` saw it and their mean residual
    /// exceeds both `min_mean_residual` (metres) and `significance` standard errors of the
    /// sensor's noise.
    pub min_frames: u16,
    pub min_mean_residual: f32,
    pub significance: f32,
    /// A point is another's surface when at least `min_frames` of the frames that saw it put
    /// another entity's label there, and more than this many times as many as put its own.
    pub other_label_ratio: f32,
    /// The sequence's depth noise as a multiple of `axial_sigma` (1 for a Kinect-class sensor;
    /// measured, `map::depth_precision`).
    pub noise_scale: f32,
}

impl FreeSpaceParams {
    /// For a map of `voxel_size`: the fused surface lies within half a voxel of the truth, so a
    /// point is carved when the frames see past it by three quarters of a voxel on average (at
    /// least `MIN_MEAN_RESIDUAL_M`), and by two standard errors of the noise (README, contact
    /// graph, for the thresholds tried).
    pub fn for_voxel(voxel_size: f32) -> Self {
        Self {
            occlusion_margin: voxel_size,
            occlusion_sigmas: 3.0,
            max_residual: 0.1,
            min_frames: 3,
            min_mean_residual: (0.75 * voxel_size).max(MIN_MEAN_RESIDUAL_M),
            significance: 2.0,
            other_label_ratio: 1.0,
            noise_scale: 1.0,
        }
    }
}

/// The least mean residual that carves, at any voxel size (metres): the distance at which two
/// boxes stop touching. A true edge is seen past by the gap behind it, so a vertex seen past by
/// less is as likely an edge in contact as run-on, and carving it could only part a touching
/// pair (at 1.5 cm the noisy kitchen's cabinet 1.8 cm off its wall lost its back edge; at 1 cm,
/// three quarters of a voxel cut a bottle's contact with a monitor 1.3 cm away).
const MIN_MEAN_RESIDUAL_M: f32 = crate::graph::proximal::PROXIMAL_MARGIN;

/// Axial depth noise (metres, one sigma) of a Kinect-class structured-light sensor at depth `z`
/// (Nguyen, Izadi and Lovell 2012; the renderer's noise model uses the same curve).
pub fn axial_sigma(z: f32) -> f32 {
    0.0012 + 0.0019 * (z - 0.4).powi(2)
}

/// Residuals are summed in micrometres and variances in square millimetres, as integers:
/// frames are counted in parallel, and integer sums do not depend on the order they meet in.
const RESIDUAL_UNITS_PER_M: f32 = 1e6;
const VARIANCE_UNITS_PER_M2: f32 = 1e6;

/// What the frames that saw a point measured beyond it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sightings {
    /// Frames whose depth at the point was not nearer than the occlusion margin.
    pub seen: u16,
    /// Their residuals (measured depth minus the point's depth), clipped, summed (micrometres).
    pub residual_sum: i64,
    /// Their noise variances at the point's depth, summed (square millimetres).
    pub variance_sum: i64,
    /// Of them, the frames whose label at the point was the point's own entity, and another
    /// entity (frames without a label there, or with one no entity kept, count for neither).
    pub own_label: u16,
    pub other_label: u16,
}

impl Sightings {
    pub fn in_free_space(&self, params: &FreeSpaceParams) -> bool {
        if self.seen < params.min_frames {
            return false;
        }
        let n = f32::from(self.seen);
        let mean = self.residual_sum as f32 / RESIDUAL_UNITS_PER_M / n;
        let standard_error = (self.variance_sum as f32 / VARIANCE_UNITS_PER_M2).sqrt() / n;
        mean > params
            .min_mean_residual
            .max(params.significance * standard_error)
    }

    /// Whether the frames that saw the point mostly saw another entity there.
    pub fn labelled_other(&self, params: &FreeSpaceParams) -> bool {
        self.other_label >= params.min_frames
            && f32::from(self.other_label) > params.other_label_ratio * f32::from(self.own_label)
    }

    fn add(&mut self, other: &Sightings) {
        self.seen = self.seen.saturating_add(other.seen);
        self.residual_sum += other.residual_sum;
        self.variance_sum += other.variance_sum;
        self.own_label = self.own_label.saturating_add(other.own_label);
        self.other_label = self.other_label.saturating_add(other.other_label);
    }
}

/// Whose surface the frames saw: each frame's label image (the mapper's, in frame order), the
/// entity each of its labels ended in (0: none), and the entity each point belongs to.
pub struct EntityLabels<'a> {
    pub frames: &'a [FrameLabels],
    /// Indexed by a frame's label.
    pub entity_of_label: &'a [u32],
    /// Indexed like the points.
    pub point_entity: &'a [u32],
}

impl EntityLabels<'_> {
    /// The entity frame `frame` showed at pixel (`u`, `v`) (0: none).
    fn entity_at(&self, frame: usize, u: u32, v: u32) -> u32 {
        let label = self.frames.get(frame).map_or(0, |f| f.at(u, v));
        self.entity_of_label
            .get(label as usize)
            .copied()
            .unwrap_or(0)
    }
}

/// Adds one depth frame's sightings of `points` (world frame). The depth compared is the pixel
/// the point projects into: a point over a gap is seen past along rays that graze the edge in
/// front of it, which a neighbourhood's nearest depth would hide.
/// With `labels` (and the frame's index in them), the frame's label at each point seen is
/// counted too.
pub fn observe_frame(
    points: &[Vec3],
    sightings: &mut [Sightings],
    depth: &[f32],
    labels: Option<(&EntityLabels, usize)>,
    camera: &Pinhole,
    camera_from_world: &Affine3A,
    params: &FreeSpaceParams,
) {
    let (w, h) = (camera.width as i32, camera.height as i32);
    for (k, (p, s)) in points.iter().zip(sightings.iter_mut()).enumerate() {
        let q = camera_from_world.transform_point3(*p);
        if q.z <= 0.05 {
            continue;
        }
        let uv = camera.project(q);
        let (u, v) = (uv.x.round() as i32, uv.y.round() as i32);
        if u < 0 || v < 0 || u >= w || v >= h {
            continue;
        }
        let measured = depth[(v * w + u) as usize];
        if measured <= 0.0 {
            continue;
        }
        let sigma = params.noise_scale * axial_sigma(q.z);
        let residual = measured - q.z;
        if residual < -params.occlusion_margin.max(params.occlusion_sigmas * sigma) {
            continue;
        }
        s.seen = s.seen.saturating_add(1);
        s.residual_sum += (residual.min(params.max_residual) * RESIDUAL_UNITS_PER_M).round() as i64;
        s.variance_sum += (sigma * sigma * VARIANCE_UNITS_PER_M2).round() as i64;
        // A frame whose depth there is nearer than the point by more than its noise saw what
        // is in front of it, not it (a cup half hidden behind a monitor's stand).
        let in_front = residual < -(0.5 * params.occlusion_margin).max(2.0 * sigma);
        if let Some((labels, frame)) = labels
            && !in_front
        {
            // The label is read at the pixel the point projects into: looking a pixel or three
            // either side for its own (masks' boundaries are no better) took the back edges of
            // the noisy kitchen's cabinets for undecided and left the shelves' run-on onto
            // their walls (README, contact graph).
            match labels.entity_at(frame, u as u32, v as u32) {
                0 => {}
                e if e == labels.point_entity[k] => s.own_label = s.own_label.saturating_add(1),
                _ => s.other_label = s.other_label.saturating_add(1),
            }
        }
    }
}

/// Every frame of `sequence`'s sightings of `points` (world frame), summed; frames are read in
/// parallel, each into its own counts. `labels`' frames are the sequence's.
pub fn sequence_sightings(
    sequence: &Sequence,
    points: &[Vec3],
    labels: Option<&EntityLabels>,
    params: &FreeSpaceParams,
) -> Result<Vec<Sightings>, InputError> {
    let empty = || vec![Sightings::default(); points.len()];
    (0..sequence.frames.len())
        .into_par_iter()
        .try_fold(empty, |mut counts, i| {
            let depth = sequence.load_depth(i)?;
            let camera_from_world = sequence.frames[i].world_from_camera.inverse();
            observe_frame(
                points,
                &mut counts,
                &depth,
                labels.map(|l| (l, i)),
                &sequence.camera,
                &camera_from_world,
                params,
            );
            Ok(counts)
        })
        .try_reduce(empty, |mut a, b| {
            for (x, y) in a.iter_mut().zip(&b) {
                x.add(y);
            }
            Ok(a)
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::SegmentLabel;

    /// `frames` frames of a camera at the origin looking down +z at a wall `wall` metres away.
    fn sightings_of_wall(points: &[Vec3], wall: f32, frames: usize) -> Vec<Sightings> {
        let camera = Pinhole::KINECT;
        let depth = vec![wall; camera.pixel_count()];
        let mut s = vec![Sightings::default(); points.len()];
        let params = FreeSpaceParams::for_voxel(0.02);
        for _ in 0..frames {
            observe_frame(
                points,
                &mut s,
                &depth,
                None,
                &camera,
                &Affine3A::IDENTITY,
                &params,
            );
        }
        s
    }

    /// Three frames of a wall 3 m away: a point on it is on the surface, points 1 m and 3 cm in
    /// front of it are in free space, one 1 cm in front is within the fused surface's accuracy,
    /// one behind the wall is occluded (never seen).
    #[test]
    fn points_in_front_of_the_measured_surface_are_in_free_space() {
        let params = FreeSpaceParams::for_voxel(0.02);
        let at = |z: f32| Vec3::new(0.1, 0.0, z);
        let s = sightings_of_wall(&[at(3.0), at(2.0), at(2.97), at(2.99), at(4.0)], 3.0, 3);
        assert_eq!(s[0].seen, 3);
        assert!(!s[0].in_free_space(&params));
        assert!(s[1].in_free_space(&params));
        assert_eq!(s[1].residual_sum, (3.0 * params.max_residual * 1e6) as i64);
        assert!(s[2].in_free_space(&params));
        assert!(!s[3].in_free_space(&params));
        assert_eq!(s[4], Sightings::default());
    }

    /// 4 cm in front of a wall 5 m away (sigma 4.1 cm): three frames are not significant,
    /// thirty are.
    #[test]
    fn far_points_need_more_frames() {
        let params = FreeSpaceParams::for_voxel(0.02);
        let point = [Vec3::new(0.0, 0.0, 4.96)];
        assert!(!sightings_of_wall(&point, 5.0, 3)[0].in_free_space(&params));
        assert!(sightings_of_wall(&point, 5.0, 30)[0].in_free_space(&params));
    }

    /// Two frames never carve, whatever they saw.
    #[test]
    fn two_frames_are_not_enough() {
        let params = FreeSpaceParams::for_voxel(0.02);
        let s = sightings_of_wall(&[Vec3::new(0.0, 0.0, 1.0)], 3.0, 2);
        assert_eq!(s[0].seen, 2);
        assert!(!s[0].in_free_space(&params));
    }

    /// A wall 3 m away whose left half the frames labelled as entity 1 and right half as
    /// entity 2 (the bottom quarter unlabelled): points of entity 1 on each half and one at the
    /// bottom. The right one was seen as another's.
    #[test]
    fn points_the_frames_labelled_as_another_entity_are_anothers() {
        let camera = Pinhole::KINECT;
        let (w, h) = (camera.width, camera.height);
        // The bottom quarter's rows (the third point, 0.8 m down) have no label.
        let image: Vec<SegmentLabel> = (0..w * h)
            .map(|i| match (i % w < w / 2, i / w < h * 3 / 4) {
                (_, false) => 0,
                (true, true) => 5,
                (false, true) => 9,
            })
            .collect();
        let frames = vec![FrameLabels::encode(&image, w, h); 3];
        let mut entity_of_label = vec![0; 10];
        entity_of_label[5] = 1;
        entity_of_label[9] = 2;
        // The third projects where the frames had no label: it counts for neither.
        let points = [
            Vec3::new(-0.2, 0.0, 3.0),
            Vec3::new(0.2, 0.0, 3.0),
            Vec3::new(0.0, 0.8, 3.0),
        ];
        let labels = EntityLabels {
            frames: &frames,
            entity_of_label: &entity_of_label,
            point_entity: &[1, 1, 1],
        };
        let params = FreeSpaceParams::for_voxel(0.02);
        let depth = vec![3.0; camera.pixel_count()];
        let mut s = vec![Sightings::default(); 3];
        for frame in 0..3 {
            observe_frame(
                &points,
                &mut s,
                &depth,
                Some((&labels, frame)),
                &camera,
                &Affine3A::IDENTITY,
                &params,
            );
        }
        assert_eq!((s[0].own_label, s[0].other_label), (3, 0));
        assert_eq!((s[1].own_label, s[1].other_label), (0, 3));
        assert!(!s[0].labelled_other(&params));
        assert!(s[1].labelled_other(&params));
        assert!(!s[1].in_free_space(&params), "on the surface all the same");
        assert_eq!((s[2].own_label, s[2].other_label), (0, 0));
    }

    #[test]
    fn noise_grows_with_depth_as_the_kinect_model() {
        assert!((axial_sigma(0.4) - 0.0012).abs() < 1e-7);
        assert!((axial_sigma(2.4) - (0.0012 + 0.0019 * 4.0)).abs() < 1e-6);
    }
}
