//! Optimisation-based alignment (Han et al., Sect. 4.2): Levenberg-Marquardt over the model's
//! scale (per model axis), yaw and horizontal translation, its bottom held on the supporting
//! plane. Residuals: the object's surface points against the model's surface (point to plane,
//! correspondences renewed ICP-style between LM runs, Huber-weighted), the box height, the
//! containment of the object's floor rectangle in the model's and of the model's in the object's
//! (with slack for unseen sides), the class's size range, and a weak prior towards the database
//! size. The alignment error AE is the RMS distance from the object's points to the
//! aligned model; the candidate with the best AE wins.

use glam::{Affine3A, DAffine3, DMat3, DVec2, DVec3, Mat3, Vec3};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{Dyn, Owned, U6};
use rayon::prelude::*;

use crate::cad::db::database::{CadDatabase, DatabaseModel, parry_mesh};
use crate::cad::replace::matching::{Candidate, ObservedObject};
use crate::cad::replace::orientation::axis_rotations;
use crate::classes::ClassTable;
use crate::perception::fronts::layout_error;

/// Object points the optimisation works with (a deterministic stride through the mesh).
const FIT_POINTS: usize = 300;
/// Object points the alignment error is measured on.
const ERROR_POINTS: usize = 4000;
/// Correspondence renewals (each followed by one LM run).
const OUTER_ITERATIONS: usize = 8;
/// Huber threshold of the point residuals, metres.
const HUBER_M: f64 = 0.03;
/// Points farther than this from the model are outliers (label bleeding) while fitting.
const OUTLIER_M: f64 = 0.15;
const HEIGHT_WEIGHT: f64 = 1.0;
const CONTAINMENT_WEIGHT: f64 = 0.1;
/// The model's floor rectangle may reach this far (metres) beyond the object's box (a back or
/// a side that was not seen) before it costs: the distance from the object's points to the
/// model says nothing of model surface that no point is near.
const OVERHANG_FREE_M: f64 = 0.1;
/// ... and at most this share of the box's side: a book's or a cup's whole footprint is in
/// view, and 10 cm around a 20 cm book would leave its size free.
const OVERHANG_FREE_SHARE: f64 = 0.25;
const OVERHANG_WEIGHT: f64 = 0.5;
/// Metres of residual per metre the scaled model leaves its class's size range (a bookshelf is
/// never 2 m deep): a wall of cost, not a preference.
const SIZE_RANGE_WEIGHT: f64 = 5.0;
/// Metres per unit of log scale: 0.02 makes a 65% stretch cost like 1 cm of misfit.
const SCALE_PRIOR_WEIGHT: f64 = 0.02;
/// The first guess of a scale stays within these bounds (the observed box may be partial).
const INITIAL_SCALE: (f64, f64) = (0.6, 1.6);

/// A candidate model aligned to an object.
#[derive(Clone, Debug, PartialEq)]
pub struct Alignment {
    pub candidate: Candidate,
    /// `T(t) Rz(yaw) R_axis S`: the model frame (canonical, scaled per axis) into the world.
    pub world_from_model: Affine3A,
    /// Per model axis.
    pub scale: Vec3,
    /// RMS distance from the object's points to the aligned model, metres.
    pub alignment_error: f32,
    /// How far the placed model's handles disagree with the perceived ones, in [0, 1]
    /// (`perception::fronts::layout_error`; 0 without a perceived front).
    pub layout_error: f32,
}

/// Metres of alignment error that lying on a side (db = 1) weighs as when choosing among
/// aligned candidates: shapes that fit alike are told apart by the priors of the ranking.
pub const PRIOR_AE_WEIGHT: f32 = 0.02;
/// ... and facing the wrong way (df = 1: sideways or into the wall behind it). A part seen of an
/// object fits a model turned a quarter better as often as not: a bookcase seen as a strip of
/// its boards, 0.24 of its 0.72 m, fitted its side panel 2 cm better than its front (room 15 of
/// `iscene benchmark`); a chair at a table took a model turned a quarter from it (room 24).
pub const FACING_AE_WEIGHT: f32 = 0.04;

