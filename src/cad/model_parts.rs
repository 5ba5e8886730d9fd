//! The doors and drawers of a placed CAD model as `contact_graph.json` lists them.

use glam::{Affine3A, Vec3};

use crate::base::JointKind;
use crate::cad::CadModel;
use crate::cad::library::perceived::is_perceived_model;
use crate::graph::parts::{PartFront, PartHandle, PartJoint, PartJointType, PartJson, PartSource};
use crate::perception::handles::Handle;

/// A handle belongs to the part whose front box, grown by this much (metres), holds its centre:
/// it stands a few centimetres out of the front.
const HANDLE_REACH_M: f32 = 0.05;

/// The moving parts of `model` placed by `world_from_model`: `Perceived` for a model built from
/// an object's perceived parts (`cad::library::perceived`), else listed from the CAD model.
pub fn model_parts(model: &CadModel, world_from_model: &Affine3A) -> Vec<PartJson> {
    let poses = model.model_from_parts(&[]);
    let source = if is_perceived_model(&model.id) {
        PartSource::Perceived
    } else {
        PartSource::Cad
    };
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
                source,
            })
        })
        .collect()
}

/// Gives each part the handle on its front: the perceived one where the camera saw one there,
/// else the model's own (both world frame); a part without either keeps none.
pub fn attach_handles(parts: &mut [PartJson], perceived: &[Handle], modelled: &[Handle]) {
    for part in parts {
        let center = Vec3::from_array(part.front.center);
        let half = 0.5 * Vec3::from_array(part.front.size) + Vec3::splat(HANDLE_REACH_M);
        let on_front = |h: &&Handle| ((h.center - center).abs() - half).max_element() <= 0.0;
        let nearest = |handles: &[Handle]| {
            handles
                .iter()
                .filter(on_front)
                .min_by(|a, b| {
                    a.center
                        .distance(center)
                        .total_cmp(&b.center.distance(center))
                })
                .copied()
        };
        part.handle = nearest(perceived)
            .or_else(|| nearest(modelled))
            .map(|h| PartHandle {
                kind: h.kind,
                center: h.center.to_array(),
                axis: h.axis.to_array(),
            });
    }
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

    #[test]
    fn each_door_of_a_two_door_cabinet_gets_the_handle_on_its_front() {
        use crate::cad::db::database::CadDatabase;
        let db = CadDatabase::parametric();
        let model = db.get("cabinet_01").expect("model");
        let frame = Affine3A::from_translation(Vec3::new(1.0, 2.0, 0.0));
        let mut parts = model_parts(&model.model, &frame);
        let modelled = model.placed_handles(&frame);
        assert_eq!(modelled.len(), 2);
        attach_handles(&mut parts, &[], &modelled);
        let left = parts.iter().find(|p| p.name == "door_left").expect("left");
        let right = parts
            .iter()
            .find(|p| p.name == "door_right")
            .expect("right");
        let (hl, hr) = (
            left.handle.as_ref().expect("a handle on the left door"),
            right.handle.as_ref().expect("a handle on the right door"),
        );
        // Each near the middle, on its own door's side, and standing out of the front (-y).
        assert!(hl.center[0] < 1.0 && hr.center[0] > 1.0, "{hl:?} {hr:?}");
        assert!(hl.center[1] < left.front.center[1]);
        // A perceived handle on the left door replaces the model's there.
        let seen = Handle {
            center: Vec3::new(0.9, 1.7, 0.5),
            ..modelled[0]
        };
        attach_handles(&mut parts, &[seen], &modelled);
        let left = parts.iter().find(|p| p.name == "door_left").expect("left");
        let handle = left.handle.as_ref().expect("a handle");
        assert_eq!(handle.center, [0.9, 1.7, 0.5]);
    }
}
