//! Per-frame fusion of geometric segments with the panoptic masks of the segmentation service:
//! geometry gives the boundaries, masks give class and instance.
//!
//! 1. A geometric segment takes the mask it overlaps most, when that mask covers enough of it.
//! 2. A mask that lies inside a larger segment (the keyboard on the desk), or that covers a large
//!    part of a segment assigned to another mask, is cut out of it as a segment of its own.
//! 3. Pixels of a mask that no geometric segment holds (objects too small to segment, surfaces
//!    seen so obliquely that depth jumps cut every pixel apart) form one more segment of that mask.
//! 4. Per mask, segments that are not near each other in 3D are clustered and only the largest
//!    cluster keeps the mask (the floor seen through a chair is not the chair); the rest become
//!    background.

use std::collections::{BTreeMap, HashMap, HashSet};

use foldhash::fast::FixedState;
use glam::IVec3;

use crate::segmentation::PanopticFrame;
use crate::segmentation::geometric::{GeometricSegmentation, find, union};

#[derive(Clone, Copy, Debug)]
pub struct FusionParams {
    /// A segment takes its best mask when the mask covers at least this fraction of it.
    pub assign_fraction: f32,
    /// Cut a mask out of a segment when this fraction of the mask lies inside the segment...
    pub contained_fraction: f32,
    /// ...or when the mask covers this fraction of the segment.
    pub covering_fraction: f32,
    /// Cut-outs smaller than this (pixels) are not made.
    pub min_cut_pixels: u32,
    /// Step 3 makes no segment of fewer pixels than this.
    pub min_remainder_pixels: u32,
    /// Cell size (metres) of the grid that decides whether two segments of a mask touch.
    pub cluster_cell: f32,
    /// The refinements of steps 2 to 4 (off for the Voxblox++ baseline).
    pub refine: bool,
}

impl Default for FusionParams {
    fn default() -> Self {
        Self {
            assign_fraction: 0.3,
            contained_fraction: 0.8,
            covering_fraction: 0.1,
            min_cut_pixels: 80,
            min_remainder_pixels: 12,
            cluster_cell: 0.05,
            refine: true,
        }
    }
}

/// A segment of one frame after fusion.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSegment {
    pub pixels: u32,
    /// The frame-local mask id it belongs to, if any.
    pub mask: Option<u16>,
    /// Cut out of a larger geometric segment by its mask (step 2): geometry did not part it
    /// from its neighbour, semantics did.
    pub cut_out: bool,
}

/// One frame's fused segments: per-pixel index into `segments` plus one (0 = none).
#[derive(Clone, Debug)]
pub struct FusedFrame {
    pub segment_of_pixel: Vec<u32>,
    pub segments: Vec<FrameSegment>,
}

