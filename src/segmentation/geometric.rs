//! Per-frame geometric segmentation of a depth image (Tateno et al.'s convexity criterion, as in
//! Voxblox++): pixels are cut apart at depth jumps and at concave creases between their normals;
//! what stays connected is a segment. Convex creases (a box's outer edges) do not cut.

use glam::Vec3;
use rayon::prelude::*;

use crate::geometry::Pinhole;

#[derive(Clone, Copy, Debug)]
pub struct GeometricParams {
    /// Normals from neighbours this many pixels away on each side (wider = less noise).
    pub normal_step: usize,
    /// A depth jump between neighbours cuts when it exceeds `jump_base + jump_quadratic * z^2`
    /// metres: depth noise and quantisation of structured-light sensors grow with z^2.
    pub jump_base: f32,
    pub jump_quadratic: f32,
    /// Depth is averaged over a window of this radius (pixels) before normals are taken.
    pub smoothing_radius: usize,
    /// A concave crease cuts when the cosine between the two normals is below this.
    pub concave_cos: f32,
    /// Connected components smaller than this (pixels) stay unsegmented.
    pub min_pixels: u32,
}

impl Default for GeometricParams {
    fn default() -> Self {
        Self {
            normal_step: 3,
            jump_base: 0.015,
            jump_quadratic: 0.012,
            smoothing_radius: 3,
            concave_cos: 0.75,
            min_pixels: 150,
        }
    }
}

/// One frame's geometric segments: per-pixel ids `1..=count` (0 = none), in scan order of their
/// first pixel, so the result is deterministic.
#[derive(Clone, Debug)]
pub struct GeometricSegmentation {
    pub segment_of_pixel: Vec<u32>,
    pub count: u32,
    /// Camera-frame point of every pixel (zero where there is no depth).
    pub points: Vec<Vec3>,
}

pub fn segment_depth(
    depth: &[f32],
    camera: &Pinhole,
    params: &GeometricParams,
) -> GeometricSegmentation {
    let (w, h) = (camera.width as usize, camera.height as usize);
    let jump = DepthJump::new(params);
    // Noise and the sensor's depth steps make raw normals useless a few metres out: normals come
    // from depth averaged over a window, across no depth jump.
    let smoothed = smooth_depth(depth, w, h, params.smoothing_radius, &jump);
    let points = unproject_image(depth, camera);
    let smooth_points = unproject_image(&smoothed, camera);
    let normals = pixel_normals(depth, &points, &smooth_points, w, params.normal_step, &jump);
    let edge = concave_edges(&normals, &smooth_points, w, 2 * params.normal_step, params);
    let (segment_of_pixel, count) = connected_segments(depth, &edge, w, h, &jump, params);
    GeometricSegmentation {
        segment_of_pixel,
        count,
        points,
    }
}

/// Whether two neighbouring depths lie on either side of a depth jump.
struct DepthJump {
    base: f32,
    quadratic: f32,
}

impl DepthJump {
    fn new(params: &GeometricParams) -> Self {
        Self {
            base: params.jump_base,
            quadratic: params.jump_quadratic,
        }
    }

    #[inline(always)]
    fn cuts(&self, a: f32, b: f32) -> bool {
        // Not `f32::min`, whose NaN rule keeps the loops over rows from vectorising; with a NaN
        // the difference below is NaN and nothing cuts either way.
        let z = if a < b { a } else { b };
        (a - b).abs() > self.base + self.quadratic * z * z
    }
}

/// Mean depth over a `(2r+1)^2` window of the neighbours on the pixel's side of every depth
/// jump; 0 where the pixel has no depth. Row by row, and for each window offset a whole row at
/// once, so that the inner loop has no branch and vectorises: the sum of each pixel still adds its
/// neighbours in the same order (rows, then columns), so the result is the scalar loop's to the bit.
fn smooth_depth(depth: &[f32], w: usize, h: usize, r: usize, jump: &DepthJump) -> Vec<f32> {
    let mut smoothed = vec![0.0f32; w * h];
    smoothed
        .par_chunks_mut(w)
        .enumerate()
        .for_each(|(v, out)| smooth_row(depth, w, h, v, r, jump, out));
    smoothed
}

