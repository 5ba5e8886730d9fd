//! A front's colours as the camera saw them, baked from the frames into an image on the front's
//! plane (issue 36, section 1: "in colour"). The map keeps a colour per 2 cm voxel, too coarse
//! for what tells doors apart on a real kitchen front: the 3-5 mm grooves between doors and the
//! 1 cm bars of their handles, which stand out of the front less than the depth noise of a
//! structured-light camera (the red 7-Scenes counter's do). A frame taken a metre or two from
//! the front resolves both: at 585 px focal length a pixel is 2-3 mm there.
//!
//! Each texel of the image takes its colour from the best frame that sees it: the few frames
//! that face the front most squarely and closely are taken, each texel from the one of them that
//! sees it most squarely and closely, and a frame sees a texel when its depth there agrees with
//! the front plane (a chair before the counter hides it). One frame per
//! texel, not a mean over frames: pose and colour-to-depth registration errors of a few
//! millimetres would blur the very lines the image is for.
//!
//! Bevy-free: the caller gives the frames' poses in the front's frame of reference and a way to
//! load a frame's colour and depth.

use glam::{Affine3A, Vec3};

use crate::geometry::Pinhole;
use crate::perception::handles::Front;

/// Texel size, metres: a handle's 1 cm bar is three texels across, and a 3 mm groove falls on a
/// texel's centre (the texels sample the frames' pixels, they do not average them).
pub const TEXEL_M: f32 = 0.003;
/// The frames baked from, at most.
const VIEWS: usize = 6;
/// Chosen frames' cameras stand at least this far apart (metres): neighbouring frames of a
/// sequence see the same thing.
const VIEW_SEPARATION_M: f32 = 0.25;
/// A frame must face the front at least this squarely (cosine between its optical axis and the
/// front's inward normal) ...
const MIN_FACING_COS: f32 = 0.5;
/// ... and see at least this share of it.
const MIN_COVERAGE: f32 = 0.2;
/// Measured depth within this distance (metres) of the front plane's sees the front: a handle
/// stands up to 8 cm out of it, anything nearer the camera hides it.
const DEPTH_AGREES_M: f32 = 0.09;
/// Texels nearer than this to the camera (metres) are not used: the image's edge at close range.
const MIN_RANGE_M: f32 = 0.3;

/// A rectangle on a front: along it (`right`, metres from `front.origin`) by world height (`z`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrontRect {
    pub front: Front,
    pub right: [f32; 2],
    pub z: [f32; 2],
}

impl FrontRect {
    /// The point on the front plane at `right` along it and height `z`.
    pub fn point(&self, right: f32, z: f32) -> Vec3 {
        let f = &self.front;
        (f.origin + f.right * right).with_z(z)
    }
}

/// One frame that may see a front: its index for the loader and its camera's pose.
#[derive(Clone, Copy, Debug)]
pub struct View {
    pub frame: usize,
    pub world_from_camera: Affine3A,
}

/// A frame's colour (row-major RGB, 8 bits) and depth (metres, 0 where none).
pub struct ViewImages {
    pub color: Vec<u8>,
    pub depth: Vec<f32>,
}

/// The front's image: `width` by `height` texels of [`TEXEL_M`], row 0 at the top, column 0 at
/// `rect.right[0]`; a texel no frame saw is `None`.
#[derive(Clone, Debug)]
pub struct FrontTexture {
    pub rect: FrontRect,
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Option<[u8; 3]>>,
}

impl FrontTexture {
    pub fn get(&self, column: usize, row: usize) -> Option<[u8; 3]> {
        self.texels[row * self.width + column]
    }

    /// The front coordinates (right, z) of texel `(column, row)`'s centre.
    pub fn texel_center(&self, column: f32, row: f32) -> (f32, f32) {
        (
            self.rect.right[0] + (column + 0.5) * TEXEL_M,
            self.rect.z[1] - (row + 0.5) * TEXEL_M,
        )
    }