pub fn fuse_masks(
    geometry: &GeometricSegmentation,
    masks: &PanopticFrame,
    params: &FusionParams,
) -> FusedFrame {
    let n = geometry.count as usize;
    // overlap[g][m]: pixels of geometric segment g under mask m (0 = no mask).
    let mut overlap: Vec<BTreeMap<u16, u32>> = vec![BTreeMap::new(); n + 1];
    let mut mask_pixels: BTreeMap<u16, u32> = BTreeMap::new();
    // Per mask, its measured pixels outside every geometric segment (for step 3).
    let mut remainder_pixels: BTreeMap<u16, u32> = BTreeMap::new();
    for ((&g, &m), p) in geometry
        .segment_of_pixel
        .iter()
        .zip(&masks.segment_of_pixel)
        .zip(&geometry.points)
    {
        if g != 0 {
            *overlap[g as usize].entry(m).or_default() += 1;
            *mask_pixels.entry(m).or_default() += 1;
        } else if m != 0 && p.z > 0.0 {
            *remainder_pixels.entry(m).or_default() += 1;
        }
    }
    // Output segments: the geometric segments (indices 1..=n), then cut-outs, then remainders.
    let mut segments: Vec<FrameSegment> = Vec::with_capacity(n);
    let mut cut_of: HashMap<(u32, u16), u32, FixedState> = HashMap::default();
    for (g, counts) in overlap.iter().enumerate().skip(1) {
        let size: u32 = counts.values().sum();
        let best = counts
            .iter()
            .filter(|(m, _)| **m != 0)
            .max_by_key(|(m, c)| (**c, std::cmp::Reverse(**m)))
            .filter(|(_, c)| **c as f32 >= params.assign_fraction * size as f32)
            .map(|(m, _)| *m);
        let mut kept = size;
        if params.refine {
            for (&m, &c) in counts {
                if m == 0 || Some(m) == best || c < params.min_cut_pixels {
                    continue;
                }
                let inside = c as f32 >= params.contained_fraction * mask_pixels[&m] as f32;
                let covering = c as f32 >= params.covering_fraction * size as f32;
                if inside || covering {
                    cut_of.insert((g as u32, m), (n + 1 + cut_of.len()) as u32);
                    kept -= c;
                }
            }
        }
        segments.push(FrameSegment {
            pixels: kept,
            mask: best,
            cut_out: false,
        });
    }
    let mut cuts: Vec<((u32, u16), u32)> = cut_of.iter().map(|(k, v)| (*k, *v)).collect();
    cuts.sort_by_key(|(_, id)| *id);
    for ((g, m), _) in &cuts {
        segments.push(FrameSegment {
            pixels: overlap[*g as usize][m],
            mask: Some(*m),
            cut_out: true,
        });
    }
    // Step 3: a mask's remainder pixels, when enough, are a segment of that mask.
    let mut remainder_of: BTreeMap<u16, u32> = BTreeMap::new();
    if params.refine {
        for (m, pixels) in remainder_pixels {
            if pixels >= params.min_remainder_pixels {
                segments.push(FrameSegment {
                    pixels,
                    mask: Some(m),
                    cut_out: false,
                });
                remainder_of.insert(m, segments.len() as u32);
            }
        }
    }
    let segment_of_pixel: Vec<u32> = geometry
        .segment_of_pixel
        .iter()
        .zip(&masks.segment_of_pixel)
        .zip(&geometry.points)
        .map(|((&g, &m), p)| {
            if g == 0 {
                let measured = p.z > 0.0;
                remainder_of
                    .get(&m)
                    .copied()
                    .filter(|_| measured)
                    .unwrap_or(0)
            } else {
                cut_of.get(&(g, m)).copied().unwrap_or(g)
            }
        })
        .collect();
    let mut fused = FusedFrame {
        segment_of_pixel,
        segments,
    };
    if params.refine {
        keep_largest_cluster_per_mask(&mut fused, geometry, params.cluster_cell);
    }
    fused
}

/// Masks that are exact (the floor and walls of a plane survey, not a network's blurred outline)
/// bound the segments that took them: a segment's pixels outside its exact mask become one
/// segment of their own, without a mask, so a floor segment that runs on up a cabinet front
/// (depth noise hides the crease) does not carry the floor's label up the cabinet.
pub fn cut_to_exact_masks(fused: &mut FusedFrame, masks: &PanopticFrame, exact: &[u16]) {
    if exact.is_empty() {
        return;
    }
    let mut outside_of: HashMap<u32, u32, FixedState> = HashMap::default();
    for (s, &m) in fused
        .segment_of_pixel
        .iter_mut()
        .zip(&masks.segment_of_pixel)
    {
        if *s == 0 {
            continue;
        }
        let Some(mask) = fused.segments[*s as usize - 1].mask else {
            continue;
        };
        if mask == m || !exact.contains(&mask) {
            continue;
        }
        let next = (fused.segments.len() + 1) as u32;
        let outside = *outside_of.entry(*s).or_insert_with(|| {
            fused.segments.push(FrameSegment {
                pixels: 0,
                mask: None,
                cut_out: false,
            });
            next
        });
        fused.segments[*s as usize - 1].pixels -= 1;
        fused.segments[outside as usize - 1].pixels += 1;
        *s = outside;
    }
}