#[inline(never)]
fn smooth_row(
    depth: &[f32],
    w: usize,
    h: usize,
    v: usize,
    r: usize,
    jump: &DepthJump,
    out: &mut [f32],
) {
    let row = &depth[v * w..(v + 1) * w];
    let mut sum = vec![0.0f32; w];
    let mut count = vec![0.0f32; w];
    for y in v.saturating_sub(r)..=(v + r).min(h - 1) {
        let other = &depth[y * w..(y + 1) * w];
        for dx in -(r as isize)..=r as isize {
            // Pixels u whose neighbour u + dx lies inside the row.
            let u0 = (-dx).max(0) as usize;
            let u1 = (w as isize - dx.max(0)) as usize;
            if u0 >= u1 {
                continue;
            }
            let n = u1 - u0;
            let centre = &row[u0..u1];
            let shifted = &other[(u0 as isize + dx) as usize..][..n];
            let sum = &mut sum[u0..u1];
            let count = &mut count[u0..u1];
            for k in 0..n {
                let (d, e) = (centre[k], shifted[k]);
                // `&`, not `&&`: no branch, so the loop vectorises.
                let keep = (e > 0.0) & !jump.cuts(d, e);
                sum[k] += if keep { e } else { 0.0 };
                count[k] += if keep { 1.0 } else { 0.0 };
            }
        }
    }
    for (((o, &d), &s), &c) in out.iter_mut().zip(row).zip(&sum).zip(&count) {
        *o = if d > 0.0 { s / c } else { 0.0 };
    }
}

/// Camera-frame point of every pixel; zero where there is no depth. The ray of each column and
/// row is computed once.
fn unproject_image(depth: &[f32], camera: &Pinhole) -> Vec<Vec3> {
    let w = camera.width as usize;
    let ray_x: Vec<f32> = (0..w).map(|u| (u as f32 - camera.cx) / camera.fx).collect();
    let mut points = vec![Vec3::ZERO; depth.len()];
    points
        .par_chunks_mut(w)
        .zip(depth.par_chunks(w))
        .enumerate()
        .for_each(|(v, (out, row))| {
            let ray_y = (v as f32 - camera.cy) / camera.fy;
            for ((p, &d), &rx) in out.iter_mut().zip(row).zip(&ray_x) {
                if d > 0.0 {
                    *p = Vec3::new(rx * d, ray_y * d, d);
                }
            }
        });
    points
}

/// Normals towards the camera from the smoothed points `s` pixels away on each side; zero where
/// a neighbour is missing or across a depth jump.
fn pixel_normals(
    depth: &[f32],
    points: &[Vec3],
    smooth_points: &[Vec3],
    w: usize,
    s: usize,
    jump: &DepthJump,
) -> Vec<Vec3> {
    let h = depth.len() / w;
    let mut normals = vec![Vec3::ZERO; depth.len()];
    normals.par_chunks_mut(w).enumerate().for_each(|(v, out)| {
        if v < s || v + s >= h || w <= 2 * s {
            return;
        }
        for (u, normal) in out.iter_mut().enumerate().take(w - s).skip(s) {
            let i = v * w + u;
            let d = depth[i];
            if d <= 0.0 {
                continue;
            }
            let neighbours = [i - s, i + s, i - s * w, i + s * w];
            if neighbours
                .iter()
                .any(|&j| depth[j] <= 0.0 || jump.cuts(d, depth[j]))
            {
                continue;
            }
            let du = smooth_points[i + s] - smooth_points[i - s];
            let dv = smooth_points[i + s * w] - smooth_points[i - s * w];
            let n = dv.cross(du).normalize_or_zero();
            *normal = if n.dot(points[i]) > 0.0 { -n } else { n };
        }
    });
    normals
}

/// Pixels without a normal or on a concave crease. A crease blurs the normals computed across
/// it, so neighbours at `far` = 2 * step (whose normal baselines do not overlap) decide.
fn concave_edges(
    normals: &[Vec3],
    smooth_points: &[Vec3],
    w: usize,
    far: usize,
    params: &GeometricParams,
) -> Vec<bool> {
    let h = normals.len() / w;
    let mut edge = vec![true; normals.len()];
    edge.par_chunks_mut(w).enumerate().for_each(|(v, out)| {
        for (u, e) in out.iter_mut().enumerate() {
            let i = v * w + u;
            let ni = normals[i];
            if ni == Vec3::ZERO {
                continue;
            }
            let neighbours = [
                (u >= far).then(|| i - far),
                (u + far < w).then(|| i + far),
                (v >= far).then(|| i - far * w),
                (v + far < h).then(|| i + far * w),
            ];
            *e = neighbours.into_iter().flatten().any(|j| {
                let nj = normals[j];
                // Concave when the surface bends towards the camera between the two points.
                nj != Vec3::ZERO
                    && ni.dot(nj) < params.concave_cos
                    && (smooth_points[j] - smooth_points[i]).dot(nj - ni) < 0.0
            });
        }
    });
    edge
}