    /// The share of texels seen.
    pub fn coverage(&self) -> f32 {
        let seen = self.texels.iter().filter(|t| t.is_some()).count();
        seen as f32 / self.texels.len().max(1) as f32
    }
}

/// Points on a 5 x 5 grid over `rect`, to rate a view by.
fn probe_points(rect: &FrontRect) -> Vec<Vec3> {
    let mut points = Vec::with_capacity(25);
    for i in 0..5 {
        for j in 0..5 {
            let right = rect.right[0] + (rect.right[1] - rect.right[0]) * (0.1 + 0.2 * i as f32);
            let z = rect.z[0] + (rect.z[1] - rect.z[0]) * (0.1 + 0.2 * j as f32);
            points.push(rect.point(right, z));
        }
    }
    points
}

/// How well `view` sees `rect`: the share of it in the image times how squarely it faces it over
/// how far it is (a texel's footprint in pixels grows as both); `None` when it faces it too
/// obliquely or sees too little of it.
fn view_quality(rect: &FrontRect, camera: &Pinhole, view: &View) -> Option<f32> {
    let forward = view.world_from_camera.matrix3.z_axis;
    let facing = -Vec3::from(forward).dot(rect.front.normal);
    if facing < MIN_FACING_COS {
        return None;
    }
    let camera_from_world = view.world_from_camera.inverse();
    let probes = probe_points(rect);
    let inside = probes
        .iter()
        .filter(|p| in_image(camera, camera_from_world.transform_point3(**p)).is_some())
        .count();
    let coverage = inside as f32 / probes.len() as f32;
    if coverage < MIN_COVERAGE {
        return None;
    }
    let centre = rect.point(
        0.5 * (rect.right[0] + rect.right[1]),
        0.5 * (rect.z[0] + rect.z[1]),
    );
    let distance = Vec3::from(view.world_from_camera.translation).distance(centre);
    Some(coverage * facing / distance.max(0.5))
}

/// The pixel (column, row) where `p` (camera frame) falls inside the image, if it does.
fn in_image(camera: &Pinhole, p: Vec3) -> Option<(usize, usize)> {
    if p.z < MIN_RANGE_M {
        return None;
    }
    let uv = camera.project(p);
    let (u, v) = (uv.x.round(), uv.y.round());
    (u >= 0.0 && v >= 0.0 && u < camera.width as f32 && v < camera.height as f32)
        .then_some((u as usize, v as usize))
}

/// The views to bake `rect` from, best first: at most [`VIEWS`], their cameras apart.
pub fn best_views(rect: &FrontRect, camera: &Pinhole, views: &[View]) -> Vec<View> {
    let mut rated: Vec<(f32, View)> = views
        .iter()
        .filter_map(|v| Some((view_quality(rect, camera, v)?, *v)))
        .collect();
    rated.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.frame.cmp(&b.1.frame)));
    let mut chosen: Vec<View> = Vec::new();
    for (_, view) in rated {
        let at = Vec3::from(view.world_from_camera.translation);
        let apart = chosen
            .iter()
            .all(|c| Vec3::from(c.world_from_camera.translation).distance(at) >= VIEW_SEPARATION_M);
        if apart {
            chosen.push(view);
            if chosen.len() == VIEWS {
                break;
            }
        }
    }
    chosen
}

