//! The physical check's verdict on each final placement: how deep it is in other models, the
//! unplaced obstacles and the layout, how much of it stands on its holder, whether it tips, and
//! the conflicts those leave.

use crate::cad::placed_solid::{PlacedSolid, layout_penetration, penetration_depth, support_area};
use crate::cad::replace::physical_check::{
    Holder, MAX_PENETRATION_M, MIN_SUPPORT_AREA, PlacementCheck,
};
use crate::geometry::Plane;

/// A model still this deep (metres) in an obstacle after separation is a conflict: an obstacle
/// neither moves nor shrinks, so what separation could not part from it (a chair squeezed
/// between two counters) would start the simulation overlapping it.
pub const MAX_OBSTACLE_PENETRATION_M: f32 = 0.001;

/// The verdict on each object's final placement (`finals`, snapped; `choice` the candidate
/// chosen; `separated_m` how far separation moved it), `None` for an object with none.
#[allow(clippy::too_many_arguments)]
pub fn placement_verdicts(
    finals: &[Option<PlacedSolid>],
    choice: &[Option<usize>],
    separated_m: &[f32],
    holders: &[Holder],
    movable: &[bool],
    layout: &[Plane],
    obstacles: &[PlacedSolid],
    obstacle_holders: &[Option<usize>],
) -> Vec<Option<PlacementCheck>> {
    let n = finals.len();
    (0..n)
        .map(|i| {
            let me = finals[i].as_ref()?;
            let depths: Vec<(usize, f32)> = (0..n)
                .filter(|&j| j != i)
                .filter_map(|j| Some((j, penetration_depth(me, finals[j].as_ref()?))))
                .collect();
            // What it holds rests on it: the box of a thing no model replaced lying on a
            // shelf's board is as deep in the board as the noise of the surface it was seen on
            // (a 1 cm "book" 1.5 mm into the board left a shelf and its eleven books unplaced,
            // seed 35), so it gets the bar two models get, not the obstacles' own.
            let (held_penetration_m, obstacle_penetration_m) =
                obstacles
                    .iter()
                    .enumerate()
                    .fold((0.0f32, 0.0f32), |(held, other), (k, o)| {
                        let depth = penetration_depth(me, o);
                        if obstacle_holders.get(k).copied().flatten() == Some(i) {
                            (held.max(depth), other)
                        } else {
                            (held, other.max(depth))
                        }
                    });
            let max_penetration_m = depths
                .iter()
                .map(|(_, d)| *d)
                .fold(obstacle_penetration_m.max(held_penetration_m), f32::max);
            // A deep overlap of two models is charged to the one that yields (`keeps_place`):
            // leaving a table as its box for a chair pushed into it starts the chair, and
            // everything on the table, inside that box.
            let overlapped = depths
                .iter()
                .any(|&(j, d)| d > MAX_PENETRATION_M && !keeps_place(i, j, holders, movable));
            let layout_penetration_m = layout_penetration(me, layout);
            let held_area = match holders[i] {
                Holder::Object(p) => finals[p].as_ref().map(|parent| support_area(me, parent)),
                Holder::Obstacle(k) => obstacles.get(k).map(|parent| support_area(me, parent)),
                _ => None,
            };
            // A child that does not stand on this model is the child's conflict, not this
            // one's: the search above has already preferred candidates that hold their children,
            // and leaving the holder as its box would start everything else it holds inside it.
            let tips_over = holders[i] != Holder::Other && !me.stands();
            let conflicts = usize::from(overlapped)
                + usize::from(obstacle_penetration_m > MAX_OBSTACLE_PENETRATION_M)
                + usize::from(held_penetration_m > MAX_PENETRATION_M)
                + usize::from(layout_penetration_m > MAX_PENETRATION_M)
                + usize::from(held_area.is_some_and(|a| a < MIN_SUPPORT_AREA))
                + usize::from(tips_over);
            Some(PlacementCheck {
                chosen: choice[i]?,
                tips_over,
                max_penetration_m,
                layout_penetration_m,
                support_area: held_area,
                conflicts,
                separated_m: separated_m[i],
            })
        })
        .collect()
}

/// Whether object `i` keeps its placement where its model and `j`'s overlap: it holds `j`, or
/// `j` does not hold it and it is fixed while `j` is movable, or, both alike, more objects rest
/// on it (directly or not). At a tie neither does, and both are left in conflict.
fn keeps_place(i: usize, j: usize, holders: &[Holder], movable: &[bool]) -> bool {
    if holders[j] == Holder::Object(i) {
        return true;
    }
    if holders[i] == Holder::Object(j) {
        return false;
    }
    let resting_on = |o: usize| {
        (0..holders.len())
            .filter(|&c| {
                let mut at = c;
                for _ in 0..holders.len() {
                    match holders[at] {
                        Holder::Object(p) if p == o => return true,
                        Holder::Object(p) => at = p,
                        _ => return false,
                    }
                }
                false
            })
            .count()
    };
    (!movable[i], resting_on(i)) > (!movable[j], resting_on(j))
}
