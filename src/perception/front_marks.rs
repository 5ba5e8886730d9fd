//! Handles and the gaps between doors and drawers, read off a front's baked image
//! (`perception::front_texture`): what the map's depth cannot resolve on a real front. A handle
//! is a compact patch whose colour differs from the front's around it, a bar long and thin along
//! or across the front, a knob small and round (the shapes `perception::handles` fits to points);
//! a gap is a line across the front a little darker than the front beside it, a groove's shadow.
//!
//! A handle's colour differs from the front's both overall and around it (a median over 12 cm):
//! light falls unevenly across a kitchen run, and the red under a black worktop differs from the
//! colour around it only. Rows mostly off the front's colour are bands along its edges (a
//! worktop's lip, a plinth), never a handle; a handle has the front's colour all round it.

use glam::Vec3;
use rayon::prelude::*;

use crate::geometry::Pinhole;
use crate::perception::front_texture::{
    FrontRect, FrontTexture, TEXEL_M, View, ViewImages, bake, best_views,
};
use crate::perception::fronts::PerceivedFront;
use crate::perception::handles::{Handle, HandleKind};
use crate::perception::parts::Gaps;

/// A front's image must cover at least this share of it to be read.
const MIN_COVERAGE: f32 = 0.5;

/// What the frames show of `seen`'s front (the rectangle its parts cover): its image baked from
/// the best of `views` (`load` gives a frame's images) and read. `None` when no frame sees it
/// well enough, or the image covers too little of it.
pub fn marks_seen(
    seen: &PerceivedFront,
    camera: &Pinhole,
    views: &[View],
    load: impl Fn(usize) -> Option<ViewImages> + Sync,
) -> Option<FrontMarks> {
    let rect = FrontRect {
        front: seen.front,
        right: seen.extent.right,
        z: seen.extent.z,
    };
    let chosen = best_views(&rect, camera, views);
    let images: Vec<(View, ViewImages)> = chosen
        .par_iter()
        .filter_map(|view| Some((*view, load(view.frame)?)))
        .collect();
    let texture = bake(&rect, camera, &images);
    tracing::debug!(
        "front texture {}x{} from frames {:?}: {:.0}% seen",
        texture.width,
        texture.height,
        chosen.iter().map(|v| v.frame).collect::<Vec<_>>(),
        100.0 * texture.coverage()
    );
    (texture.coverage() >= MIN_COVERAGE).then(|| front_marks(&texture))
}

/// A texel differs from the front's colour when they are this far apart (RGB, 0-255, Euclidean):
/// a steel bar in the shade of a worktop on a red front is about 40 apart from it.
const OFF_COLOUR: f32 = 35.0;
/// The window the front's own colour around a texel is the median of, texels (12 cm) ...
const BASE_WINDOW: usize = 41;
/// ... taken on a grid this many texels apart.
const BASE_STEP: usize = 4;
/// A row with at least this share of its texels seen off the front's colour is a band along an
/// edge of the front, no part of a handle.
const BAND_SHARE: f32 = 0.6;
/// A handle has the front's colour all round it: at most this share of the texels in a ring
/// [`RING_TEXELS`] wide around its rectangle differ from it.
const MAX_RING_OFF: f32 = 0.25;
const RING_TEXELS: usize = 3;

/// A bar is this long, metres (a towel rail is longer, a scratch shorter) ...
const BAR_LENGTH_M: std::ops::RangeInclusive<f32> = 0.06..=0.45;
/// ... at most this thick, metres ...
const MAX_BAR_THICKNESS_M: f32 = 0.03;
/// ... and this many times longer than thick.
const MIN_BAR_ELONGATION: f32 = 4.0;
/// A vertical bar is shorter than this share of the front's height: a longer dark line is a gap.
const MAX_BAR_HEIGHT_SHARE: f32 = 0.6;
/// A knob is this wide either way, metres, ...
const KNOB_SIZE_M: std::ops::RangeInclusive<f32> = 0.015..=0.06;
/// ... and at most this many times longer one way than the other.
const MAX_KNOB_ASPECT: f32 = 1.7;
/// A handle covers at least this share of its bounding rectangle.
const MIN_FILL: f32 = 0.35;
/// Patches this close (metres) to the image's edge are the edges of the front (a worktop's lip, a
/// plinth, the neighbouring unit), not handles.
const BORDER_M: f32 = 0.02;
/// How far a handle is taken to stand out of the front, metres: the image does not tell, and
/// bar handles stand 2 to 4 cm out.
pub const SEEN_HANDLE_OUT_M: f32 = 0.03;