/// Bakes `rect`'s image from `views` (best first, as [`best_views`] gives them) with their
/// images: each texel from the view that sees it most squarely and closely among those whose
/// depth there agrees with the plane, its colour
/// scaled by that view's gain (each channel's median ratio to the best view's colour where both
/// see the front): frames differ in exposure, and a door seen in a darker frame would differ
/// from its neighbour as a handle does.
pub fn bake(rect: &FrontRect, camera: &Pinhole, views: &[(View, ViewImages)]) -> FrontTexture {
    let width = ((rect.right[1] - rect.right[0]) / TEXEL_M).ceil().max(0.0) as usize;
    let height = ((rect.z[1] - rect.z[0]) / TEXEL_M).ceil().max(0.0) as usize;
    let cameras: Vec<Affine3A> = views
        .iter()
        .map(|(v, _)| v.world_from_camera.inverse())
        .collect();
    let mut texture = FrontTexture {
        rect: *rect,
        width,
        height,
        texels: Vec::new(),
    };
    // View k's colour of texel i, with how well it sees it there.
    let sample = |i: usize, k: usize| -> Option<Sample> {
        let (right, z) = texture.texel_center((i % width) as f32, (i / width) as f32);
        let p = rect.point(right, z);
        let (images, camera_from_world) = (&views[k].1, &cameras[k]);
        let in_camera = camera_from_world.transform_point3(p);
        let (u, v) = in_image(camera, in_camera)?;
        let pixel = v * camera.width as usize + u;
        let depth = *images.depth.get(pixel)?;
        if depth <= 0.0 || (depth - in_camera.z).abs() > DEPTH_AGREES_M {
            return None;
        }
        let c = images.color.get(3 * pixel..3 * pixel + 3)?;
        // Squarely and closely: the texel's footprint in pixels.
        let square = -in_camera
            .normalize()
            .dot(camera_from_world.transform_vector3(rect.front.normal));
        Some(([c[0], c[1], c[2]], square / in_camera.length()))
    };
    // The gains from every `GAIN_STEP`th texel each way: enough samples, and nothing held for
    // every texel of a long run of units.
    let probes: Vec<usize> = (0..height)
        .step_by(GAIN_STEP)
        .flat_map(|r| (0..width).step_by(GAIN_STEP).map(move |c| r * width + c))
        .collect();
    let gains: Vec<[f32; 3]> = (0..views.len())
        .map(|k| {
            exposure_gain(
                probes
                    .iter()
                    .map(|&i| (sample(i, 0).map(|s| s.0), sample(i, k).map(|s| s.0))),
            )
        })
        .collect();
    let texels = (0..width * height)
        .map(|i| {
            let best = (0..views.len())
                .filter_map(|k| Some((sample(i, k)?, gains[k])))
                .max_by(|a, b| a.0.1.total_cmp(&b.0.1));
            best.map(|((c, _), gain)| {
                std::array::from_fn(|ch| {
                    (f32::from(c[ch]) * gain[ch]).round().clamp(0.0, 255.0) as u8
                })
            })
        })
        .collect();
    texture.texels = texels;
    texture
}

/// A view's colour of a texel, and how squarely and closely it sees it (larger is better).
type Sample = ([u8; 3], f32);

/// Overlapping samples fewer than this leave a view's gain at 1 ...
const MIN_GAIN_SAMPLES: usize = 100;
/// ... taken every this many texels each way (1.2 cm).
const GAIN_STEP: usize = 4;
/// Channels darker than this (of 255) say little of a ratio.
const MIN_GAIN_LEVEL: u8 = 10;

