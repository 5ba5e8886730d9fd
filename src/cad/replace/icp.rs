//! The ICP route of Sivananda et al., an option beside ranking and Levenberg-Marquardt
//! (`iscene reconstruct --align icp`): every model the object's class may take, upright, scaled
//! to the object's height, started at a sweep of yaws about the object's box centre and refined
//! by ICP: each step fits yaw and horizontal translation to the correspondences (2D Kabsch),
//! then the model's width and depth scales (a line fit per model axis, where the seen points
//! spread along it), its bottom held on the supporting plane. The alignment error decides, as
//! on the LM route.
//!
//! What it gives up against LM: no box, containment or size-prior residuals (the class's size
//! range only clamps the scales), so an unseen side keeps the height's scale; what it keeps: no
//! ranking, so a model whose box shape differs from the observed (partial) box is still tried.

use glam::{Affine3A, Mat3, Vec2, Vec3};
use rayon::prelude::*;

use crate::cad::db::database::{CadDatabase, DatabaseModel};
use crate::cad::replace::alignment::{
    Alignment, FACING_AE_WEIGHT, alignment_error, choice_score, placed_layout_error, stride_sample,
};
use crate::cad::replace::matching::{Candidate, KEEP_CANDIDATES, ObservedObject, class_models};
use crate::classes::ClassTable;

/// Starting yaws, evenly spread over the full turn.
const YAW_STARTS: usize = 8;
/// The coarse pass runs every start on this many points for this many iterations ...
const COARSE_POINTS: usize = 100;
const COARSE_ITERATIONS: usize = 10;
/// ... and the best starts of each model go on to the fine pass.
const FINE_STARTS: usize = 2;
const FINE_POINTS: usize = 300;
const FINE_ITERATIONS: usize = 30;
/// Correspondences farther apart than this (metres) are label bleeding and left out; the
/// fitness counts them at this distance.
const OUTLIER_M: f32 = 0.15;
/// Fewer inlier correspondences than this and the pose is not updated.
const MIN_PAIRS: usize = 10;
/// Scale bounds for a class the class table does not know (else its size range bounds them).
const SCALE_BOUNDS: (f32, f32) = (0.6, 1.6);
/// A horizontal scale is fitted only where the matched model points spread along its axis by at
/// least this share of the model's size there (standard deviation): points on the front face
/// alone say nothing of the depth.
const MIN_SPREAD_SHARE: f32 = 0.15;
/// Convergence: the step's rotation (radians) and translation (metres).
const CONVERGED: f32 = 1e-4;

/// The candidates of the ICP route: every model `object`'s class may take, upright (its yaw is
/// found by ICP, so the four upright axis rotations are one), in database order. The matching
/// error stays 0 until [`align_all`] fills in the fitness.
pub fn class_candidates(object: &ObservedObject, db: &CadDatabase) -> Vec<Candidate> {
    class_models(object.class, db)
        .map(|(model, _)| Candidate {
            model,
            orientation: 0,
            matching_error: 0.0,
            upright_error: 0.0,
            facing_error: 0.0,
        })
        .collect()
}

/// Aligns each candidate by ICP; the alignments come best first by [`choice_score`] (alignment
/// error plus the facing prior), at most [`KEEP_CANDIDATES`] of them.
pub fn align_all(
    object: &ObservedObject,
    db: &CadDatabase,
    candidates: &[Candidate],
) -> Vec<Alignment> {
    let mut aligned: Vec<Alignment> = candidates
        .par_iter()
        .filter_map(|c| align_candidate(object, &db.models()[c.model], *c))
        .collect();
    aligned.sort_by(|a, b| choice_score(a).total_cmp(&choice_score(b)));
    aligned.truncate(KEEP_CANDIDATES);
    aligned
}

/// The per-axis scale, yaw and translation of an upright model (its bottom on the support).
#[derive(Clone, Copy, Debug)]
struct UprightPose {
    scale: Vec3,
    yaw: f32,
    translation: Vec3,
}

impl UprightPose {
    fn world_from_model(&self) -> Affine3A {
        Affine3A::from_mat3_translation(
            Mat3::from_rotation_z(self.yaw) * Mat3::from_diagonal(self.scale),
            self.translation,
        )
    }

    /// Turns the pose by `angle` about the world's z axis through the origin, then shifts it by
    /// `shift` (horizontal).
    fn moved(&self, angle: f32, shift: Vec2) -> Self {
        let turned = Mat3::from_rotation_z(angle) * self.translation;
        Self {
            yaw: self.yaw + angle,
            translation: turned + shift.extend(0.0),
            ..*self
        }
    }
}

