//! Ranking-based matching (Han et al., Sect. 4.1): every model of the object's class in each of
//! the 24 axis orientations, scored by the matching error ME = ds + dpi + 0.2 db, best first.

use std::borrow::Cow;

use glam::{Mat3, Vec3};
use pathfinding::kuhn_munkres::kuhn_munkres_min;
use pathfinding::matrix::Matrix;

use crate::cad::db::database::{CadDatabase, DatabaseModel};
use crate::cad::replace::orientation::axis_rotations;
use crate::classes::{ClassTable, EntityKind};
use crate::geometry::{GravityBox, Plane};
use crate::perception::fronts::PerceivedFront;

/// How many candidates go on to alignment (the paper's top 10).
pub const KEEP_CANDIDATES: usize = 10;

/// Weight of the upright prior db in ME.
const UPRIGHT_WEIGHT: f32 = 0.2;
/// Weight in ME of df, the facing prior (an object with its back to a wall faces the room):
/// a box-shaped fridge or oven fits its box as well sideways, so the front needs a prior.
const FACING_WEIGHT: f32 = 0.3;

/// Normals closer than this (|cos|) are one direction: RANSAC finds the same face more than once.
const SAME_DIRECTION_COS: f32 = 0.985;

/// What replacement knows of one object, in the gravity-aligned world.
#[derive(Clone, Debug)]
pub struct ObservedObject<'a> {
    pub id: &'a str,
    pub class: &'a str,
    /// The refined gravity-aligned box (its bottom on the supporting plane).
    pub bbox: GravityBox,
    /// Where its top is: the box's top, or the plane the objects it holds rest on when that is
    /// just under the box's top (a table's box reaches up into the bleeding of the cups on it).
    pub top_z: f32,
    pub planes: Vec<Plane>,
    /// The surface points seen of it, less those standing out in front of a perceived front
    /// (an open door, something in front of it).
    pub points: Cow<'a, [Vec3]>,
    /// The way it most likely faces; `None` when the class has no front.
    pub facing: Option<Facing>,
    /// The front and its handles as the camera saw them, for an object of an articulated class
    /// with a facing.
    pub front: Option<PerceivedFront>,
}

/// A prior on the way an object faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Facing {
    /// Horizontal unit vector.
    pub direction: Vec3,
    /// 1 for an object with its back to a wall (it faces away from it); less for weaker
    /// evidence (it faces the middle of the room, where it is seen from).
    pub confidence: f32,
    /// Whether the object stands with its back to a wall: then facing along the wall is as
    /// wrong as facing it (a cabinet does not stand with its side to the wall it backs onto),
    /// where an object facing the room's middle may well face a little to the side.
    pub against_wall: bool,
}

impl Facing {
    /// df in [0, 1] for a model whose front points along `front` (horizontal unit vector): 0
    /// facing `direction`; against a wall the confidence once turned a quarter or more, else
    /// half the confidence per unit of `1 - cos` (the confidence facing away).
    pub fn error(&self, front: Vec3) -> f32 {
        let off = 1.0 - front.dot(self.direction);
        if self.against_wall {
            self.confidence * off.min(1.0)
        } else {
            self.confidence * 0.5 * off
        }
    }
}

/// One model in one axis orientation, with its matching error.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Candidate {
    /// Index into the database.
    pub model: usize,
    /// Index into [`axis_rotations`]: how the model stands in the object's box frame.
    pub orientation: usize,
    pub matching_error: f32,
    /// db in [0, 2]: 0 upright, 2 upside down; part of `matching_error`, used again after
    /// alignment (an upside-down box-shaped model fits as well as an upright one).
    pub upright_error: f32,
    /// df in [0, 1] ([`Facing::error`]; 0 without a facing); part of `matching_error`, used again
    /// after alignment.
    pub facing_error: f32,
}