/// Connected components of the non-edge pixels across no depth jump, numbered `1..=count` in
/// scan order of their first pixel; components under `min_pixels` get 0.
fn connected_segments(
    depth: &[f32],
    edge: &[bool],
    w: usize,
    h: usize,
    jump: &DepthJump,
    params: &GeometricParams,
) -> (Vec<u32>, u32) {
    let mut parent: Vec<u32> = (0..(w * h) as u32).collect();
    for v in 0..h {
        for u in 0..w {
            let i = v * w + u;
            if edge[i] {
                continue;
            }
            if u + 1 < w && !edge[i + 1] && !jump.cuts(depth[i], depth[i + 1]) {
                union(&mut parent, i as u32, (i + 1) as u32);
            }
            if v + 1 < h && !edge[i + w] && !jump.cuts(depth[i], depth[i + w]) {
                union(&mut parent, i as u32, (i + w) as u32);
            }
        }
    }
    let roots: Vec<u32> = (0..(w * h) as u32).map(|i| find(&mut parent, i)).collect();
    let mut size = vec![0u32; w * h];
    for (i, &r) in roots.iter().enumerate() {
        if !edge[i] {
            size[r as usize] += 1;
        }
    }
    let mut id_of_root = vec![0u32; w * h];
    let mut count = 0;
    let segment_of_pixel = roots
        .iter()
        .enumerate()
        .map(|(i, &r)| {
            if edge[i] || size[r as usize] < params.min_pixels {
                return 0;
            }
            if id_of_root[r as usize] == 0 {
                count += 1;
                id_of_root[r as usize] = count;
            }
            id_of_root[r as usize]
        })
        .collect();
    (segment_of_pixel, count)
}

/// Union-find root with path halving.
pub fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let grandparent = parent[parent[i as usize] as usize];
        parent[i as usize] = grandparent;
        i = grandparent;
    }
    i
}