/// Aligns every candidate; the alignments come best first: lowest alignment error plus prior
/// penalties (`choice_score`), ties by rank.
pub fn align_all(
    object: &ObservedObject,
    db: &CadDatabase,
    candidates: &[Candidate],
) -> Vec<Alignment> {
    let mut aligned: Vec<Alignment> = candidates
        .par_iter()
        .filter_map(|c| align_candidate(object, &db.models()[c.model], *c))
        .collect();
    // A stable sort keeps the rank order among equal scores.
    aligned.sort_by(|a, b| choice_score(a).total_cmp(&choice_score(b)));
    aligned
}

/// The best of [`align_all`].
pub fn align_best(
    object: &ObservedObject,
    db: &CadDatabase,
    candidates: &[Candidate],
) -> Option<Alignment> {
    align_all(object, db, candidates).into_iter().next()
}

/// Metres of alignment error that a model whose handles disagree wholly with the perceived ones
/// (layout error 1) weighs as: the handles tell a chest of drawers from a cabinet with doors
/// where their boxes fit alike, and a noisy map may miss some handles.
pub const LAYOUT_AE_WEIGHT: f32 = 0.03;

/// What candidates are chosen by: the alignment error plus the ranking's priors and the
/// disagreement of the model's handles with the perceived ones, metres.
pub fn choice_score(a: &Alignment) -> f32 {
    a.alignment_error
        + FACING_AE_WEIGHT * a.candidate.facing_error
        + PRIOR_AE_WEIGHT * a.candidate.upright_error
        + LAYOUT_AE_WEIGHT * a.layout_error
}

/// The layout error of `model` placed at `world_from_model` against the front perceived on
/// `object` (0 when none was). A library model's handles are the stretched nominal model's,
/// not those of the model built to the placed size (`cad::replace::sizing`): measured on the
/// built one, seeds 0-9 lost two rooms (a dishwasher and a cabinet chose another model).
pub fn placed_layout_error(
    object: &ObservedObject,
    model: &DatabaseModel,
    world_from_model: &Affine3A,
) -> f32 {
    let Some(front) = &object.front else {
        return 0.0;
    };
    layout_error(&front.handles, &model.placed_handles(world_from_model))
}

/// Aligns one candidate; `None` when the object has no points or the fit breaks down numerically.
pub fn align_candidate(
    object: &ObservedObject,
    model: &DatabaseModel,
    candidate: Candidate,
) -> Option<Alignment> {
    let fit_points: Vec<DVec3> = stride_sample(&object.points, FIT_POINTS)
        .map(|p| p.as_dvec3())
        .collect();
    if fit_points.is_empty() {
        return None;
    }
    let frame = PoseFrame::new(object, model, candidate);
    let mut params = frame.initial_params();
    for _ in 0..OUTER_ITERATIONS {
        let pose = frame.pose(&params);
        let correspondences: Vec<Correspondence> = fit_points
            .iter()
            .filter_map(|q| Correspondence::find(model, &pose, *q))
            .collect();
        let problem = AlignmentProblem {
            frame: &frame,
            correspondences,
            params: nalgebra::Vector6::from_column_slice(&params),
        };
        let (solved, _report) = LevenbergMarquardt::new()
            .with_patience(20)
            .minimize(problem);
        let next: [f64; 6] = solved.params.into();
        if !next.iter().all(|v| v.is_finite()) {
            return None;
        }
        let step = next
            .iter()
            .zip(&params)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        params = next;
        if step < 1e-4 {
            break;
        }
    }
    let pose = frame.pose(&params);
    let world_from_model = pose.world_from_model().as_affine3a();
    let alignment_error = alignment_error(&object.points, model, &world_from_model)?;
    Some(Alignment {
        candidate,
        world_from_model,
        scale: pose.scale.as_vec3(),
        alignment_error,
        layout_error: placed_layout_error(object, model, &world_from_model),
    })
}

/// Every `len / n`-th point, at most about `n`.
pub(crate) fn stride_sample(points: &[Vec3], n: usize) -> impl Iterator<Item = Vec3> + '_ {
    let step = points.len().div_ceil(n.max(1)).max(1);
    points.iter().step_by(step).copied()
}

