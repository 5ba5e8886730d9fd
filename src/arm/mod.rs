//! A robot arm read from its URDF file: the chain of joints from its root link to its tool, the
//! fingers beside it, and each link's convex collision pieces; forward kinematics, inverse
//! kinematics, collision checking against a scene and motion planning in joint space.
//!
//! Bevy-free. The URDF is read by the CAD importer's reader (urdf-rs, meshes as their convex
//! hulls, `package://` paths beside the file), so a robot file and a furniture file are one
//! format to this program. A link's frame is its joint's origin in the parent link's frame,
//! turned or slid by the joint's value about or along its axis, as URDF defines it.

pub mod collision;
pub mod grasp;
pub mod ik;
pub mod reach;
pub mod rig;
pub mod rrt;

use std::path::Path;

use glam::{Affine3A, Quat, Vec3};

use crate::base::JointKind;
use crate::cad::import::body_tree::{BodyJoint, BodyTree, ModelFileError};
use crate::geometry::TriMesh;

/// Names a tool link is looked for by when none is given, in this order (the Panda of the
/// PyBullet package has `panda_grasptarget` between its fingertips).
const TOOL_LINK_WORDS: [&str; 5] = ["grasptarget", "tcp", "tool", "ee_link", "hand"];

/// The link [`Arm::on_lift`] puts under an arm's root, and its joint.
pub const LIFT_LINK: &str = "iscene_lift";
pub const LIFT_JOINT: &str = "iscene_lift_joint";

/// One link of the arm.
#[derive(Clone, Debug)]
pub struct ArmLink {
    pub name: String,
    /// Index of the parent link; `None` for the root (index 0), which the base carries.
    pub parent: Option<usize>,
    /// The link's frame in its parent's at joint value zero.
    pub parent_from_link: Affine3A,
    /// The joint that moves it relative to its parent; `None` when welded to it.
    pub joint: Option<BodyJoint>,
    /// Convex collision pieces in the link's frame.
    pub pieces: Vec<TriMesh>,
    /// What it looks like, in its frame: the file's visual meshes, or its collision pieces
    /// where it has none. Only the viewer draws it (shared: an arm is cloned per rig).
    pub look: std::sync::Arc<TriMesh>,
}

/// What moves a link: a joint of the chain (an index into the configuration), a finger joint
/// (set by the gripper's opening), or nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkMotion {
    Welded,
    Chain(usize),
    Finger,
}

/// A serial arm with a gripper: the links parent first, the chain's joints root to tool.
#[derive(Clone, Debug)]
pub struct Arm {
    pub name: String,
    pub links: Vec<ArmLink>,
    /// Link index of each joint of the chain, root to tool: configuration value `i` moves
    /// `links[chain[i]]`.
    pub chain: Vec<usize>,
    /// The tool link: where a grasp puts the object.
    pub tool: usize,
    /// How each link moves.
    pub motion: Vec<LinkMotion>,
}

/// An arm file that cannot be used, with what is wrong (the caller names the file).
#[derive(Debug, thiserror::Error)]
pub enum ArmError {
    #[error(transparent)]
    File(#[from] ModelFileError),
    #[error("{0}")]
    Structure(String),
}

impl Arm {
    /// Reads the URDF file at `path`; the tool link is `tool` or, when `None`, the first link
    /// named like one (`TOOL_LINK_WORDS`).
    pub fn read_urdf(path: &Path, tool: Option<&str>) -> Result<Self, ArmError> {
        let tree = crate::cad::import::urdf::read_urdf(path)?;
        tree.check_size()?;
        Self::from_body_tree(tree, tool)
    }

