//! The kinematic tree as glTF 2.0 (`scene.glb`): one node per link under its parent, named by
//! the link (contact-graph ids for objects and layout, `<id>_<part>` for moving parts), posed at
//! the current joint values, with the joint, class and mass in the node's extras.

use crate::io::gltf_write::{GlbError, GltfNode, glb_bytes, nest};
use crate::kinematics::tree::KinematicTree;

/// The name of the node that turns the scene's +z up into glTF's +y up.
pub const UP_AXIS_NODE: &str = "z_up";

pub fn scene_glb(tree: &KinematicTree) -> Result<Vec<u8>, GlbError> {
    let nodes: Vec<GltfNode> = tree
        .links
        .iter()
        .map(|link| {
            let mut node = GltfNode::new(link.name.clone());
            let (_, rotation, translation) =
                link.parent_from_link_now().to_scale_rotation_translation();
            node.translation = translation;
            node.rotation = rotation.normalize();
            if let Some(g) = &link.geometry {
                node.mesh = Some((g.visual.clone(), g.color));
                node.extras = Some(serde_json::json!({
                    "node": link.node,
                    "class": link.class,
                    "joint": link.joint,
                    "joint_value": link.value,
                    "mass_kg": g.inertial.mass,
                }));
            }
            node
        })
        .collect();
    let root = nest(nodes, |i| tree.links[i].parent.unwrap_or(0)).ok_or(GlbError::Empty)?;
    glb_bytes(&root, UP_AXIS_NODE)
}