/// Step 4: segments of one mask that do not touch in 3D form clusters; all but the largest
/// cluster (by pixels) lose the mask.
fn keep_largest_cluster_per_mask(
    fused: &mut FusedFrame,
    geometry: &GeometricSegmentation,
    cell: f32,
) {
    let mut by_mask: BTreeMap<u16, Vec<u32>> = BTreeMap::new();
    for (i, seg) in fused.segments.iter().enumerate() {
        if let Some(m) = seg.mask {
            by_mask.entry(m).or_default().push(i as u32 + 1);
        }
    }
    // Cells only of segments that share their mask with another: the others have nothing to be
    // clustered with. A run of pixels in one cell is inserted once.
    let mut clustered = vec![false; fused.segments.len() + 1];
    for members in by_mask.values().filter(|m| m.len() > 1) {
        for &s in members {
            clustered[s as usize] = true;
        }
    }
    let mut cells: Vec<HashSet<IVec3, FixedState>> =
        vec![HashSet::default(); fused.segments.len() + 1];
    let mut last: Option<(u32, IVec3)> = None;
    for (&s, p) in fused.segment_of_pixel.iter().zip(&geometry.points) {
        if clustered[s as usize] {
            let c = (*p / cell).floor().as_ivec3();
            if last != Some((s, c)) {
                cells[s as usize].insert(c);
                last = Some((s, c));
            }
        }
    }
    for members in by_mask.values().filter(|m| m.len() > 1) {
        let mut parent: Vec<u32> = (0..members.len() as u32).collect();
        for a in 0..members.len() {
            for b in a + 1..members.len() {
                if touching(&cells[members[a] as usize], &cells[members[b] as usize]) {
                    union(&mut parent, a as u32, b as u32);
                }
            }
        }
        let mut cluster_pixels: BTreeMap<u32, u32> = BTreeMap::new();
        for (k, &s) in members.iter().enumerate() {
            let root = find(&mut parent, k as u32);
            *cluster_pixels.entry(root).or_default() += fused.segments[s as usize - 1].pixels;
        }
        let Some((&largest, _)) = cluster_pixels
            .iter()
            .max_by_key(|(r, p)| (**p, std::cmp::Reverse(**r)))
        else {
            continue;
        };
        for (k, &s) in members.iter().enumerate() {
            if find(&mut parent, k as u32) != largest {
                fused.segments[s as usize - 1].mask = None;
            }
        }
    }
}

