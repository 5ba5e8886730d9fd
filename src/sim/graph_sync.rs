//! The contact graph after simulated actions: support edges read off the kinematic tree (a
//! placed cup is supported by its new parent, a held one by nothing), boxes and CAD placements
//! moved with their objects, joint values as they are now, and the proximal pairs of every
//! object that moved found again from the moved boxes (the others keep theirs).

use glam::{Affine3A, Mat4};

use crate::geometry::GravityBox;
use crate::graph::proximal::{ProximalMargins, proximal_edges};
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
    let mut moved_nodes: Vec<String> = Vec::new();
    for node in &mut out.nodes {
        let (Some(a), Some(b)) = (old.node_link(&node.id), now.node_link(&node.id)) else {
            continue;
        };
        let moved: Affine3A = now.poses[b] * old.poses[a].inverse();
        if moves(&moved) {
            moved_nodes.push(node.id.clone());
        }
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
    let supports: Vec<(String, String)> = now
        .nodes()
        .into_iter()
        .filter_map(|child| {
            now.support_of(child)
                .map(|parent| (parent.to_string(), child.to_string()))
        })
        .collect();
    let moved = |id: &str| moved_nodes.iter().any(|m| m == id);
    // Proximal pairs between unmoved objects stand as the graph had them (a reconstruction's
    // wider margins included); those of a moved object are found again where it is now.
    let kept_proximal = out.edges.iter().filter(|e| match e {
        GraphEdge::Proximal { a, b } => !moved(a) && !moved(b),
        GraphEdge::Support { .. } => false,
    });
    let boxed: Vec<(&str, GravityBox, &str)> = out
        .nodes
        .iter()
        .map(|n| (n.id.as_str(), GravityBox::from(&n.bbox), n.class.as_str()))
        .collect();
    let support_pairs: Vec<(&str, &str)> = supports
        .iter()
        .map(|(p, c)| (p.as_str(), c.as_str()))
        .collect();
    let found_proximal = proximal_edges(&boxed, &support_pairs, ProximalMargins::EXACT)
        .into_iter()
        .filter(|e| matches!(e, GraphEdge::Proximal { a, b } if moved(a) || moved(b)));
    let edges: Vec<GraphEdge> = supports
        .iter()
        .map(|(parent, child)| GraphEdge::Support {
            parent: parent.clone(),
            child: child.clone(),
        })
        .chain(kept_proximal.cloned())
        .chain(found_proximal)
        .collect();
    out.edges = edges;
    out
}

/// Whether a rigid motion moves anything (beyond rounding: 0.1 mm, 1e-4 of a turn per axis).
fn moves(motion: &Affine3A) -> bool {
    let turned = (motion.matrix3 - glam::Mat3A::IDENTITY)
        .to_cols_array()
        .iter()
        .any(|d| d.abs() > 1e-4);
    turned || motion.translation.length() > 1e-4
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use glam::Vec3;

    use super::*;
    use crate::classes::EntityKind;
    use crate::geometry::TriMesh;
    use crate::graph::{BoxJson, GraphNode};
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;

    const CUP: Vec3 = Vec3::new(0.04, 0.04, 0.1);

    /// A floor, a table (top at 0.75) with cup_1 on it, and cup_2 on the table at `cup_2_at`
    /// (table frame, bottom centre).
    fn tree(cup_2_at: Vec3) -> KinematicTree {
        let cup = TriMesh::cuboid(
            Vec3::new(-CUP.x, -CUP.y, 0.0),
            Vec3::new(CUP.x, CUP.y, CUP.z),
        );
        KinematicTree {
            links: vec![
                TreeLink::root(),
                TreeLink::body(
                    "floor",
                    "floor",
                    0,
                    JointSpec::FIXED,
                    Affine3A::IDENTITY,
                    TriMesh::cuboid(Vec3::new(-3.0, -3.0, -0.1), Vec3::new(3.0, 3.0, 0.0)),
                ),
                TreeLink::body(
                    "table_1",
                    "table",
                    1,
                    JointSpec::FIXED,
                    Affine3A::IDENTITY,
                    TriMesh::cuboid(Vec3::new(-0.6, -0.4, 0.0), Vec3::new(0.6, 0.4, 0.75)),
                ),
                TreeLink::body(
                    "cup_1",
                    "cup",
                    2,
                    JointSpec::FLOATING,
                    Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.75)),
                    cup.clone(),
                ),
                TreeLink::body(
                    "cup_2",
                    "cup",
                    2,
                    JointSpec::FLOATING,
                    Affine3A::from_translation(cup_2_at),
                    cup,
                ),
            ],
        }
    }

    fn node(id: &str, class: &str, center: Vec3, size: Vec3) -> GraphNode {
        GraphNode {
            id: id.into(),
            class: class.into(),
            kind: if class == "floor" {
                EntityKind::Layout
            } else {
                EntityKind::Rigid
            },
            bbox: BoxJson {
                center: center.to_array(),
                yaw: 0.0,
                size: size.to_array(),
            },
            planes: Vec::new(),
            cad: None,
            joints: BTreeMap::new(),
            parts: Vec::new(),
        }
    }

    fn support(parent: &str, child: &str) -> GraphEdge {
        GraphEdge::Support {
            parent: parent.into(),
            child: child.into(),
        }
    }

    #[test]
    fn a_moved_cup_gets_its_new_neighbour_as_proximal_and_loses_the_old_one() {
        let far = Vec3::new(0.5, 0.3, 0.75);
        let cup_height = 0.75 + CUP.z / 2.0;
        let graph = ContactGraph {
            nodes: vec![
                node(
                    "floor",
                    "floor",
                    Vec3::new(0.0, 0.0, -0.05),
                    Vec3::new(6.0, 6.0, 0.1),
                ),
                node(
                    "table_1",
                    "table",
                    Vec3::new(0.0, 0.0, 0.375),
                    Vec3::new(1.2, 0.8, 0.75),
                ),
                node("cup_1", "cup", Vec3::new(0.0, 0.0, cup_height), 2.0 * CUP),
                node(
                    "cup_2",
                    "cup",
                    Vec3::new(far.x, far.y, cup_height),
                    2.0 * CUP,
                ),
                // An unmoved pair the graph had (a reconstruction's wider margin): kept.
                node(
                    "chair_1",
                    "chair",
                    Vec3::new(0.0, 0.5, 0.45),
                    Vec3::new(0.4, 0.4, 0.9),
                ),
            ],
            edges: vec![
                support("floor", "table_1"),
                support("table_1", "cup_1"),
                support("table_1", "cup_2"),
                GraphEdge::Proximal {
                    a: "table_1".into(),
                    b: "chair_1".into(),
                },
                GraphEdge::Proximal {
                    a: "cup_2".into(),
                    b: "chair_1".into(),
                },
            ],
        };
        // cup_2 slides next to cup_1 (1 cm apart).
        let after = graph_after(&graph, &tree(far), &tree(Vec3::new(0.09, 0.0, 0.75)));
        let proximal: Vec<(&str, &str)> = after
            .edges
            .iter()
            .filter_map(|e| match e {
                GraphEdge::Proximal { a, b } => Some((a.as_str(), b.as_str())),
                GraphEdge::Support { .. } => None,
            })
            .collect();
        assert_eq!(proximal, [("table_1", "chair_1"), ("cup_1", "cup_2")]);
        assert_eq!(after.parent_of("cup_2"), Some("table_1"));
        let moved = after.node("cup_2").expect("cup_2").bbox.center;
        assert!((Vec3::from_array(moved) - Vec3::new(0.09, 0.0, cup_height)).length() < 1e-5);
    }
}