/// Joins the sets of `a` and `b`; the smaller root becomes the root, so results do not depend on
/// the order of unions.
pub fn union(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (find(parent, a), find(parent, b));
    if ra != rb {
        let (lo, hi) = (ra.min(rb), ra.max(rb));
        parent[hi as usize] = lo;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::trajectory::room_loop;
    use crate::scene::render_sequence::render_frame;
    use crate::scene::{SceneSpec, SceneWorld};

    /// The scalar per-pixel loops `segment_depth` replaced (smoothing, points, normals, creases),
    /// kept as the reference it must equal.
    fn reference_segment_depth(
        depth: &[f32],
        camera: &Pinhole,
        params: &GeometricParams,
    ) -> GeometricSegmentation {
        let (w, h) = (camera.width as usize, camera.height as usize);
        let jump = |a: f32, b: f32| {
            let z = a.min(b);
            (a - b).abs() > params.jump_base + params.jump_quadratic * z * z
        };
        // Noise and the sensor's depth steps make raw normals useless a few metres out: normals come
        // from depth averaged over a window, across no depth jump.
        let r = params.smoothing_radius as isize;
        let smoothed: Vec<f32> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let d = depth[i];
                if d <= 0.0 {
                    return 0.0;
                }
                let (u, v) = ((i % w) as isize, (i / w) as isize);
                let (mut sum, mut n) = (0.0, 0.0);
                for y in (v - r).max(0)..=(v + r).min(h as isize - 1) {
                    for x in (u - r).max(0)..=(u + r).min(w as isize - 1) {
                        let e = depth[y as usize * w + x as usize];
                        if e > 0.0 && !jump(d, e) {
                            sum += e;
                            n += 1.0;
                        }
                    }
                }
                sum / n
            })
            .collect();
        let unproject = |values: &[f32]| -> Vec<Vec3> {
            values
                .par_iter()
                .enumerate()
                .map(|(i, &d)| {
                    if d > 0.0 {
                        camera.unproject((i % w) as f32, (i / w) as f32, d)
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect()
        };
        let points = unproject(depth);
        let smooth_points = unproject(&smoothed);
        let s = params.normal_step;
        // Normals towards the camera; zero where a neighbour is missing or across a depth jump.
        let normals: Vec<Vec3> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let (u, v) = (i % w, i / w);
                if depth[i] <= 0.0 || u < s || v < s || u + s >= w || v + s >= h {
                    return Vec3::ZERO;
                }
                let neighbours = [i - s, i + s, i - s * w, i + s * w];
                if neighbours
                    .iter()
                    .any(|&j| depth[j] <= 0.0 || jump(depth[i], depth[j]))
                {
                    return Vec3::ZERO;
                }
                let du = smooth_points[i + s] - smooth_points[i - s];
                let dv = smooth_points[i + s * w] - smooth_points[i - s * w];
                let n = dv.cross(du).normalize_or_zero();
                if n.dot(points[i]) > 0.0 { -n } else { n }
            })
            .collect();
        // A crease blurs the normals computed across it, so neighbours at 2 * step (whose normal
        // baselines do not overlap) decide whether a pixel sits on a concave crease.
        let far = 2 * s;
        let edge: Vec<bool> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let ni = normals[i];
                if ni == Vec3::ZERO {
                    return true;
                }
                let (u, v) = (i % w, i / w);
                let mut neighbours = [None; 4];
                if u >= far {
                    neighbours[0] = Some(i - far);
                }
                if u + far < w {
                    neighbours[1] = Some(i + far);
                }
                if v >= far {
                    neighbours[2] = Some(i - far * w);
                }
                if v + far < h {
                    neighbours[3] = Some(i + far * w);
                }
                neighbours.into_iter().flatten().any(|j| {
                    let nj = normals[j];
                    // Concave when the surface bends towards the camera between the two points.
                    nj != Vec3::ZERO
                        && ni.dot(nj) < params.concave_cos
                        && (smooth_points[j] - smooth_points[i]).dot(nj - ni) < 0.0
                })
            })
            .collect();
        // The components were not rewritten: the reference shares them.
        let (segment_of_pixel, count) =
            connected_segments(depth, &edge, w, h, &DepthJump::new(params), params);
        GeometricSegmentation {
            segment_of_pixel,
            count,
            points,
        }
    }

    /// The row-wise segmentation gives the scalar reference's segments, points and ids to the bit,
    /// on a noisy rendered frame and on random depth full of holes and jumps.
    #[test]
    fn equals_the_scalar_reference() {
        let path = std::path::Path::new("kitchen.json");
        let spec = SceneSpec::parse(crate::BUILTIN_KITCHEN, path).expect("spec");
        let world = SceneWorld::from_spec(&spec, path).expect("world");
        let camera = Pinhole::KINECT;
        let poses = room_loop(world.room_size, 40, 1.45);
        let rendered = render_frame(
            &world.render_scene(),
            &camera,
            &poses[11],
            Some(&crate::render::noise::DepthNoise::KINECT),
            5,
            11,
        );
        let small = Pinhole {
            width: 97,
            height: 61,
            ..Pinhole::KINECT
        };
        let mut state = 12345u64;
        let mut random = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let noisy: Vec<f32> = (0..small.pixel_count())
            .map(|i| {
                let r = random();
                if r < 0.1 {
                    0.0
                } else {
                    1.0 + (i % 97 / 20) as f32 * 0.5 + r * 0.05
                }
            })
            .collect();
        let params = GeometricParams::default();
        for (depth, camera) in [(&rendered.depth, camera), (&noisy, small)] {
            let fast = segment_depth(depth, &camera, &params);
            let slow = reference_segment_depth(depth, &camera, &params);
            assert_eq!(fast.count, slow.count);
            assert_eq!(fast.segment_of_pixel, slow.segment_of_pixel);
            assert_eq!(fast.points, slow.points);
        }
    }

    /// On a rendered kitchen frame, most geometric segments lie on one object: the cut at
    /// concave creases and depth jumps separates objects from their supports and the walls.
    #[test]
    fn segments_rarely_straddle_two_objects() {
        let path = std::path::Path::new("kitchen.json");
        let spec = SceneSpec::parse(crate::BUILTIN_KITCHEN, path).expect("spec");
        let world = SceneWorld::from_spec(&spec, path).expect("world");
        let scene = world.render_scene();
        let camera = Pinhole::KINECT;
        let poses = room_loop(world.room_size, 40, 1.45);
        let mut pure = 0usize;
        let mut total = 0usize;
        for k in [3, 17, 29] {
            let f = render_frame(
                &scene,
                &camera,
                &poses[k],
                Some(&crate::render::noise::DepthNoise::KINECT),
                5,
                k,
            );
            let seg = segment_depth(&f.depth, &camera, &GeometricParams::default());
            assert!(seg.count >= 5, "only {} segments", seg.count);
            let valid = f.depth.iter().filter(|d| **d > 0.0).count();
            let covered = seg.segment_of_pixel.iter().filter(|s| **s != 0).count();
            assert!(
                covered as f64 > 0.7 * valid as f64,
                "{covered} of {valid} pixels segmented"
            );
            for id in 1..=seg.count {
                let mut counts = std::collections::BTreeMap::<u16, usize>::new();
                for (i, &s) in seg.segment_of_pixel.iter().enumerate() {
                    if s == id {
                        *counts.entry(f.labels[i]).or_default() += 1;
                    }
                }
                let n: usize = counts.values().sum();
                let best = counts.values().max().copied().unwrap_or(0);
                total += n;
                pure += best;
            }
        }
        let purity = pure as f64 / total as f64;
        assert!(
            purity > 0.93,
            "pixel purity of geometric segments {purity:.3}"
        );
    }
}