/// One candidate aligned: the best of the yaw starts, its error measured like the LM route's.
fn align_candidate(
    object: &ObservedObject,
    model: &DatabaseModel,
    candidate: Candidate,
) -> Option<Alignment> {
    let (lo, hi) = model.mesh.bounds()?;
    let model_size = (hi - lo).max(Vec3::splat(1e-3));
    let object_height = object.top_z - object.bbox.bottom_z();
    let fit = ScaleFit::new(object.class, model_size);
    // The height's scale on every axis, the horizontal ones kept in the class's range.
    let scale = fit.clamped(Vec3::splat(
        (object_height / model_size.z).clamp(fit.lo.z, fit.hi.z),
    ));
    let start = |k: usize| {
        let yaw = object.bbox.yaw + k as f32 * std::f32::consts::TAU / YAW_STARTS as f32;
        let centre = Mat3::from_rotation_z(yaw) * (0.5 * (lo + hi) * scale);
        UprightPose {
            scale,
            yaw,
            translation: (object.bbox.center - centre)
                .truncate()
                .extend(object.bbox.bottom_z() - lo.z * scale.z),
        }
    };
    let coarse: Vec<Vec3> = stride_sample(&object.points, COARSE_POINTS).collect();
    let fine: Vec<Vec3> = stride_sample(&object.points, FINE_POINTS).collect();
    let mut starts: Vec<(f32, UprightPose)> = (0..YAW_STARTS)
        .map(|k| {
            let pose = icp(model, &fit, &coarse, start(k), COARSE_ITERATIONS);
            (score(object, model, &coarse, &pose), pose)
        })
        .collect();
    starts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (_, pose) = starts
        .iter()
        .take(FINE_STARTS)
        .map(|(_, p)| {
            let pose = icp(model, &fit, &fine, *p, FINE_ITERATIONS);
            (score(object, model, &fine, &pose), pose)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))?;
    let world_from_model = pose.world_from_model();
    let alignment_error = alignment_error(&object.points, model, &world_from_model)?;
    Some(Alignment {
        candidate: Candidate {
            matching_error: alignment_error,
            facing_error: facing_error(object, pose.yaw),
            ..candidate
        },
        world_from_model,
        scale: pose.scale,
        alignment_error,
        layout_error: placed_layout_error(object, model, &world_from_model),
    })
}

/// What bounds the horizontal scales: the model's size and its class's size range.
struct ScaleFit {
    model_size: Vec3,
    /// Scale bounds per model axis.
    lo: Vec3,
    hi: Vec3,
}

impl ScaleFit {
    fn new(class: &str, model_size: Vec3) -> Self {
        let (lo, hi) = ClassTable::builtin().get(class).map_or(
            (Vec3::splat(SCALE_BOUNDS.0), Vec3::splat(SCALE_BOUNDS.1)),
            |c| (c.size_min / model_size, c.size_max / model_size),
        );
        Self {
            model_size,
            lo: lo.min(hi),
            hi,
        }
    }

    /// `scale` with its horizontal axes inside the class's size range.
    fn clamped(&self, scale: Vec3) -> Vec3 {
        scale.clamp(self.lo, self.hi).with_z(scale.z)
    }

    /// The pose with its width and depth scales (and the translation along them) fitted to the
    /// pairs of unscaled model points and world points, axis by axis where the model points
    /// spread enough.
    fn refit(&self, pose: UprightPose, pairs: &[(Vec3, Vec3)]) -> UprightPose {
        if pairs.len() < MIN_PAIRS {
            return pose;
        }
        let rotation = Mat3::from_rotation_z(pose.yaw);
        let n = pairs.len() as f32;
        let mut scale = pose.scale;
        let mut offset = Vec3::ZERO;
        for axis in 0..2 {
            // In the turned, unscaled model frame: q = s m + c along the axis.
            let (m, q): (Vec<f32>, Vec<f32>) = pairs
                .iter()
                .map(|(m, w)| {
                    (
                        m[axis],
                        (rotation.transpose() * (*w - pose.translation))[axis],
                    )
                })
                .unzip();
            let (m_mean, q_mean) = (m.iter().sum::<f32>() / n, q.iter().sum::<f32>() / n);
            let var = m.iter().map(|v| (v - m_mean).powi(2)).sum::<f32>() / n;
            if var.sqrt() < MIN_SPREAD_SHARE * self.model_size[axis] {
                continue;
            }
            let cov = m
                .iter()
                .zip(&q)
                .map(|(a, b)| (a - m_mean) * (b - q_mean))
                .sum::<f32>()
                / n;
            let s = (cov / var).clamp(self.lo[axis], self.hi[axis]);
            scale[axis] = s;
            offset[axis] = q_mean - s * m_mean;
        }
        UprightPose {
            scale,
            translation: pose.translation + rotation * offset,
            ..pose
        }
    }
}