    /// The arm of a body tree (a parent before its children): the joints from the root to
    /// the tool are the chain; every other moving joint is a finger.
    pub fn from_body_tree(tree: BodyTree, tool: Option<&str>) -> Result<Self, ArmError> {
        let tool = match tool {
            Some(name) => tree
                .bodies
                .iter()
                .position(|b| b.name == name)
                .ok_or_else(|| ArmError::Structure(format!("no link named {name:?}")))?,
            None => TOOL_LINK_WORDS
                .iter()
                .find_map(|word| tree.bodies.iter().position(|b| b.name.contains(word)))
                .ok_or_else(|| {
                    ArmError::Structure(format!(
                        "no link is named like a tool ({}); name one",
                        TOOL_LINK_WORDS.join(", ")
                    ))
                })?,
        };
        let links: Vec<ArmLink> = tree
            .bodies
            .into_iter()
            .map(|b| {
                let mut look = TriMesh::default();
                for mesh in if b.visual_meshes.is_empty() {
                    &b.pieces
                } else {
                    &b.visual_meshes
                } {
                    look.append(mesh);
                }
                ArmLink {
                    name: b.name,
                    parent: b.parent,
                    parent_from_link: b.parent_from_body,
                    joint: b.joint,
                    pieces: b.pieces,
                    look: std::sync::Arc::new(look),
                }
            })
            .collect();
        let mut path = vec![tool];
        while let Some(parent) = links[*path.last().expect("not empty")].parent {
            path.push(parent);
        }
        path.reverse();
        let chain: Vec<usize> = path
            .iter()
            .copied()
            .filter(|&l| links[l].joint.is_some())
            .collect();
        if chain.is_empty() {
            return Err(ArmError::Structure(format!(
                "no joint moves the tool link {:?}",
                links[tool].name
            )));
        }
        let motion = (0..links.len())
            .map(|l| match chain.iter().position(|&c| c == l) {
                Some(i) => LinkMotion::Chain(i),
                None if links[l].joint.is_some() => LinkMotion::Finger,
                None => LinkMotion::Welded,
            })
            .collect();
        Ok(Self {
            name: tree.name,
            links,
            chain,
            tool,
            motion,
        })
    }

    /// The arm on a lift (a torso lift, as on Fetch, TIAGo or PR2): a new root link whose
    /// prismatic joint slides everything else along +z, from `range.0` to `range.1` metres of
    /// where the base mounts the arm. It is the chain's first joint, so inverse kinematics and
    /// planning choose the shoulder's height with the rest; it has no collision pieces (the
    /// base's column is the robot's own body).
    pub fn on_lift(self, range: (f32, f32)) -> Self {
        let lift = ArmLink {
            name: LIFT_LINK.to_string(),
            parent: None,
            parent_from_link: Affine3A::IDENTITY,
            joint: Some(BodyJoint {
                name: LIFT_JOINT.to_string(),
                kind: JointKind::Prismatic,
                origin: Vec3::ZERO,
                axis: Vec3::Z,
                limits: range,
            }),
            pieces: Vec::new(),
            look: Default::default(),
        };
        let links: Vec<ArmLink> = std::iter::once(lift)
            .chain(self.links.into_iter().map(|link| ArmLink {
                parent: Some(link.parent.map_or(0, |p| p + 1)),
                ..link
            }))
            .collect();
        let chain: Vec<usize> = std::iter::once(0)
            .chain(self.chain.iter().map(|&l| l + 1))
            .collect();
        let motion = std::iter::once(LinkMotion::Chain(0))
            .chain(self.motion.into_iter().map(|m| match m {
                LinkMotion::Chain(i) => LinkMotion::Chain(i + 1),
                other => other,
            }))
            .collect();
        Self {
            name: self.name,
            links,
            chain,
            tool: self.tool + 1,
            motion,
        }
    }

    /// The lift's index in the chain (`on_lift`), if the arm stands on one.
    pub fn lift(&self) -> Option<usize> {
        (self.links[self.chain[0]].name == LIFT_LINK).then_some(0)
    }

    /// Number of joints in the chain.
    pub fn dof(&self) -> usize {
        self.chain.len()
    }

    /// The chain's joint limits, root to tool.
    pub fn limits(&self) -> Vec<(f32, f32)> {
        self.chain
            .iter()
            .map(|&l| self.links[l].joint.as_ref().expect("chain joint").limits)
            .collect()
    }