/// What stays fixed while one candidate is optimised.
struct PoseFrame {
    /// The candidate's axis rotation.
    axis: DMat3,
    /// The model's bounds in its own frame.
    model_lo: DVec3,
    model_hi: DVec3,
    /// Database size of the model.
    model_size: DVec3,
    /// The class's size range, per model axis (canonical frame).
    class_size: Option<(DVec3, DVec3)>,
    support_z: f64,
    object_height: f64,
    object_yaw: f64,
    object_center: DVec2,
    object_size: DVec3,
    /// The object's floor rectangle corners.
    footprint: [DVec2; 4],
}

/// The pose a parameter vector `[ln sx, ln sy, ln sz, yaw, tx, ty]` stands for.
#[derive(Clone, Copy, Debug)]
struct Pose {
    scale: DVec3,
    /// `Rz(yaw) R_axis`.
    rotation: DMat3,
    translation: DVec3,
}

impl Pose {
    fn world_from_model(&self) -> DAffine3 {
        DAffine3::from_mat3_translation(
            self.rotation * DMat3::from_diagonal(self.scale),
            self.translation,
        )
    }

    /// `world` in the unscaled model frame.
    fn model_point(&self, world: DVec3) -> DVec3 {
        (self.rotation.transpose() * (world - self.translation)) / self.scale
    }
}

impl PoseFrame {
    fn new(object: &ObservedObject, model: &DatabaseModel, candidate: Candidate) -> Self {
        let (lo, hi) = model
            .mesh
            .bounds()
            .unwrap_or((-0.5 * model.model.size, 0.5 * model.model.size));
        let b = &object.bbox;
        Self {
            axis: mat3_f64(&axis_rotations()[candidate.orientation]),
            model_lo: lo.as_dvec3(),
            model_hi: hi.as_dvec3(),
            model_size: model.model.size.as_dvec3().max(DVec3::splat(1e-3)),
            class_size: ClassTable::builtin()
                .get(object.class)
                .map(|c| (c.size_min.as_dvec3(), c.size_max.as_dvec3())),
            support_z: f64::from(b.bottom_z()),
            object_height: f64::from(object.top_z - b.bottom_z()),
            object_yaw: f64::from(b.yaw),
            object_center: b.center.truncate().as_dvec2(),
            object_size: b.size.as_dvec3(),
            footprint: b.footprint().map(|c| c.as_dvec2()),
        }
    }

