//! The kinematic tree as URDF (written with urdf-rs) plus its OBJ meshes: one visual mesh per
//! link and one collision mesh per convex piece, referenced by paths relative to the URDF.

use glam::{Affine3A, EulerRot, Mat3, Vec3};

use crate::export::obj::obj_text;
use crate::kinematics::JointKind;
use crate::kinematics::tree::{KinematicTree, drive_limits};

/// The folder of the meshes, beside the URDF.
pub const MESH_DIR: &str = "meshes";

/// A file of the export: its path relative to the output folder and its text.
pub struct ExportFile {
    pub path: String,
    pub text: String,
}

pub fn visual_mesh_path(link: &str) -> String {
    format!("{MESH_DIR}/{link}.obj")
}

pub fn collision_mesh_path(link: &str, piece: usize) -> String {
    format!("{MESH_DIR}/{link}_collision_{piece}.obj")
}

/// The f64 that prints as the shortest decimal of `x` (no `0.7300000190734863` for 0.73).
pub fn tidy(x: f32) -> f64 {
    format!("{x}").parse().unwrap_or(x as f64)
}

fn tidy3(v: Vec3) -> urdf_rs::Vec3 {
    urdf_rs::Vec3(v.to_array().map(tidy))
}

/// URDF's pose: `xyz` and fixed-axis roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)).
pub fn urdf_pose(a: &Affine3A) -> urdf_rs::Pose {
    let (_, rotation, translation) = a.to_scale_rotation_translation();
    let (yaw, pitch, roll) = rotation.normalize().to_euler(EulerRot::ZYX);
    urdf_rs::Pose {
        xyz: tidy3(translation),
        rpy: tidy3(Vec3::new(roll, pitch, yaw)),
    }
}

fn inertia(m: &Mat3) -> urdf_rs::Inertia {
    urdf_rs::Inertia {
        ixx: tidy(m.x_axis.x),
        ixy: tidy(m.y_axis.x),
        ixz: tidy(m.z_axis.x),
        iyy: tidy(m.y_axis.y),
        iyz: tidy(m.z_axis.y),
        izz: tidy(m.z_axis.z),
    }
}

fn joint_type(kind: JointKind) -> urdf_rs::JointType {
    match kind {
        JointKind::Fixed => urdf_rs::JointType::Fixed,
        JointKind::Floating => urdf_rs::JointType::Floating,
        JointKind::Revolute => urdf_rs::JointType::Revolute,
        JointKind::Prismatic => urdf_rs::JointType::Prismatic,
    }
}

/// The URDF parent of link `i` and the joint origin in it. A floating link hangs from its tree
/// parent unless something on the way up to the root moves (a chair the book lies on, a drawer
/// the cup stands in): then from the nearest ancestor welded to the root, at the link's current
/// world pose. MuJoCo turns a URDF `floating` joint into a free joint only when every joint above
/// it is fixed, and refuses the file otherwise (../shared/VALIDATORS.md); the support relation
/// itself stays in contact_graph.json.
fn urdf_parent(
    tree: &KinematicTree,
    i: usize,
    world_from: &[Affine3A],
) -> Option<(usize, Affine3A)> {
    let link = &tree.links[i];
    let parent = link.parent?;
    if link.joint.kind != JointKind::Floating {
        return Some((parent, link.parent_from_link));
    }
    let welded_to_root = |mut at: usize| loop {
        match tree.links[at].parent {
            None => return true,
            Some(up) if tree.links[at].joint.kind == JointKind::Fixed => at = up,
            Some(_) => return false,
        }
    };
    let mut anchor = parent;
    while !welded_to_root(anchor) {
        anchor = tree.links[anchor].parent?;
    }
    if anchor == parent {
        return Some((parent, link.parent_from_link));
    }
    Some((anchor, world_from[anchor].inverse() * world_from[i]))
}

