//! The room's layout for a segmenter that knows no floor or wall class (COCO and PASCAL-VOC have
//! neither): a survey of a sample of the sequence's depth frames finds the up direction, the
//! floor's height and the walls (large vertical planes with nothing measured behind them), and
//! every frame's pixels on them are labelled floor or wall.

use glam::{Affine3A, Vec3};
use rayon::prelude::*;

use crate::error::InputError;
use crate::geometry::plane::fit_plane;
use crate::geometry::{Plane, TriMesh};
use crate::graph::gravity::{camera_up_hint, estimate_up};
use crate::io::Sequence;
use crate::segmentation::onnx::depth_surface::{Surfel, depth_grid_mesh, depth_patches};

/// Parts of one plane this close along it (metres) are one wall: the far ends of a long wall
/// that its first band left out, on either side of a door frame or a pillar's shadow.
const WALL_GAP_M: f32 = 0.3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayoutParams {
    /// Frames surveyed: about this many, evenly spread over the sequence.
    pub survey_frames: usize,
    /// Pixels sampled every this many in each direction.
    pub stride: usize,
    /// Surface elements are planes fitted to square patches of this many samples a side.
    pub patch: usize,
    /// A surface within this angle (degrees) of horizontal or vertical counts as such.
    pub orientation_tolerance_deg: f32,
    /// Height-histogram bin and plane-binning step (metres).
    pub bin: f32,
    /// Pixels this close (metres) to the floor or a wall are labelled with it.
    pub label_distance: f32,
    /// A wall has at least this share of the surveyed vertical area...
    pub min_wall_share: f32,
    /// ...spans at least this much along it and this much in height (metres)...
    pub min_wall_length: f32,
    pub min_wall_height: f32,
    /// ...and at most this share of the surveyed points lie more than `behind` metres behind it.
    pub max_behind_share: f32,
    pub behind: f32,
}

impl Default for LayoutParams {
    fn default() -> Self {
        Self {
            survey_frames: 60,
            stride: 4,
            patch: 8,
            orientation_tolerance_deg: 10.0,
            bin: 0.04,
            label_distance: 0.05,
            min_wall_share: 0.02,
            min_wall_length: 1.0,
            min_wall_height: 0.5,
            max_behind_share: 0.005,
            behind: 0.15,
        }
    }
}

/// A wall: its plane (normal into the room) and its surveyed extent, along the wall (horizontal
/// coordinate on `along`) and in height above the floor.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    pub plane: Plane,
    pub along: Vec3,
    pub span: [f32; 2],
    pub heights: [f32; 2],
}

/// What the survey found, in the sequence's world frame.
#[derive(Clone, Debug, PartialEq)]
pub struct RoomLayout {
    pub up: Vec3,
    /// Height of the floor along `up`; `None` when no floor was seen.
    pub floor_height: Option<f32>,
    pub walls: Vec<Wall>,
    pub params: LayoutParams,
}

/// What a pixel of the layout is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LayoutLabel {
    Floor,
    Wall(usize),
}

