//! The kinematic tree as MuJoCo MJCF (`scene.xml`), using the URDF export's collision meshes.
//!
//! MuJoCo allows a free joint only on a body whose parent is the world, so every link with a
//! floating joint becomes a top-level body at its current world pose, with its fixed and
//! articulated descendants nested inside it. Links joined to the world by fixed joints are
//! static bodies; doors and drawers keep their hinge and slide joints with their ranges.

use std::fmt::Write;

use glam::Affine3A;

use crate::export::urdf::{collision_mesh_path, tidy};
use crate::kinematics::JointKind;
use crate::kinematics::tree::{KinematicTree, TreeLink};

/// Damping on hinge and slide joints (N m s/rad, N s/m): doors swing shut slowly, not forever.
const JOINT_DAMPING: f32 = 0.5;

pub fn attr_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

pub fn numbers(values: &[f32]) -> String {
    values
        .iter()
        .map(|v| tidy(*v).to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

/// `pos` and `quat` (w x y z) attributes of a rigid pose.
pub fn pose_attrs(a: &Affine3A) -> String {
    let (_, q, t) = a.to_scale_rotation_translation();
    let q = q.normalize();
    format!(
        "pos=\"{}\" quat=\"{}\"",
        numbers(&t.to_array()),
        numbers(&[q.w, q.x, q.y, q.z])
    )
}

fn mesh_name(link: &str, piece: usize) -> String {
    format!("{link}_c{piece}")
}

/// `scene.xml`: the MJCF model of `tree`, its meshes referenced relative to the file.
pub fn mjcf_text(tree: &KinematicTree, name: &str) -> String {
    mjcf_document(tree, name, &[], &MjcfExtra::default())
}

/// What a document adds to a tree's model: assets and top-level bodies, as MJCF text.
#[derive(Default)]
pub struct MjcfExtra {
    pub assets: String,
    pub bodies: String,
}

/// The MJCF model of `tree` without the links `skip` (and what hangs from them), with `extra`.
pub fn mjcf_document(
    tree: &KinematicTree,
    name: &str,
    skip: &[usize],
    extra: &MjcfExtra,
) -> String {
    let world_from_links = tree.world_from_links();
    let children = crate::base::parent_chain::children(
        tree.links
            .iter()
            .enumerate()
            .map(|(i, link)| link.parent.filter(|_| !skip.contains(&i))),
    );
    let skipped = |i: usize| skip.iter().any(|&s| tree.descends_from(i, s));
    let mut xml = String::new();
    let _ = writeln!(xml, "<mujoco model=\"{}\">", attr_escape(name));
    let _ = writeln!(
        xml,
        "  <compiler angle=\"radian\" inertiafromgeom=\"false\" autolimits=\"true\"/>"
    );
    let _ = writeln!(xml, "  <option timestep=\"0.002\" gravity=\"0 0 -9.81\"/>");
    let _ = writeln!(xml, "  <asset>");
    for (i, link) in tree.links.iter().enumerate() {
        let Some(g) = &link.geometry else { continue };
        if skipped(i) {
            continue;
        }
        for k in 0..g.collision.len() {
            let _ = writeln!(
                xml,
                "    <mesh name=\"{}\" file=\"{}\"/>",
                attr_escape(&mesh_name(&link.name, k)),
                attr_escape(&collision_mesh_path(&link.name, k))
            );
        }
    }
    xml.push_str(&extra.assets);
    let _ = writeln!(xml, "  </asset>");
    let _ = writeln!(xml, "  <worldbody>");
    let _ = writeln!(
        xml,
        "    <light pos=\"0 0 5\" dir=\"0 0 -1\" directional=\"true\"/>"
    );
    // Top-level bodies: the world's children and every floating link wherever it hangs.
    let mut top: Vec<usize> = children[0].clone();
    top.extend(
        tree.links
            .iter()
            .enumerate()
            .skip(1)
            .filter(|(i, l)| {
                l.joint.kind == JointKind::Floating && l.parent != Some(0) && !skipped(*i)
            })
            .map(|(i, _)| i),
    );
    for i in top {
        let pose = if tree.links[i].parent == Some(0) {
            tree.links[i].parent_from_link_now()
        } else {
            world_from_links[i]
        };
        write_body(&mut xml, tree, &children, i, &pose, 2);
    }
    xml.push_str(&extra.bodies);
    let _ = writeln!(xml, "  </worldbody>");
    let _ = writeln!(xml, "</mujoco>");
    xml
}

fn write_body(
    xml: &mut String,
    tree: &KinematicTree,
    children: &[Vec<usize>],
    i: usize,
    pose: &Affine3A,
    depth: usize,
) {
    let link = &tree.links[i];
    let pad = "  ".repeat(depth);
    let _ = writeln!(
        xml,
        "{pad}<body name=\"{}\" {}>",
        attr_escape(&link.name),
        pose_attrs(pose)
    );
    write_joint(xml, tree, i, &pad);
    if let Some(g) = &link.geometry {
        let m = g.inertial.inertia;
        let _ = writeln!(
            xml,
            "{pad}  <inertial pos=\"{}\" mass=\"{}\" fullinertia=\"{}\"/>",
            numbers(&g.inertial.center_of_mass.to_array()),
            tidy(g.inertial.mass),
            numbers(&[
                m.x_axis.x, m.y_axis.y, m.z_axis.z, m.y_axis.x, m.z_axis.x, m.z_axis.y
            ])
        );
        let [r, gr, b] = g.color;
        for k in 0..g.collision.len() {
            let _ = writeln!(
                xml,
                "{pad}  <geom type=\"mesh\" mesh=\"{}\" rgba=\"{}\" friction=\"{} 0.005 0.0001\"/>",
                attr_escape(&mesh_name(&link.name, k)),
                numbers(&[r, gr, b, 1.0]),
                tidy(g.friction)
            );
        }
    }
    for &c in &children[i] {
        // Floating children are top-level bodies of their own.
        if tree.links[c].joint.kind == JointKind::Floating {
            continue;
        }
        // Posed as the joint stands now, which `ref` makes the joint's initial value: a drawer
        // seen open starts open, in the same joint coordinates and range.
        let child = &tree.links[c];
        write_body(
            xml,
            tree,
            children,
            c,
            &child.parent_from_link_now(),
            depth + 1,
        );
    }
    let _ = writeln!(xml, "{pad}</body>");
}

fn write_joint(xml: &mut String, tree: &KinematicTree, i: usize, pad: &str) {
    let link: &TreeLink = &tree.links[i];
    let name = attr_escape(&tree.joint_name(i));
    let axis = numbers(&link.joint.axis.to_array());
    let range = |limits: Option<(f32, f32)>| {
        limits.map_or(String::new(), |(lo, hi)| {
            format!(" range=\"{}\"", numbers(&[lo, hi]))
        })
    };
    match link.joint.kind {
        JointKind::Fixed => {}
        JointKind::Floating => {
            let _ = writeln!(xml, "{pad}  <freejoint name=\"{name}\"/>");
        }
        JointKind::Revolute | JointKind::Prismatic => {
            let kind = if link.joint.kind == JointKind::Revolute {
                "hinge"
            } else {
                "slide"
            };
            let _ = writeln!(
                xml,
                "{pad}  <joint name=\"{name}\" type=\"{kind}\" axis=\"{axis}\"{} damping=\"{}\" ref=\"{}\"/>",
                range(link.joint.limits),
                tidy(JOINT_DAMPING),
                tidy(link.value)
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;

    fn link(name: &str, parent: usize, joint: JointSpec, at: Vec3) -> TreeLink {
        let mesh = TriMesh::cuboid(Vec3::splat(-0.1), Vec3::splat(0.1));
        TreeLink::body(
            name,
            "chair",
            parent,
            joint,
            Affine3A::from_translation(at),
            mesh,
        )
    }

    #[test]
    fn floating_links_become_top_level_free_bodies_at_their_world_pose() {
        let tree = KinematicTree {
            links: vec![
                TreeLink::root(),
                link("floor", 0, JointSpec::FIXED, Vec3::ZERO),
                link("chair_1", 1, JointSpec::FLOATING, Vec3::new(1.0, 0.0, 0.5)),
                link("book_1", 2, JointSpec::FLOATING, Vec3::new(0.0, 0.0, 0.3)),
                link(
                    "cabinet_1_door",
                    1,
                    JointSpec::revolute(Vec3::Z, 0.0, 1.5),
                    Vec3::Y,
                ),
            ],
        };
        let xml = mjcf_text(&tree, "scene");
        assert_eq!(xml.matches("<freejoint").count(), 2);
        let book = xml
            .lines()
            .find(|l| l.contains("<body name=\"book_1\""))
            .expect("book body");
        assert!(book.starts_with("    <body"), "top level: {book:?}");
        assert!(book.contains("pos=\"1 0 0.8\""), "{book}");
        assert!(xml.contains("type=\"hinge\" axis=\"0 0 1\" range=\"0 1.5\""));
        assert_eq!(
            xml.matches("<body ").count(),
            xml.matches("</body>").count()
        );
        assert_eq!(xml.matches("<body ").count(), 4);
    }

    #[test]
    fn a_drawer_standing_open_starts_open_in_the_same_joint_coordinates() {
        let mut drawer = link(
            "cabinet_1_drawer_1",
            2,
            JointSpec::prismatic(Vec3::NEG_Y, 0.0, 0.3),
            Vec3::new(0.0, -0.2, 0.5),
        );
        drawer.value = 0.16;
        let tree = KinematicTree {
            links: vec![
                TreeLink::root(),
                link("floor", 0, JointSpec::FIXED, Vec3::ZERO),
                link("cabinet_1", 1, JointSpec::FIXED, Vec3::new(1.0, 0.0, 0.0)),
                drawer,
            ],
        };
        let xml = mjcf_text(&tree, "scene");
        let body = xml
            .lines()
            .find(|l| l.contains("<body name=\"cabinet_1_drawer_1\""))
            .expect("drawer body");
        // 16 cm out along -y from where it stands shut, and that is the joint's initial value.
        assert!(body.contains("pos=\"0 -0.36 0.5\""), "{body}");
        assert!(
            xml.contains(
                "type=\"slide\" axis=\"0 -1 0\" range=\"0 0.3\" damping=\"0.5\" ref=\"0.16\""
            ),
            "{xml}"
        );
    }
}
