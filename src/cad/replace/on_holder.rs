//! Sliding a movable object that overhangs what holds it back onto it. The contact graph saw it
//! standing there, so in the room it stood; but a model fitted to a partial segment, then
//! pulled apart from its neighbours (`separation`), can end with half its bottom past its
//! support's edge. The physical check's support bar (half the bottom held) lets that pass, and a
//! simulator drops it: over seeds 0-49, a box held on 0.50 of its bottom fell 72 cm off its
//! cabinet (seed 31), and a cup held on 0.50 tipped 15 degrees (seed 16). A slide that would
//! push the object into a neighbour is no way back: a cup pulled to the edge by the neighbour
//! behind it stays there, and the rest test reports it (seed 22).

use glam::{Affine3A, Vec2};

use crate::cad::db::database::DatabaseModel;
use crate::cad::placed_solid::{PlacedSolid, penetration_depth, support_area};

/// A movable object held on less than this share of its bottom rectangle is slid back.
const FULLY_HELD: f32 = 0.9;
/// Horizontal directions tried, evenly spaced (the first along +x: deterministic ties).
const SLIDE_DIRECTIONS: usize = 16;
/// Step (metres) of the slide distances tried, nearest first.
const SLIDE_STEP_M: f32 = 0.005;
/// A slide may take an object this much deeper (metres) into a neighbour or its holder than it
/// already is: the check's separation leaves neighbours 2 mm apart.
const SLIDE_CONTACT_SLACK_M: f32 = 0.001;

/// Whether `solid` stands on less than `FULLY_HELD` of its bottom on `holder`: what `slide_onto`
/// slides.
pub(crate) fn overhangs(solid: &PlacedSolid, holder: &PlacedSolid) -> bool {
    support_area(solid, holder) < FULLY_HELD
}

/// The shortest horizontal slide of `solid` (a movable object's model at `pose`) that puts at
/// least `FULLY_HELD` of its bottom on `holder`'s surface without taking it deeper into the
/// holder or any of `neighbours`, at most half its bottom's longer side (as far as a bottom half
/// over the edge needs); `None` when it is held enough already or no slide within that does it.
/// The slide's pose and its length in metres.
pub(crate) fn slide_onto(
    solid: &PlacedSolid,
    pose: &Affine3A,
    model: &DatabaseModel,
    holder: &PlacedSolid,
    neighbours: &[PlacedSolid],
) -> Option<(Affine3A, f32)> {
    if !overhangs(solid, holder) {
        return None;
    }
    let [c0, c1, _, c3] = solid.footprint;
    let reach = 0.5 * (c1 - c0).length().max((c3 - c0).length());
    let depth_bar = |other: &PlacedSolid| penetration_depth(solid, other) + SLIDE_CONTACT_SLACK_M;
    let holder_bar = depth_bar(holder);
    let neighbour_bars: Vec<f32> = neighbours.iter().map(depth_bar).collect();
    let steps = (reach / SLIDE_STEP_M).ceil() as usize;
    (1..=steps).find_map(|step| {
        let distance = step as f32 * SLIDE_STEP_M;
        (0..SLIDE_DIRECTIONS).find_map(|k| {
            let angle = std::f32::consts::TAU * k as f32 / SLIDE_DIRECTIONS as f32;
            let shift = Vec2::from_angle(angle) * distance;
            let slid = Affine3A::from_translation(shift.extend(0.0)) * *pose;
            let moved = PlacedSolid::new(model, &slid);
            let held = support_area(&moved, holder) >= FULLY_HELD
                && penetration_depth(&moved, holder) <= holder_bar
                && neighbours
                    .iter()
                    .zip(&neighbour_bars)
                    .all(|(n, &bar)| penetration_depth(&moved, n) <= bar);
            held.then_some((slid, distance))
        })
    })
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::cad::db::database::CadDatabase;

    fn model<'a>(db: &'a CadDatabase, id: &str) -> &'a DatabaseModel {
        db.get(id).expect("a library model")
    }

    /// The library's table at the origin.
    fn table(db: &CadDatabase) -> PlacedSolid {
        PlacedSolid::new(model(db, "table_01"), &Affine3A::IDENTITY)
    }

    /// The library's table at the origin, and the cup standing on its top at `xy`.
    fn cup_on_table(db: &CadDatabase, xy: Vec2) -> (PlacedSolid, PlacedSolid, Affine3A) {
        let table = table(db);
        let pose = Affine3A::from_translation(xy.extend(table.hi.z));
        let cup = PlacedSolid::new(model(db, "cup_01"), &pose);
        (table, cup, pose)
    }

    #[test]
    fn a_cup_half_over_the_edge_slides_back_onto_the_table_the_shortest_way() {
        let db = CadDatabase::parametric();
        let edge = table(&db).hi.x;
        let (table, cup, pose) = cup_on_table(&db, Vec2::new(edge, 0.0));
        assert!(support_area(&cup, &table) < FULLY_HELD);
        let model = model(&db, "cup_01");
        let (slid, distance) = slide_onto(&cup, &pose, model, &table, &[]).expect("a slide");
        assert!(support_area(&PlacedSolid::new(model, &slid), &table) >= FULLY_HELD);
        let shift = Vec3::from(slid.translation - pose.translation);
        assert!(
            shift.x < 0.0 && shift.y.abs() < 1e-4 && shift.z == 0.0,
            "{shift}"
        );
        let width = cup.hi.x - cup.lo.x;
        assert!(distance <= 0.5 * width, "{distance} m for a {width} m cup");
    }

    #[test]
    fn a_cup_well_on_the_table_stays() {
        let db = CadDatabase::parametric();
        let (table, cup, pose) = cup_on_table(&db, Vec2::new(0.1, 0.05));
        let model = model(&db, "cup_01");
        assert!(slide_onto(&cup, &pose, model, &table, &[]).is_none());
    }

    #[test]
    fn a_slide_never_pushes_into_a_neighbour() {
        let db = CadDatabase::parametric();
        let edge = table(&db).hi.x;
        let (table, cup, pose) = cup_on_table(&db, Vec2::new(edge, 0.0));
        let width = cup.hi.x - cup.lo.x;
        // A second cup 2 mm behind it: the way straight back, the shortest, is taken.
        let (_, behind, _) = cup_on_table(&db, Vec2::new(edge - width - 0.002, 0.0));
        let model = model(&db, "cup_01");
        let (free, _) = slide_onto(&cup, &pose, model, &table, &[]).expect("a slide");
        assert!(penetration_depth(&PlacedSolid::new(model, &free), &behind) > 0.005);
        if let Some((slid, _)) =
            slide_onto(&cup, &pose, model, &table, std::slice::from_ref(&behind))
        {
            let moved = PlacedSolid::new(model, &slid);
            assert!(penetration_depth(&moved, &behind) <= SLIDE_CONTACT_SLACK_M);
            assert!(support_area(&moved, &table) >= FULLY_HELD);
        }
    }

    #[test]
    fn nothing_within_reach_to_slide_onto_is_no_slide() {
        let db = CadDatabase::parametric();
        let edge = table(&db).hi.x;
        let (table, cup, pose) = cup_on_table(&db, Vec2::new(edge + 0.5, 0.0));
        let model = model(&db, "cup_01");
        assert!(slide_onto(&cup, &pose, model, &table, &[]).is_none());
    }
}
