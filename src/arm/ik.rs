//! Inverse kinematics: joint values that put the tool at a pose, by damped least squares
//! (Wampler 1986; Buss 2004, "Introduction to inverse kinematics with Jacobian transpose,
//! pseudoinverse and damped least squares methods"), within the joint limits.
//!
//! Each step solves `(J J^T + lambda^2 I) y = e` for the 6-vector error `e` (position, and the
//! rotation vector that turns the tool onto the target) and moves the joints by `J^T y`, then
//! clamps them to their limits. A run that stalls restarts from random configurations drawn from
//! a seeded generator, so the same target and seed give the same answer.

use glam::{Affine3A, Mat3, Quat, Vec3};
use nalgebra::{Matrix6, Vector6};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::arm::{Arm, joint_axis, random_configuration};
use crate::base::JointKind;

/// What counts as reaching the target, and how hard to try.
#[derive(Clone, Copy, Debug)]
pub struct IkSettings {
    /// Position error at or under which the target is reached, metres.
    pub position_tolerance: f32,
    /// Rotation error at or under which the target is reached, radians.
    pub rotation_tolerance: f32,
    /// Whether the rotation counts at all (a point to reach rather than a pose).
    pub orientation: bool,
    /// Damping: larger is steadier near singular configurations, slower elsewhere.
    pub damping: f32,
    /// The largest joint change of one step, radians or metres.
    pub max_step: f32,
    /// Steps of one run before it restarts.
    pub iterations: usize,
    /// Runs from random configurations after the run from the seed configuration.
    pub restarts: usize,
    pub seed: u64,
    /// How strongly each step also moves the joints towards the middle of their ranges in the
    /// null space of the tool's motion (a redundant arm's self-motion; Liegeois 1977): 0 leaves
    /// the redundancy alone. Keeps a hand that follows a path away from the joints' limits.
    pub centering: f32,
}

impl Default for IkSettings {
    fn default() -> Self {
        Self {
            position_tolerance: 1e-3,
            rotation_tolerance: 1e-2,
            orientation: true,
            damping: 0.05,
            max_step: 0.3,
            iterations: 150,
            restarts: 40,
            seed: 0,
            centering: 0.0,
        }
    }
}

/// The geometric Jacobian of the tool's position and rotation (6 rows: linear, then angular
/// velocity in the world) with respect to the chain's joints, one column per joint.
pub fn jacobian(arm: &Arm, world_from_root: &Affine3A, q: &[f32]) -> Vec<[f32; 6]> {
    let poses = arm.link_poses(world_from_root, q, 0.0);
    let tool = Vec3::from(poses[arm.tool].translation);
    (0..arm.dof())
        .map(|i| {
            let (axis, point) = joint_axis(arm, &poses, i);
            let kind = arm.links[arm.chain[i]].joint.as_ref().expect("joint").kind;
            match kind {
                JointKind::Revolute => {
                    let v = axis.cross(tool - point);
                    [v.x, v.y, v.z, axis.x, axis.y, axis.z]
                }
                JointKind::Prismatic => [axis.x, axis.y, axis.z, 0.0, 0.0, 0.0],
                // A body tree's joints are revolute or prismatic.
                JointKind::Fixed | JointKind::Floating => [0.0; 6],
            }
        })
        .collect()
}

/// The error that takes the tool at `current` to `target`: the position difference and the
/// rotation vector (axis times angle, in the world) of `target`'s rotation after `current`'s.
pub fn pose_error(current: &Affine3A, target: &Affine3A) -> (Vec3, Vec3) {
    let position = Vec3::from(target.translation - current.translation);
    let rc = Quat::from_mat3(&Mat3::from(current.matrix3)).normalize();
    let rt = Quat::from_mat3(&Mat3::from(target.matrix3)).normalize();
    let mut turn = rt * rc.inverse();
    // The shorter way round.
    if turn.w < 0.0 {
        turn = -turn;
    }
    let (axis, angle) = turn.to_axis_angle();
    (position, axis * angle)
}

/// Joint values within the limits that put the tool at `target` (with the arm's root at
/// `world_from_root`) and that `accept` accepts (say, free of collisions), starting from
/// `seed_q`; `None` when no run reaches it.
pub fn solve(
    arm: &Arm,
    world_from_root: &Affine3A,
    target: &Affine3A,
    seed_q: &[f32],
    settings: &IkSettings,
    accept: &dyn Fn(&[f32]) -> bool,
) -> Option<Vec<f32>> {
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut start = arm.clamped(seed_q);
    // A lift first holds the seed's height: the arm alone, as if it had no lift (the same runs
    // from the same draws), so that the lift moves only for what the arm cannot reach there.
    let held = arm.limits_between(&start, &start);
    for _ in 0..=settings.restarts {
        if let Some(q) = descend(arm, world_from_root, target, start.clone(), settings, false)
            && accept(&q)
        {
            return Some(q);
        }
        start = random_configuration(&held, &mut rng);
    }
    arm.lift()?;
    let limits = arm.limits();
    for _ in 0..settings.restarts / 2 {
        start = random_configuration(&limits, &mut rng);
        if let Some(q) = descend(arm, world_from_root, target, start.clone(), settings, true)
            && accept(&q)
        {
            return Some(q);
        }
    }
    None
}

/// How much a free lift's joint (`Arm::on_lift`) takes part in a step, against 1 for the arm's
/// own joints: the least-squares step is weighted (the weighted pseudoinverse with
/// `W = diag(LIFT_WEIGHT^2, 1, ...)`), so the lift moves where the arm alone does not reach;
/// the starting configuration (a random restart) mostly chooses its height.
const LIFT_WEIGHT: f32 = 0.3;

