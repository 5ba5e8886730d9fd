//! Pulling apart what the physical check's search left overlapping: neighbours side by side
//! (a movable one moved, two fixed ones shrunk apart) and models reaching behind a wall.

use glam::{Affine3A, Vec3};

use crate::cad::db::database::DatabaseModel;
use crate::cad::placed_solid::{PlacedSolid, deepest_contact, layout_penetration, overlap_along};
use crate::cad::replace::physical_check::{Holder, MAX_PENETRATION_M};
use crate::geometry::Plane;

/// Side by side, neighbours overlapping by at most this much (metres) are pulled apart when one
/// of them is movable; more is a segmentation fault (a cup's label over its neighbour) that
/// moving it would hide. Two fixed neighbours (cabinets in a row) are shrunk apart however deep
/// they overlap, as long as each keeps over half its width: flush fronts fuse in a 2 cm map, and
/// one label can bleed over most of its neighbour's shared top. Both were widened by the same
/// bleeding across their shared boundary, so the middle of the overlap is the best guess of it,
/// and two models sharing a third of a metre stand in no simulator. `separated_m` records it.
const MAX_SEPARATED_M: f32 = 0.1;
/// ... or this share of the movable object's width, if more: a chair pushed under a table or a
/// counter, its model taller than the knee space, starts 10-12 cm inside it (7-Scenes
/// redkitchen), and is pulled out rather than left in.
const MAX_SEPARATED_SHARE: f32 = 0.3;
/// How deep (metres) a neighbour may overlap `solid`, when it is movable, and still be pulled
/// apart from it: `MAX_SEPARATED_M` or `MAX_SEPARATED_SHARE` of its width.
fn separation_limit(solid: &PlacedSolid) -> f32 {
    MAX_SEPARATED_M.max(MAX_SEPARATED_SHARE * (solid.hi - solid.lo).truncate().max_element())
}
/// Rounds of pulling apart (a pair's separation can push one into a third).
const SEPARATION_ROUNDS: usize = 10;
/// Pulled-apart neighbours end this far apart (metres).
const SEPARATION_GAP_M: f32 = 0.002;
/// Neighbours overlapping by more than this (metres) are pulled apart: simulators take any
/// overlap as a contact to resolve at the first step, and MuJoCo's rest test counts over 1 mm
/// as a start overlap (two books on a table shared 2 mm).
const SEPARATION_TOLERANCE_M: f32 = 0.0005;
/// A fixed model (a cabinet) reaching behind a wall by more than this (metres) is shrunk out of
/// it; a movable one is moved out past `SEPARATION_TOLERANCE_M`. Walls are planes fitted to
/// noisy depth, and a cabinet shrunk off a wall by a few millimetres squeezed its neighbours in
/// a row of three (the rendered kitchen's imported cabinets) past what ten rounds of
/// `separate_neighbours` undo: 1.1 cm left between two of them.
const WALL_SHRINK_TOLERANCE_M: f32 = 0.5 * MAX_PENETRATION_M;