/// The URDF robot of `tree`.
pub fn urdf_robot(tree: &KinematicTree, name: &str) -> urdf_rs::Robot {
    let world_from = tree.world_from_links();
    let mut links = Vec::with_capacity(tree.links.len());
    let mut joints = Vec::new();
    for (i, link) in tree.links.iter().enumerate() {
        let mut urdf_link = urdf_rs::Link {
            name: link.name.clone(),
            inertial: urdf_rs::Inertial::default(),
            visual: Vec::new(),
            collision: Vec::new(),
        };
        if let Some(g) = &link.geometry {
            urdf_link.inertial = urdf_rs::Inertial {
                origin: urdf_rs::Pose {
                    xyz: tidy3(g.inertial.center_of_mass),
                    rpy: urdf_rs::Vec3::default(),
                },
                mass: urdf_rs::Mass {
                    value: tidy(g.inertial.mass),
                },
                inertia: inertia(&g.inertial.inertia),
            };
            let [r, gr, b] = g.color;
            urdf_link.visual.push(urdf_rs::Visual {
                name: None,
                origin: urdf_rs::Pose::default(),
                geometry: urdf_rs::Geometry::Mesh {
                    filename: visual_mesh_path(&link.name),
                    scale: None,
                },
                material: Some(urdf_rs::Material {
                    name: format!("{}_material", link.name),
                    color: Some(urdf_rs::Color {
                        rgba: urdf_rs::Vec4([tidy(r), tidy(gr), tidy(b), 1.0]),
                    }),
                    texture: None,
                }),
            });
            for k in 0..g.collision.len() {
                urdf_link.collision.push(urdf_rs::Collision {
                    name: None,
                    origin: urdf_rs::Pose::default(),
                    geometry: urdf_rs::Geometry::Mesh {
                        filename: collision_mesh_path(&link.name, k),
                        scale: None,
                    },
                });
            }
        }
        links.push(urdf_link);
        let Some((parent, origin)) = urdf_parent(tree, i, &world_from) else {
            continue;
        };
        let (effort, velocity) = drive_limits(link.joint.kind);
        let (lower, upper) = link.joint.limits.unwrap_or((0.0, 0.0));
        joints.push(urdf_rs::Joint {
            name: tree.joint_name(i),
            joint_type: joint_type(link.joint.kind),
            origin: urdf_pose(&origin),
            parent: urdf_rs::LinkName {
                link: tree.links[parent].name.clone(),
            },
            child: urdf_rs::LinkName {
                link: link.name.clone(),
            },
            axis: urdf_rs::Axis {
                xyz: tidy3(link.joint.axis),
            },
            limit: urdf_rs::JointLimit {
                lower: tidy(lower),
                upper: tidy(upper),
                effort: tidy(effort),
                velocity: tidy(velocity),
                ..Default::default()
            },
            calibration: None,
            dynamics: None,
            mimic: None,
            safety_controller: None,
        });
    }
    urdf_rs::Robot {
        name: name.into(),
        version: None,
        links,
        joints,
        materials: Vec::new(),
    }
}

/// Why the URDF could not be written.
#[derive(Debug, thiserror::Error)]
pub enum UrdfWriteError {
    #[error("writing URDF: {0}")]
    Write(#[from] urdf_rs::UrdfError),
    /// urdf-rs's text lacks a link's element, where friction goes.
    #[error("writing URDF: no element for link {0}")]
    NoLinkElement(String),
    #[error("writing URDF: link {0} is not closed")]
    UnclosedLink(String),
}

/// `scene.urdf` and every mesh it references.
pub fn urdf_files(tree: &KinematicTree, name: &str) -> Result<Vec<ExportFile>, UrdfWriteError> {
    let robot = urdf_robot(tree, name);
    let text = urdf_rs::write_to_string(&robot)?;
    let text = with_friction(&text, tree)?;
    let mut files = vec![ExportFile {
        path: "scene.urdf".into(),
        text,
    }];
    for link in &tree.links {
        let Some(g) = &link.geometry else { continue };
        files.push(ExportFile {
            path: visual_mesh_path(&link.name),
            text: obj_text(&g.visual),
        });
        for (k, piece) in g.collision.iter().enumerate() {
            files.push(ExportFile {
                path: collision_mesh_path(&link.name, k),
                text: obj_text(piece),
            });
        }
    }
    Ok(files)
}

/// `urdf` with each link's friction coefficient as a `<contact><lateral_friction/></contact>`
/// element at the end of the link. URDF itself has no friction; this is the extension PyBullet
/// reads (and Gazebo's importer maps), and parsers that do not know it skip it (check_urdf stays
/// silent, MuJoCo ignores it). urdf-rs cannot write it, so it goes into urdf-rs's text.
fn with_friction(urdf: &str, tree: &KinematicTree) -> Result<String, UrdfWriteError> {
    let mut out = String::with_capacity(urdf.len() + 80 * tree.links.len());
    let mut rest = urdf;
    for link in &tree.links {
        let Some(g) = &link.geometry else { continue };
        let open = format!("<link name=\"{}\">", link.name);
        let start = rest
            .find(&open)
            .ok_or_else(|| UrdfWriteError::NoLinkElement(link.name.clone()))?;
        let end = start
            + rest[start..]
                .find("</link>")
                .ok_or_else(|| UrdfWriteError::UnclosedLink(link.name.clone()))?;
        out.push_str(&rest[..end]);
        out.push_str(&format!(
            "  <contact>\n      <lateral_friction value=\"{}\"/>\n    </contact>\n  ",
            tidy(g.friction)
        ));
        rest = &rest[end..];
    }
    out.push_str(rest);
    Ok(out)
}

/// The inverse of `urdf_pose`, for tests and importers.
pub fn affine_of_urdf_pose(pose: &urdf_rs::Pose) -> Affine3A {
    let [x, y, z] = pose.xyz.0;
    let [roll, pitch, yaw] = pose.rpy.0;
    Affine3A::from_rotation_translation(
        glam::Quat::from_euler(EulerRot::ZYX, yaw as f32, pitch as f32, roll as f32),
        Vec3::new(x as f32, y as f32, z as f32),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;

    fn tree() -> KinematicTree {
        let board = |size: Vec3| TriMesh::cuboid_centered(Vec3::Z * size.z / 2.0, size);
        let pose = Affine3A::from_rotation_translation(
            glam::Quat::from_euler(EulerRot::ZYX, 0.7, 0.1, -0.2),
            Vec3::new(1.0, 2.0, 3.0),
        );
        let mut door = TreeLink::body(
            "cabinet_1_door",
            "cabinet",
            1,
            JointSpec::revolute(Vec3::Z, 0.0, 1.9),
            Affine3A::from_translation(Vec3::new(-0.3, -0.25, 0.0)),
            board(Vec3::new(0.6, 0.02, 0.8)),
        );
        door.node = Some("cabinet_1".into());
        door.value = 0.5;
        KinematicTree {
            links: vec![
                TreeLink::root(),
                TreeLink::body(
                    "cabinet_1",
                    "cabinet",
                    0,
                    JointSpec::FIXED,
                    pose,
                    board(Vec3::new(0.6, 0.5, 0.8)),
                ),
                door,
            ],
        }
    }

    #[test]
    fn a_floating_link_on_a_floating_one_hangs_from_the_nearest_welded_ancestor() {
        let mut tree = tree();
        let chair_pose = Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(0.4),
            Vec3::new(2.0, 0.5, 0.0),
        );
        let book_on_chair = Affine3A::from_translation(Vec3::new(0.1, 0.0, 0.45));
        let box_mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::splat(0.2));
        tree.links.push(TreeLink::body(
            "chair_1",
            "chair",
            0,
            JointSpec::FLOATING,
            chair_pose,
            box_mesh.clone(),
        ));
        tree.links.push(TreeLink::body(
            "book_1",
            "book",
            3,
            JointSpec::FLOATING,
            book_on_chair,
            box_mesh,
        ));
        let robot = urdf_robot(&tree, "room");
        let joint = |child: &str| {
            robot
                .joints
                .iter()
                .find(|j| j.child.link == child)
                .expect("joint")
        };
        assert_eq!(joint("chair_1").parent.link, "world");
        assert_eq!(joint("book_1").parent.link, "world");
        let back = affine_of_urdf_pose(&joint("book_1").origin);
        assert!(back.abs_diff_eq(chair_pose * book_on_chair, 1e-5));
        // Fixed and revolute joints keep their tree parent.
        assert_eq!(joint("cabinet_1_door").parent.link, "cabinet_1");
    }