/// ICP over yaw, horizontal translation and horizontal scale, at most `iterations` steps.
fn icp(
    model: &DatabaseModel,
    fit: &ScaleFit,
    points: &[Vec3],
    mut pose: UprightPose,
    iterations: usize,
) -> UprightPose {
    for _ in 0..iterations {
        let world_from_model = pose.world_from_model();
        let model_from_world = world_from_model.inverse();
        // (unscaled model point, world point)
        let pairs: Vec<(Vec3, Vec3)> = points
            .iter()
            .filter_map(|q| {
                let m = model.closest(model_from_world.transform_point3(*q)).point;
                (world_from_model.transform_point3(m).distance(*q) <= OUTLIER_M).then_some((m, *q))
            })
            .collect();
        let planar: Vec<(Vec2, Vec2)> = pairs
            .iter()
            .map(|(m, q)| {
                (
                    world_from_model.transform_point3(*m).truncate(),
                    q.truncate(),
                )
            })
            .collect();
        let Some((angle, shift)) = rigid_2d(&planar) else {
            break;
        };
        let before = pose;
        pose = fit.refit(pose.moved(angle, shift), &pairs);
        let moved = pose.translation.distance(before.translation)
            + (pose.scale - before.scale).abs().max_element();
        if angle.abs() < CONVERGED && moved < CONVERGED {
            break;
        }
    }
    pose
}

/// The rotation angle and translation (in the plane) that move the points `a` onto `b` in the
/// least-squares sense (2D Kabsch); `None` for too few pairs.
fn rigid_2d(pairs: &[(Vec2, Vec2)]) -> Option<(f32, Vec2)> {
    if pairs.len() < MIN_PAIRS {
        return None;
    }
    let n = pairs.len() as f32;
    let a_mean = pairs.iter().map(|(a, _)| *a).sum::<Vec2>() / n;
    let b_mean = pairs.iter().map(|(_, b)| *b).sum::<Vec2>() / n;
    let (sin, cos) = pairs.iter().fold((0.0, 0.0), |(s, c), (a, b)| {
        let (a, b) = (*a - a_mean, *b - b_mean);
        (s + a.perp_dot(b), c + a.dot(b))
    });
    let angle = sin.atan2(cos);
    let shift = b_mean - Vec2::from_angle(angle).rotate(a_mean);
    (angle.is_finite() && shift.is_finite()).then_some((angle, shift))
}

/// What the starts compete on: the RMS distance from `points` to the model, each counted at most
/// `OUTLIER_M` (a start that leaves half the points far off is not thereby good), plus the
/// facing prior as the LM route weighs it.
fn score(
    object: &ObservedObject,
    model: &DatabaseModel,
    points: &[Vec3],
    pose: &UprightPose,
) -> f32 {
    let world_from_model = pose.world_from_model();
    let model_from_world = world_from_model.inverse();
    let sum: f32 = points
        .iter()
        .map(|q| {
            // The model's closest point to q, back in the world (exact for a uniform scale,
            // close for mildly unequal ones).
            let m = model.closest(model_from_world.transform_point3(*q)).point;
            world_from_model
                .transform_point3(m)
                .distance(*q)
                .min(OUTLIER_M)
                .powi(2)
        })
        .sum();
    (sum / points.len().max(1) as f32).sqrt() + FACING_AE_WEIGHT * facing_error(object, pose.yaw)
}