    /// The rotated, scaled model's bounds (relative to the model origin) in the frame of its
    /// axis rotation: `(lo, hi)`.
    fn rotated_bounds(&self, scale: DVec3) -> (DVec3, DVec3) {
        let m = self.axis * DMat3::from_diagonal(scale);
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for i in 0..8 {
            let corner = DVec3::new(
                if i & 1 == 0 {
                    self.model_lo.x
                } else {
                    self.model_hi.x
                },
                if i & 2 == 0 {
                    self.model_lo.y
                } else {
                    self.model_hi.y
                },
                if i & 4 == 0 {
                    self.model_lo.z
                } else {
                    self.model_hi.z
                },
            );
            let p = m * corner;
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    fn pose(&self, x: &[f64; 6]) -> Pose {
        let scale = DVec3::new(x[0].exp(), x[1].exp(), x[2].exp());
        let rotation = DMat3::from_rotation_z(x[3]) * self.axis;
        let (lo, _) = self.rotated_bounds(scale);
        Pose {
            scale,
            rotation,
            // The vertical translation is tied to the supporting plane: the bottom rests on it.
            translation: DVec3::new(x[4], x[5], self.support_z - lo.z),
        }
    }

    /// Scale from the box sizes (each model axis against the box axis it is turned onto), yaw
    /// from the box, the model's centre on the box's.
    fn initial_params(&self) -> [f64; 6] {
        let turned = self.axis;
        let mut log_scale = [0.0; 3];
        for (i, s) in log_scale.iter_mut().enumerate() {
            let column = turned.col(i).abs();
            let box_axis = if column.x > 0.5 {
                0
            } else if column.y > 0.5 {
                1
            } else {
                2
            };
            let ratio = self.object_size[box_axis] / self.model_size[i];
            *s = ratio.clamp(INITIAL_SCALE.0, INITIAL_SCALE.1).ln();
        }
        let scale = DVec3::from_array(log_scale).exp();
        let (lo, hi) = self.rotated_bounds(scale);
        let centre = DMat3::from_rotation_z(self.object_yaw) * (0.5 * (lo + hi));
        let t = self.object_center - centre.truncate();
        [
            log_scale[0],
            log_scale[1],
            log_scale[2],
            self.object_yaw,
            t.x,
            t.y,
        ]
    }
}

fn mat3_f64(m: &Mat3) -> DMat3 {
    DMat3::from_cols(
        m.x_axis.as_dvec3(),
        m.y_axis.as_dvec3(),
        m.z_axis.as_dvec3(),
    )
}

/// One object point held against a point of the model surface for one LM run.
struct Correspondence {
    object: DVec3,
    /// On the model, in its unscaled frame.
    model_point: DVec3,
    /// The residual's direction in the unscaled model frame: the face normal, or the direction
    /// from the model point to the object point at the time of matching.
    model_normal: DVec3,
    /// Huber weight.
    weight: f64,
}

impl Correspondence {
    fn find(model: &DatabaseModel, pose: &Pose, object: DVec3) -> Option<Self> {
        let local = pose.model_point(object);
        let surface = model.closest(local.as_vec3());
        let model_point = surface.point.as_dvec3();
        let world_point = pose.world_from_model().transform_point3(model_point);
        let offset = object - world_point;
        let distance = offset.length();
        if distance > OUTLIER_M || !distance.is_finite() {
            return None;
        }
        let model_normal = match surface.face_normal {
            Some(n) => n.as_dvec3(),
            None => (local - model_point).try_normalize().unwrap_or(DVec3::Z),
        };
        let weight = if distance <= HUBER_M {
            1.0
        } else {
            (HUBER_M / distance).sqrt()
        };
        Some(Self {
            object,
            model_point,
            model_normal,
            weight,
        })
    }

    fn residual(&self, pose: &Pose) -> f64 {
        let on_model = pose.world_from_model().transform_point3(self.model_point);
        // Normals go through the inverse transpose: R S^-1.
        let normal = (pose.rotation * (self.model_normal / pose.scale)).normalize_or_zero();
        self.weight * normal.dot(self.object - on_model)
    }
}

struct AlignmentProblem<'a> {
    frame: &'a PoseFrame,
    correspondences: Vec<Correspondence>,
    params: nalgebra::Vector6<f64>,
}

impl AlignmentProblem<'_> {
    fn residuals_at(&self, x: &[f64; 6]) -> Vec<f64> {
        let frame = self.frame;
        let pose = frame.pose(x);
        let norm = 1.0 / (self.correspondences.len().max(1) as f64).sqrt();
        let mut r: Vec<f64> = self
            .correspondences
            .iter()
            .map(|c| norm * c.residual(&pose))
            .collect();
        let (lo, hi) = frame.rotated_bounds(pose.scale);
        r.push(HEIGHT_WEIGHT * ((hi.z - lo.z) - frame.object_height));
        // The floor rectangle inside the model's, in the frame of the model's rotated box.
        let to_box = DMat3::from_rotation_z(-x[3]);
        for corner in frame.footprint {
            let u = to_box * (corner - pose.translation.truncate()).extend(0.0);
            for axis in 0..2 {
                let outside = (lo[axis] - u[axis]).max(0.0) + (u[axis] - hi[axis]).max(0.0);
                r.push(CONTAINMENT_WEIGHT * outside);
            }
        }
        // The model's floor rectangle not much beyond the object's box, in the box's frame.
        let side = frame.object_size.truncate();
        let half = 0.5 * side + (OVERHANG_FREE_SHARE * side).min(DVec2::splat(OVERHANG_FREE_M));
        let to_object_box = DMat3::from_rotation_z(-frame.object_yaw);
        let posed = DMat3::from_rotation_z(x[3]);
        for i in 0..4 {
            let corner = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                0.0,
            );
            let world = pose.translation.truncate() + (posed * corner).truncate();
            let u = (to_object_box * (world - frame.object_center).extend(0.0)).truncate();
            for axis in 0..2 {
                r.push(OVERHANG_WEIGHT * (u[axis].abs() - half[axis]).max(0.0));
            }
        }
        if let Some((min, max)) = frame.class_size {
            let size = pose.scale * frame.model_size;
            for axis in 0..3 {
                let outside = (min[axis] - size[axis]).max(0.0) + (size[axis] - max[axis]).max(0.0);
                r.push(SIZE_RANGE_WEIGHT * outside);
            }
        }
        r.extend(x[..3].iter().map(|ln_s| SCALE_PRIOR_WEIGHT * ln_s));
        r
    }
}