impl RoomLayout {
    /// Surveys `sequence`: the up direction is its gravity file's when it has one, else estimated
    /// from the horizontal surfaces seen.
    pub fn survey(sequence: &Sequence, params: LayoutParams) -> Result<Self, InputError> {
        let n = sequence.frames.len();
        let step = n.div_ceil(params.survey_frames.max(1)).max(1);
        let surveyed: Vec<(TriMesh, Vec<Surfel>)> = (0..n)
            .step_by(step)
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|i| {
                let frame = sequence.load_frame(i)?;
                let (depth, camera, pose) = (&frame.depth, &frame.camera, &frame.world_from_camera);
                Ok((
                    depth_grid_mesh(depth, camera, pose, params.stride),
                    depth_patches(depth, camera, pose, params.stride, params.patch),
                ))
            })
            .collect::<Result<_, InputError>>()?;
        let mut mesh = TriMesh::default();
        let mut surfels = Vec::new();
        for (m, p) in &surveyed {
            mesh.append(m);
            surfels.extend_from_slice(p);
        }
        let cameras: Vec<Affine3A> = sequence
            .frames
            .iter()
            .map(|f| f.world_from_camera)
            .collect();
        let up = match sequence.gravity.and_then(|g| (-g).try_normalize()) {
            Some(up) => up,
            None => camera_up_hint(cameras.iter().copied())
                .and_then(|hint| estimate_up(&mesh, hint))
                .map_or(Vec3::Z, |rough| refine_up(&mesh, rough, &params)),
        };
        let camera_centre = cameras
            .iter()
            .map(|c| Vec3::from(c.translation))
            .sum::<Vec3>()
            / cameras.len().max(1) as f32;
        Ok(Self::from_surfels(
            &surfels,
            &mesh.positions,
            up,
            camera_centre,
            params,
        ))
    }

    /// The floor and walls of a surface mesh with a known up direction, seen from around
    /// `camera_centre`, its triangles taken as surface elements.
    pub fn from_mesh(mesh: &TriMesh, up: Vec3, camera_centre: Vec3, params: LayoutParams) -> Self {
        let faces: Vec<Surfel> = (0..mesh.triangles.len())
            .filter_map(|t| {
                let [a, b, c] = mesh.triangle(t);
                let cross = (b - a).cross(c - a);
                let n = cross.try_normalize()?;
                Some(((a + b + c) / 3.0, n, 0.5 * cross.length()))
            })
            .collect();
        Self::from_surfels(&faces, &mesh.positions, up, camera_centre, params)
    }

    /// The floor and walls of surface elements with a known up direction, seen from around
    /// `camera_centre`; `points` are every surface point surveyed (what may lie behind a wall).
    pub fn from_surfels(
        faces: &[Surfel],
        points: &[Vec3],
        up: Vec3,
        camera_centre: Vec3,
        params: LayoutParams,
    ) -> Self {
        let sin_tol = params.orientation_tolerance_deg.to_radians().sin();
        let cos_tol = params.orientation_tolerance_deg.to_radians().cos();
        let horizontal: Vec<(f32, f32)> = faces
            .iter()
            .filter(|(_, n, _)| n.dot(up).abs() >= cos_tol)
            .map(|(c, _, a)| (c.dot(up), *a))
            .collect();
        let floor_height = lowest_surface(&horizontal, params.bin);
        let vertical: Vec<(Vec3, Vec3, f32)> = faces
            .iter()
            .filter(|(_, n, _)| n.dot(up).abs() <= sin_tol)
            .map(|&(c, n, a)| (c, (n - up * n.dot(up)).normalize(), a))
            .collect();
        let walls = find_walls(
            &vertical,
            points,
            up,
            floor_height.unwrap_or(0.0),
            camera_centre,
            &params,
        );
        Self {
            up,
            floor_height,
            walls,
            params,
        }
    }

    /// What `point` (world frame) is part of, if it is on the floor or a wall.
    pub fn label(&self, point: Vec3) -> Option<LayoutLabel> {
        let d = self.params.label_distance;
        let floor = self.floor_height?;
        let height = point.dot(self.up) - floor;
        if height.abs() <= d {
            return Some(LayoutLabel::Floor);
        }
        self.walls
            .iter()
            .position(|w| {
                let along = point.dot(w.along);
                w.plane.signed_distance(point).abs() <= d
                    && along >= w.span[0] - d
                    && along <= w.span[1] + d
                    && height >= w.heights[0] - d
                    && height <= w.heights[1] + d
            })
            .map(LayoutLabel::Wall)
    }
}