/// Whether two cell sets share a cell or have face/edge/corner neighbours.
fn touching(a: &HashSet<IVec3, FixedState>, b: &HashSet<IVec3, FixedState>) -> bool {
    let (small, large) = if a.len() <= b.len() { (a, b) } else { (b, a) };
    small.iter().any(|c| {
        (-1..=1).any(|z| {
            (-1..=1).any(|y| (-1..=1).any(|x| large.contains(&(*c + IVec3::new(x, y, z)))))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::segmentation::PanopticSegment;
    use glam::Vec3;

    /// A 20x10 frame: geometric segment 1 is the left 10 columns (a desk at 1 m), segment 2 the
    /// right 10 columns (far floor at 4 m).
    fn frame(mask_of: impl Fn(usize, usize) -> u16) -> (GeometricSegmentation, PanopticFrame) {
        let (w, h) = (20usize, 10usize);
        let mut seg = Vec::new();
        let mut points = Vec::new();
        let mut masks = Vec::new();
        for v in 0..h {
            for u in 0..w {
                let left = u < 10;
                seg.push(if left { 1 } else { 2 });
                let z = if left { 1.0 } else { 4.0 };
                points.push(Vec3::new(u as f32 * 0.01 * z, v as f32 * 0.01 * z, z));
                masks.push(mask_of(u, v));
            }
        }
        (
            GeometricSegmentation {
                segment_of_pixel: seg,
                count: 2,
                points,
            },
            PanopticFrame {
                width: w as u32,
                height: h as u32,
                segment_of_pixel: masks,
                segments: vec![
                    PanopticSegment {
                        id: 1,
                        class: "table".into(),
                        score: 1.0,
                    },
                    PanopticSegment {
                        id: 2,
                        class: "book".into(),
                        score: 1.0,
                    },
                ],
            },
        )
    }

    fn params() -> FusionParams {
        FusionParams {
            min_cut_pixels: 5,
            ..FusionParams::default()
        }
    }

    /// The Voxblox++ baseline's fusion: no cut-outs, no clustering.
    fn unrefined_params() -> FusionParams {
        FusionParams {
            refine: false,
            ..params()
        }
    }

    #[test]
    fn an_exact_mask_bounds_the_segment_that_took_it() {
        // Mask 1 covers the left segment's top 6 rows: the segment takes it, and with mask 1 exact
        // its bottom 4 rows become a segment of their own without a mask.
        let (g, m) = frame(|u, v| u16::from(u < 10 && v < 6));
        let mut fused = fuse_masks(&g, &m, &params());
        let before = fused.clone();
        cut_to_exact_masks(&mut fused, &m, &[]);
        assert_eq!(
            fused.segment_of_pixel, before.segment_of_pixel,
            "no exact mask, no change"
        );
        cut_to_exact_masks(&mut fused, &m, &[1]);
        assert_eq!(fused.segments[0].mask, Some(1));
        assert_eq!(fused.segments[0].pixels, 60);
        let outside = fused.segment_of_pixel[8 * 20 + 3];
        assert_eq!(fused.segments[outside as usize - 1].mask, None);
        assert_eq!(fused.segments[outside as usize - 1].pixels, 40);
        // The right segment had no mask and is untouched.
        assert_eq!(fused.segment_of_pixel[5 * 20 + 15], 2);
    }

    #[test]
    fn a_mask_inside_a_segment_is_cut_out() {
        // Mask 1 (table) over the left half, mask 2 (book) a 3x3 patch inside it.
        let (g, m) = frame(|u, v| match (u, v) {
            (2..=4, 2..=4) => 2,
            (0..=9, _) => 1,
            _ => 0,
        });
        let fused = fuse_masks(&g, &m, &params());
        assert_eq!(fused.segments.len(), 3);
        assert_eq!(fused.segments[0].mask, Some(1));
        assert_eq!(fused.segments[0].pixels, 100 - 9);
        assert_eq!(fused.segments[1].mask, None);
        assert_eq!(fused.segments[2].mask, Some(2));
        assert_eq!(fused.segments[2].pixels, 9);
        assert!(fused.segments[2].cut_out && !fused.segments[0].cut_out);
        assert_eq!(fused.segment_of_pixel[3 * 20 + 3], 3);
        let unrefined = fuse_masks(&g, &m, &unrefined_params());
        assert_eq!(unrefined.segments.len(), 2);
    }

    #[test]
    fn far_segments_of_one_mask_go_to_the_background() {
        // The chair mask (1) covers the near desk segment and bleeds over the far floor segment.
        let (g, m) = frame(|u, _| if u < 14 { 1 } else { 0 });
        let mut m = m;
        // The far part alone would take mask 1 (40 of 100 pixels >= 30 %).
        let fused = fuse_masks(&g, &m, &params());
        assert_eq!(fused.segments[0].mask, Some(1));
        assert_eq!(
            fused.segments[1].mask, None,
            "far floor lost the chair mask"
        );
        m.segment_of_pixel.iter_mut().for_each(|x| *x = 1);
        let unrefined = fuse_masks(&g, &m, &unrefined_params());
        assert_eq!(unrefined.segments[1].mask, Some(1));
    }

    #[test]
    fn masked_pixels_outside_every_segment_become_a_segment_of_their_mask() {
        // A book (mask 2) on the desk too small for the geometric segmentation: its pixels have
        // no segment; one pixel of it has no depth either.
        let (mut g, m) = frame(|u, v| match (u, v) {
            (2..=5, 2..=5) => 2,
            (0..=9, _) => 1,
            _ => 0,
        });
        for v in 2..=5 {
            for u in 2..=5 {
                g.segment_of_pixel[v * 20 + u] = 0;
            }
        }
        g.points[2 * 20 + 2] = Vec3::ZERO;
        let fused = fuse_masks(&g, &m, &params());
        let book = fused.segment_of_pixel[3 * 20 + 3];
        assert_eq!(book as usize, fused.segments.len(), "the last segment");
        assert_eq!(fused.segments[book as usize - 1].mask, Some(2));
        assert_eq!(fused.segments[book as usize - 1].pixels, 15);
        assert_eq!(
            fused.segment_of_pixel[2 * 20 + 2],
            0,
            "no depth, no segment"
        );
        assert_eq!(fused.segments[0].mask, Some(1), "the desk keeps its mask");
        // Fewer pixels than the minimum make no segment; the baseline makes none at all.
        let strict = FusionParams {
            min_remainder_pixels: 16,
            ..params()
        };
        assert_eq!(fuse_masks(&g, &m, &strict).segment_of_pixel[3 * 20 + 3], 0);
        let unrefined = fuse_masks(&g, &m, &unrefined_params());
        assert_eq!(unrefined.segment_of_pixel[3 * 20 + 3], 0);
        assert_eq!(unrefined.segments.len(), 2);
    }
}