    #[test]
    fn the_urdf_reads_back_with_the_same_links_joints_and_poses() {
        let tree = tree();
        let files = urdf_files(&tree, "kitchen").expect("writes");
        let robot = urdf_rs::read_from_string(&files[0].text).expect("urdf-rs reads it back");
        assert_eq!(robot.links.len(), 3);
        assert_eq!(robot.joints.len(), 2);
        let cabinet = &robot.joints[0];
        assert_eq!(cabinet.child.link, "cabinet_1");
        let back = affine_of_urdf_pose(&cabinet.origin);
        assert!(back.abs_diff_eq(tree.links[1].parent_from_link, 1e-5));
        let door = &robot.joints[1];
        assert_eq!(door.joint_type, urdf_rs::JointType::Revolute);
        assert!((door.limit.upper - 1.9).abs() < 1e-6 && door.limit.effort > 0.0);
        let mass = robot.links[1].inertial.mass.value;
        assert!((mass - 500.0 * 0.6 * 0.5 * 0.8).abs() < 0.1, "{mass}");
        // Every mesh the URDF names is among the files.
        for link in &robot.links {
            for v in &link.visual {
                let urdf_rs::Geometry::Mesh { filename, .. } = &v.geometry else {
                    panic!("mesh geometry")
                };
                assert!(files.iter().any(|f| &f.path == filename), "{filename}");
            }
        }
        assert_eq!(files.len(), 1 + 2 * 2);
    }

    #[test]
    fn each_link_carries_its_friction_as_a_contact_element_inside_it() {
        let tree = tree();
        let text = &urdf_files(&tree, "kitchen").expect("writes")[0].text;
        assert_eq!(text.matches("<contact>").count(), 2, "{text}");
        for link in &tree.links[1..] {
            let start = text
                .find(&format!("<link name=\"{}\">", link.name))
                .expect("the link");
            let end = start + text[start..].find("</link>").expect("closed");
            let friction = link.geometry.as_ref().expect("geometry").friction;
            let element = format!("<lateral_friction value=\"{}\"/>", tidy(friction));
            assert!(text[start..end].contains(&element), "{}", &text[start..end]);
        }
    }
}
