//! The global physical check of CAD placements (Han et al., Sect. 4.3): placed models must not
//! interpenetrate each other or the layout, and every object resting on another must stand on
//! enough of its supporting surface. A min-conflict search over each object's aligned candidates
//! (start from the best, move the most conflicted object to its least conflicting candidate,
//! bounded) picks the final models; neighbours still overlapping side by side are pulled apart
//! (`separation`); then every model is snapped onto its supporting surface (`snapping`) and
//! judged (`placement_verdict`).

use std::borrow::Cow;

use glam::Affine3A;
use rayon::prelude::*;
use serde::Serialize;

use crate::cad::db::database::DatabaseModel;
pub use crate::cad::placed_solid::{
    PlacedSolid, deepest_contact, layout_penetration, penetration_depth, support_area,
};
use crate::cad::replace::height_fit::fit_heights_to_children;
use crate::cad::replace::placement_verdict::placement_verdicts;
use crate::cad::replace::separation::{parted, retreat_from_walls, separate_neighbours};
use crate::cad::replace::sizing::built_to_fit;
use crate::cad::replace::snapping::{Snapped, snap_onto_holders};
use crate::geometry::Plane;

/// Deeper interpenetration than this (metres) is a conflict (the bar).
pub const MAX_PENETRATION_M: f32 = 0.01;
/// A child must stand on at least this share of its bottom rectangle (the contact graph's
/// stable-support bar).
pub const MIN_SUPPORT_AREA: f32 = 0.5;
/// What holds an object up, as the check needs it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Holder {
    /// Another object (index among the checked objects).
    Object(usize),
    /// An obstacle (index among the check's obstacles): an object no model replaced.
    Obstacle(usize),
    /// The floor plane.
    Floor(Plane),
    /// A wall, or nothing: no support test, no snapping.
    Other,
}

/// The final state of one object's placement.
#[derive(Clone, Debug, Serialize)]
pub struct PlacementCheck {
    /// Which of the object's aligned candidates was chosen (0: the best by alignment).
    pub chosen: usize,
    /// Deepest interpenetration with another object, metres.
    pub max_penetration_m: f32,
    /// Deepest reach behind the floor or a wall, metres.
    pub layout_penetration_m: f32,
    /// Share of its bottom on the parent model's surface, when another object holds it.
    pub support_area: Option<f32>,
    /// Conflicts left: penetrations over 1 cm (layout, or another model when this one yields
    /// to it), any into an obstacle, failed support tests, tipping over.
    pub conflicts: usize,
    /// How far it was pulled apart from its neighbours and out of walls (metres): moved, for a
    /// movable object, or taken off its width or depth, for a fixed one; with how far a movable
    /// object overhanging what holds it was slid back onto it (`on_holder`). Over a few
    /// centimetres this is the map's segmentation at fault (one label bled over the neighbour)
    /// or a model deeper than the object (big handles), fixed here, not hidden.
    pub separated_m: f32,
    /// Its centre of mass is not over what it stands on (`PlacedSolid::stands`).
    pub tips_over: bool,
}

/// The min-conflict choice of every object's placement, snapped onto its support.
pub struct CheckedPlacements {
    /// Per object: the chosen alignment's index and its world-from-model after snapping.
    pub chosen: Vec<Option<(usize, Affine3A)>>,
    pub checks: Vec<Option<PlacementCheck>>,
    /// Objects moved off their best alignment by the search.
    pub swaps: usize,
    /// Per object: the chosen model as built to its fitted size, when it is a library model
    /// (`sizing`); the pose in `chosen` places this model, not the database's.
    pub built: Vec<Option<DatabaseModel>>,
}

/// Search steps at most (each moves one object to another candidate).
const MAX_SEARCH_STEPS: usize = 64;

