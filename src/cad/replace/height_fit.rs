//! A holder's model fitted in height to what it holds (part of the physical check): what
//! stands on a table was seen where its top is, while the table's model was fitted to its
//! segment, which chairs pushed under it bled into.

use std::borrow::Cow;

use glam::{Affine3A, Vec3};
use rayon::prelude::*;

use crate::cad::db::database::DatabaseModel;
use crate::cad::placed_solid::PlacedSolid;
use crate::cad::replace::physical_check::Holder;
use crate::cad::replace::sizing::built_to_fit;

/// How far (metres) above or below what an object holds its model's top may be for its height
/// to be fitted to it, and the scales that fit may take.
const HEIGHT_FIT_BAND_M: f32 = 0.2;
const HEIGHT_FIT_SCALES: std::ops::RangeInclusive<f32> = 0.7..=1.3;

/// `options` with every holder's candidates stretched or squashed in height, about their
/// bottom, so that the surface under what they hold meets its bottom: what stands on a table
/// was seen where its top is, while the table's model was scaled to its segment, which the
/// chairs pushed under it bled into (7-Scenes redkitchen: a table segment 0.84 m tall under
/// cups standing at 0.715 m). The median over the held objects' best candidates decides; a
/// scale outside `HEIGHT_FIT_SCALES` is left alone. A library model is built again at the
/// fitted height, where the library lays out its inner surfaces anew (a bookcase's boards keep
/// their spacing), so the fitted height is kept only when it seats the held objects better
/// than the height the model was aligned at.
pub(crate) fn fit_heights_to_children<'a>(
    options: Vec<Vec<(Cow<'a, DatabaseModel>, Affine3A)>>,
    holders: &[Holder],
) -> Vec<Vec<(Cow<'a, DatabaseModel>, Affine3A)>> {
    let held: Vec<Option<PlacedSolid>> = options
        .iter()
        .map(|options| options.first().map(|(m, pose)| PlacedSolid::new(m, pose)))
        .collect();
    options
        .into_par_iter()
        .enumerate()
        .map(|(i, options)| {
            let children: Vec<&PlacedSolid> = (0..holders.len())
                .filter(|&c| holders[c] == Holder::Object(i))
                .filter_map(|c| held[c].as_ref())
                .collect();
            if children.is_empty() {
                return options;
            }
            options
                .into_iter()
                .map(|(model, pose)| {
                    let solid = PlacedSolid::new(&model, &pose);
                    let Some(scale) = height_fit_scale(&solid, &children) else {
                        return (model, pose);
                    };
                    let base = solid.bottom_z();
                    let about_base = Affine3A::from_translation(Vec3::Z * base)
                        * Affine3A::from_scale(Vec3::new(1.0, 1.0, scale))
                        * Affine3A::from_translation(-Vec3::Z * base);
                    let stretched = about_base * pose;
                    match built_to_fit(&model, &stretched) {
                        Some((rebuilt, rebuilt_pose)) => {
                            let seated = PlacedSolid::new(&rebuilt, &rebuilt_pose);
                            if seat_error(&seated, &children) < seat_error(&solid, &children) {
                                (Cow::Owned(rebuilt), rebuilt_pose)
                            } else {
                                (model, pose)
                            }
                        }
                        None => (model, stretched),
                    }
                })
                .collect()
        })
        .collect()
}

/// The height scale about its bottom that brings `solid`'s surfaces under `children` to their
/// bottoms (the median over the children), when it lies within `HEIGHT_FIT_SCALES`.
fn height_fit_scale(solid: &PlacedSolid, children: &[&PlacedSolid]) -> Option<f32> {
    let base = solid.bottom_z();
    let mut scales: Vec<f32> = children
        .iter()
        .filter_map(|c| {
            let centre = 0.25 * c.footprint.iter().sum::<Vec3>();
            let z = c.bottom_z();
            let top = solid.surface_height_within(centre.truncate(), z, HEIGHT_FIT_BAND_M)?;
            (top - base > 0.05).then(|| (z - base) / (top - base))
        })
        .collect();
    if scales.is_empty() {
        return None;
    }
    scales.sort_by(f32::total_cmp);
    let scale = scales[scales.len() / 2];
    HEIGHT_FIT_SCALES.contains(&scale).then_some(scale)
}

/// The median height (metres) between the children's bottoms and `solid`'s surfaces under them;
/// a child with no surface within `HEIGHT_FIT_BAND_M` counts as that far.
fn seat_error(solid: &PlacedSolid, children: &[&PlacedSolid]) -> f32 {
    let mut gaps: Vec<f32> = children
        .iter()
        .map(|c| {
            let centre = 0.25 * c.footprint.iter().sum::<Vec3>();
            let z = c.bottom_z();
            solid
                .surface_height_within(centre.truncate(), z, HEIGHT_FIT_BAND_M)
                .map_or(HEIGHT_FIT_BAND_M, |top| (top - z).abs())
        })
        .collect();
    gaps.sort_by(f32::total_cmp);
    gaps.get(gaps.len() / 2).copied().unwrap_or(0.0)
}