/// A line (a column or a row of texels) is a gap where its brightness dips at least this share
/// under the front's on either side of it: a groove's shadow, blurred over a centimetre or two
/// by the camera, is 4 to 10% darker on a glossy red front ...
const MIN_GAP_DIP: f32 = 0.04;
/// ... the front on either side being the lines from this far (texels, 1.2 cm) ...
const GAP_SIDE_NEAR: usize = 4;
/// ... to this far (6 cm) from it; a shadow wider than that dips under its own sides no more.
const GAP_SIDE_FAR: usize = 20;
/// A gap is the darkest line within this many texels either way.
const GAP_PEAK_TEXELS: usize = 5;
/// A line's brightness is the median over its texels seen, when at least this share is.
const MIN_GAP_SEEN_SHARE: f32 = 0.5;
/// Lines within this distance of the image's ends along them are not counted (the worktop's
/// shadow, the plinth), metres.
const GAP_END_MARGIN_M: f32 = 0.05;
/// Gaps closer than this to the image's sides (metres) are the front's own edges.
const GAP_SIDE_MARGIN_M: f32 = 0.04;

/// What a front's image shows: its handles (world frame, standing [`SEEN_HANDLE_OUT_M`] out of
/// the front) and where its gaps run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrontMarks {
    pub handles: Vec<Handle>,
    pub gaps: Gaps,
}

fn brightness(c: [f32; 3]) -> f32 {
    (c[0] + c[1] + c[2]) / 3.0
}

/// The median of `values` (not empty), as the map takes it.
fn median(mut values: Vec<f32>) -> f32 {
    crate::map::median(&mut values)
}

/// The front's own colour overall: the median, channel by channel, of its texels seen.
fn front_colour(texture: &FrontTexture) -> Option<[f32; 3]> {
    let seen: Vec<[u8; 3]> = texture.texels.iter().flatten().copied().collect();
    (!seen.is_empty())
        .then(|| std::array::from_fn(|ch| median(seen.iter().map(|t| f32::from(t[ch])).collect())))
}

/// The front's own colour around each texel: the median, channel by channel, of the texels seen
/// within [`BASE_WINDOW`] of it, taken on a grid [`BASE_STEP`] apart (a median of row medians: a
/// handle is too small to move it, a shade across the front is not); `whole` where nothing near
/// is seen.
fn front_colours(texture: &FrontTexture, whole: [f32; 3]) -> Vec<[f32; 3]> {
    let (w, h) = (texture.width, texture.height);
    let (gw, gh) = (w.div_ceil(BASE_STEP), h.div_ceil(BASE_STEP));
    let reach = BASE_WINDOW / 2;
    // Medians along each row, at the grid's columns.
    let row_medians: Vec<Option<[f32; 3]>> = (0..h)
        .flat_map(|r| (0..gw).map(move |gc| (r, gc * BASE_STEP)))
        .map(|(r, c)| {
            let seen: Vec<[u8; 3]> = (c.saturating_sub(reach)..(c + reach + 1).min(w))
                .filter_map(|k| texture.get(k, r))
                .collect();
            (!seen.is_empty()).then(|| {
                std::array::from_fn(|ch| median(seen.iter().map(|t| f32::from(t[ch])).collect()))
            })
        })
        .collect();
    // ... and of those down each column, at the grid's rows.
    let grid: Vec<Option<[f32; 3]>> = (0..gh)
        .flat_map(|gr| (0..gw).map(move |gc| (gr * BASE_STEP, gc)))
        .map(|(r, gc)| {
            let seen: Vec<[f32; 3]> = (r.saturating_sub(reach)..(r + reach + 1).min(h))
                .filter_map(|k| row_medians[k * gw + gc])
                .collect();
            (!seen.is_empty())
                .then(|| std::array::from_fn(|ch| median(seen.iter().map(|t| t[ch]).collect())))
        })
        .collect();
    (0..w * h)
        .map(|i| {
            let (gc, gr) = (
                (i % w + BASE_STEP / 2) / BASE_STEP,
                (i / w + BASE_STEP / 2) / BASE_STEP,
            );
            grid[gr.min(gh - 1) * gw + gc.min(gw - 1)].unwrap_or(whole)
        })
        .collect()
}

