//! Counters found from geometry alone. No segmenter we ship knows the class (COCO and PASCAL VOC
//! have none), yet a kitchen's counter holds the cups, bottles and monitors on it: without it
//! they would be given to the floor. A counter top is a large horizontal surface at counter
//! height that no entity claims: the unlabelled surface of the map, in the aligned frame, is
//! binned by height, and a height band holding enough of it is cut into connected pieces on a
//! floor grid; a piece broad enough (not the line a wall or a cabinet front leaves in the band)
//! and filled enough is a counter top.

use glam::{IVec2, Vec3};

use crate::geometry::GravityBox;

/// What counts as a counter top.
#[derive(Clone, Copy, Debug)]
pub struct CounterParams {
    /// Heights of counter tops above the floor, metres (chair seats are lower, shelves higher).
    pub min_height: f32,
    pub max_height: f32,
    /// Half the height band a top's points lie in, metres (depth noise, a slight tilt).
    pub band: f32,
    /// Floor grid cell, metres.
    pub cell: f32,
    /// The least area of a top, m^2, and the least width of its minimal rectangle, metres.
    pub min_area: f32,
    pub min_width: f32,
    /// The least share of its minimal rectangle a top covers.
    pub min_fill: f32,
    /// Cells this many apart (in cells, either way) are connected: objects on a counter hide
    /// strips of its top, and their labels bleed over more.
    pub reach_cells: i32,
}

impl Default for CounterParams {
    fn default() -> Self {
        Self {
            min_height: 0.6,
            max_height: 1.2,
            band: 0.03,
            cell: 0.05,
            min_area: 0.25,
            min_width: 0.25,
            min_fill: 0.3,
            reach_cells: 2,
        }
    }
}

/// The counter tops among `unclaimed` (surface points no entity claims, z up, floor at 0): each
/// top's points, largest first.
pub fn find_counter_tops(unclaimed: &[Vec3], params: &CounterParams) -> Vec<Vec<Vec3>> {
    let cell_area = params.cell * params.cell;
    let in_range: Vec<Vec3> = unclaimed
        .iter()
        .copied()
        .filter(|p| (params.min_height..=params.max_height).contains(&p.z))
        .collect();
    // Height bins of half the band; a top's points fill two or three neighbouring ones.
    let bin = params.band / 2.0;
    let bin_of = |z: f32| ((z - params.min_height) / bin).floor() as i32;
    let bins = bin_of(params.max_height) + 1;
    let mut counts = vec![0usize; bins.max(0) as usize];
    for p in &in_range {
        if let Some(c) = counts.get_mut(bin_of(p.z) as usize) {
            *c += 1;
        }
    }
    // Band centres, best first: each a local maximum of the band's count.
    let band_count = |b: i32| {
        (b - 1..=b + 1)
            .filter_map(|k| counts.get(usize::try_from(k).ok()?))
            .sum::<usize>()
    };
    let mut peaks: Vec<(usize, i32)> = (0..bins)
        .map(|b| (band_count(b), b))
        .filter(|&(n, b)| n > 0 && n >= band_count(b - 1) && n > band_count(b + 1))
        .collect();
    peaks.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut taken = vec![false; in_range.len()];
    let mut tops = Vec::new();
    for (_, peak) in peaks {
        let z = params.min_height + (peak as f32 + 0.5) * bin;
        let members: Vec<usize> = (0..in_range.len())
            .filter(|&i| !taken[i] && (in_range[i].z - z).abs() <= params.band)
            .collect();
        for piece in grid_pieces(&in_range, &members, params.cell, params.reach_cells) {
            let points: Vec<Vec3> = piece.iter().map(|&i| in_range[i]).collect();
            let cells = occupied_cells(&points, params.cell);
            let area = cells as f32 * cell_area;
            let Some(rect) = GravityBox::minimal(&points) else {
                continue;
            };
            let (width, length) = (rect.size.x.min(rect.size.y), rect.size.x.max(rect.size.y));
            let fill = area / ((width + params.cell) * (length + params.cell));
            if area >= params.min_area && width >= params.min_width && fill >= params.min_fill {
                for &i in &piece {
                    taken[i] = true;
                }
                tops.push(points);
            }
        }
    }
    tops.sort_by_key(|t| std::cmp::Reverse(t.len()));
    tops
}

/// How far beyond a counter top's outline (metres) its front and ends are gathered: a worktop
/// overhangs its doors, so they lie under it, but a top seen short of its edge does not.
const BODY_REACH_M: f32 = 0.05;
/// The body's points lie from this high above the floor (the floor's own points lie lower) ...
const BODY_ABOVE_FLOOR_M: f32 = 0.03;
/// ... to this far under the top's lowest point.
const BODY_UNDER_TOP_M: f32 = 0.02;

/// What the map saw of a counter under its `top` (z up, floor at 0) among `surface`: its front
/// of doors and drawers and its ends, the points under the top's outline (grown by
/// [`BODY_REACH_M`]) between the floor and the top. The segmenters know no counter, so these
/// points are unclaimed or a wall's (its front is a large vertical plane); the caller leaves out
/// other objects' (a chair pushed under it).
pub fn counter_body(top: &[Vec3], surface: &[Vec3]) -> Vec<Vec3> {
    let Some(outline) = GravityBox::minimal(top) else {
        return Vec::new();
    };
    let under = top.iter().map(|p| p.z).fold(f32::MAX, f32::min) - BODY_UNDER_TOP_M;
    let reach = GravityBox {
        size: outline.size + Vec3::new(2.0 * BODY_REACH_M, 2.0 * BODY_REACH_M, 0.0),
        ..outline
    };
    surface
        .iter()
        .copied()
        .filter(|p| (BODY_ABOVE_FLOOR_M..=under).contains(&p.z))
        .filter(|p| reach.contains(p.with_z(reach.center.z), 0.0))
        .collect()
}