/// The up direction from least-squares planes through the large horizontal surfaces near
/// `rough` (floor, table tops, counters). Depth quantisation makes a depth image's small
/// triangles stair-stepped towards the camera, which biases their mean normal by degrees; a plane
/// through thousands of points of a surface averages the steps out.
fn refine_up(mesh: &TriMesh, rough: Vec3, params: &LayoutParams) -> Vec3 {
    let cos_tol = params.orientation_tolerance_deg.to_radians().cos();
    let faces: Vec<(Vec3, f32)> = (0..mesh.triangles.len())
        .filter_map(|t| {
            let [a, b, c] = mesh.triangle(t);
            let cross = (b - a).cross(c - a);
            let n = cross.try_normalize()?;
            (n.dot(rough).abs() >= cos_tol).then(|| ((a + b + c) / 3.0, 0.5 * cross.length()))
        })
        .collect();
    let mut up = rough;
    // Each round's planes tilt the heights less, so a surface fits its window better.
    for _ in 0..3 {
        let heights: Vec<(f32, f32)> = faces.iter().map(|(c, a)| (c.dot(up), *a)).collect();
        let peaks = surface_heights(&heights, params.bin, 0.2);
        let mut sum = Vec3::ZERO;
        for h in peaks {
            let (points, area): (Vec<Vec3>, f32) = faces
                .iter()
                .filter(|(c, _)| (c.dot(up) - h).abs() <= 1.5 * params.bin)
                .fold((Vec::new(), 0.0), |(mut p, a), (c, w)| {
                    p.push(*c);
                    (p, a + w)
                });
            if let Some(plane) = fit_plane(&points) {
                let n = if plane.normal.dot(up) < 0.0 {
                    -plane.normal
                } else {
                    plane.normal
                };
                sum += n * area;
            }
        }
        match sum.try_normalize() {
            Some(n) => up = n,
            None => break,
        }
    }
    up
}

/// Smoothed area per height bin of `bin` metres over (height, area) pairs, from the lowest
/// height: each bin summed with its neighbours, so a surface split over two bins counts once.
fn height_histogram(heights_areas: &[(f32, f32)], bin: f32) -> Option<(f32, Vec<f32>)> {
    let lo = heights_areas
        .iter()
        .map(|h| h.0)
        .fold(f32::INFINITY, f32::min);
    if !lo.is_finite() {
        return None;
    }
    let mut bins: Vec<f32> = Vec::new();
    for &(h, a) in heights_areas {
        let i = ((h - lo) / bin) as usize;
        if bins.len() <= i {
            bins.resize(i + 1, 0.0);
        }
        bins[i] += a;
    }
    let smoothed = (0..bins.len())
        .map(|i| {
            bins[i.saturating_sub(1)..(i + 2).min(bins.len())]
                .iter()
                .sum()
        })
        .collect();
    Some((lo, smoothed))
}

/// The area-weighted mean height of the faces within a bin and a half of `centre`.
fn mean_height_near(heights_areas: &[(f32, f32)], centre: f32, bin: f32) -> Option<f32> {
    let (sum, weight) = heights_areas
        .iter()
        .filter(|(h, _)| (h - centre).abs() <= 1.5 * bin)
        .fold((0.0, 0.0), |(s, w), (h, a)| (s + h * a, w + a));
    (weight > 0.0).then(|| sum / weight)
}

/// The heights of the horizontal surfaces with at least `share` of the largest one's area: the
/// local maxima of the height histogram.
fn surface_heights(heights_areas: &[(f32, f32)], bin: f32, share: f32) -> Vec<f32> {
    let Some((lo, smoothed)) = height_histogram(heights_areas, bin) else {
        return Vec::new();
    };
    let largest = smoothed.iter().copied().fold(0.0, f32::max);
    (0..smoothed.len())
        .filter(|&i| {
            let a = smoothed[i];
            a >= share * largest
                && (i == 0 || smoothed[i - 1] < a)
                && (i + 1 == smoothed.len() || smoothed[i + 1] <= a)
        })
        .filter_map(|i| mean_height_near(heights_areas, lo + (i as f32 + 0.5) * bin, bin))
        .collect()
}

/// The height of the lowest horizontal surface with a substantial share of the horizontal area:
/// the floor (reflections and noise below it are small; table tops above it are higher).
fn lowest_surface(heights_areas: &[(f32, f32)], bin: f32) -> Option<f32> {
    let (lo, smoothed) = height_histogram(heights_areas, bin)?;
    let largest = smoothed.iter().copied().fold(0.0, f32::max);
    let first = smoothed.iter().position(|&a| a >= 0.2 * largest)?;
    mean_height_near(heights_areas, lo + (first as f32 + 0.5) * bin, bin)
}