/// The handles and gaps `texture` shows.
pub fn front_marks(texture: &FrontTexture) -> FrontMarks {
    let Some(whole) = front_colour(texture) else {
        return FrontMarks::default();
    };
    let around = front_colours(texture, whole);
    let apart = |c: [u8; 3], base: [f32; 3]| {
        let d2: f32 = (0..3).map(|k| (f32::from(c[k]) - base[k]).powi(2)).sum();
        d2.sqrt() > OFF_COLOUR
    };
    // Off the front's colour both around it and overall: the red under a black worktop differs
    // from the colour around it only, a shaded stretch of the front from the overall only.
    let off_whole: Vec<bool> = texture
        .texels
        .iter()
        .map(|t| t.is_some_and(|c| apart(c, whole)))
        .collect();
    let off: Vec<bool> = texture
        .texels
        .iter()
        .zip(&around)
        .zip(&off_whole)
        .map(|((t, base), whole)| *whole && t.is_some_and(|c| apart(c, *base)))
        .collect();
    FrontMarks {
        handles: handles(texture, &off, &band_rows(texture, &off_whole)),
        gaps: Gaps {
            vertical: gaps(texture, true),
            horizontal: gaps(texture, false),
        },
    }
}

/// The connected patches (8-neighbours) of `mask`, each as its texels' (column, row).
fn patches(mask: &[bool], w: usize, h: usize) -> Vec<Vec<(usize, usize)>> {
    let mut seen = vec![false; mask.len()];
    let mut out = Vec::new();
    for start in 0..mask.len() {
        if !mask[start] || seen[start] {
            continue;
        }
        seen[start] = true;
        let mut stack = vec![start];
        let mut patch = Vec::new();
        while let Some(i) = stack.pop() {
            let (c, r) = (i % w, i / w);
            patch.push((c, r));
            for dr in -1i64..=1 {
                for dc in -1i64..=1 {
                    let (nc, nr) = (c as i64 + dc, r as i64 + dr);
                    if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                        continue;
                    }
                    let j = nr as usize * w + nc as usize;
                    if mask[j] && !seen[j] {
                        seen[j] = true;
                        stack.push(j);
                    }
                }
            }
        }
        out.push(patch);
    }
    out
}

/// The rows that are bands along the front's top and bottom edges (a worktop's lip, a plinth):
/// at least [`BAND_SHARE`] of their seen texels are `off_whole`, off the front's overall colour.
/// (Columns are not: a stretch of the front in shade is off the overall colour too, with its
/// handles on it.)
fn band_rows(texture: &FrontTexture, off_whole: &[bool]) -> Vec<bool> {
    let w = texture.width;
    (0..texture.height)
        .map(|r| {
            let row = r * w..(r + 1) * w;
            let (mut seen, mut off_count) = (0usize, 0usize);
            for (texel, off) in texture.texels[row.clone()].iter().zip(&off_whole[row]) {
                if texel.is_some() {
                    seen += 1;
                    off_count += usize::from(*off);
                }
            }
            seen > 0 && off_count as f32 >= BAND_SHARE * seen as f32
        })
        .collect()
}

/// The share of the texels in a ring [`RING_TEXELS`] wide around the rectangle `[c0, c1, r0,
/// r1]` (inclusive) that are `off`.
fn ring_off_share(off: &[bool], w: usize, h: usize, [c0, c1, r0, r1]: [usize; 4]) -> f32 {
    let (mut ring, mut off_count) = (0usize, 0usize);
    for r in r0.saturating_sub(RING_TEXELS)..(r1 + RING_TEXELS + 1).min(h) {
        for c in c0.saturating_sub(RING_TEXELS)..(c1 + RING_TEXELS + 1).min(w) {
            if (r0..=r1).contains(&r) && (c0..=c1).contains(&c) {
                continue;
            }
            ring += 1;
            off_count += usize::from(off[r * w + c]);
        }
    }
    if ring == 0 {
        return 1.0;
    }
    off_count as f32 / ring as f32
}

