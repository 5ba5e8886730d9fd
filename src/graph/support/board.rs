//! The board a movable object stands on inside another's box, seen beside it and hidden under
//! it (a bottle on a shelf's board).

use glam::Vec3;

use super::footprint::Footprint;
use super::{SupportEntity, SupportParams};
use crate::classes::EntityKind;
use crate::geometry::GravityBox;

/// Grid cells (`area_cell` wide) holding a parent's surface seen beside a child's footprint
/// (within `surface_reach`), at one height (within `plane_band` of their median), that make the
/// board it stands on: a board's edge seen along a bottle is a row of them; a table's legs
/// beside a box under it are a cell or two each, at every height.
const BOARD_MIN_CELLS: usize = 4;

/// The object whose box the footprint of `child` stands in, from below its bottom to above it,
/// whose surface is seen beside the child's footprint at its bottom (within `max_gap` under it
/// or `above_tolerance` over it, in `BOARD_MIN_CELLS` at one height), and that height: the
/// board it stands on, hidden under it. The innermost such box (highest bottom) when several
/// hold it.
pub(super) fn board_inside(
    child: usize,
    entities: &[SupportEntity],
    params: &SupportParams,
) -> Option<(usize, f32)> {
    let c = &entities[child];
    let bottom = c.bbox.bottom_z();
    let footprint = Footprint::of(&c.bbox);
    let ring = Footprint::of(&GravityBox {
        size: c.bbox.size + Vec3::new(2.0, 2.0, 0.0) * params.surface_reach,
        ..c.bbox
    });
    entities
        .iter()
        .enumerate()
        .filter(|(p, parent)| {
            *p != child
                && parent.kind != EntityKind::Layout
                && parent.bbox.bottom_z() < bottom
                && parent.bbox.top_z() > bottom + params.above_tolerance
                && footprint.overlap_with_box(&parent.bbox) >= params.min_area
        })
        .filter_map(|(p, parent)| {
            let beside: Vec<&Vec3> = parent
                .vertices
                .iter()
                .filter(|v| {
                    v.z >= bottom - params.max_gap && v.z <= bottom + params.above_tolerance
                })
                .filter(|v| ring.contains(v.truncate()) && !footprint.contains(v.truncate()))
                .collect();
            let mut heights: Vec<f32> = beside.iter().map(|v| v.z).collect();
            heights.sort_by(f32::total_cmp);
            let height = *heights.get(heights.len() / 2)?;
            let cells: std::collections::BTreeSet<(i32, i32)> = beside
                .iter()
                .filter(|v| (v.z - height).abs() <= params.plane_band)
                .map(|v| {
                    let cell = (v.truncate() / params.area_cell).floor();
                    (cell.x as i32, cell.y as i32)
                })
                .collect();
            (cells.len() >= BOARD_MIN_CELLS).then_some((p, parent.bbox.bottom_z(), height))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(p, _, height)| (p, height))
}
