//! The moving parts of a node of `contact_graph.json` (DESIGN.md, second round): each door or
//! drawer with its joint in the aligned world frame, the box of its front, and where it came
//! from. The ground truth lists the parts of its models (`cad::model_parts`); a reconstruction
//! lists what it placed.

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PartJointType {
    Revolute,
    Prismatic,
}

/// A part's joint, world frame: a hinge line through `origin` along `axis` (a positive value
/// turns the part right-handed about it), or a slide along `axis`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartJoint {
    #[serde(rename = "type")]
    pub kind: PartJointType,
    pub axis: [f32; 3],
    pub origin: [f32; 3],
    pub lower: f32,
    pub upper: f32,
}

/// The box of a part's front (its part at the joint's zero), axis-aligned in the world.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartFront {
    pub center: [f32; 3],
    pub size: [f32; 3],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum HandleKind {
    Bar,
    Knob,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartHandle {
    pub kind: HandleKind,
    pub center: [f32; 3],
    pub axis: [f32; 3],
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PartSource {
    /// Seen in the map.
    Perceived,
    /// Taken from the CAD model that replaced the object.
    Cad,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartJson {
    pub name: String,
    pub joint: PartJoint,
    pub front: PartFront,
    pub handle: Option<PartHandle>,
    pub source: PartSource,
}

impl PartJson {
    pub fn axis(&self) -> Vec3 {
        Vec3::from_array(self.joint.axis).normalize_or_zero()
    }

    pub fn front_center(&self) -> Vec3 {
        Vec3::from_array(self.front.center)
    }

    /// The way the front's centre starts to move when the part opens (unit): towards the end of
    /// its range farther from zero, which is the negative end for some imported models (LIBERO's
    /// drawers slide along +y from -0.5 to 0.03).
    pub fn opening_direction(&self) -> Vec3 {
        let sign = if self.joint.upper.abs() >= self.joint.lower.abs() {
            1.0
        } else {
            -1.0
        };
        let direction = match self.joint.kind {
            PartJointType::Prismatic => self.axis(),
            PartJointType::Revolute => self
                .axis()
                .cross(self.front_center() - Vec3::from_array(self.joint.origin))
                .normalize_or_zero(),
        };
        sign * direction
    }

    /// The same part seen from another frame (`to_from_this` may scale; axes stay unit).
    pub fn transformed(&self, to_from_this: &Affine3A) -> PartJson {
        let point = |p: [f32; 3]| {
            to_from_this
                .transform_point3(Vec3::from_array(p))
                .to_array()
        };
        let vector = |v: [f32; 3]| {
            to_from_this
                .transform_vector3(Vec3::from_array(v))
                .normalize_or_zero()
                .to_array()
        };
        PartJson {
            name: self.name.clone(),
            joint: PartJoint {
                kind: self.joint.kind,
                axis: vector(self.joint.axis),
                origin: point(self.joint.origin),
                lower: self.joint.lower,
                upper: self.joint.upper,
            },
            front: PartFront {
                center: point(self.front.center),
                size: self.front.size,
            },
            handle: self.handle.as_ref().map(|h| PartHandle {
                kind: h.kind,
                center: point(h.center),
                axis: vector(h.axis),
            }),
            source: self.source,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(kind: PartJointType, axis: [f32; 3], lower: f32, upper: f32) -> PartJson {
        PartJson {
            name: "p".into(),
            joint: PartJoint {
                kind,
                axis,
                origin: [0.0, 0.0, 0.0],
                lower,
                upper,
            },
            front: PartFront {
                center: [0.3, 0.0, 0.4],
                size: [0.6, 0.02, 0.8],
            },
            handle: None,
            source: PartSource::Cad,
        }
    }

    #[test]
    fn a_part_opens_towards_the_end_of_its_range_farther_from_zero() {
        // The library's drawer slides along -y from 0 to 0.3; LIBERO's along +y from -0.5 to
        // 0.03: both come out towards -y.
        let library = part(PartJointType::Prismatic, [0.0, -1.0, 0.0], 0.0, 0.3);
        let libero = part(PartJointType::Prismatic, [0.0, 1.0, 0.0], -0.5, 0.03);
        assert!(library.opening_direction().dot(Vec3::NEG_Y) > 0.99);
        assert!(libero.opening_direction().dot(Vec3::NEG_Y) > 0.99);
        // A door hinged at x = 0 with its front towards +x: turning about -z swings it out to -y;
        // about +z to a negative limit as well.
        let door = part(PartJointType::Revolute, [0.0, 0.0, -1.0], 0.0, 1.8);
        let negative = part(PartJointType::Revolute, [0.0, 0.0, 1.0], -1.8, 0.0);
        assert!(door.opening_direction().dot(Vec3::NEG_Y) > 0.99);
        assert!(negative.opening_direction().dot(Vec3::NEG_Y) > 0.99);
    }
}