/// The `keep` best candidates for `object` among the models of its class, lowest ME first (ties
/// by model index, then orientation, so the order is deterministic), and after them the best
/// upright one when none of those is upright. Empty when the database
/// has no model of the class; the models are [`class_models`]. Articulated models are tried
/// upright only.
pub fn rank_candidates(object: &ObservedObject, db: &CadDatabase, keep: usize) -> Vec<Candidate> {
    let box_from_world = Mat3::from_rotation_z(-object.bbox.yaw);
    let world_from_box = box_from_world.transpose();
    let object_directions =
        distinct_directions(object.planes.iter().map(|p| box_from_world * p.normal));
    let object_shape = relative_size(object.bbox.size);
    let rotations = axis_rotations();
    let mut candidates = Vec::new();
    for (index, entry) in class_models(object.class, db) {
        let model_directions = distinct_directions(entry.planes.iter().map(|p| p.normal));
        // An articulated model stands upright: its hinges and slides are made for gravity
        // along -z (a cabinet on its side opens its drawers upwards). The first four of the
        // 24 orientations are the upright ones.
        let orientations = if entry.model.is_articulated() { 4 } else { 24 };
        for (orientation, rotation) in rotations.iter().enumerate().take(orientations) {
            let model_shape = relative_size((*rotation * entry.model.size).abs());
            let ds = (object_shape - model_shape).abs().element_sum();
            let rotated: Vec<Vec3> = model_directions.iter().map(|n| *rotation * *n).collect();
            let dpi = plane_misalignment(&object_directions, &rotated);
            // db = 1 + g . z(y) with g = -z: 0 upright, 1 on its side, 2 upside down.
            let db = 1.0 - rotation.z_axis.z;
            let df = object.facing.map_or(0.0, |facing| {
                facing.error(world_from_box * (*rotation * -Vec3::Y))
            });
            candidates.push(Candidate {
                model: index,
                orientation,
                matching_error: ds + dpi + UPRIGHT_WEIGHT * db + FACING_WEIGHT * df,
                upright_error: db,
                facing_error: df,
            });
        }
    }
    candidates.sort_by(|a, b| {
        a.matching_error
            .total_cmp(&b.matching_error)
            .then(a.model.cmp(&b.model))
            .then(a.orientation.cmp(&b.orientation))
    });
    // The best upright candidate goes on to alignment even when lying ones rank above it: a
    // mug seen from above has a flat box that a mug on its side fits best, and a model lying
    // on its side may roll (the physical check tries the best one that stands).
    let best_upright = candidates.iter().position(|c| c.upright_error == 0.0);
    if let Some(upright) = best_upright.filter(|&k| k >= keep) {
        candidates.swap(keep, upright);
        candidates.truncate(keep + 1);
    } else {
        candidates.truncate(keep);
    }
    candidates
}