/// The handles among the patches of `off` texels outside the `band_rows`.
fn handles(texture: &FrontTexture, off: &[bool], band_rows: &[bool]) -> Vec<Handle> {
    let (w, h) = (texture.width, texture.height);
    let border = (BORDER_M / TEXEL_M).round() as usize;
    let front = &texture.rect.front;
    let front_height = texture.rect.z[1] - texture.rect.z[0];
    let on_handle: Vec<bool> = (0..w * h).map(|i| off[i] && !band_rows[i / w]).collect();
    let mut found = Vec::new();
    for patch in patches(&on_handle, w, h) {
        let (mut c0, mut c1, mut r0, mut r1) = (usize::MAX, 0, usize::MAX, 0);
        for &(c, r) in &patch {
            (c0, c1, r0, r1) = (c0.min(c), c1.max(c), r0.min(r), r1.max(r));
        }
        if c0 < border || r0 < border || c1 + border >= w || r1 + border >= h {
            continue;
        }
        if ring_off_share(off, w, h, [c0, c1, r0, r1]) > MAX_RING_OFF {
            continue;
        }
        let (cols, rows) = (c1 - c0 + 1, r1 - r0 + 1);
        let fill = patch.len() as f32 / (cols * rows) as f32;
        let (across, up) = (cols as f32 * TEXEL_M, rows as f32 * TEXEL_M);
        let (long, thin) = (across.max(up), across.min(up));
        let kind = if BAR_LENGTH_M.contains(&long)
            && thin <= MAX_BAR_THICKNESS_M
            && long >= MIN_BAR_ELONGATION * thin
            && (across >= up || up <= MAX_BAR_HEIGHT_SHARE * front_height)
        {
            HandleKind::Bar
        } else if KNOB_SIZE_M.contains(&long)
            && KNOB_SIZE_M.contains(&thin)
            && long <= MAX_KNOB_ASPECT * thin
        {
            HandleKind::Knob
        } else {
            continue;
        };
        if fill < MIN_FILL {
            continue;
        }
        let (right, z) = texture.texel_center(0.5 * (c0 + c1) as f32, 0.5 * (r0 + r1) as f32);
        let center = texture.rect.point(right, z) + front.normal * SEEN_HANDLE_OUT_M;
        let axis = match kind {
            HandleKind::Bar if across >= up => front.right,
            HandleKind::Bar => Vec3::Z,
            HandleKind::Knob => front.normal,
        };
        found.push(Handle {
            kind,
            center,
            axis,
            length: long,
            depth: SEEN_HANDLE_OUT_M,
        });
    }
    found.sort_by(|a, b| {
        a.center
            .z
            .total_cmp(&b.center.z)
            .then(front.local(a.center).x.total_cmp(&front.local(b.center).x))
    });
    found
}

