//! An arm ready to work on the robot's base: its model, collision pieces, where it is mounted
//! (on a lift or a fixed column), and the compact configuration it travels in.

use glam::{Affine3A, Vec3};

use crate::arm::collision::{ArmCollider, Obstacles};
use crate::arm::ik::IkSettings;
use crate::arm::reach::TRANSIT_MARGIN_M;
use crate::arm::rrt::PlanSettings;
use crate::arm::{Arm, LinkMotion};
use crate::base::JointKind;

/// An arm ready to work: its model, collision pieces and where it sits on the base.
pub struct ArmRig {
    pub arm: Arm,
    pub collider: ArmCollider,
    /// The configuration it travels in.
    pub stow: Vec<f32>,
    /// The arm's root in the base's frame.
    pub base_from_root: Affine3A,
    /// How wide its fingers open, metres.
    pub max_opening: f32,
    /// How far the palm lies behind the tool point, metres (`Arm::palm_depth`).
    pub palm_depth: f32,
    pub plan: PlanSettings,
    pub ik: IkSettings,
}

impl ArmRig {
    /// The fingers' opening on an arm motion's reach, on a part's handle and on its retreat,
    /// the fingers a gap of `grip_m` apart on what they hold: a hand that comes `holding`
    /// something (a place) lets go at the end of the reach; a pick's fingers close on the
    /// object there; a hand on a `handle` holds it while the part follows. Open when `grip_m`
    /// is `None` (nothing between them).
    pub fn finger_openings(&self, grip_m: Option<f32>, holding: bool, handle: bool) -> [f32; 3] {
        let closed = grip_m.map_or(1.0, |g| self.finger_opening(g));
        match (holding, handle) {
            (true, _) => [closed, 1.0, 1.0],
            (false, true) => [1.0, closed, 1.0],
            (false, false) => [1.0, 1.0, closed],
        }
    }

    /// The fingers' opening (0 closed .. 1 open, as `Arm::link_poses` takes it) for a gap of
    /// `gap_m` between them.
    pub fn finger_opening(&self, gap_m: f32) -> f32 {
        if self.max_opening > 0.0 {
            (gap_m / self.max_opening).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }

    /// The arm on top of a base column `mount_height` high, stowed folded over its root
    /// ([`compact_stow`]).
    pub fn new(arm: Arm, mount_height: f32) -> Self {
        let collider = ArmCollider::new(&arm);
        let stow = compact_stow(&arm, &collider);
        let max_opening = arm
            .links
            .iter()
            .zip(&arm.motion)
            .filter(|(_, m)| **m == LinkMotion::Finger)
            .filter_map(|(l, _)| l.joint.as_ref())
            .filter(|j| j.kind == JointKind::Prismatic)
            .map(|j| j.limits.1 - j.limits.0)
            .sum();
        Self {
            palm_depth: arm.palm_depth(),
            arm,
            collider,
            stow,
            base_from_root: Affine3A::from_translation(Vec3::Z * mount_height),
            max_opening,
            plan: PlanSettings {
                resolution: 0.01,
                ..PlanSettings::default()
            },
            ik: IkSettings::default(),
        }
    }
}

/// Radius of the mast seen under the root of an arm on a lift, metres.
pub const MAST_RADIUS_M: f32 = 0.07;

impl ArmRig {
    /// This rig with its arm on a lift sliding its root from `range.0` to `range.1` metres of
    /// where the base mounts it (`Arm::on_lift`; the range holds 0). The arm travels stowed as
    /// before, the lift at 0, so drives and what the hand carries on them are unchanged.
    pub fn on_lift(self, range: (f32, f32)) -> Self {
        Self {
            arm: self.arm.on_lift(range),
            collider: self.collider.on_lift(),
            stow: std::iter::once(0.0).chain(self.stow).collect(),
            ..self
        }
    }

