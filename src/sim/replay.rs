//! A task's replay for MuJoCo: `replay.xml`, the scene as the task found it with the robot in
//! it (its base on two slides and a turn about the vertical, the arm's links nested with their
//! joints and collision meshes), and `trajectory.csv`, every joint's value over the executed
//! task ([`crate::sim::trajectory`]). A replay sets each line's values as the model's joint
//! positions: MuJoCo then has the arm where it moved, the objects where they were carried and
//! the doors as they stood, and its collision detection checks the motion.

use std::fmt::Write;

use glam::Affine3A;

use crate::arm::rig::{ArmRig, MAST_RADIUS_M};
use crate::base::JointKind;
use crate::export::mjcf::{MjcfExtra, attr_escape, mjcf_document, numbers, pose_attrs};
use crate::export::obj::obj_text;
use crate::export::urdf::{ExportFile, MESH_DIR, tidy};
use crate::kinematics::tree::KinematicTree;
use crate::sim::robot::RobotSpec;
use crate::sim::trajectory::{BASE_JOINTS, arm_joint_name};

/// The replay model's top body: the base, with the arm on it.
pub const ROBOT_BODY: &str = "robot_base";
/// Mass and inertia of the robot's bodies: MuJoCo refuses moving bodies without them, and a
/// replay sets positions, so their values do not matter.
const ROBOT_INERTIAL: &str = "<inertial pos=\"0 0 0\" mass=\"1\" diaginertia=\"0.01 0.01 0.01\"/>";

/// `replay.xml` of the scene `before` (without its links `skip`: the simulator's own robot)
/// with the robot `spec` carrying the arm of `rig`, and the arm's meshes it refers to.
pub fn replay_files(
    before: &KinematicTree,
    skip: &[usize],
    spec: &RobotSpec,
    rig: &ArmRig,
) -> Vec<ExportFile> {
    let mut files = Vec::new();
    let mut assets = String::new();
    for link in &rig.arm.links {
        for (k, piece) in link.pieces.iter().enumerate() {
            let name = arm_mesh_name(&link.name, k);
            let path = format!("{MESH_DIR}/{name}.obj");
            let _ = writeln!(
                assets,
                "    <mesh name=\"{}\" file=\"{}\"/>",
                attr_escape(&name),
                attr_escape(&path)
            );
            files.push(ExportFile {
                path,
                text: obj_text(piece),
            });
        }
    }
    let extra = MjcfExtra {
        assets,
        bodies: robot_bodies(spec, rig),
    };
    files.push(ExportFile {
        path: "replay.xml".into(),
        text: mjcf_document(before, "replay", skip, &extra),
    });
    files
}

fn arm_mesh_name(link: &str, piece: usize) -> String {
    format!("robot_{link}_c{piece}")
}

/// The base (a column of the footprint's size) on its three joints, the arm nested on it.
fn robot_bodies(spec: &RobotSpec, rig: &ArmRig) -> String {
    let mut xml = String::new();
    let _ = writeln!(xml, "    <body name=\"{ROBOT_BODY}\">");
    let [x, y, yaw] = BASE_JOINTS;
    let _ = writeln!(
        xml,
        "      <joint name=\"{x}\" type=\"slide\" axis=\"1 0 0\"/>"
    );
    let _ = writeln!(
        xml,
        "      <joint name=\"{y}\" type=\"slide\" axis=\"0 1 0\"/>"
    );
    let _ = writeln!(
        xml,
        "      <joint name=\"{yaw}\" type=\"hinge\" axis=\"0 0 1\"/>"
    );
    let _ = writeln!(xml, "      {ROBOT_INERTIAL}");
    let half = 0.5 * spec.column_height();
    let _ = writeln!(
        xml,
        "      <geom type=\"cylinder\" size=\"{} {}\" pos=\"0 0 {}\" rgba=\"0.2 0.3 0.6 1\"/>",
        tidy(spec.radius - 0.01),
        tidy(half),
        tidy(half)
    );
    let children = crate::base::parent_chain::children(rig.arm.links.iter().map(|l| l.parent));
    arm_body(&mut xml, rig, &children, 0, &rig.base_from_root, 3);
    let _ = writeln!(xml, "    </body>");
    xml
}

fn arm_body(
    xml: &mut String,
    rig: &ArmRig,
    children: &[Vec<usize>],
    l: usize,
    pose: &Affine3A,
    depth: usize,
) {
    let link = &rig.arm.links[l];
    let pad = "  ".repeat(depth);
    let _ = writeln!(
        xml,
        "{pad}<body name=\"{}\" {}>",
        attr_escape(&format!("robot_{}", link.name)),
        pose_attrs(pose)
    );
    if let Some(joint) = &link.joint {
        let kind = match joint.kind {
            JointKind::Prismatic => "slide",
            _ => "hinge",
        };
        let (lo, hi) = joint.limits;
        let _ = writeln!(
            xml,
            "{pad}  <joint name=\"{}\" type=\"{kind}\" pos=\"{}\" axis=\"{}\" range=\"{}\"/>",
            attr_escape(&arm_joint_name(rig, l)),
            numbers(&joint.origin.to_array()),
            numbers(&joint.axis.to_array()),
            numbers(&[lo, hi])
        );
    }
    let _ = writeln!(xml, "{pad}  {ROBOT_INERTIAL}");
    if let Some((_, length)) = rig.mast().filter(|(mast, _)| *mast == l) {
        // Seen, never touching: the lift's mast stands inside the column and its footprint.
        let _ = writeln!(
            xml,
            "{pad}  <geom type=\"cylinder\" size=\"{} {}\" pos=\"0 0 {}\" contype=\"0\" conaffinity=\"0\" rgba=\"0.2 0.3 0.6 1\"/>",
            tidy(MAST_RADIUS_M),
            tidy(0.5 * length),
            tidy(-0.5 * length)
        );
    }
    for k in 0..link.pieces.len() {
        let _ = writeln!(
            xml,
            "{pad}  <geom type=\"mesh\" mesh=\"{}\" rgba=\"0.9 0.9 0.9 1\"/>",
            attr_escape(&arm_mesh_name(&link.name, k))
        );
    }
    for &c in &children[l] {
        arm_body(
            xml,
            rig,
            children,
            c,
            &rig.arm.links[c].parent_from_link,
            depth + 1,
        );
    }
    let _ = writeln!(xml, "{pad}</body>");
}