/// The gain (per channel) that brings a view's colours to the reference view's: the median ratio
/// over `pairs` of (reference, view) samples of the same texels; 1 where too few overlap.
fn exposure_gain(pairs: impl Iterator<Item = (Option<[u8; 3]>, Option<[u8; 3]>)>) -> [f32; 3] {
    let mut ratios: [Vec<f32>; 3] = Default::default();
    for (reference, view) in pairs {
        let (Some(r), Some(v)) = (reference, view) else {
            continue;
        };
        for ch in 0..3 {
            if r[ch] >= MIN_GAIN_LEVEL && v[ch] >= MIN_GAIN_LEVEL {
                ratios[ch].push(f32::from(r[ch]) / f32::from(v[ch]));
            }
        }
    }
    ratios.map(|mut r| {
        if r.len() < MIN_GAIN_SAMPLES {
            return 1.0;
        }
        r.sort_by(f32::total_cmp);
        r[r.len() / 2]
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A camera 1.5 m in front of a front facing -y through the origin, looking at it square.
    pub(crate) fn square_view(frame: usize, at_right: f32) -> View {
        // Camera axes: x right (world +x), y down (world -z), z forward (world +y).
        let rotation = glam::Mat3::from_cols(Vec3::X, Vec3::NEG_Z, Vec3::Y);
        View {
            frame,
            world_from_camera: Affine3A::from_mat3_translation(
                rotation,
                Vec3::new(at_right, -1.5, 0.5),
            ),
        }
    }

    /// What `view` sees of a front plane y = 0 painted by `paint(x, z)`, nothing else in the room.
    pub(crate) fn render_front(
        camera: &Pinhole,
        view: &View,
        paint: impl Fn(f32, f32) -> [u8; 3],
    ) -> ViewImages {
        let n = camera.pixel_count();
        let mut images = ViewImages {
            color: vec![0; 3 * n],
            depth: vec![0.0; n],
        };
        let origin = Vec3::from(view.world_from_camera.translation);
        for v in 0..camera.height {
            for u in 0..camera.width {
                let ray = view
                    .world_from_camera
                    .transform_vector3(camera.unproject(u as f32, v as f32, 1.0));
                let t = -origin.y / ray.y;
                if t <= 0.0 {
                    continue;
                }
                let hit = origin + ray * t;
                let pixel = (v * camera.width + u) as usize;
                images.depth[pixel] = t;
                images.color[3 * pixel..3 * pixel + 3].copy_from_slice(&paint(hit.x, hit.z));
            }
        }
        images
    }

    #[test]
    fn a_front_is_baked_from_the_frame_that_sees_it_best_and_never_through_what_stands_before_it() {
        let camera = Pinhole::KINECT;
        let front = Front::new(Vec3::ZERO, Vec3::NEG_Y).expect("a front");
        let rect = FrontRect {
            front,
            right: [-0.6, 0.6],
            z: [0.1, 0.9],
        };
        // A red front with a silver bar at x in 0.1..0.3, z in 0.8..0.81 (facing -y, the front's
        // right is +x).
        let paint = |x: f32, z: f32| {
            if (0.1..0.3).contains(&x) && (0.8..0.81).contains(&z) {
                [200, 200, 205]
            } else {
                [150, 20, 25]
            }
        };
        let views = [
            square_view(0, 0.0),
            square_view(1, 0.1),
            square_view(2, 3.0),
        ];
        let chosen = best_views(&rect, &camera, &views);
        // The third stands 3 m to the side, seeing little of the front.
        assert_eq!(chosen.len(), 1, "{chosen:?}");
        let mut images = render_front(&camera, &chosen[0], paint);
        // Something 40 cm before the front hides its left part in this frame.
        for v in 0..camera.height as usize {
            for u in 0..200 {
                images.depth[v * camera.width as usize + u] = 1.1;
            }
        }
        let texture = bake(&rect, &camera, &[(chosen[0], images)]);
        assert_eq!((texture.width, texture.height), (400, 267));
        let at = |x: f32, z: f32| {
            let right = front.local(Vec3::new(x, 0.0, z)).x;
            let column = ((right - rect.right[0]) / TEXEL_M) as usize;
            let row = ((rect.z[1] - z) / TEXEL_M) as usize;
            texture.get(column, row)
        };
        assert_eq!(at(0.2, 0.805), Some([200, 200, 205]));
        assert_eq!(at(0.0, 0.5), Some([150, 20, 25]));
        // The hidden part: u < 200 is x < -0.34 at 1.5 m.
        assert_eq!(at(-0.5, 0.5), None);
        assert!(
            (0.7..0.95).contains(&texture.coverage()),
            "{}",
            texture.coverage()
        );
    }
}
