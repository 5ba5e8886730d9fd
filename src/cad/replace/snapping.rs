//! Snapping the chosen models onto what holds them, after the physical check's search and
//! separation: a child's bottom onto its parent model's final surface (parents first), an
//! object's onto the floor plane or an unplaced obstacle's top.

use glam::{Affine3A, Vec3};

use crate::cad::db::database::DatabaseModel;
use crate::cad::placed_solid::PlacedSolid;
use crate::cad::replace::physical_check::Holder;

/// How far (metres) from a child's bottom its parent's final surface may be for the child to be
/// snapped onto it: the contact graph says the parent holds it, and the parent's model may be
/// a few centimetres taller or lower than the surface the child was seen on (a table model
/// scaled to the whole table segment, chairs and all).
const SNAP_HEIGHT_BAND_M: f32 = 0.1;
/// Moves each placed model (`models[i]` at `poses[i]`) up or down onto what holds it
/// (`holders`; `obstacles` are the unplaced objects a holder may index), rewriting `poses`, and
/// returns the models as finally placed.
pub fn snap_onto_holders(
    models: &[Option<&DatabaseModel>],
    holders: &[Holder],
    obstacles: &[PlacedSolid],
    poses: &mut [Option<Affine3A>],
) -> Vec<Option<PlacedSolid>> {
    // Parents before children: a child rests on its parent's final surface.
    let mut finals: Vec<Option<PlacedSolid>> = (0..models.len()).map(|_| None).collect();
    for i in support_order(holders) {
        let (Some(model), Some(pose)) = (models[i], poses[i]) else {
            continue;
        };
        let solid = PlacedSolid::new(model, &pose);
        let centre = 0.25 * solid.footprint.iter().sum::<Vec3>();
        let target = match holders[i] {
            Holder::Object(p) => finals[p].as_ref().and_then(|parent| {
                parent.surface_height_within(
                    centre.truncate(),
                    solid.bottom_z(),
                    SNAP_HEIGHT_BAND_M,
                )
            }),
            Holder::Obstacle(k) => obstacles[k].surface_height_within(
                centre.truncate(),
                solid.bottom_z(),
                SNAP_HEIGHT_BAND_M,
            ),
            Holder::Floor(plane) if plane.normal.z.abs() > 1e-3 => Some(
                -(plane.normal.x * centre.x + plane.normal.y * centre.y + plane.offset)
                    / plane.normal.z,
            ),
            _ => None,
        };
        let snapped = match target {
            Some(z) => Affine3A::from_translation(Vec3::Z * (z - solid.bottom_z())) * pose,
            None => pose,
        };
        poses[i] = Some(snapped);
        finals[i] = Some(PlacedSolid::new(model, &snapped));
    }
    finals
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
