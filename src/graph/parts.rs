//! The moving parts of a node of `contact_graph.json` (DESIGN.md, second round): each door or
//! drawer with its joint in the aligned world frame, the box of its front, and where it came
//! from. The ground truth lists the parts of its models; a reconstruction lists what it placed.

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::cad::CadModel;
use crate::kinematics::JointKind;

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

    /// The way the front's centre starts to move when the part opens (unit).
    pub fn opening_direction(&self) -> Vec3 {
        match self.joint.kind {
            PartJointType::Prismatic => self.axis(),
            PartJointType::Revolute => self
                .axis()
                .cross(self.front_center() - Vec3::from_array(self.joint.origin))
                .normalize_or_zero(),
        }
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

/// The moving parts of `model` placed by `world_from_model`, listed from the model (`Cad`).
pub fn model_parts(model: &CadModel, world_from_model: &Affine3A) -> Vec<PartJson> {
    let poses = model.model_from_parts(&[]);
    model
        .parts
        .iter()
        .zip(&poses)
        .filter_map(|(part, model_from_part)| {
            let (lower, upper) = part.joint.limits?;
            let kind = match part.joint.kind {
                JointKind::Revolute => PartJointType::Revolute,
                JointKind::Prismatic => PartJointType::Prismatic,
                _ => return None,
            };
            let world_from_part = *world_from_model * *model_from_part;
            let (lo, hi) = part.visual_mesh().transformed(&world_from_part).bounds()?;
            Some(PartJson {
                name: part.name.clone(),
                joint: PartJoint {
                    kind,
                    axis: world_from_part
                        .transform_vector3(part.joint.axis)
                        .normalize_or_zero()
                        .to_array(),
                    origin: world_from_part.translation.to_array(),
                    lower,
                    upper,
                },
                front: PartFront {
                    center: (0.5 * (lo + hi)).to_array(),
                    size: (hi - lo).to_array(),
                },
                handle: None,
                source: PartSource::Cad,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::ParametricLibrary;

    #[test]
    fn a_cabinet_door_opens_out_of_its_front_in_the_world() {
        let model = ParametricLibrary::get("cabinet_01").expect("model").model();
        // Turned to face +x (its front -y turned by 90 degrees).
        let frame = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
            Vec3::new(2.0, 1.0, 0.0),
        );
        let parts = model_parts(&model, &frame);
        assert!(!parts.is_empty());
        for p in &parts {
            let out = p.opening_direction();
            assert!(out.x > 0.5, "{} opens along {out}", p.name);
            assert!(p.front_center().z > 0.0);
        }
    }
}
