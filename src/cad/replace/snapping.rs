//! Snapping the chosen models onto what holds them, after the physical check's search and
//! separation: a child's bottom onto its parent model's final surface (parents first), an
//! object's onto the floor plane or an unplaced obstacle's top; a movable child overhanging
//! what holds it is first slid back onto it (`on_holder`).

use glam::{Affine3A, Vec3};

use crate::cad::db::database::DatabaseModel;
use crate::cad::placed_solid::PlacedSolid;
use crate::cad::replace::on_holder::{overhangs, slide_onto};
use crate::cad::replace::physical_check::Holder;

/// How far (metres) from a child's bottom its parent's final surface may be for the child to be
/// snapped onto it: the contact graph says the parent holds it, and the parent's model may be
/// a few centimetres taller or lower than the surface the child was seen on (a table model
/// scaled to the whole table segment, chairs and all).
const SNAP_HEIGHT_BAND_M: f32 = 0.1;

/// The models as finally placed, and how far each was slid onto what holds it (metres).
pub struct Snapped {
    pub finals: Vec<Option<PlacedSolid>>,
    pub slid_m: Vec<f32>,
}

/// Moves each placed model (`models[i]` at `poses[i]`) up or down onto what holds it
/// (`holders`; `obstacles` are the unplaced objects a holder may index), a `movable` one that
/// overhangs its holding object or obstacle slid back onto it first, rewriting `poses`.
pub fn snap_onto_holders(
    models: &[Option<&DatabaseModel>],
    holders: &[Holder],
    movable: &[bool],
    obstacles: &[PlacedSolid],
    poses: &mut [Option<Affine3A>],
) -> Snapped {
    // Parents before children: a child rests on its parent's final surface.
    let n = models.len();
    let mut finals: Vec<Option<PlacedSolid>> = (0..n).map(|_| None).collect();
    let mut slid_m = vec![0.0f32; n];
    for i in support_order(holders) {
        let (Some(model), Some(pose)) = (models[i], poses[i]) else {
            continue;
        };
        let holder = match holders[i] {
            Holder::Object(p) => finals[p].as_ref(),
            Holder::Obstacle(k) => obstacles.get(k),
            _ => None,
        };
        let mut pose = snapped_onto(model, pose, holders[i], holder);
        let mut solid = PlacedSolid::new(model, &pose);
        // Only an overhanging object pays for its neighbours' solids and the slide search.
        if let Some(holder) = holder.filter(|h| movable[i] && overhangs(&solid, h)) {
            let neighbours = neighbours_on(i, holders, models, poses, &finals);
            if let Some((slid, distance)) = slide_onto(&solid, &pose, model, holder, &neighbours) {
                tracing::debug!("physical check: object {i} slid {distance:.3} m onto its holder");
                pose = snapped_onto(model, slid, holders[i], Some(holder));
                solid = PlacedSolid::new(model, &pose);
                slid_m[i] = distance;
            }
        }
        poses[i] = Some(pose);
        finals[i] = Some(solid);
    }
    Snapped { finals, slid_m }
}

/// `model` at `pose` moved up or down onto `holder`'s surface (the object or obstacle holding
/// it, as placed) or the floor plane, under the centre of its bottom; as it was when neither
/// is within the snapping band there.
fn snapped_onto(
    model: &DatabaseModel,
    pose: Affine3A,
    holds: Holder,
    holder: Option<&PlacedSolid>,
) -> Affine3A {
    let solid = PlacedSolid::new(model, &pose);
    let centre = 0.25 * solid.footprint.iter().sum::<Vec3>();
    let target = match (holds, holder) {
        (Holder::Object(_) | Holder::Obstacle(_), Some(holder)) => {
            holder.surface_height_within(centre.truncate(), solid.bottom_z(), SNAP_HEIGHT_BAND_M)
        }
        (Holder::Floor(plane), _) if plane.normal.z.abs() > 1e-3 => Some(
            -(plane.normal.x * centre.x + plane.normal.y * centre.y + plane.offset)
                / plane.normal.z,
        ),
        _ => None,
    };
    match target {
        Some(z) => Affine3A::from_translation(Vec3::Z * (z - solid.bottom_z())) * pose,
        None => pose,
    }
}

/// The other objects held by what holds object `i`, as placed so far (snapped when already
/// done): what a slide along that surface could run into.
fn neighbours_on(
    i: usize,
    holders: &[Holder],
    models: &[Option<&DatabaseModel>],
    poses: &[Option<Affine3A>],
    finals: &[Option<PlacedSolid>],
) -> Vec<PlacedSolid> {
    (0..holders.len())
        .filter(|&j| j != i && holders[j] == holders[i])
        .filter_map(|j| match &finals[j] {
            Some(done) => Some(done.clone()),
            None => Some(PlacedSolid::new(models[j]?, &poses[j]?)),
        })
        .collect()
}

/// Object indices with every holder before what it holds (objects in a support cycle, which
/// the contact graph never makes, come last).
fn support_order(holders: &[Holder]) -> Vec<usize> {
    let depth = |mut i: usize| {
        let mut d = 0;
        while let Holder::Object(p) = holders[i] {
            d += 1;
            i = p;
            if d > holders.len() {
                break;
            }
        }
        d
    };
    let mut order: Vec<usize> = (0..holders.len()).collect();
    order.sort_by_key(|&i| (depth(i), i));
    order
}
