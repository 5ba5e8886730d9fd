//! The kinematic tree as plain data, read off the ECS hierarchy and handed to the exporters and
//! the physics check: links in depth-first order from the `world` root, each with the joint to
//! its parent.

use std::sync::Arc;

use glam::Affine3A;

use crate::geometry::TriMesh;
use crate::kinematics::link::LinkGeometry;
use crate::kinematics::{JointKind, JointSpec};

/// The name of the root link (the world frame, aligned: z up, floor at 0).
pub const ROOT_LINK: &str = "world";

#[derive(Clone, Debug)]
pub struct TreeLink {
    /// Unique: the contact-graph id for a node's own link, `<id>_<part>` for a CAD part.
    pub name: String,
    /// The contact-graph node the link belongs to (`None` for the root).
    pub node: Option<String>,
    pub class: Option<String>,
    /// Index of the parent link; `None` only for the root (index 0).
    pub parent: Option<usize>,
    pub joint: JointSpec,
    /// The joint's current value (radians or metres; 0 for fixed and floating joints).
    pub value: f32,
    /// The link's frame in its parent's at joint value zero (the joint frame, as in URDF).
    pub parent_from_link: Affine3A,
    /// `None` for the root.
    pub geometry: Option<Arc<LinkGeometry>>,
    /// Whether a CAD model makes the link: false for the root, the layout, and an object no
    /// model replaced (its geometry is its segment's box).
    pub modelled: bool,
}

impl TreeLink {
    /// The `world` root link.
    pub fn root() -> Self {
        Self {
            name: ROOT_LINK.into(),
            node: None,
            class: None,
            parent: None,
            joint: JointSpec::FIXED,
            value: 0.0,
            parent_from_link: Affine3A::IDENTITY,
            geometry: None,
            modelled: false,
        }
    }

    /// A node's own link made of `mesh` (its frame), grey, with the class's density and
    /// friction, as a model would make it; the link is named by the node.
    pub fn body(
        name: &str,
        class: &str,
        parent: usize,
        joint: JointSpec,
        parent_from_link: Affine3A,
        mesh: TriMesh,
    ) -> Self {
        Self {
            name: name.into(),
            node: Some(name.into()),
            class: Some(class.into()),
            parent: Some(parent),
            joint,
            value: 0.0,
            parent_from_link,
            geometry: Some(Arc::new(LinkGeometry::new(mesh, [0.5; 3], class))),
            modelled: true,
        }
    }

    /// The link's frame in its parent's at the current joint value.
    pub fn parent_from_link_now(&self) -> Affine3A {
        self.parent_from_link * self.joint.motion(self.value)
    }
}

#[derive(Clone, Debug, Default)]
pub struct KinematicTree {
    pub links: Vec<TreeLink>,
}

impl KinematicTree {
    /// Whether `link` is `ancestor` or hangs below it.
    pub fn descends_from(&self, link: usize, ancestor: usize) -> bool {
        crate::base::parent_chain::descends_from(link, ancestor, |l| self.links[l].parent)
    }

    /// `link`, with what it carries, hung from `parent` at `parent_from_link` on `joint` (value
    /// 0), as an action's attachment does in the world; the links reordered depth first,
    /// children in name order (as the world is read), so parents still come first. Nothing
    /// changes when `parent` hangs below `link`.
    pub fn reparent(
        &mut self,
        link: usize,
        parent: usize,
        parent_from_link: Affine3A,
        joint: JointSpec,
    ) {
        if link == 0 || self.descends_from(parent, link) {
            return;
        }
        let moved = &mut self.links[link];
        moved.parent = Some(parent);
        moved.parent_from_link = parent_from_link;
        moved.joint = joint;
        moved.value = 0.0;
        let mut children = crate::base::parent_chain::children(self.links.iter().map(|l| l.parent));
        for c in &mut children {
            c.sort_by(|a, b| self.links[*a].name.cmp(&self.links[*b].name));
        }
        let mut order = Vec::with_capacity(self.links.len());
        let mut stack = vec![0];
        while let Some(l) = stack.pop() {
            order.push(l);
            stack.extend(children[l].iter().rev());
        }
        let mut index = vec![0; self.links.len()];
        for (k, &l) in order.iter().enumerate() {
            index[l] = k;
        }
        let mut old: Vec<Option<TreeLink>> = std::mem::take(&mut self.links)
            .into_iter()
            .map(Some)
            .collect();
        self.links = order
            .iter()
            .filter_map(|&l| old[l].take())
            .map(|mut l| {
                l.parent = l.parent.map(|p| index[p]);
                l
            })
            .collect();
    }

    /// Every link's pose in the world at the current joint values.
    pub fn world_from_links(&self) -> Vec<Affine3A> {
        let mut poses: Vec<Affine3A> = Vec::with_capacity(self.links.len());
        for link in &self.links {
            let parent = link.parent.map_or(Affine3A::IDENTITY, |p| poses[p]);
            poses.push(parent * link.parent_from_link_now());
        }
        poses
    }

    /// The joint's name: `<child>_joint` (link names are unique, so joint names are).
    pub fn joint_name(&self, link: usize) -> String {
        format!("{}_joint", self.links[link].name)
    }