    /// The mast of an arm on a lift: its link and length (the lift's travel), a cylinder of
    /// [`MAST_RADIUS_M`] down from the root, what is seen of the lift above the base's column
    /// (which hides the rest). It collides with nothing: it stands inside the base's footprint.
    pub fn mast(&self) -> Option<(usize, f32)> {
        let i = self.arm.lift()?;
        let (lo, hi) = self.arm.limits()[i];
        Some((self.arm.chain[i], hi - lo))
    }
}

/// Random configurations tried for the stowed arm, and refinements of the best.
const STOW_SAMPLES: usize = 4000;
const STOW_REFINEMENTS: usize = 1500;
/// The stowed hand points down (its approach within 25 degrees of the vertical) with its tool
/// at least this high above the arm's root, metres: what it holds hangs clear of the column.
const STOW_DOWN_COS: f32 = 0.9;
const STOW_TOOL_HEIGHT_M: f32 = 0.3;
/// The stowed arm's clearance from itself: the planner's on the way, and 5 mm to spare.
const STOW_SELF_CLEARANCE_M: f32 = TRANSIT_MARGIN_M + 0.005;

/// Every vertex of `arm`'s collision pieces with its links at `poses`.
fn piece_points<'a>(arm: &'a Arm, poses: &'a [Affine3A]) -> impl Iterator<Item = Vec3> + 'a {
    arm.links.iter().zip(poses).flat_map(|(link, pose)| {
        link.pieces
            .iter()
            .flat_map(|piece| piece.positions.iter().map(|p| pose.transform_point3(*p)))
    })
}

/// The configuration the arm travels in: of the middle of its joint ranges and seeded random
/// configurations (then small random changes of the best), the one whose links stay nearest
/// the vertical through its root (the farthest point of any piece, horizontally), clear of
/// itself by more than the planner's margin, its hand pointing down with the tool at least 30 cm over the root. A drive
/// then carries the arm and what it holds no farther out than that, and a door the base stands
/// clear of misses them. The middle of the ranges held the Panda's hand 50 cm out in front of
/// the base, where the fridge's door swung into it.
pub fn compact_stow(arm: &Arm, collider: &ArmCollider) -> Vec<f32> {
    use rand::{Rng, SeedableRng};
    let limits = arm.limits();
    let reach_out = |q: &[f32]| -> Option<f32> {
        let poses = arm.link_poses(&Affine3A::IDENTITY, q, 1.0);
        let tool = poses[arm.tool];
        let down = -tool.transform_vector3(Vec3::Z).normalize().z;
        if down < STOW_DOWN_COS || tool.translation.z < STOW_TOOL_HEIGHT_M {
            return None;
        }
        if collider
            .touching(&poses, &Obstacles::default(), STOW_SELF_CLEARANCE_M)
            .is_some()
        {
            return None;
        }
        let far = piece_points(arm, &poses)
            .map(|p| p.truncate().length())
            .fold(0.0f32, f32::max);
        Some(far)
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x5704);
    let middle = arm.middle();
    let mut best = (reach_out(&middle).unwrap_or(f32::MAX), middle);
    for _ in 0..STOW_SAMPLES {
        let q = crate::arm::random_configuration(&limits, &mut rng);
        if let Some(far) = reach_out(&q)
            && far < best.0
        {
            best = (far, q);
        }
    }
    for _ in 0..STOW_REFINEMENTS {
        let q: Vec<f32> = best
            .1
            .iter()
            .map(|v| v + rng.random_range(-0.1f32..0.1))
            .collect();
        let q = arm.clamped(&q);
        if let Some(far) = reach_out(&q)
            && far < best.0
        {
            best = (far, q);
        }
    }
    best.1
}

impl ArmRig {
    /// The tool's pose in the base's frame with the arm stowed: where a held object rides
    /// between a pick and a place.
    pub fn base_from_stowed_tool(&self) -> Affine3A {
        self.base_from_root * self.arm.tool_pose(&Affine3A::IDENTITY, &self.stow)
    }

    /// Every link's pose in the base's frame with the arm stowed, fingers open.
    pub fn stowed_link_poses(&self) -> Vec<Affine3A> {
        self.arm.link_poses(&self.base_from_root, &self.stow, 1.0)
    }

    /// The stowed arm's envelope in the base's frame: how high (metres above the floor) its
    /// highest collision piece reaches, and how far out from the base's vertical axis any
    /// reaches. A door swinging lower than that over the base meets the arm folded there,
    /// whatever the column's height.
    pub fn stowed_envelope(&self) -> (f32, f32) {
        let poses = self.stowed_link_poses();
        piece_points(&self.arm, &poses)
            .fold((self.base_from_root.translation.z, 0.0), |(top, out), p| {
                (top.max(p.z), out.max(p.truncate().length()))
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;

    /// The planar two-link arm mounted 0.5 m up, its forearm (1 m from the root) a bar 1 m long
    /// and 10 cm thick, stowed at `stow`.
    fn bar_rig(stow: [f32; 2]) -> ArmRig {
        let mut arm = crate::arm::tests::two_link_arm();
        arm.links[2].pieces = vec![TriMesh::cuboid(
            Vec3::new(0.0, -0.05, -0.05),
            Vec3::new(1.0, 0.05, 0.05),
        )];
        ArmRig {
            stow: stow.to_vec(),
            ..ArmRig::new(arm, 0.5)
        }
    }

    #[test]
    fn the_stowed_envelope_holds_the_stowed_pieces_as_high_and_as_far_out_as_they_reach() {
        let (top, out) = bar_rig([0.0, 0.0]).stowed_envelope();
        assert!((top - 0.55).abs() < 1e-5, "{top}");
        assert!((out - 2.0f32.hypot(0.05)).abs() < 1e-5, "{out}");
        // The forearm folded a quarter turn: its far corner is 1.05 m along and 1 m across.
        let (top, out) = bar_rig([0.0, std::f32::consts::FRAC_PI_2]).stowed_envelope();
        assert!((top - 0.55).abs() < 1e-5, "{top}");
        assert!((out - 1.05f32.hypot(1.0)).abs() < 1e-4, "{out}");
    }
}