/// Neighbours that interpenetrate side by side (by no more than the movable one's
/// `separation_limit`, when one is movable) are pulled apart horizontally: along the contact
/// normal when it is horizontal and, for two objects on one support, roughly along the line
/// between their centres; else, for such two (which cannot part vertically), along that line. A
/// movable object (a cup) is moved; a fixed one (a cabinet) is shrunk with its far side kept: two
/// fixed neighbours were widened by the same bleeding across their shared boundary, so the truth
/// lies in the middle. Against an obstacle (`obstacles`: it neither moves nor shrinks) the
/// object gives way alone. Returns how far each object was moved or shrunk, metres.
pub(crate) fn separate_neighbours(
    models: &[Option<&DatabaseModel>],
    holders: &[Holder],
    movable: &[bool],
    obstacles: &[PlacedSolid],
    poses: &mut [Option<Affine3A>],
) -> Vec<f32> {
    let n = models.len();
    let mut separated = vec![0.0f32; n];
    for _ in 0..SEPARATION_ROUNDS {
        let solids: Vec<Option<PlacedSolid>> = (0..n)
            .map(|i| Some(PlacedSolid::new(models[i]?, &poses[i]?)))
            .collect();
        let mut moved = false;
        for i in 0..n {
            // The other objects after this one, then every obstacle (index n + k).
            let later = ((i + 1)..n).filter_map(|j| Some((j, solids[j].as_ref()?)));
            let fixed = obstacles.iter().enumerate().map(|(k, o)| (n + k, o));
            for (j, b) in later.chain(fixed) {
                let Some(a) = &solids[i] else {
                    continue;
                };
                let Some((depth, normal)) = deepest_contact(a, b) else {
                    continue;
                };
                if depth <= SEPARATION_TOLERANCE_M {
                    continue;
                }
                let Some(direction) = parted(i, j, depth, normal, a, b, holders, movable) else {
                    continue;
                };
                let obstacle = j >= n;
                let b_movable = !obstacle && movable[j];
                // Parting across the contact normal, the depth is not how far: two books lying
                // 2 cm over each other's edge touch 2 mm deep, up, and rounds of 2 mm steps left
                // them overlapping. Their overlap along the line is, up to `MAX_SEPARATED_M`;
                // more (a chair under a table, overlapping it 40 cm along the line between
                // their centres) is left to the rounds' steps, as before, which pull the chair
                // partly out without moving the table by half of it.
                let far = match overlap_along(a, b, direction) {
                    along if direction.dot(normal) < 0.9 && along <= MAX_SEPARATED_M => along,
                    _ => depth,
                };
                let push = far + 2.0 * SEPARATION_GAP_M;
                let share = match (movable[i], b_movable) {
                    _ if obstacle => [1.0, 0.0],
                    (true, false) => [1.0, 0.0],
                    (false, true) => [0.0, 1.0],
                    _ => [0.5, 0.5],
                };
                for ((k, away), part) in [(i, -direction), (j, direction)].into_iter().zip(share) {
                    if part == 0.0 {
                        continue;
                    }
                    if let (Some(pose), Some(solid)) = (poses[k], &solids[k]) {
                        let parted = if movable[k] {
                            Some(Affine3A::from_translation(away * part * push) * pose)
                        } else {
                            shrink_from(pose, solid, away, part * push)
                        };
                        if let Some(parted) = parted {
                            poses[k] = Some(parted);
                            separated[k] += part * push;
                            moved = true;
                        }
                    }
                }
            }
        }
        if !moved {
            break;
        }
    }
    separated
}

/// Which way (horizontal unit vector, from `a` towards `b`) object `i` (`a`) and object `j`
/// (`b`; obstacle `j - n` for `j` past the objects), overlapping `depth` deep with the deepest
/// contact `normal` (out of `a`), are pulled apart; `None` when they are not:
/// - when one is movable and the overlap is deeper than its `separation_limit` (a segmentation
///   fault that moving it would hide), or `a` stands on obstacle `b` (snapping's business);
/// - neighbours on one support part along the line between them when the deepest contact
///   points elsewhere: vertically, or across it where two thin panels cross (an imported
///   cabinet's back panel through its neighbour's side panel is shallowest to push out front to
///   back);
/// - others along a horizontal contact normal, and out of an obstacle (a chair tucked under a
///   counter no model replaced) away from its middle. Others overlapping vertically (a cup sunk
///   into the shelf above it) cannot part sideways.
#[allow(clippy::too_many_arguments)]
pub(crate) fn parted(
    i: usize,
    j: usize,
    depth: f32,
    normal: Vec3,
    a: &PlacedSolid,
    b: &PlacedSolid,
    holders: &[Holder],
    movable: &[bool],
) -> Option<Vec3> {
    let n = movable.len();
    let obstacle = j >= n;
    let b_movable = !obstacle && movable[j];
    let too_deep = [(movable[i], a), (b_movable, b)]
        .iter()
        .filter(|(m, _)| *m)
        .all(|(_, s)| depth > separation_limit(s));
    if ((movable[i] || b_movable) && too_deep)
        || (obstacle && holders[i] == Holder::Obstacle(j - n))
    {
        return None;
    }
    let siblings = !obstacle && holders[i] == holders[j] && holders[i] != Holder::Other;
    let horizontal = normal.with_z(0.0);
    let between = (b.centre() - a.centre()).with_z(0.0).try_normalize();
    match between {
        Some(d)
            if siblings
                && (horizontal.length() < 0.9 || horizontal.normalize().dot(d).abs() < 0.7) =>
        {
            Some(d)
        }
        _ if horizontal.length() >= 0.9 => Some(horizontal.normalize()),
        Some(d) if obstacle => Some(d),
        _ => None,
    }
}