/// df of the ranking (`Candidate::facing_error`) for a model turned by `yaw`.
fn facing_error(object: &ObservedObject, yaw: f32) -> f32 {
    object.facing.map_or(0.0, |facing| {
        facing.error(Mat3::from_rotation_z(yaw) * -Vec3::Y)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::GravityBox;

    /// Dense samples of the posed model's faces that look towards `toward` (what a camera
    /// there sees, occlusion ignored), with a deterministic jitter of `noise` metres.
    fn seen_points(model: &DatabaseModel, world_from_model: &Affine3A, toward: Vec3) -> Vec<Vec3> {
        let mut points = Vec::new();
        let mesh = &model.mesh;
        for (k, t) in mesh.triangles.iter().enumerate() {
            let [a, b, c] =
                t.map(|i| world_from_model.transform_point3(mesh.positions[i as usize]));
            let normal = (b - a).cross(c - a);
            if normal.length() < 1e-9 || normal.dot(toward) <= 0.0 {
                continue;
            }
            let area = 0.5 * normal.length();
            let samples = ((area / 0.0004) as usize).clamp(1, 400);
            for s in 0..samples {
                let u = ((s * 7 + k) % 19) as f32 / 19.0;
                let v = ((s * 11 + 3 * k) % 23) as f32 / 23.0 * (1.0 - u);
                points.push(a + u * (b - a) + v * (c - a));
            }
        }
        points
    }

    /// Aligns `class`'s first parametric model, posed by `truth`, to what a camera looking
    /// along `-toward` sees of it; checks yaw, position and scale.
    fn recovers(class: &str, truth: UprightPose, toward: Vec3) {
        let db = CadDatabase::parametric();
        let (index, model) = db.of_class(class).next().expect("a model");
        let world_from_model = truth.world_from_model();
        let points = seen_points(model, &world_from_model, toward);
        // The observed box is the box of what was seen: partial, and not the model's yaw.
        let bbox = GravityBox::minimal(&points).expect("a box");
        let object = ObservedObject {
            id: "object_1",
            class,
            bbox: GravityBox {
                // Resting on the floor, as the contact graph's refined box does.
                center: bbox.center.with_z(0.5 * bbox.top_z()),
                size: bbox.size.with_z(bbox.top_z()),
                ..bbox
            },
            top_z: bbox.top_z(),
            planes: Vec::new(),
            points: std::borrow::Cow::Borrowed(&points),
            facing: None,
            front: None,
        };
        let candidates = class_candidates(&object, &db);
        assert!(candidates.iter().any(|c| c.model == index));
        let alignment = align_all(&object, &db, &candidates)
            .into_iter()
            .find(|a| a.candidate.model == index)
            .expect("aligned");
        assert!(alignment.alignment_error < 0.01, "{alignment:?}");
        let (_, rotation, translation) = alignment.world_from_model.to_scale_rotation_translation();
        let (axis, angle) = rotation.to_axis_angle();
        let yaw = angle * axis.z.signum();
        // Up to the class's symmetry (a table turned half round is the same table), and so is
        // its origin, the bottom centre.
        let info = ClassTable::builtin().get(class).expect("a class").clone();
        assert!(info.yaw_difference(yaw, truth.yaw) < 0.05, "yaw {yaw}");
        assert!(
            translation.distance(truth.translation) < 0.02,
            "{translation}"
        );
        let scale_error = (alignment.scale / truth.scale - Vec3::ONE)
            .abs()
            .max_element();
        assert!(scale_error < 0.05, "{:?}", alignment.scale);
    }

    #[test]
    fn icp_recovers_yaw_and_position_of_a_chair_seen_from_one_side() {
        let truth = UprightPose {
            scale: Vec3::ONE,
            yaw: 2.3,
            translation: Vec3::new(1.2, -0.4, 0.0),
        };
        recovers("chair", truth, Vec3::new(1.0, -1.0, 0.6));
    }

    #[test]
    fn icp_recovers_the_width_and_depth_of_a_stretched_table() {
        let truth = UprightPose {
            scale: Vec3::new(1.3, 0.8, 1.1),
            yaw: -0.7,
            translation: Vec3::new(-0.5, 2.0, 0.0),
        };
        recovers("table", truth, Vec3::new(-0.6, -1.0, 1.0));
    }

    #[test]
    fn the_2d_fit_undoes_a_known_motion() {
        let a: Vec<Vec2> = (0..20)
            .map(|i| Vec2::new((i as f32 * 0.37).sin(), (i as f32 * 0.61).cos() * 2.0))
            .collect();
        let motion = |p: Vec2| Vec2::from_angle(0.4).rotate(p) + Vec2::new(0.3, -1.1);
        let pairs: Vec<(Vec2, Vec2)> = a.iter().map(|p| (*p, motion(*p))).collect();
        let (angle, shift) = rigid_2d(&pairs).expect("enough pairs");
        assert!((angle - 0.4).abs() < 1e-5);
        assert!(shift.distance(Vec2::new(0.3, -1.1)) < 1e-5);
        assert!(rigid_2d(&pairs[..5]).is_none());
    }
}