fn cell_of(p: Vec3, cell: f32) -> IVec2 {
    IVec2::new((p.x / cell).floor() as i32, (p.y / cell).floor() as i32)
}

fn occupied_cells(points: &[Vec3], cell: f32) -> usize {
    let cells: std::collections::BTreeSet<(i32, i32)> = points
        .iter()
        .map(|p| cell_of(*p, cell))
        .map(|c| (c.x, c.y))
        .collect();
    cells.len()
}

/// `members` of `points` split into pieces connected on the floor grid (cells at most `reach`
/// cells apart either way), in order of their first member.
fn grid_pieces(points: &[Vec3], members: &[usize], cell: f32, reach: i32) -> Vec<Vec<usize>> {
    use std::collections::BTreeMap;
    let mut by_cell: BTreeMap<(i32, i32), Vec<usize>> = BTreeMap::new();
    for &i in members {
        let c = cell_of(points[i], cell);
        by_cell.entry((c.x, c.y)).or_default().push(i);
    }
    let mut piece_of: BTreeMap<(i32, i32), usize> = BTreeMap::new();
    let mut pieces: Vec<Vec<usize>> = Vec::new();
    let keys: Vec<(i32, i32)> = by_cell.keys().copied().collect();
    for start in keys {
        if piece_of.contains_key(&start) {
            continue;
        }
        let id = pieces.len();
        let mut piece = Vec::new();
        let mut stack = vec![start];
        piece_of.insert(start, id);
        while let Some((x, y)) = stack.pop() {
            piece.extend(by_cell[&(x, y)].iter().copied());
            for dx in -reach..=reach {
                for dy in -reach..=reach {
                    let next = (x + dx, y + dy);
                    if by_cell.contains_key(&next) && !piece_of.contains_key(&next) {
                        piece_of.insert(next, id);
                        stack.push(next);
                    }
                }
            }
        }
        piece.sort_unstable();
        pieces.push(piece);
    }
    pieces.sort_by_key(|p| p[0]);
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on a 2 cm grid over the rectangle `lo..hi` at height `z`.
    fn grid(lo: (f32, f32), hi: (f32, f32), z: f32) -> Vec<Vec3> {
        let mut points = Vec::new();
        let mut x = lo.0;
        while x <= hi.0 {
            let mut y = lo.1;
            while y <= hi.1 {
                points.push(Vec3::new(x, y, z));
                y += 0.02;
            }
            x += 0.02;
        }
        points
    }

    #[test]
    fn a_counter_top_is_found_and_a_wall_or_a_small_shelf_is_not() {
        // A 2.4 m by 0.6 m counter top at 0.9 m, with depth noise.
        let mut points: Vec<Vec3> = grid((0.0, 3.0), (2.4, 3.6), 0.9)
            .into_iter()
            .enumerate()
            .map(|(i, p)| p + Vec3::Z * (0.008 * ((i * 7919 % 13) as f32 / 6.0 - 1.0)))
            .collect();
        // A wall at x = -0.5: a vertical strip through every height band.
        for k in 0..150 {
            for j in 0..100 {
                points.push(Vec3::new(-0.5, 1.0 + 0.02 * j as f32, 0.01 * k as f32));
            }
        }
        // A 30 cm shelf at 1.1 m and a chair seat at 0.45 m.
        points.extend(grid((3.0, 0.0), (3.3, 0.3), 1.1));
        points.extend(grid((1.0, 1.0), (1.5, 1.5), 0.45));
        let tops = find_counter_tops(&points, &CounterParams::default());
        assert_eq!(
            tops.len(),
            1,
            "{:?}",
            tops.iter().map(Vec::len).collect::<Vec<_>>()
        );
        let top = GravityBox::minimal(&tops[0]).expect("a box");
        assert!((top.top_z() - 0.9).abs() < 0.02, "{top:?}");
        let (w, l) = (top.size.x.min(top.size.y), top.size.x.max(top.size.y));
        assert!((w - 0.6).abs() < 0.05 && (l - 2.4).abs() < 0.05, "{top:?}");
    }

    #[test]
    fn a_counter_s_body_is_what_lies_under_its_top() {
        let top = grid((0.0, 3.0), (2.4, 3.6), 0.9);
        // Its front at y = 2.98 under a 2 cm overhang, the floor before it, a chair 30 cm out
        // and the wall above the top.
        let mut surface: Vec<Vec3> = (0..40)
            .flat_map(|i| (2..44).map(move |k| Vec3::new(0.06 * i as f32, 2.98, 0.02 * k as f32)))
            .collect();
        let front = surface.len();
        surface.extend(grid((0.0, 2.0), (2.4, 2.9), 0.0));
        surface.extend(grid((1.0, 2.5), (1.4, 2.7), 0.45));
        surface.extend((0..20).map(|k| Vec3::new(1.0, 3.62, 0.95 + 0.05 * k as f32)));
        let body = counter_body(&top, &surface);
        assert_eq!(body.len(), front);
        assert!(
            body.iter()
                .all(|p| p.y == 2.98 && (0.03..=0.88).contains(&p.z))
        );
    }

    #[test]
    fn nothing_unclaimed_is_no_counter() {
        assert!(find_counter_tops(&[], &CounterParams::default()).is_empty());
    }
}