/// Objects reaching behind a wall are brought out of it: a fixed one (a cabinet) is shrunk with
/// its side facing the room kept, where it was seen (an imported cabinet's big handles make its
/// model deeper than the cabinet), a movable one is moved. The walls are the layout planes that
/// stand upright. Returns how far each object was shrunk or moved, metres.
pub(crate) fn retreat_from_walls(
    models: &[Option<&DatabaseModel>],
    movable: &[bool],
    layout: &[Plane],
    poses: &mut [Option<Affine3A>],
) -> Vec<f32> {
    let walls: Vec<Plane> = layout
        .iter()
        .filter(|p| p.normal.z.abs() < 0.1)
        .copied()
        .collect();
    let mut retreated = vec![0.0f32; models.len()];
    for (i, model) in models.iter().enumerate() {
        let Some(model) = model else { continue };
        for wall in &walls {
            let Some(pose) = poses[i] else { continue };
            let solid = PlacedSolid::new(model, &pose);
            let depth = layout_penetration(&solid, std::slice::from_ref(wall));
            let tolerance = if movable[i] {
                SEPARATION_TOLERANCE_M
            } else {
                WALL_SHRINK_TOLERANCE_M
            };
            if depth <= tolerance {
                continue;
            }
            let Some(into_room) = wall.normal.with_z(0.0).try_normalize() else {
                continue;
            };
            let amount = depth + SEPARATION_GAP_M;
            let out = if movable[i] {
                Some(Affine3A::from_translation(into_room * amount) * pose)
            } else {
                shrink_from(pose, &solid, into_room, amount)
            };
            if let Some(out) = out {
                poses[i] = Some(out);
                retreated[i] += amount;
            }
        }
    }
    retreated
}

/// `pose` with the model shrunk by `amount` metres along the model axis nearest to `away`, its
/// side towards `away` kept where it is (the other side retreats); `None` when that would take
/// half its width or more.
fn shrink_from(pose: Affine3A, solid: &PlacedSolid, away: Vec3, amount: f32) -> Option<Affine3A> {
    let axes = [
        pose.matrix3.x_axis,
        pose.matrix3.y_axis,
        pose.matrix3.z_axis,
    ];
    let k = (0..3).max_by(|&a, &b| {
        let along = |v: glam::Vec3A| Vec3::from(v).normalize_or_zero().dot(away).abs();
        along(axes[a]).total_cmp(&along(axes[b]))
    })?;
    let extent = solid
        .pieces
        .iter()
        .flat_map(|(p, _, _)| p.points().iter())
        .map(|v| v.dot(away))
        .fold((f32::MAX, f32::MIN), |(lo, hi), d| (lo.min(d), hi.max(d)));
    let width = extent.1 - extent.0;
    if width <= 2.0 * amount {
        return None;
    }
    let mut scale = Vec3::ONE;
    scale[k] = 1.0 - amount / width;
    let shrunk = pose * Affine3A::from_scale(scale);
    // Shrinking about the model's origin moved the kept side; move it back.
    let kept_before = extent.1;
    let kept_after = solid
        .pieces
        .iter()
        .flat_map(|(p, _, _)| p.points().iter())
        .map(|v| {
            let model_point = pose.inverse().transform_point3(*v);
            shrunk.transform_point3(model_point).dot(away)
        })
        .fold(f32::MIN, f32::max);
    Some(Affine3A::from_translation(away * (kept_before - kept_after)) * shrunk)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::db::database::CadDatabase;
    use crate::cad::placed_solid::penetration_depth;

    #[test]
    fn two_books_lying_over_each_others_edge_are_parted_along_the_line_between_them() {
        // Book B lies 8 cm over book A's edge, sunk 1 mm into its cover: the shallowest way out
        // is up, 1 mm, but siblings part sideways, and 1 mm a round (ten rounds) was not enough.
        let db = CadDatabase::parametric();
        let book = db
            .models()
            .iter()
            .find(|m| m.model.id == "book_01")
            .expect("book model");
        let size = book.model.size;
        let floor = Plane::from_point_normal(Vec3::ZERO, Vec3::Z);
        let start = [Vec3::ZERO, Vec3::new(size.x - 0.08, 0.0, size.z - 0.001)];
        let mut poses: Vec<Option<Affine3A>> = start
            .iter()
            .map(|&at| Some(Affine3A::from_translation(at)))
            .collect();
        let solid = |pose: &Option<Affine3A>| PlacedSolid::new(book, &pose.expect("placed"));
        let before = penetration_depth(&solid(&poses[0]), &solid(&poses[1]));
        assert!(before > 0.0005, "they start overlapping: {before}");
        let separated = separate_neighbours(
            &[Some(book), Some(book)],
            &[Holder::Floor(floor), Holder::Floor(floor)],
            &[true, true],
            &[],
            &mut poses,
        );
        let depth = penetration_depth(&solid(&poses[0]), &solid(&poses[1]));
        assert!(depth <= SEPARATION_TOLERANCE_M, "{depth} m left");
        // Apart along x by the overlap and the gap, no further.
        let x = |pose: &Option<Affine3A>| pose.expect("placed").translation.x;
        let parted = (x(&poses[1]) - x(&poses[0])) - (start[1].x - start[0].x);
        assert!((0.08..0.09).contains(&parted), "parted by {parted} m");
        assert!(separated.iter().all(|&s| s > 0.0), "{separated:?}");
    }
}