    /// For each link, the link that carries it as one rigid body: itself when its joint moves
    /// (floating, revolute, prismatic), else its parent's body; the root's body is the root.
    /// Links of body 0 are static.
    pub fn bodies(&self) -> Vec<usize> {
        let mut body = Vec::with_capacity(self.links.len());
        for (i, link) in self.links.iter().enumerate() {
            body.push(match (link.parent, link.joint.kind) {
                (None, _) => i,
                (Some(p), JointKind::Fixed) => body[p],
                (Some(_), _) => i,
            });
        }
        body
    }

    /// Whether the tree is well formed: one root first, parents before children, unique names,
    /// finite rigid frames and a geometry on every link but the root.
    pub fn check(&self) -> Result<(), TreeError> {
        let mut names = std::collections::HashSet::new();
        for (i, link) in self.links.iter().enumerate() {
            if !names.insert(link.name.as_str()) {
                return Err(TreeError::DuplicateName(link.name.clone()));
            }
            match link.parent {
                None if i != 0 => return Err(TreeError::NoParent(link.name.clone())),
                Some(p) if p >= i => return Err(TreeError::BeforeParent(link.name.clone())),
                _ => {}
            }
            if i > 0 && link.geometry.is_none() {
                return Err(TreeError::NoGeometry(link.name.clone()));
            }
            let m = glam::Mat4::from(link.parent_from_link);
            if !m.is_finite() || !link.value.is_finite() {
                return Err(TreeError::NotFinite(link.name.clone()));
            }
        }
        Ok(())
    }
}

/// What makes a kinematic tree malformed: the exports and the simulators would misread it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TreeError {
    #[error("two links are named {0:?}")]
    DuplicateName(String),
    #[error("link {0:?} has no parent")]
    NoParent(String),
    #[error("link {0:?} comes before its parent")]
    BeforeParent(String),
    #[error("link {0:?} has no geometry")]
    NoGeometry(String),
    #[error("link {0:?} has a non-finite pose")]
    NotFinite(String),
}

/// Effort and velocity limits written for a moving joint: what a person's hand or a mobile
/// manipulator's arm applies to a door (N m, rad/s) or a drawer (N, m/s).
pub fn drive_limits(kind: JointKind) -> (f32, f32) {
    match kind {
        JointKind::Revolute => (30.0, 1.5),
        JointKind::Prismatic => (100.0, 0.5),
        JointKind::Fixed | JointKind::Floating => (0.0, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn link(name: &str, parent: usize, joint: JointSpec, at: Vec3) -> TreeLink {
        let mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::ONE);
        TreeLink::body(
            name,
            "box",
            parent,
            joint,
            Affine3A::from_translation(at),
            mesh,
        )
    }

    #[test]
    fn bodies_follow_fixed_joints_and_poses_follow_joint_values() {
        let mut tree = KinematicTree {
            links: vec![
                TreeLink::root(),
                link("table_1", 0, JointSpec::FIXED, Vec3::X),
                link("cup_1", 1, JointSpec::FLOATING, Vec3::Z),
                link(
                    "fridge_1_door",
                    1,
                    JointSpec::revolute(Vec3::Z, 0.0, 2.0),
                    Vec3::Y,
                ),
            ],
        };
        assert_eq!(tree.bodies(), vec![0, 0, 2, 3]);
        tree.check().expect("well formed");
        tree.links[3].value = std::f32::consts::FRAC_PI_2;
        let poses = tree.world_from_links();
        let p = poses[3].transform_point3(Vec3::X);
        assert!(p.distance(Vec3::new(1.0, 2.0, 0.0)) < 1e-5, "{p}");
        tree.links[2].name = "table_1".into();
        assert!(tree.check().is_err());
    }

    #[test]
    fn a_cup_hung_from_a_link_after_it_comes_after_it() {
        let mut tree = KinematicTree {
            links: vec![
                TreeLink::root(),
                link("table_1", 0, JointSpec::FIXED, Vec3::X),
                link("cup_1", 1, JointSpec::FLOATING, Vec3::Z),
                link("robot", 0, JointSpec::FIXED, Vec3::Y),
                link("robot_gripper", 3, JointSpec::FIXED, Vec3::Z),
            ],
        };
        let grip = Affine3A::from_translation(Vec3::new(0.0, 0.0, -0.1));
        tree.reparent(2, 4, grip, JointSpec::FIXED);
        tree.check().expect("well formed");
        let names: Vec<&str> = tree.links.iter().map(|l| l.name.as_str()).collect();
        assert_eq!(
            names,
            ["world", "robot", "robot_gripper", "cup_1", "table_1"]
        );
        let cup = tree.world_from_links()[3].translation;
        assert!(
            Vec3::from(cup).distance(Vec3::new(0.0, 1.0, 0.9)) < 1e-6,
            "{cup}"
        );
        // Hanging a link from what it carries changes nothing.
        let before = tree.clone();
        tree.reparent(1, 1, Affine3A::IDENTITY, JointSpec::FIXED);
        assert_eq!(tree.links.len(), before.links.len());
    }
}