    /// The chain's joint limits with a lift's range narrowed to the heights between those of
    /// `a` and `b`: what a plan between them samples (the lift goes straight from one height to
    /// the other, the arm's joints anywhere). With a lift at one height it is drawn nothing
    /// for, so the arm's own joints are drawn as on an arm without a lift.
    pub fn limits_between(&self, a: &[f32], b: &[f32]) -> Vec<(f32, f32)> {
        let mut limits = self.limits();
        if let Some(i) = self.lift() {
            limits[i] = (a[i].min(b[i]), a[i].max(b[i]));
        }
        limits
    }

    /// The middle of every joint's range: a configuration inside the limits.
    pub fn middle(&self) -> Vec<f32> {
        self.limits()
            .iter()
            .map(|&(lo, hi)| 0.5 * (lo + hi))
            .collect()
    }

    /// Whether `q` is a configuration of this arm: one finite value per joint, within limits.
    pub fn within_limits(&self, q: &[f32]) -> bool {
        q.len() == self.dof()
            && q.iter()
                .zip(self.limits())
                .all(|(&v, (lo, hi))| v.is_finite() && v >= lo - 1e-6 && v <= hi + 1e-6)
    }

    /// `q` moved into the limits.
    pub fn clamped(&self, q: &[f32]) -> Vec<f32> {
        q.iter()
            .zip(self.limits())
            .map(|(&v, (lo, hi))| v.clamp(lo, hi))
            .collect()
    }

    /// Every link's world pose with the root at `world_from_root`, the chain at `q` and the
    /// fingers at `opening` (0 closed .. 1 open, along their joints' ranges).
    pub fn link_poses(&self, world_from_root: &Affine3A, q: &[f32], opening: f32) -> Vec<Affine3A> {
        let mut poses: Vec<Affine3A> = Vec::with_capacity(self.links.len());
        for (l, link) in self.links.iter().enumerate() {
            let parent = link.parent.map_or(*world_from_root, |p| poses[p]);
            let moved = match (self.motion[l], &link.joint) {
                (LinkMotion::Chain(i), Some(joint)) => joint_motion(joint, q[i]),
                (LinkMotion::Finger, Some(joint)) => {
                    let (lo, hi) = joint.limits;
                    joint_motion(joint, lo + opening.clamp(0.0, 1.0) * (hi - lo))
                }
                _ => Affine3A::IDENTITY,
            };
            poses.push(parent * link.parent_from_link * moved);
        }
        poses
    }

    /// The hand in the tool's frame, its fingers open: the pieces of every link past the
    /// chain's last joint (the hand, its fingers, the tool). What the tree shows of the arm.
    pub fn hand_mesh(&self) -> TriMesh {
        // The chain's values do not move the hand in the tool's frame: any will do.
        let poses = self.link_poses(&Affine3A::IDENTITY, &self.middle(), 1.0);
        let tool_from_root = poses[self.tool].inverse();
        let mut hand = TriMesh::default();
        for l in self.hand_links() {
            for piece in &self.links[l].pieces {
                hand.append(&piece.transformed(&(tool_from_root * poses[l])));
            }
        }
        hand
    }

    /// How far the hand's palm (every piece past the chain's last joint but the fingers) lies
    /// behind the tool point along the tool's +z, metres: how deep into an object the tool may
    /// go before the palm meets it. Infinite for a hand with no pieces but its fingers.
    pub fn palm_depth(&self) -> f32 {
        let poses = self.link_poses(&Affine3A::IDENTITY, &self.middle(), 1.0);
        let tool_from_root = poses[self.tool].inverse();
        let nearest = self
            .hand_links()
            .into_iter()
            .filter(|&l| self.motion[l] != LinkMotion::Finger)
            .flat_map(|l| {
                let tool_from_link = tool_from_root * poses[l];
                self.links[l].pieces.iter().flat_map(move |p| {
                    p.positions
                        .iter()
                        .map(move |v| tool_from_link.transform_point3(*v).z)
                })
            })
            .fold(f32::NEG_INFINITY, f32::max);
        (-nearest).max(0.0)
    }

