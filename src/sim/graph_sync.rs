//! The contact graph after simulated actions: support edges read off the kinematic tree (a
//! placed cup is supported by its new parent, a held one by nothing), boxes and CAD placements
//! moved with their objects, joint values as they are now.

use glam::{Affine3A, Mat4};

use crate::graph::{ContactGraph, GraphEdge};
use crate::kinematics::tree::KinematicTree;
use crate::sim::scene_view::{SceneView, yaw_of};

/// `graph` (whose tree was `before`) updated to the tree `after`.
pub fn graph_after(
    graph: &ContactGraph,
    before: &KinematicTree,
    after: &KinematicTree,
) -> ContactGraph {
    let (old, now) = (SceneView::new(before), SceneView::new(after));
    let mut out = graph.clone();
    for node in &mut out.nodes {
        let (Some(a), Some(b)) = (old.node_link(&node.id), now.node_link(&node.id)) else {
            continue;
        };
        let moved: Affine3A = now.poses[b] * old.poses[a].inverse();
        let centre = moved.transform_point3(glam::Vec3::from_array(node.bbox.center));
        node.bbox.center = centre.to_array();
        node.bbox.yaw += yaw_of(&moved);
        if let Some(cad) = &mut node.cad {
            let m = Affine3A::from_mat4(Mat4::from_cols_array(&cad.world_from_model));
            cad.world_from_model = Mat4::from(moved * m).to_cols_array();
        }
        let prefix = format!("{}_", node.id);
        for (i, link) in after.links.iter().enumerate() {
            if link.node.as_deref() == Some(node.id.as_str())
                && let Some(part) = link.name.strip_prefix(&prefix)
                && now.moving_parts(&node.id).contains(&i)
            {
                node.joints.insert(part.to_string(), link.value);
            }
        }
        // Planes move with the object: [n, d] with n . p + d = 0.
        for plane in &mut node.planes {
            let n = moved.transform_vector3(glam::Vec3::new(plane[0], plane[1], plane[2]));
            let p =
                moved.transform_point3(-plane[3] * glam::Vec3::new(plane[0], plane[1], plane[2]));
            *plane = [n.x, n.y, n.z, -n.dot(p)];
        }
    }
    out.edges
        .retain(|e| !matches!(e, GraphEdge::Support { .. }));
    let mut supports: Vec<GraphEdge> = now
        .nodes()
        .into_iter()
        .filter_map(|child| {
            now.support_of(child).map(|parent| GraphEdge::Support {
                parent: parent.to_string(),
                child: child.to_string(),
            })
        })
        .collect();
    supports.append(&mut out.edges);
    out.edges = supports;
    out
}