/// One damped-least-squares run from `q`, a lift held where `q` has it unless `lift_free`; the
/// configuration when it reaches the target.
fn descend(
    arm: &Arm,
    world_from_root: &Affine3A,
    target: &Affine3A,
    mut q: Vec<f32>,
    settings: &IkSettings,
    lift_free: bool,
) -> Option<Vec<f32>> {
    let lambda2 = settings.damping * settings.damping;
    let limits = arm.limits();
    // The lift's joint and the weight of its column (the arm's own are 1).
    let lift = arm
        .lift()
        .map(|i| (i, if lift_free { LIFT_WEIGHT } else { 0.0 }));
    for _ in 0..settings.iterations {
        let (position, mut rotation) = pose_error(&arm.tool_pose(world_from_root, &q), target);
        if !settings.orientation {
            rotation = Vec3::ZERO;
        }
        if position.length() <= settings.position_tolerance
            && rotation.length() <= settings.rotation_tolerance
        {
            return Some(q);
        }
        let e = Vector6::new(
            position.x, position.y, position.z, rotation.x, rotation.y, rotation.z,
        );
        let mut columns = jacobian(arm, world_from_root, &q);
        if !settings.orientation {
            for c in &mut columns {
                c[3..].fill(0.0);
            }
        }
        if let Some((i, weight)) = lift {
            columns[i].iter_mut().for_each(|v| *v *= weight);
        }
        // A joint at its limit that the step would push past it is held where it is, and the
        // step solved again with the other joints: clamping it afterwards would stall the run
        // with the rest of the arm waiting for a motion it cannot make.
        let mut dq = damped_step(&columns, &e, lambda2)?;
        for _ in 0..columns.len() {
            let pushed: Vec<usize> = (0..columns.len())
                .filter(|&i| {
                    let (lo, hi) = limits[i];
                    columns[i] != [0.0; 6]
                        && ((q[i] <= lo && dq[i] < 0.0) || (q[i] >= hi && dq[i] > 0.0))
                })
                .collect();
            if pushed.is_empty() {
                break;
            }
            for i in pushed {
                columns[i] = [0.0; 6];
            }
            dq = damped_step(&columns, &e, lambda2)?;
        }
        if settings.centering > 0.0 {
            let toward_middle: Vec<f32> = (0..columns.len())
                .map(|i| {
                    let (lo, hi) = limits[i];
                    settings.centering * (0.5 * (lo + hi) - q[i]) / (hi - lo).max(1e-3)
                })
                .collect();
            // Its part that moves the tool, taken off: J+ J z.
            let moved = columns
                .iter()
                .zip(&toward_middle)
                .fold(Vector6::zeros(), |w, (c, z)| {
                    w + Vector6::from_row_slice(c) * *z
                });
            let along_task = damped_step(&columns, &moved, lambda2)?;
            for i in 0..dq.len() {
                dq[i] += toward_middle[i] - along_task[i];
            }
        }
        if let Some((i, weight)) = lift {
            dq[i] *= weight;
        }
        let largest = dq.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        if !largest.is_finite() {
            return None;
        }
        if largest > settings.max_step {
            let scale = settings.max_step / largest;
            dq.iter_mut().for_each(|v| *v *= scale);
        }
        let stepped: Vec<f32> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
        q = arm.clamped(&stepped);
    }
    None
}

/// The damped least-squares step `J^T (J J^T + lambda2 I)^-1 e` for the Jacobian's `columns`.
fn damped_step(columns: &[[f32; 6]], e: &Vector6<f32>, lambda2: f32) -> Option<Vec<f32>> {
    let mut a = Matrix6::<f32>::identity() * lambda2;
    for c in columns {
        let c = Vector6::from_row_slice(c);
        a += c * c.transpose();
    }
    let y = a.cholesky()?.solve(e);
    Some(
        columns
            .iter()
            .map(|c| Vector6::from_row_slice(c).dot(&y))
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::tests::two_link_arm;

    #[test]
    fn the_planar_arm_reaches_a_point_of_its_annulus() {
        let arm = two_link_arm();
        let target = Affine3A::from_translation(Vec3::new(1.2, 0.7, 0.0));
        let settings = IkSettings {
            orientation: false,
            ..IkSettings::default()
        };
        let q = solve(
            &arm,
            &Affine3A::IDENTITY,
            &target,
            &[0.1, 0.1],
            &settings,
            &|_| true,
        )
        .expect("reachable");
        let tool = arm.tool_pose(&Affine3A::IDENTITY, &q).translation;
        assert!((Vec3::from(tool) - Vec3::new(1.2, 0.7, 0.0)).length() < 1e-3);
        // Out of reach: no answer.
        let far = Affine3A::from_translation(Vec3::new(2.5, 0.0, 0.0));
        assert!(
            solve(
                &arm,
                &Affine3A::IDENTITY,
                &far,
                &[0.1, 0.1],
                &settings,
                &|_| true
            )
            .is_none()
        );
    }

    #[test]
    fn the_jacobian_matches_finite_differences() {
        let arm = two_link_arm();
        let q = [0.3, -0.7];
        let columns = jacobian(&arm, &Affine3A::IDENTITY, &q);
        for (i, c) in columns.iter().enumerate() {
            let mut moved = q;
            moved[i] += 1e-3;
            let a = arm.tool_pose(&Affine3A::IDENTITY, &q).translation;
            let b = arm.tool_pose(&Affine3A::IDENTITY, &moved).translation;
            let numeric = Vec3::from(b - a) / 1e-3;
            assert!(
                (numeric - Vec3::new(c[0], c[1], c[2])).length() < 1e-2,
                "{numeric} {c:?}"
            );
        }
    }
}