/// Where dark lines run across the image, vertical ones (`vertical`) as distances along the
/// front, horizontal ones as heights, in increasing order: the lines whose brightness dips the
/// most within [`GAP_PEAK_TEXELS`] and at least [`MIN_GAP_DIP`] under the front beside them.
fn gaps(texture: &FrontTexture, vertical: bool) -> Vec<f32> {
    let (w, h) = (texture.width, texture.height);
    let (lines, along) = if vertical { (w, h) } else { (h, w) };
    let end = (GAP_END_MARGIN_M / TEXEL_M).round() as usize;
    let side = (GAP_SIDE_MARGIN_M / TEXEL_M).round() as usize;
    let profile: Vec<Option<f32>> = (0..lines)
        .map(|line| {
            let cells = end.min(along / 2)..along.saturating_sub(end);
            let length = cells.len();
            let seen: Vec<f32> = cells
                .filter_map(|k| {
                    let (c, r) = if vertical { (line, k) } else { (k, line) };
                    texture.get(c, r).map(|t| brightness(t.map(f32::from)))
                })
                .collect();
            (!seen.is_empty() && seen.len() as f32 >= MIN_GAP_SEEN_SHARE * length as f32)
                .then(|| median(seen))
        })
        .collect();
    let dip: Vec<f32> = (0..lines)
        .map(|line| {
            let Some(here) = profile[line] else {
                return 0.0;
            };
            let beside: Vec<f32> = (line.saturating_sub(GAP_SIDE_FAR)
                ..line.saturating_sub(GAP_SIDE_NEAR - 1))
                .chain((line + GAP_SIDE_NEAR..=line + GAP_SIDE_FAR).filter(|k| *k < lines))
                .filter(|k| k.abs_diff(line) >= GAP_SIDE_NEAR)
                .filter_map(|k| profile[k])
                .collect();
            if beside.is_empty() {
                return 0.0;
            }
            let front = median(beside);
            if front > 0.0 {
                (front - here) / front
            } else {
                0.0
            }
        })
        .collect();
    let mut found: Vec<f32> = (side..lines.saturating_sub(side))
        .filter(|&line| {
            let near =
                line.saturating_sub(GAP_PEAK_TEXELS)..(line + GAP_PEAK_TEXELS + 1).min(lines);
            // The darkest line within reach; of equally dark ones, the first.
            dip[line] >= MIN_GAP_DIP
                && near
                    .clone()
                    .all(|k| dip[k] < dip[line] || (dip[k] == dip[line] && k >= line))
        })
        .map(|line| {
            let (right, z) = texture.texel_center(line as f32, line as f32);
            if vertical { right } else { z }
        })
        .collect();
    found.sort_by(f32::total_cmp);
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::perception::front_texture::FrontRect;
    use crate::perception::handles::Front;

    const RED: [u8; 3] = [150, 20, 25];
    const SILVER: [u8; 3] = [200, 200, 205];
    const GROOVE: [u8; 3] = [40, 5, 8];

    /// A texture of the front rectangle 1.2 m by 0.7 m (right from 0, z from 0.1) painted by
    /// `paint(right, z)`.
    fn painted(paint: impl Fn(f32, f32) -> [u8; 3]) -> FrontTexture {
        let front = Front::new(Vec3::ZERO, Vec3::NEG_Y).expect("a front");
        let rect = FrontRect {
            front,
            right: [0.0, 1.2],
            z: [0.1, 0.8],
        };
        let (width, height) = ((1.2 / TEXEL_M) as usize, (0.7 / TEXEL_M) as usize);
        let mut texture = FrontTexture {
            rect,
            width,
            height,
            texels: Vec::new(),
        };
        texture.texels = (0..height)
            .flat_map(|r| (0..width).map(move |c| (c, r)))
            .map(|(c, r)| {
                let (right, z) = texture.texel_center(c as f32, r as f32);
                Some(paint(right, z))
            })
            .collect();
        texture
    }

    /// Two doors 60 cm wide side by side, a 4 mm groove between them, each with a 20 cm
    /// horizontal bar 1 cm high centred near its top, and a knob on the left door.
    fn two_doors(right: f32, z: f32) -> [u8; 3] {
        if (0.598..0.602).contains(&right) {
            return GROOVE;
        }
        let bar = |centre: f32| (right - centre).abs() < 0.1 && (0.7..0.71).contains(&z);
        if bar(0.3) || bar(0.9) {
            return SILVER;
        }
        if (right - 0.1).abs() < 0.015 && (z - 0.4).abs() < 0.015 {
            return SILVER;
        }
        // Light falling off to the right: the front's own colour changes across it.
        let shade = 1.0 - 0.3 * right / 1.2;
        RED.map(|v| (f32::from(v) * shade) as u8)
    }

    #[test]
    fn bars_knobs_and_the_groove_between_two_doors_are_read_off_the_image() {
        let marks = front_marks(&painted(two_doors));
        let kinds: Vec<HandleKind> = marks.handles.iter().map(|h| h.kind).collect();
        assert_eq!(
            kinds,
            [HandleKind::Knob, HandleKind::Bar, HandleKind::Bar],
            "{marks:?}"
        );
        let front = Front::new(Vec3::ZERO, Vec3::NEG_Y).expect("a front");
        for (handle, (right, z)) in
            marks
                .handles
                .iter()
                .zip([(0.1, 0.4), (0.3, 0.705), (0.9, 0.705)])
        {
            let local = front.local(handle.center);
            assert!((local.x - right).abs() < 0.01, "{handle:?}");
            assert!((handle.center.z - z).abs() < 0.01, "{handle:?}");
            assert!((local.z - SEEN_HANDLE_OUT_M).abs() < 1e-4, "{handle:?}");
        }
        assert!((marks.handles[1].length - 0.2).abs() < 0.011, "{marks:?}");
        assert!(marks.handles[1].axis.abs_diff_eq(front.right, 1e-5));
        assert_eq!(marks.gaps.vertical.len(), 1, "{marks:?}");
        assert!((marks.gaps.vertical[0] - 0.6).abs() < 0.004, "{marks:?}");
        assert!(marks.gaps.horizontal.is_empty(), "{marks:?}");
    }

    #[test]
    fn a_plain_front_shows_nothing_and_its_edges_are_no_handles() {
        // A worktop's silver lip along the top edge and a dark plinth along the bottom.
        let marks = front_marks(&painted(|_, z| {
            if z > 0.79 {
                SILVER
            } else if z < 0.13 {
                GROOVE
            } else {
                RED
            }
        }));
        assert_eq!(marks, FrontMarks::default());
    }

    #[test]
    fn a_stack_of_drawers_shows_its_horizontal_gaps() {
        let marks = front_marks(&painted(|_, z| {
            if (0.348..0.352).contains(&z) || (0.548..0.552).contains(&z) {
                GROOVE
            } else {
                RED
            }
        }));
        assert!(marks.gaps.vertical.is_empty(), "{marks:?}");
        assert_eq!(marks.gaps.horizontal.len(), 2, "{marks:?}");
        assert!((marks.gaps.horizontal[0] - 0.35).abs() < 0.004, "{marks:?}");
        assert!((marks.gaps.horizontal[1] - 0.55).abs() < 0.004, "{marks:?}");
    }
}