/// Chooses among each object's `alignments` (database model and world-from-model, best first)
/// so that as few conflicts as possible remain, pulls overlapping neighbours apart, then snaps
/// every model onto what holds it. `holders` says what holds each object; `movable` which
/// objects may be moved rather than shrunk when neighbours overlap; `layout` are the floor's
/// and walls' planes, facing into the room; `obstacles` the objects that keep their segment
/// meshes, which neither move nor shrink (a counter no model replaced), and `obstacle_holders`
/// the object that holds each, when one of `alignments`' objects does (empty: none).
pub fn check_placements(
    alignments: &[Vec<(&DatabaseModel, Affine3A)>],
    holders: &[Holder],
    movable: &[bool],
    layout: &[Plane],
    obstacles: &[PlacedSolid],
    obstacle_holders: &[Option<usize>],
) -> CheckedPlacements {
    // Library models are built to the size they were fitted at rather than stretched to it
    // (`sizing`), then fitted in height to what they hold.
    let sized: Vec<Vec<(Cow<DatabaseModel>, Affine3A)>> = alignments
        .par_iter()
        .map(|options| {
            options
                .iter()
                .map(|&(model, pose)| match built_to_fit(model, &pose) {
                    Some((built, pose)) => (Cow::Owned(built), pose),
                    None => (Cow::Borrowed(model), pose),
                })
                .collect()
        })
        .collect();
    let fitted = fit_heights_to_children(sized, holders);
    let alignments: &Vec<Vec<(&DatabaseModel, Affine3A)>> = &fitted
        .iter()
        .map(|options| {
            options
                .iter()
                .map(|(model, pose)| (model.as_ref(), *pose))
                .collect()
        })
        .collect();
    let solids: Vec<Vec<PlacedSolid>> = alignments
        .par_iter()
        .map(|options| {
            options
                .iter()
                .map(|(model, pose)| PlacedSolid::new(model, pose))
                .collect()
        })
        .collect();
    let n = alignments.len();
    let stands: Vec<Vec<bool>> = solids
        .par_iter()
        .map(|options| options.iter().map(PlacedSolid::stands).collect())
        .collect();
    let mut choice: Vec<Option<usize>> = solids
        .iter()
        .map(|s| (!s.is_empty()).then_some(0))
        .collect();
    // Object i (as `me`) overlapping `other` (object j, or obstacle j - n) is a conflict
    // unless one is movable and pulling apart will undo it: a chair tucked under the table is no
    // reason to choose another table, whose next best model, taller, leaves the cups inside its
    // top. (Two fixed neighbours are shrunk apart; another candidate may spare that.)
    let conflict = |i: usize, me: &PlacedSolid, j: usize, other: &PlacedSolid| {
        let Some((depth, normal)) = deepest_contact(me, other) else {
            return false;
        };
        let movable_pair = movable[i] || (j < n && movable[j]);
        depth > MAX_PENETRATION_M
            && !(movable_pair && parted(i, j, depth, normal, me, other, holders, movable).is_some())
    };
    let conflicts_of = |i: usize, k: usize, choice: &[Option<usize>]| -> usize {
        let me = &solids[i][k];
        let placed = |j: usize| choice[j].map(|m| &solids[j][m]);
        let mut count = usize::from(layout_penetration(me, layout) > MAX_PENETRATION_M);
        count += usize::from(holders[i] != Holder::Other && !stands[i][k]);
        count += obstacles
            .iter()
            .enumerate()
            .filter(|(k, o)| conflict(i, me, n + k, o))
            .count();
        for j in (0..n).filter(|&j| j != i) {
            if let Some(other) = placed(j) {
                count += usize::from(conflict(i, me, j, other));
                if holders[j] == Holder::Object(i) {
                    count += usize::from(support_area(other, me) < MIN_SUPPORT_AREA);
                }
            }
        }
        let parent = match holders[i] {
            Holder::Object(p) => placed(p),
            Holder::Obstacle(k) => obstacles.get(k),
            _ => None,
        };
        if let Some(parent) = parent {
            count += usize::from(support_area(me, parent) < MIN_SUPPORT_AREA);
        }
        count
    };
    let mut tried_in_vain = vec![false; n];
    for _ in 0..MAX_SEARCH_STEPS {
        let current: Vec<usize> = (0..n)
            .map(|i| choice[i].map_or(0, |k| conflicts_of(i, k, &choice)))
            .collect();
        let Some(worst) = (0..n)
            .filter(|&i| current[i] > 0 && !tried_in_vain[i])
            .max_by_key(|&i| (current[i], std::cmp::Reverse(i)))
        else {
            break;
        };
        let best = (0..solids[worst].len())
            .map(|k| (conflicts_of(worst, k, &choice), k))
            .min();
        match best {
            Some((c, k)) if c < current[worst] => {
                tracing::debug!(
                    "physical check: {} ({} conflicts) gives way to {} ({c})",
                    choice[worst].map_or("nothing", |m| alignments[worst][m].0.model.id.as_str()),
                    current[worst],
                    alignments[worst][k].0.model.id,
                );
                choice[worst] = Some(k);
                tried_in_vain.iter_mut().for_each(|t| *t = false);
            }
            _ => tried_in_vain[worst] = true,
        }
    }
    let swaps = choice
        .iter()
        .filter(|c| matches!(c, Some(k) if *k > 0))
        .count();
    let mut poses: Vec<Option<Affine3A>> = (0..n)
        .map(|i| choice[i].map(|k| alignments[i][k].1))
        .collect();
    let models: Vec<Option<&DatabaseModel>> = (0..n)
        .map(|i| choice[i].map(|k| alignments[i][k].0))
        .collect();
    let retreated_m = retreat_from_walls(&models, movable, layout, &mut poses);
    let separated = separate_neighbours(&models, holders, movable, obstacles, &mut poses);
    let Snapped { finals, slid_m } =
        snap_onto_holders(&models, holders, movable, obstacles, &mut poses);
    let separated_m: Vec<f32> = (0..n)
        .map(|i| separated[i] + retreated_m[i] + slid_m[i])
        .collect();
    let checks = placement_verdicts(
        &finals,
        &choice,
        &separated_m,
        holders,
        movable,
        layout,
        obstacles,
        obstacle_holders,
    );
    CheckedPlacements {
        chosen: (0..n).map(|i| Some((choice[i]?, poses[i]?))).collect(),
        checks,
        swaps,
        built: (0..n)
            .map(|i| match &fitted[i][choice[i]?].0 {
                Cow::Owned(built) => Some(built.clone()),
                Cow::Borrowed(_) => None,
            })
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    use crate::cad::db::database::CadDatabase;
    use crate::cad::replace::placement_verdict::MAX_OBSTACLE_PENETRATION_M;

    fn model_of<'a>(db: &'a CadDatabase, id: &str) -> &'a DatabaseModel {
        db.models()
            .iter()
            .find(|m| m.model.id == id)
            .expect("model")
    }

    fn placed(db: &CadDatabase, id: &str, at: Vec3) -> PlacedSolid {
        PlacedSolid::new(model_of(db, id), &Affine3A::from_translation(at))
    }

    #[test]
    fn a_cup_on_a_table_is_supported_and_one_sunk_into_it_penetrates() {
        let db = CadDatabase::parametric();
        let table = placed(&db, "table_01", Vec3::ZERO);
        let top = table.hi.z;
        let cup = placed(&db, "cup_01", Vec3::new(0.2, 0.1, top));
        assert!(support_area(&cup, &table) > 0.99);
        assert!(penetration_depth(&cup, &table) < 1e-3);
        let sunk = placed(&db, "cup_01", Vec3::new(0.2, 0.1, top - 0.03));
        let depth = penetration_depth(&sunk, &table);
        assert!((depth - 0.03).abs() < 0.005, "depth {depth}");
        // Half over the edge: about half supported.
        let edge_x = table.hi.x;
        let half = placed(&db, "cup_01", Vec3::new(edge_x, 0.0, top));
        let area = support_area(&half, &table);
        assert!((0.3..0.7).contains(&area), "area {area}");
        // Through the floor.
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let low = placed(&db, "table_01", Vec3::new(0.0, 0.0, -0.02));
        assert!((layout_penetration(&low, &[floor]) - 0.02).abs() < 1e-3);
        assert!(layout_penetration(&table, &[floor]) < 1e-4);
    }

    #[test]
    fn the_search_moves_a_sunk_cup_to_a_candidate_that_rests_on_the_table_and_snaps_it() {
        let db = CadDatabase::parametric();
        let model = |id: &str| model_of(&db, id);
        let table = model("table_01");
        let top = table.model.size.z;
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let cup = model("cup_01");
        let book = model("book_01");
        let book_at = |x: f32| vec![(book, Affine3A::from_translation(Vec3::new(x, -0.2, top)))];
        let alignments = vec![
            vec![(table, Affine3A::IDENTITY)],
            vec![
                // Best by alignment, but 4 cm into the table top.
                (
                    cup,
                    Affine3A::from_translation(Vec3::new(0.2, 0.1, top - 0.04)),
                ),
                // Second best: floating 5 mm above it.
                (
                    cup,
                    Affine3A::from_translation(Vec3::new(0.2, 0.1, top + 0.005)),
                ),
            ],
            // Two books seen on the top: the table's height is not fitted to the sunk cup.
            book_at(-0.4),
            book_at(0.4),
        ];
        let holders = [
            Holder::Floor(floor),
            Holder::Object(0),
            Holder::Object(0),
            Holder::Object(0),
        ];
        let movable = [false, true, true, true];
        let checked = check_placements(&alignments, &holders, &movable, &[floor], &[], &[]);
        let (k, pose) = checked.chosen[1].expect("cup placed");
        assert_eq!(k, 1, "the cup that does not sink in");
        assert_eq!(checked.swaps, 1);
        assert!(
            (pose.translation.z - top).abs() < 1e-4,
            "snapped onto the top: {}",
            pose.translation.z
        );
        let check = checked.checks[1].as_ref().expect("cup check");
        assert_eq!(check.conflicts, 0, "{check:?}");
        assert!(check.support_area.expect("held by the table") > 0.99);
    }

    #[test]
    fn a_holder_keeps_its_model_when_a_chair_is_pushed_into_it_or_a_child_misses_its_top() {
        let db = CadDatabase::parametric();
        let model = |id: &str| model_of(&db, id);
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let table = model("table_01");
        let top = table.model.size.z;
        let at = |m: &'static str, p: Vec3| vec![(model(m), Affine3A::from_translation(p))];
        let alignments = vec![
            vec![(table, Affine3A::IDENTITY)],
            // A cup on the top.
            at("cup_01", Vec3::new(0.3, 0.1, top)),
            // A book "on" the table that is seen beside it, over nothing.
            at("book_01", Vec3::new(1.5, 0.0, top)),
            // A chair standing 35 cm into the table's middle: no pulling apart undoes that.
            at("chair_01", Vec3::new(0.0, 0.05, 0.0)),
        ];
        let holders = [
            Holder::Floor(floor),
            Holder::Object(0),
            Holder::Object(0),
            Holder::Floor(floor),
        ];
        let movable = [false, true, true, true];
        let checked = check_placements(&alignments, &holders, &movable, &[floor], &[], &[]);
        let check = |i: usize| checked.checks[i].as_ref().expect("checked");
        assert!(check(0).max_penetration_m > 0.1, "{:?}", check(0));
        assert_eq!(check(0).conflicts, 0, "the table stays: {:?}", check(0));
        assert_eq!(check(1).conflicts, 0, "{:?}", check(1));
        assert!(
            check(2).conflicts > 0,
            "the book over nothing: {:?}",
            check(2)
        );
        assert!(
            check(3).conflicts > 0,
            "the chair in the table: {:?}",
            check(3)
        );
    }

    #[test]
    fn two_cabinets_overlapping_deep_are_shrunk_to_the_middle_but_a_movable_object_is_not_moved() {
        let db = CadDatabase::parametric();
        let model = |id: &str| model_of(&db, id);
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let cabinet = model("cabinet_01");
        let width = cabinet.model.size.x;
        // Side by side along x, 30 cm inside each other.
        let overlap = 0.3;
        let at = |x: f32| vec![(cabinet, Affine3A::from_translation(Vec3::X * x))];
        let alignments = vec![at(0.0), at(width - overlap)];
        let holders = [Holder::Floor(floor), Holder::Floor(floor)];
        let checked = check_placements(&alignments, &holders, &[false, false], &[floor], &[], &[]);
        let solids: Vec<PlacedSolid> = (0..2)
            .map(|i| PlacedSolid::new(cabinet, &checked.chosen[i].expect("placed").1))
            .collect();
        assert!(penetration_depth(&solids[0], &solids[1]) < 0.005);
        // Each gave up half the overlap; their far sides stayed.
        let middle = width - overlap / 2.0 - cabinet.model.size.x / 2.0;
        assert!(
            (solids[0].hi.x - middle).abs() < 0.01,
            "{} vs {middle}",
            solids[0].hi.x
        );
        assert!(
            (solids[1].lo.x - middle).abs() < 0.01,
            "{} vs {middle}",
            solids[1].lo.x
        );
        assert!((solids[0].lo.x + width / 2.0).abs() < 1e-3);
        for check in checked.checks.iter().flatten() {
            assert_eq!(check.conflicts, 0, "{check:?}");
            assert!(
                (check.separated_m - overlap / 2.0).abs() < 0.01,
                "{check:?}"
            );
        }

        // The same overlap with a movable object (as if the second were a chair) is a
        // segmentation fault too deep to move it over: it stays, reported.
        let alignments = vec![at(0.0), at(width - overlap)];
        let checked = check_placements(&alignments, &holders, &[false, true], &[floor], &[], &[]);
        let check = checked.checks[1].as_ref().expect("second check");
        assert_eq!(check.separated_m, 0.0);
        assert!(check.conflicts > 0, "{check:?}");
    }

    #[test]
    fn a_chair_tucked_into_an_obstacle_is_pulled_out_of_it() {
        let db = CadDatabase::parametric();
        let chair = model_of(&db, "chair_01");
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        // A counter no model replaced, seen as a box 2 m long, 0.6 m deep and 0.9 m tall, its
        // front at y = 0.
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                Vec3::new(
                    [0.0, 2.0][k & 1],
                    [0.0, 0.6][(k >> 1) & 1],
                    [0.0, 0.9][k >> 2],
                )
            })
            .collect();
        let counter = PlacedSolid::from_hull(&corners).expect("a box spans volume");
        assert!((counter.hi - Vec3::new(2.0, 0.6, 0.9)).length() < 1e-5);
        let depth = chair.model.size.y;
        let tucked = Affine3A::from_translation(Vec3::new(1.0, -depth / 2.0 + 0.08, 0.0));
        let before = PlacedSolid::new(chair, &tucked);
        assert!((penetration_depth(&before, &counter) - 0.08).abs() < 0.01);
        let checked = check_placements(
            &[vec![(chair, tucked)]],
            &[Holder::Floor(floor)],
            &[true],
            &[floor],
            std::slice::from_ref(&counter),
            &[],
        );
        let (_, pose) = checked.chosen[0].expect("placed");
        let after = PlacedSolid::new(chair, &pose);
        assert!(penetration_depth(&after, &counter) < 0.005);
        assert!(
            pose.translation.y < tucked.translation.y - 0.07,
            "pulled out to the front"
        );
        let check = checked.checks[0].as_ref().expect("check");
        assert_eq!(check.conflicts, 0, "{check:?}");
        assert!((0.07..0.1).contains(&check.separated_m), "{check:?}");
    }

    #[test]
    fn a_chair_squeezed_between_two_obstacles_is_in_conflict() {
        let db = CadDatabase::parametric();
        let chair = model_of(&db, "chair_01");
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let width = chair.model.size.x;
        // Two counters 0.6 m deep whose gap is 6 mm narrower than the chair, the chair in it: too
        // little overlap for a conflict of its own (`MAX_PENETRATION_M`), and none that parts.
        let counter = |x0: f32, x1: f32| {
            let corners: Vec<Vec3> = (0..8)
                .map(|k| {
                    Vec3::new(
                        [x0, x1][k & 1],
                        [0.0, 0.6][(k >> 1) & 1],
                        [0.0, 0.9][k >> 2],
                    )
                })
                .collect();
            PlacedSolid::from_hull(&corners).expect("a box spans volume")
        };
        let counters = [counter(0.0, 1.0), counter(1.0 + width - 0.006, 2.0 + width)];
        let squeezed = Affine3A::from_translation(Vec3::new(1.0 + width / 2.0 - 0.003, 0.3, 0.0));
        let checked = check_placements(
            &[vec![(chair, squeezed)]],
            &[Holder::Floor(floor)],
            &[true],
            &[floor],
            &counters,
            &[],
        );
        let check = checked.checks[0].as_ref().expect("check");
        assert!(
            (MAX_OBSTACLE_PENETRATION_M..MAX_PENETRATION_M).contains(&check.max_penetration_m),
            "{check:?}"
        );
        assert!(check.conflicts > 0, "{check:?}");
    }

    #[test]
    fn a_thing_no_model_replaced_lying_on_a_table_is_no_conflict_of_the_table() {
        let db = CadDatabase::parametric();
        let table = model_of(&db, "table_01");
        let top = table.model.size.z;
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        // A 1 cm "book" seen on the top, its box 1.5 mm into the table's model.
        let corners: Vec<Vec3> = (0..8)
            .map(|k| {
                Vec3::new(
                    [-0.1, 0.1][k & 1],
                    [-0.1, 0.1][(k >> 1) & 1],
                    [top - 0.0015, top + 0.0085][k >> 2],
                )
            })
            .collect();
        let book = PlacedSolid::from_hull(&corners).expect("a box spans volume");
        let check = |holder: Option<usize>| {
            let checked = check_placements(
                &[vec![(table, Affine3A::IDENTITY)]],
                &[Holder::Floor(floor)],
                &[false],
                &[floor],
                std::slice::from_ref(&book),
                &[holder],
            );
            checked.checks[0].clone().expect("check")
        };
        let holding = check(Some(0));
        assert_eq!(holding.conflicts, 0, "{holding:?}");
        assert!(holding.max_penetration_m > MAX_OBSTACLE_PENETRATION_M);
        // The same box not on it is an obstacle the table may not enter.
        assert!(check(None).conflicts > 0);
    }

    #[test]
    fn chairs_overlapping_a_table_are_pulled_away_rather_than_the_table_swapped_for_a_worse_fit() {
        let db = CadDatabase::parametric();
        let model = |id: &str| model_of(&db, id);
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let (table, chair, cup) = (model("table_01"), model("chair_01"), model("cup_01"));
        let (half, top) = (table.model.size.x / 2.0, table.model.size.z);
        // The table's best fit, and a narrower, taller second one that no chair touches but
        // whose top is 7.5 cm above the cup.
        let best = Affine3A::IDENTITY;
        let second = Affine3A::from_scale(Vec3::new(0.85, 1.0, 1.1));
        // A chair on either end, 5 cm into the table (tucked under its top).
        let chair_at = |x: f32| vec![(chair, Affine3A::from_translation(Vec3::X * x))];
        let reach = half + chair.model.size.x / 2.0 - 0.05;
        let on_top = Affine3A::from_translation(Vec3::new(0.2, 0.1, top));
        let holders = [
            Holder::Floor(floor),
            Holder::Floor(floor),
            Holder::Floor(floor),
            Holder::Object(0),
        ];
        let movable = [false, true, true, true];
        let alignments = vec![
            vec![(table, best), (table, second)],
            chair_at(reach),
            chair_at(-reach),
            vec![(cup, on_top)],
        ];
        let checked = check_placements(&alignments, &holders, &movable, &[floor], &[], &[]);
        assert_eq!(
            checked.chosen[0].expect("table").0,
            0,
            "the table's best fit"
        );
        let solids: Vec<PlacedSolid> = (0..4)
            .map(|i| {
                let (k, pose) = checked.chosen[i].expect("placed");
                PlacedSolid::new(alignments[i][k].0, &pose)
            })
            .collect();
        for chair in &solids[1..3] {
            assert!(penetration_depth(chair, &solids[0]) < 0.005);
        }
        for check in checked.checks.iter().flatten() {
            assert_eq!(check.conflicts, 0, "{check:?}");
        }

        // With only the taller table, its height is fitted to the cup it holds: its top comes
        // down to where the cup was seen standing.
        let alignments = vec![vec![(table, second)], vec![(cup, on_top)]];
        let holders = [Holder::Floor(floor), Holder::Object(0)];
        let checked = check_placements(&alignments, &holders, &[false, true], &[floor], &[], &[]);
        let (_, table_pose) = checked.chosen[0].expect("table");
        let table_top = PlacedSolid::new(table, &table_pose).hi.z;
        assert!((table_top - top).abs() < 1e-3, "{table_top}");
        let (_, pose) = checked.chosen[1].expect("cup");
        assert!(
            (pose.translation.z - top).abs() < 1e-3,
            "{}",
            pose.translation.z
        );
        let check = checked.checks[1].as_ref().expect("cup check");
        assert!(check.support_area.expect("held") > 0.99, "{check:?}");
    }
}