/// The models an object of `class` may be replaced by, with their database indices: the
/// models of its class, and of an articulated class (a fridge, a cabinet) only the articulated
/// ones where the database has any, since a rigid model fitting its box a little better would
/// leave its doors shut for good.
pub fn class_models<'a>(
    class: &'a str,
    db: &'a CadDatabase,
) -> impl Iterator<Item = (usize, &'a DatabaseModel)> + 'a {
    let articulated_class = ClassTable::builtin()
        .get(class)
        .is_some_and(|c| c.kind == EntityKind::Articulated);
    let articulated_only =
        articulated_class && db.of_class(class).any(|(_, m)| m.model.is_articulated());
    db.of_class(class)
        .filter(move |(_, m)| !articulated_only || m.model.is_articulated())
}

/// Box size divided by its length: the shape without the scale.
fn relative_size(size: Vec3) -> Vec3 {
    size / size.length().max(1e-6)
}

/// Unit normals with near-duplicates (either sign) dropped, first occurrence kept.
fn distinct_directions(normals: impl Iterator<Item = Vec3>) -> Vec<Vec3> {
    let mut kept: Vec<Vec3> = Vec::new();
    for n in normals {
        let n = n.normalize_or_zero();
        if n != Vec3::ZERO && kept.iter().all(|k| k.dot(n).abs() < SAME_DIRECTION_COS) {
            kept.push(n);
        }
    }
    kept
}

/// dpi: the mean of 1 - |cos| over the object's plane directions under the best one-to-one
/// assignment to the model's (Kuhn-Munkres); a direction left without a partner costs 1.
fn plane_misalignment(object: &[Vec3], model: &[Vec3]) -> f32 {
    if object.is_empty() {
        return 0.0;
    }
    if model.is_empty() {
        return 1.0;
    }
    // Kuhn-Munkres wants no more rows than columns; the assignment is symmetric.
    let (rows, cols) = if object.len() <= model.len() {
        (object, model)
    } else {
        (model, object)
    };
    const SCALE: f32 = 1e6;
    let weights: Vec<Vec<i64>> = rows
        .iter()
        .map(|r| {
            cols.iter()
                .map(|c| ((1.0 - r.dot(*c).abs()) * SCALE).round() as i64)
                .collect()
        })
        .collect();
    let assigned = match Matrix::from_rows(weights) {
        Ok(matrix) => kuhn_munkres_min(&matrix).0 as f32 / SCALE,
        Err(_) => return 1.0,
    };
    let unmatched = object.len().saturating_sub(model.len()) as f32;
    (assigned + unmatched) / object.len() as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::replace::orientation::upright_yaw;
    use crate::geometry::plane::dominant_planes;

    #[test]
    fn against_a_wall_facing_sideways_is_as_wrong_as_facing_the_wall() {
        let wall = Facing {
            direction: Vec3::Y,
            confidence: 1.0,
            against_wall: true,
        };
        assert_eq!(wall.error(Vec3::Y), 0.0);
        assert_eq!(wall.error(Vec3::X), 1.0);
        assert_eq!(wall.error(-Vec3::Y), 1.0);
        let slight = Vec3::new(0.1f32.sin(), 0.1f32.cos(), 0.0);
        assert!(wall.error(slight) < 0.01);
        let middle = Facing {
            against_wall: false,
            confidence: 0.5,
            ..wall
        };
        assert_eq!(middle.error(Vec3::X), 0.25);
        assert_eq!(middle.error(-Vec3::Y), 0.5);
    }

    /// An object seen completely: the model's own mesh placed with a yaw.
    fn observe(db: &CadDatabase, id: &str, yaw: f32) -> (GravityBox, Vec<Plane>, Vec<Vec3>) {
        let entry = db
            .models()
            .iter()
            .find(|m| m.model.id == id)
            .expect("model");
        let pose = glam::Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(yaw),
            Vec3::new(1.0, 2.0, 0.0),
        );
        let mesh = entry.mesh.transformed(&pose);
        let planes = dominant_planes(&mesh, 0.01, 8)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let bbox = GravityBox::minimal(&mesh.positions).expect("box");
        (bbox, planes, mesh.positions)
    }

    #[test]
    fn an_articulated_object_gets_only_articulated_candidates_where_there_are_some() {
        let library = CadDatabase::parametric();
        let fridge = library.get("fridge_01").expect("fridge").model.clone();
        assert!(fridge.is_articulated());
        // The same fridge welded shut: one rigid part, a box that fits exactly as well.
        let mut rigid = fridge.clone();
        rigid.id = "fridge_rigid".into();
        let mesh = rigid.merged_mesh(&[]);
        rigid.parts.truncate(1);
        rigid.parts[0].mesh = mesh;
        let (bbox, planes, points) = observe(&library, "fridge_01", 0.0);
        let object = ObservedObject {
            id: "fridge_1",
            class: "fridge",
            top_z: bbox.top_z(),
            bbox,
            planes,
            points: Cow::Borrowed(&points),
            facing: None,
            front: None,
        };
        let both = CadDatabase::from_models(vec![rigid.clone(), fridge]).expect("db");
        let ranked = rank_candidates(&object, &both, KEEP_CANDIDATES);
        assert!(!ranked.is_empty());
        assert!(
            ranked
                .iter()
                .all(|c| both.models()[c.model].model.is_articulated())
        );
        // Without an articulated fridge, the rigid one serves.
        let only_rigid = CadDatabase::from_models(vec![rigid]).expect("db");
        assert!(!rank_candidates(&object, &only_rigid, KEEP_CANDIDATES).is_empty());
    }

    #[test]
    fn a_seen_model_ranks_itself_upright_at_its_own_aspect_first() {
        let db = CadDatabase::parametric();
        for id in ["table_01", "fridge_01", "sofa_01", "cabinet_01"] {
            let (bbox, planes, points) = observe(&db, id, 0.3);
            let class = id.split('_').next().expect("class");
            let object = ObservedObject {
                id,
                class,
                top_z: bbox.top_z(),
                bbox,
                planes,
                points: Cow::Borrowed(&points),
                facing: None,
                front: None,
            };
            let ranked = rank_candidates(&object, &db, KEEP_CANDIDATES);
            // Articulated models are tried in the four upright orientations only.
            let orientations: usize = db
                .of_class(class)
                .map(|(_, m)| if m.model.is_articulated() { 4 } else { 24 })
                .sum();
            assert_eq!(ranked.len(), KEEP_CANDIDATES.min(orientations));
            assert!(
                ranked
                    .iter()
                    .all(|c| db.models()[c.model].model.class == class)
            );
            let best = ranked[0];
            assert!(
                upright_yaw(&axis_rotations()[best.orientation]).is_some(),
                "{id}: best orientation {} lays the model down",
                best.orientation
            );
            assert!(
                ranked
                    .iter()
                    .take(4)
                    .any(|c| db.models()[c.model].model.id == id),
                "{id}: not among the first four: {:?}",
                ranked
                    .iter()
                    .map(|c| (
                        &db.models()[c.model].model.id,
                        c.orientation,
                        c.matching_error
                    ))
                    .collect::<Vec<_>>()
            );
            assert!(
                ranked
                    .windows(2)
                    .all(|w| w[0].matching_error <= w[1].matching_error)
            );
        }
    }

    #[test]
    fn plane_misalignment_is_zero_for_the_same_directions_and_one_for_none_alike() {
        let axes = [Vec3::X, Vec3::Y, Vec3::Z];
        assert!(plane_misalignment(&axes, &[Vec3::Z, -Vec3::X, Vec3::Y]) < 1e-5);
        assert!((plane_misalignment(&[Vec3::Z], &[Vec3::X, Vec3::Y]) - 1.0).abs() < 1e-5);
        // Two object directions, one model direction: one is left over at cost 1.
        assert!((plane_misalignment(&[Vec3::Z, Vec3::X], &[Vec3::Z]) - 0.5).abs() < 1e-5);
    }
}