impl LeastSquaresProblem<f64, Dyn, U6> for AlignmentProblem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, U6>;
    type ParameterStorage = Owned<f64, U6>;

    fn set_params(&mut self, x: &nalgebra::Vector6<f64>) {
        self.params = *x;
    }

    fn params(&self) -> nalgebra::Vector6<f64> {
        self.params
    }

    fn residuals(&self) -> Option<nalgebra::DVector<f64>> {
        let r = self.residuals_at(&self.params.into());
        r.iter()
            .all(|v| v.is_finite())
            .then(|| nalgebra::DVector::from_vec(r))
    }

    /// Central differences: the residuals are cheap once correspondences are fixed.
    fn jacobian(&self) -> Option<nalgebra::OMatrix<f64, Dyn, U6>> {
        const H: f64 = 1e-6;
        let x: [f64; 6] = self.params.into();
        let rows = self.residuals_at(&x).len();
        let mut j = nalgebra::OMatrix::<f64, Dyn, U6>::zeros(rows);
        for k in 0..6 {
            let (mut plus, mut minus) = (x, x);
            plus[k] += H;
            minus[k] -= H;
            let (rp, rm) = (self.residuals_at(&plus), self.residuals_at(&minus));
            for (i, (a, b)) in rp.iter().zip(&rm).enumerate() {
                j[(i, k)] = (a - b) / (2.0 * H);
            }
        }
        j.iter().all(|v| v.is_finite()).then_some(j)
    }
}

