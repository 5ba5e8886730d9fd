//! The doors and drawers of a placed CAD model as `contact_graph.json` lists them.

use glam::Affine3A;

use crate::base::JointKind;
use crate::cad::CadModel;
use crate::graph::parts::{PartFront, PartJoint, PartJointType, PartJson, PartSource};

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
    use glam::Vec3;

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