/// Walls among the vertical faces (centre, horizontal unit normal, area): repeatedly the plane
/// carrying the most area (binned by direction and offset, then refitted), kept when it is long,
/// tall and has almost nothing of `points` behind it (a cabinet front has the wall behind it).
fn find_walls(
    vertical: &[Surfel],
    points: &[Vec3],
    up: Vec3,
    floor_height: f32,
    camera_centre: Vec3,
    params: &LayoutParams,
) -> Vec<Wall> {
    let total: f32 = vertical.iter().map(|f| f.2).sum();
    let (east, north) = up.any_orthonormal_pair();
    let angle_bins = 72; // 5 degrees over a half turn: a plane and its flip share a bin.
    let key = |c: Vec3, n: Vec3| {
        // Normals turned into one half-plane so the two sides of a wall bin together.
        let mut a = n.dot(north).atan2(n.dot(east));
        let mut n = n;
        if a < 0.0 {
            a += std::f32::consts::PI;
            n = -n;
        }
        let ai = ((a / std::f32::consts::PI * angle_bins as f32) as i32).min(angle_bins - 1);
        (ai, (n.dot(c) / params.bin).floor() as i32)
    };
    let mut remaining: Vec<bool> = vec![true; vertical.len()];
    let mut walls: Vec<Wall> = Vec::new();
    for _ in 0..12 {
        let mut bins: std::collections::BTreeMap<(i32, i32), f32> = Default::default();
        for (f, _) in vertical.iter().zip(&remaining).filter(|(_, r)| **r) {
            *bins.entry(key(f.0, f.1)).or_default() += f.2;
        }
        // The heaviest bin with its neighbours in offset (a wall's noise spreads over two).
        let Some((&(ai, di), _)) = bins
            .keys()
            .map(|k| {
                let around: f32 = (-1..=1).filter_map(|o| bins.get(&(k.0, k.1 + o))).sum();
                (k, around)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(a.0)))
        else {
            break;
        };
        let angle = (ai as f32 + 0.5) / angle_bins as f32 * std::f32::consts::PI;
        let n0 = east * angle.cos() + north * angle.sin();
        let d0 = (di as f32 + 0.5) * params.bin;
        let cos_tol = params.orientation_tolerance_deg.to_radians().cos();
        let members: Vec<usize> = (0..vertical.len())
            .filter(|&i| {
                let (c, n, _) = vertical[i];
                remaining[i]
                    && n.dot(n0).abs() >= cos_tol
                    && (n0.dot(c) - d0).abs() <= 1.5 * params.bin
            })
            .collect();
        let area: f32 = members.iter().map(|&i| vertical[i].2).sum();
        if area < params.min_wall_share * total || members.is_empty() {
            break;
        }
        for &i in &members {
            remaining[i] = false;
        }
        // Refit: the area-weighted offset along the bin's normal.
        let d = members
            .iter()
            .map(|&i| n0.dot(vertical[i].0) * vertical[i].2)
            .sum::<f32>()
            / area;
        let mut plane = Plane {
            normal: n0,
            offset: -d,
        };
        if plane.signed_distance(camera_centre) < 0.0 {
            plane = Plane {
                normal: -n0,
                offset: d,
            };
        }
        let along = up.cross(plane.normal).normalize();
        let extent = |along: Vec3| {
            let (mut span, mut heights) = ([f32::MAX, f32::MIN], [f32::MAX, f32::MIN]);
            for &i in &members {
                let c = vertical[i].0;
                let (s, h) = (c.dot(along), c.dot(up) - floor_height);
                span = [span[0].min(s), span[1].max(s)];
                heights = [heights[0].min(h), heights[1].max(h)];
            }
            (span, heights)
        };
        // A parallel candidate within `behind` of a found wall and beside it is more of it,
        // whatever its length: it extends the wall. The bin's normal is up to 1.25 degrees off
        // the wall's, which along a long wall walks its far ends out of the band, and on real
        // sequences a wall is a fan of planes (redkitchen's backsplash comes out of single
        // frames up to 2.3 degrees and 5 cm apart: pose and depth calibration errors). Refitting
        // the normal to the members instead moved redkitchen's wall by 2 degrees (a line
        // through the patches' centres) or 3 (their mean normal) and changed its segments.
        let centroid = members
            .iter()
            .map(|&i| vertical[i].0 * vertical[i].2)
            .sum::<Vec3>()
            / area;
        if let Some(wall) = walls.iter_mut().find(|w| {
            let (span, _) = extent(w.along);
            w.plane.normal.dot(plane.normal) >= cos_tol
                && w.plane.signed_distance(centroid).abs() <= params.behind
                && span[0] <= w.span[1] + WALL_GAP_M
                && span[1] >= w.span[0] - WALL_GAP_M
        }) {
            let (span, heights) = extent(wall.along);
            wall.span = [wall.span[0].min(span[0]), wall.span[1].max(span[1])];
            wall.heights = [
                wall.heights[0].min(heights[0]),
                wall.heights[1].max(heights[1]),
            ];
            continue;
        }
        let (span, heights) = extent(along);
        if span[1] - span[0] < params.min_wall_length
            || heights[1] - heights[0] < params.min_wall_height
        {
            continue;
        }
        let (behind, beside) = points
            .iter()
            .filter(|p| (span[0]..=span[1]).contains(&p.dot(along)))
            .fold((0usize, 0usize), |(b, n), p| {
                (
                    b + usize::from(plane.signed_distance(*p) < -params.behind),
                    n + 1,
                )
            });
        if (behind as f32) <= params.max_behind_share * beside as f32 {
            walls.push(Wall {
                plane,
                along,
                span,
                heights,
            });
        }
    }
    walls
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box room 4 x 3 m, 2.5 m high, tilted, with a cabinet (a box against the +y wall) and a
    /// table top, seen from the middle.
    fn room() -> (TriMesh, Vec3, glam::Quat) {
        let tilt = glam::Quat::from_rotation_x(0.3) * glam::Quat::from_rotation_y(0.2);
        let mut mesh = TriMesh::default();
        // Floor, walls and ceiling as thin slabs (a camera sees only their inner faces; the slabs'
        // outer faces are what a survey would see through a window, which the test keeps away
        // by making them thin).
        for (lo, hi) in [
            (Vec3::new(0.0, 0.0, -0.01), Vec3::new(4.0, 3.0, 0.0)),
            (Vec3::new(-0.01, 0.0, 0.0), Vec3::new(0.0, 3.0, 2.5)),
            (Vec3::new(4.0, 0.0, 0.0), Vec3::new(4.01, 3.0, 2.5)),
            (Vec3::new(0.0, -0.01, 0.0), Vec3::new(4.0, 0.0, 2.5)),
            (Vec3::new(0.0, 3.0, 0.0), Vec3::new(4.0, 3.01, 2.5)),
            (Vec3::new(0.5, 2.4, 0.0), Vec3::new(2.5, 3.0, 0.9)),
            (Vec3::new(1.0, 0.5, 0.72), Vec3::new(2.2, 1.3, 0.75)),
        ] {
            mesh.append(&subdivided(&TriMesh::cuboid(lo, hi), 0.15));
        }
        (
            mesh.transformed(&Affine3A::from_quat(tilt)),
            tilt * Vec3::Z,
            tilt,
        )
    }

    /// Splits every triangle into four at its edge midpoints until no edge is longer than
    /// `max_edge`, so a box has vertices all over its faces.
    fn subdivided(mesh: &TriMesh, max_edge: f32) -> TriMesh {
        let mut out = TriMesh::default();
        let mut stack: Vec<[Vec3; 3]> = (0..mesh.triangles.len())
            .map(|t| mesh.triangle(t))
            .collect();
        while let Some([a, b, c]) = stack.pop() {
            if a.distance(b).max(b.distance(c)).max(c.distance(a)) <= max_edge {
                let base = out.positions.len() as u32;
                out.positions.extend([a, b, c]);
                out.triangles.push([base, base + 1, base + 2]);
                continue;
            }
            let (ab, bc, ca) = ((a + b) / 2.0, (b + c) / 2.0, (c + a) / 2.0);
            stack.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        out
    }

    #[test]
    fn the_floor_and_four_walls_are_found_and_the_cabinet_front_is_not_a_wall() {
        let (mesh, up, tilt) = room();
        let centre = tilt * Vec3::new(2.0, 1.5, 1.2);
        let layout = RoomLayout::from_mesh(&mesh, up, centre, LayoutParams::default());
        let floor = layout.floor_height.expect("a floor");
        assert!(floor.abs() < 0.01, "floor at {floor}");
        assert_eq!(layout.walls.len(), 4, "{:?}", layout.walls);
        for w in &layout.walls {
            assert!(
                w.plane.signed_distance(centre) > 1.0,
                "normals face the room"
            );
        }
        let at = |p: Vec3| layout.label(tilt * p);
        assert_eq!(at(Vec3::new(3.0, 2.0, 0.01)), Some(LayoutLabel::Floor));
        assert!(matches!(
            at(Vec3::new(0.0, 1.0, 1.5)),
            Some(LayoutLabel::Wall(_))
        ));
        // The cabinet's front (y = 2.4) and the table top are neither.
        assert_eq!(at(Vec3::new(1.5, 2.4, 0.5)), None);
        assert_eq!(at(Vec3::new(1.5, 0.9, 0.75)), None);
    }

    #[test]
    fn a_long_wall_off_its_direction_bins_centre_is_one_wall_over_its_whole_length() {
        // A wall 6 m long and 2.5 m high whose normal is 1.2 degrees off its direction bin's
        // centre (the most is 1.25) and whose offset is 1.9 cm off its offset bin's: the band of
        // +-6 cm about the bin's plane holds only 3 to 4 m of it, and the rest came back as a
        // second wall. Patch normals jitter by up to 2 degrees, as real ones do, and spread
        // over neighbouring bins.
        let up = Vec3::Z;
        let (east, north) = up.any_orthonormal_pair();
        let angle = (10.5f32 * 2.5 + 1.2).to_radians();
        let normal = east * angle.cos() + north * angle.sin();
        let along = up.cross(normal);
        let offset = 2.039;
        let mut surfels = Vec::new();
        let mut jitter = 0u32;
        for i in 0..60 {
            for j in 0..25 {
                let s = -1.0 + 0.1 * i as f32 + 0.05;
                let h = 0.1 * j as f32 + 0.05;
                // A deterministic spread in (-2, 2) degrees about the vertical axis.
                jitter = jitter.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let turn = (jitter >> 8) as f32 / (1 << 24) as f32 * 4.0 - 2.0;
                let n = glam::Quat::from_axis_angle(up, turn.to_radians()) * normal;
                surfels.push((normal * offset + along * s + up * h, n, 0.01));
            }
        }
        // The floor in front of the wall, 4 m deep.
        for i in 0..60 {
            for k in 0..40 {
                let s = -1.0 + 0.1 * i as f32 + 0.05;
                let t = offset - 0.1 * k as f32 - 0.05;
                surfels.push((normal * t + along * s, up, 0.01));
            }
        }
        let points: Vec<Vec3> = surfels.iter().map(|f| f.0).collect();
        let camera = normal * (offset - 2.0) + along * 2.0 + up * 1.5;
        let layout =
            RoomLayout::from_surfels(&surfels, &points, up, camera, LayoutParams::default());
        assert_eq!(layout.walls.len(), 1, "{:?}", layout.walls);
        let wall = &layout.walls[0];
        assert!(
            wall.span[1] - wall.span[0] > 5.8,
            "the wall spans {:?} of its 6 m",
            wall.span
        );
        let error = wall.plane.normal.dot(-normal).acos().to_degrees();
        assert!(error < 1.3, "its normal is {error} degrees off");
        assert!((wall.plane.signed_distance(Vec3::ZERO) - offset).abs() < 0.03);
    }
}