/// RMS distance (metres) from `points` to the model placed by `world_from_model` (a rotation
/// times a per-axis scale, then a translation), exact for the scaled model; `None` without
/// points or for a degenerate placement.
pub fn alignment_error(
    points: &[Vec3],
    model: &DatabaseModel,
    world_from_model: &Affine3A,
) -> Option<f32> {
    let m = world_from_model.matrix3;
    let scale = Vec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length());
    if scale.min_element() < 1e-6 || !scale.is_finite() {
        return None;
    }
    let rotation = Mat3::from_cols(
        Vec3::from(m.x_axis) / scale.x,
        Vec3::from(m.y_axis) / scale.y,
        Vec3::from(m.z_axis) / scale.z,
    );
    let mut scaled = model.mesh.clone();
    for p in &mut scaled.positions {
        *p *= scale;
    }
    let shape = parry_mesh(&scaled).ok()?;
    let rotation_t = rotation.transpose();
    let translation = Vec3::from(world_from_model.translation);
    let sampled: Vec<Vec3> = stride_sample(points, ERROR_POINTS).collect();
    if sampled.is_empty() {
        return None;
    }
    use parry3d::query::PointQuery;
    let sum: f64 = sampled
        .iter()
        .map(|q| {
            let local = rotation_t * (*q - translation);
            let d = f64::from(
                shape
                    .project_local_point(local, false)
                    .point
                    .distance(local),
            );
            d * d
        })
        .sum();
    Some((sum / sampled.len() as f64).sqrt() as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::replace::matching::{KEEP_CANDIDATES, rank_candidates};
    use crate::geometry::{GravityBox, Plane, plane::dominant_planes};
    use glam::Quat;

    /// What a viewer looking along `-toward` sees of a posed model: dense samples on the
    /// triangles that face it (occlusion ignored).
    fn partial_view(entry: &DatabaseModel, world_from_model: Affine3A, toward: Vec3) -> Vec<Vec3> {
        let mesh = entry.mesh.transformed(&world_from_model);
        let mut points = Vec::new();
        for i in 0..mesh.triangles.len() {
            let [a, b, c] = mesh.triangle(i);
            let n = mesh.face_normal(i);
            if n.dot(toward) <= 0.1 {
                continue;
            }
            let area = 0.5 * (b - a).cross(c - a).length();
            let k = ((area / 0.0004).sqrt().ceil() as usize).clamp(1, 30);
            for u in 0..=k {
                for v in 0..=(k - u) {
                    let (s, r) = (u as f32 / k as f32, v as f32 / k as f32);
                    points.push(a + s * (b - a) + r * (c - a));
                }
            }
        }
        points
    }

    fn observe<'a>(id: &'a str, points: &'a [Vec3], floor_z: f32) -> ObservedObject<'a> {
        let mut bbox = GravityBox::minimal(points).expect("box");
        // The box reaches down to the supporting plane, as the contact graph refines it.
        let top = bbox.top_z();
        bbox.size.z = top - floor_z;
        bbox.center.z = 0.5 * (top + floor_z);
        ObservedObject {
            id,
            class: id.split('_').next().expect("class"),
            top_z: bbox.top_z(),
            bbox,
            planes: Vec::<Plane>::new(),
            points: points.into(),
            facing: None,
            front: None,
        }
    }

    #[test]
    fn a_partially_seen_stretched_model_is_found_with_its_yaw_scale_and_place() {
        let db = CadDatabase::parametric();
        for (id, yaw, stretch) in [
            ("chair_01", 0.7f32, Vec3::new(1.1, 0.95, 1.0)),
            ("fridge_02", -0.2, Vec3::new(0.9, 1.0, 1.05)),
            ("table_03", 2.0, Vec3::new(0.9, 1.1, 1.0)),
        ] {
            let entry = db
                .models()
                .iter()
                .find(|m| m.model.id == id)
                .expect("model");
            let truth = Affine3A::from_scale_rotation_translation(
                stretch,
                Quat::from_rotation_z(yaw),
                Vec3::new(1.5, -0.5, 0.0),
            );
            // Seen from the front and the left, from above.
            let toward = Quat::from_rotation_z(yaw) * Vec3::new(-0.6, -1.0, 0.6);
            let points = partial_view(entry, truth, toward.normalize());
            let mut object = observe(id, &points, 0.0);
            let mesh_planes = dominant_planes(&entry.mesh.transformed(&truth), 0.02, 8);
            object.planes = mesh_planes.into_iter().map(|(p, _)| p).collect();
            let ranked = rank_candidates(&object, &db, KEEP_CANDIDATES);
            let best = align_best(&object, &db, &ranked).expect("aligned");
            let chosen = &db.models()[best.candidate.model].model.id;
            assert!(
                best.alignment_error < 0.01,
                "{id}: AE {} with {chosen}",
                best.alignment_error
            );
            assert_eq!(chosen, id, "{id}");
            let yaw_of = |a: &Affine3A| {
                let x = a.transform_vector3(Vec3::X);
                x.y.atan2(x.x)
            };
            let class = crate::classes::ClassTable::builtin()
                .get(object.class)
                .expect("class");
            let angle = class
                .yaw_difference(yaw_of(&best.world_from_model), yaw_of(&truth))
                .to_degrees();
            assert!(angle < 5.0, "{id}: yaw off by {angle} degrees");
            let origin = best.world_from_model.translation;
            assert!(
                Vec3::from(origin).distance(Vec3::from(truth.translation)) < 0.03,
                "{id}: origin {origin} vs {}",
                truth.translation
            );
            assert!(
                (best.scale - stretch).abs().max_element() < 0.06,
                "{id}: scale {} vs {stretch}",
                best.scale
            );
        }
    }
}
