//! Library models built to the size an object was fitted at, instead of stretched.
//!
//! Alignment fits a model with a scale per axis. Stretching a model scales everything in it: a
//! bookcase fitted at half its nominal height keeps all its boards, half as far apart and half
//! as thick, so the bottles inside meet the board above, and a door's handle grows with the
//! door. A model of the parametric library can instead be built again to the fitted size, the
//! way the library builds any size (boards keep their thickness, a bookcase its board spacing),
//! which is also how a room's truth is built (`LibraryEntry::model_sized`). Models imported from
//! a database have fixed meshes and stay stretched.

use glam::{Affine3A, Mat3A, Vec3};

use crate::cad::db::database::{DatabaseModel, LibraryBuild};

/// Sizes are built to the millimetre, the resolution of a sized model's id: one id, one mesh.
const SIZE_STEP_M: f32 = 1e-3;

/// The scale per model axis of `world_from_model`.
pub fn pose_scale(world_from_model: &Affine3A) -> Vec3 {
    let m = world_from_model.matrix3;
    Vec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
}

/// The size `model` is stretched to by `world_from_model`, built by its library entry, with the
/// pose that places the built model where the stretched one stands (the same rotation and
/// translation, no scale). `None` when the library did not build the model or the stretched
/// size rounds to the one it was built at.
pub fn built_to_fit(
    model: &DatabaseModel,
    world_from_model: &Affine3A,
) -> Option<(DatabaseModel, Affine3A)> {
    let build = model.built?;
    let scale = pose_scale(world_from_model);
    if scale.min_element() <= 0.0 || !scale.is_finite() {
        return None;
    }
    let size = (build.size * scale / SIZE_STEP_M).round() * SIZE_STEP_M;
    if (size - build.size).abs().max_element() < 0.5 * SIZE_STEP_M {
        return None;
    }
    let m = world_from_model.matrix3;
    let rotation = Mat3A::from_cols(m.x_axis / scale.x, m.y_axis / scale.y, m.z_axis / scale.z);
    let pose = Affine3A {
        matrix3: rotation,
        translation: world_from_model.translation,
    };
    // A library builder gives proper meshes at any positive size (tested in `cad::library`).
    let mut built = DatabaseModel::new(build.entry.model_sized(size))
        .inspect_err(|e| tracing::warn!("{} at {size}: not built ({e})", build.entry.id))
        .ok()?;
    built.built = Some(LibraryBuild {
        entry: build.entry,
        size,
    });
    Some((built, pose))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::db::database::CadDatabase;

    fn library_model<'a>(db: &'a CadDatabase, id: &str) -> &'a DatabaseModel {
        db.get(id).expect("library model")
    }

    #[test]
    fn a_bookcase_fitted_lower_is_built_with_its_board_spacing_where_the_stretched_one_stood() {
        let db = CadDatabase::parametric();
        let shelf = library_model(&db, "shelf_01");
        // Half the nominal height, turned a quarter and moved.
        let stretched = Affine3A::from_translation(Vec3::new(1.0, 2.0, 0.0))
            * Affine3A::from_rotation_z(std::f32::consts::FRAC_PI_2)
            * Affine3A::from_scale(Vec3::new(1.0, 1.0, 0.5));
        let (built, pose) = built_to_fit(shelf, &stretched).expect("built");
        assert_eq!(built.model.id, "shelf_01.800x300x900");
        assert!((pose_scale(&pose) - Vec3::ONE).abs().max_element() < 1e-5);
        // The same box in the world.
        let corners = |m: &DatabaseModel, p: &Affine3A| {
            let (lo, hi) = m.mesh.bounds().expect("mesh");
            [lo, hi].map(|c| p.transform_point3(c))
        };
        let (a, b) = (corners(shelf, &stretched), corners(&built, &pose));
        for (x, y) in a.iter().zip(&b) {
            assert!(x.distance(*y) < 2e-3, "{a:?} against {b:?}");
        }
        // Boards keep their spacing (about 0.35 m): the stretched bookcase squeezes its four
        // inner boards into 0.9 m, the built one has one.
        let boards = |m: &DatabaseModel| {
            m.pieces
                .iter()
                .filter(|p| {
                    let (lo, hi) = p.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), v| {
                        (lo.min(*v), hi.max(*v))
                    });
                    let s = hi - lo;
                    s.z < 0.05 && s.x > 0.5 && lo.z > 0.05 && hi.z < m.model.size.z - 0.05
                })
                .count()
        };
        assert!(
            boards(shelf) > boards(&built),
            "{} {}",
            boards(shelf),
            boards(&built)
        );
        assert_eq!(boards(&built), 1, "a 0.9 m bookcase has one inner board");
    }

    #[test]
    fn nominal_sizes_and_models_from_outside_the_library_are_left_as_they_are() {
        let db = CadDatabase::parametric();
        let table = library_model(&db, "table_01");
        let pose = Affine3A::from_translation(Vec3::X);
        assert!(built_to_fit(table, &pose).is_none());
        let mut imported = table.clone();
        imported.built = None;
        let stretched = Affine3A::from_scale(Vec3::splat(0.8));
        assert!(built_to_fit(&imported, &stretched).is_none());
        assert!(built_to_fit(table, &stretched).is_some());
    }
}