    /// The links past the chain's last joint: the hand, its fingers and the tool.
    pub fn hand_links(&self) -> Vec<usize> {
        let last = self.chain.last().copied().unwrap_or(0);
        (0..self.links.len())
            .filter(|&l| l != last && self.descends_from(l, last))
            .collect()
    }

    /// Whether link `l` is `ancestor` or hangs from it.
    fn descends_from(&self, l: usize, ancestor: usize) -> bool {
        crate::base::parent_chain::descends_from(l, ancestor, |k| self.links[k].parent)
    }

    /// The tool's world pose.
    pub fn tool_pose(&self, world_from_root: &Affine3A, q: &[f32]) -> Affine3A {
        // Only the chain leads to the tool; the fingers do not move it.
        self.link_poses(world_from_root, q, 0.0)[self.tool]
    }
}

/// A joint's motion in its link's frame at value `v`: a turn about its axis through its origin,
/// or a slide along its axis.
pub fn joint_motion(joint: &BodyJoint, v: f32) -> Affine3A {
    match joint.kind {
        JointKind::Revolute => {
            Affine3A::from_translation(joint.origin)
                * Affine3A::from_quat(Quat::from_axis_angle(joint.axis, v))
                * Affine3A::from_translation(-joint.origin)
        }
        JointKind::Prismatic => Affine3A::from_translation(joint.axis * v),
        // A body tree's joints are revolute or prismatic.
        JointKind::Fixed | JointKind::Floating => Affine3A::IDENTITY,
    }
}

/// A configuration drawn uniformly within `limits` (a joint with no range at its one value).
pub fn random_configuration(limits: &[(f32, f32)], rng: &mut impl rand::Rng) -> Vec<f32> {
    limits
        .iter()
        .map(|&(lo, hi)| {
            if hi > lo {
                rng.random_range(lo..hi)
            } else {
                lo
            }
        })
        .collect()
}

/// Where the chain's joint `i` turns or slides, in the world, from the link poses: the axis's
/// direction and a point on it.
pub fn joint_axis(arm: &Arm, poses: &[Affine3A], i: usize) -> (Vec3, Vec3) {
    let link = arm.chain[i];
    let joint = arm.links[link].joint.as_ref().expect("chain joint");
    let pose = poses[link];
    (
        pose.transform_vector3(joint.axis).normalize(),
        pose.transform_point3(joint.origin),
    )
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::cad::import::body_tree::Body;

    /// A planar arm of two revolute joints about z with 1 m links and a tool at the end.
    pub(crate) fn two_link_arm() -> Arm {
        let body = |name: &str, parent: Option<usize>, x: f32, joint: bool| Body {
            name: name.to_string(),
            parent,
            parent_from_body: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)),
            joint: joint.then(|| BodyJoint {
                name: format!("{name}_joint"),
                kind: JointKind::Revolute,
                origin: Vec3::ZERO,
                axis: Vec3::Z,
                limits: (-3.0, 3.0),
            }),
            pieces: Vec::new(),
            visual_pieces: Vec::new(),
            visual_meshes: Vec::new(),
            colors: Vec::new(),
        };
        let tree = BodyTree {
            name: "planar".into(),
            bodies: vec![
                body("base", None, 0.0, false),
                body("upper", Some(0), 0.0, true),
                body("fore", Some(1), 1.0, true),
                body("tool", Some(2), 1.0, false),
            ],
        };
        Arm::from_body_tree(tree, None).expect("arm")
    }

    #[test]
    fn forward_kinematics_of_a_planar_arm() {
        let arm = two_link_arm();
        assert_eq!(arm.dof(), 2);
        let tool = |q: &[f32]| arm.tool_pose(&Affine3A::IDENTITY, q).translation;
        assert!((tool(&[0.0, 0.0]) - glam::Vec3A::new(2.0, 0.0, 0.0)).length() < 1e-6);
        let half = std::f32::consts::FRAC_PI_2;
        assert!((tool(&[half, 0.0]) - glam::Vec3A::new(0.0, 2.0, 0.0)).length() < 1e-6);
        assert!((tool(&[0.0, half]) - glam::Vec3A::new(1.0, 1.0, 0.0)).length() < 1e-6);
    }
}
