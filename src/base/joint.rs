//! Joint kinds, axes and limits, and the motion a joint value produces (URDF conventions).

use glam::{Affine3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// What a file may have broken in a joint.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum JointSpecError {
    #[error("axis {0:?} is not a unit vector")]
    NotUnitAxis([f32; 3]),
    #[error("limits {lower}..{upper} reach past {max} {unit} of rest")]
    BeyondReach {
        lower: f32,
        upper: f32,
        max: f32,
        unit: &'static str,
    },
    #[error("limits {lower}..{upper} are not finite and in order")]
    BadLimits { lower: f32, upper: f32 },
    #[error("a revolute or prismatic joint without limits")]
    NoLimits,
}

/// How a child link may move relative to its parent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Rigidly attached (a table on the floor, a shelf board in a cabinet).
    Fixed,
    /// Free in all six degrees of freedom, resting on its parent (a cup on a table).
    Floating,
    /// Rotation about `axis` through the child frame's origin, value in radians (a door).
    Revolute,
    /// Translation along `axis`, value in metres (a drawer).
    Prismatic,
}

/// A joint's kind, axis (a unit vector in the child's joint frame) and limits `(lower, upper)`.
///
/// As in URDF, the joint frame is the child link's frame at value zero: the child's pose in its
/// parent is `parent_from_joint * motion(value)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSpec {
    pub kind: JointKind,
    pub axis: Vec3,
    /// `(lower, upper)` for revolute (radians) and prismatic (metres) joints.
    pub limits: Option<(f32, f32)>,
}

/// The widest a revolute joint may turn either way from rest: a full turn.
pub const MAX_REVOLUTE_RAD: f32 = std::f32::consts::TAU;
/// The farthest a prismatic joint may slide either way from rest, metres.
pub const MAX_PRISMATIC_M: f32 = 3.0;

impl JointSpec {
    pub const FIXED: JointSpec = JointSpec {
        kind: JointKind::Fixed,
        axis: Vec3::Z,
        limits: None,
    };
    pub const FLOATING: JointSpec = JointSpec {
        kind: JointKind::Floating,
        axis: Vec3::Z,
        limits: None,
    };

    pub fn revolute(axis: Vec3, lower: f32, upper: f32) -> Self {
        Self {
            kind: JointKind::Revolute,
            axis: axis.normalize(),
            limits: Some((lower, upper)),
        }
    }

    pub fn prismatic(axis: Vec3, lower: f32, upper: f32) -> Self {
        Self {
            kind: JointKind::Prismatic,
            axis: axis.normalize(),
            limits: Some((lower, upper)),
        }
    }

    /// Checks what a file may have broken: a unit axis, and limits that are finite, in order and
    /// within [`MAX_REVOLUTE_RAD`] or [`MAX_PRISMATIC_M`] of rest (a range of 1e30 would make
    /// every sweep of the joint endless).
    pub fn check(&self) -> Result<(), JointSpecError> {
        if !(self.axis.is_finite() && (self.axis.length() - 1.0).abs() < 1e-3) {
            return Err(JointSpecError::NotUnitAxis(self.axis.to_array()));
        }
        let max = match self.kind {
            JointKind::Revolute => MAX_REVOLUTE_RAD,
            JointKind::Prismatic => MAX_PRISMATIC_M,
            JointKind::Fixed | JointKind::Floating => return Ok(()),
        };
        match self.limits {
            Some((lo, hi)) if lo.is_finite() && hi.is_finite() && lo <= hi => {
                if lo < -max || hi > max {
                    Err(JointSpecError::BeyondReach {
                        lower: lo,
                        upper: hi,
                        max,
                        unit: if self.kind == JointKind::Revolute {
                            "rad"
                        } else {
                            "m"
                        },
                    })
                } else {
                    Ok(())
                }
            }
            Some((lo, hi)) => Err(JointSpecError::BadLimits {
                lower: lo,
                upper: hi,
            }),
            None => Err(JointSpecError::NoLimits),
        }
    }

    /// `value` clamped to the joint's limits (unchanged for joints without limits).
    pub fn clamp(&self, value: f32) -> f32 {
        match self.limits {
            Some((lo, hi)) => value.clamp(lo, hi),
            None => value,
        }
    }

    /// The child's motion in its joint frame at `value` (identity for fixed and floating joints,
    /// whose pose is carried by the parent-from-joint transform).
    pub fn motion(&self, value: f32) -> Affine3A {
        match self.kind {
            JointKind::Fixed | JointKind::Floating => Affine3A::IDENTITY,
            JointKind::Revolute => Affine3A::from_quat(Quat::from_axis_angle(self.axis, value)),
            JointKind::Prismatic => Affine3A::from_translation(self.axis * value),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn revolute_motion_rotates_about_the_axis_through_the_origin() {
        let hinge = JointSpec::revolute(Vec3::Z, 0.0, 2.0);
        let p = hinge
            .motion(std::f32::consts::FRAC_PI_2)
            .transform_point3(Vec3::X);
        assert!((p - Vec3::Y).length() < 1e-6, "{p}");
        assert_eq!(hinge.clamp(3.0), 2.0);
    }

    #[test]
    fn prismatic_motion_translates_along_the_axis() {
        let slide = JointSpec::prismatic(-Vec3::Y, 0.0, 0.4);
        let p = slide.motion(0.3).transform_point3(Vec3::ZERO);
        assert!((p - Vec3::new(0.0, -0.3, 0.0)).length() < 1e-6);
    }
}
