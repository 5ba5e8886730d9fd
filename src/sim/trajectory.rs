//! An executed task as motion over time, for a simulator to replay: every joint's value (the
//! base's two slides and turn, the arm's joints, the doors and drawers, and the free joint of
//! every loose object) at instants of the drives, joint moves and arm motions of the trace.
//!
//! The walk keeps each link's world pose and what hangs from what as the steps leave them: a
//! drive moves the base with what it carries, a door turns with what stands on it, the arm's
//! hand (the gripper link) follows the arm's configurations with what it holds, and an object
//! changes hands between a reach and its retreat (taken at the end of a pick's reach, let go at
//! the end of a place's).

use std::fmt::Write;

use glam::Affine3A;

use crate::arm::LinkMotion;
use crate::arm::rig::ArmRig;
use crate::base::JointKind;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::Change;
use crate::sim::motion_path::link_motion;
use crate::sim::robot::{BasePose, GRIPPER_LINK, ROBOT_LINK};
use crate::sim::scene_view::yaw_of;

/// Seconds between the instants of a drive or a door's motion.
const SAMPLE_S: f32 = 0.1;
/// The fingers close or open in this many instants, `SAMPLE_S` apart.
const FINGER_SAMPLES: usize = 5;
/// The arm's fastest joint, radians (or metres) a second: the time between two configurations
/// of a motion.
pub const ARM_SPEED: f32 = 1.0;

/// What a column of the trajectory holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Column {
    /// The base's position along the world's x and y, metres, and its heading, radians.
    BaseX,
    BaseY,
    BaseYaw,
    /// Joint `i` of the arm's chain.
    Arm(usize),
    /// A finger's joint (arm link index).
    Finger(usize),
    /// Component `component` of the free joint of tree link `link`: x, y, z, then the
    /// orientation's w, x, y, z (MuJoCo's order).
    Free {
        link: usize,
        component: usize,
    },
    /// A door's or drawer's joint (tree link index).
    Joint(usize),
}

/// One instant: when, during which step, what the hand holds, and each column's value.
#[derive(Clone, Debug)]
pub struct Sample {
    pub time: f32,
    pub step: usize,
    pub held: Option<String>,
    pub values: Vec<f32>,
}

/// Joint values over time; `names[i]` is column `columns[i]`'s joint (a free joint's
/// components are `<joint>.x` .. `<joint>.qz`).
#[derive(Clone, Debug)]
pub struct Trajectory {
    pub names: Vec<String>,
    pub columns: Vec<Column>,
    pub samples: Vec<Sample>,
}

/// The names of the robot's base joints in the replay model.
pub const BASE_JOINTS: [&str; 3] = ["robot_x", "robot_y", "robot_yaw"];
const FREE_COMPONENTS: [&str; 7] = ["x", "y", "z", "qw", "qx", "qy", "qz"];

/// The columns for the scene `tree` (its links but `skip` and what hangs from them) and the
/// arm of `rig`, with their names.
pub fn columns(tree: &KinematicTree, skip: &[usize], rig: &ArmRig) -> (Vec<String>, Vec<Column>) {
    let mut names: Vec<String> = BASE_JOINTS.iter().map(|s| s.to_string()).collect();
    let mut columns = vec![Column::BaseX, Column::BaseY, Column::BaseYaw];
    for (i, &l) in rig.arm.chain.iter().enumerate() {
        names.push(arm_joint_name(rig, l));
        columns.push(Column::Arm(i));
    }
    for (l, motion) in rig.arm.motion.iter().enumerate() {
        if *motion == LinkMotion::Finger {
            names.push(arm_joint_name(rig, l));
            columns.push(Column::Finger(l));
        }
    }
    for (l, link) in tree.links.iter().enumerate().skip(1) {
        if skip.iter().any(|&s| tree.descends_from(l, s)) {
            continue;
        }
        match link.joint.kind {
            JointKind::Floating => {
                for (component, c) in FREE_COMPONENTS.iter().enumerate() {
                    names.push(format!("{}.{c}", tree.joint_name(l)));
                    columns.push(Column::Free { link: l, component });
                }
            }
            JointKind::Revolute | JointKind::Prismatic => {
                names.push(tree.joint_name(l));
                columns.push(Column::Joint(l));
            }
            JointKind::Fixed => {}
        }
    }
    (names, columns)
}

/// The name of the joint that moves arm link `l`.
pub fn arm_joint_name(rig: &ArmRig, l: usize) -> String {
    let link = &rig.arm.links[l];
    link.joint
        .as_ref()
        .map_or_else(|| format!("{}_joint", link.name), |j| j.name.clone())
}

/// The trajectory of `steps` (each performed step's index and changes, in order) from the scene
/// `before` them, the robot carrying the arm of `rig` (stowed between its motions; the fingers
/// close on what the hand takes once it holds it and open before it lets go, and close on a
/// handle while the part follows). `None` when the tree has no robot.
pub fn trajectory(
    before: &KinematicTree,
    rig: &ArmRig,
    steps: &[(usize, &[Change])],
) -> Option<Trajectory> {
    let robot = before.links.iter().position(|l| l.name == ROBOT_LINK)?;
    let gripper = before.links.iter().position(|l| l.name == GRIPPER_LINK)?;
    let (names, columns) = columns(before, &[robot], rig);
    let poses = before.world_from_links();
    let mut walk = Walk {
        tree: before,
        rig,
        columns: &columns,
        parent: before.links.iter().map(|l| l.parent).collect(),
        base: BasePose {
            position: poses[robot].translation.truncate(),
            yaw: yaw_of(&poses[robot]),
        },
        values: before.links.iter().map(|l| l.value).collect(),
        poses,
        q: rig.stow.clone(),
        opening: 1.0,
        robot,
        gripper,
        time: 0.0,
        samples: Vec::new(),
    };
    walk.record(steps.first().map_or(0, |s| s.0));
    for &(step, changes) in steps {
        let mut k = 0;
        while k < changes.len() {
            // An object changes hands between an arm's reach and its retreat.
            let handover = match (&changes[k], changes.get(k + 1)) {
                (Change::ArmMotion { .. }, Some(attach @ Change::Attach { .. })) => Some(attach),
                _ => None,
            };
            walk.change(step, &changes[k], handover);
            k += if handover.is_some() { 2 } else { 1 };
        }
    }
    let samples = walk.samples;
    Some(Trajectory {
        names,
        columns,
        samples,
    })
}

/// The scene's state as the walk through the steps leaves it.
struct Walk<'a> {
    tree: &'a KinematicTree,
    rig: &'a ArmRig,
    columns: &'a [Column],
    /// What each link hangs from now.
    parent: Vec<Option<usize>>,
    /// Each link's world pose now.
    poses: Vec<Affine3A>,
    /// Each link's joint value now.
    values: Vec<f32>,
    base: BasePose,
    /// The arm's configuration, and its fingers' opening (0 closed .. 1 open).
    q: Vec<f32>,
    opening: f32,
    robot: usize,
    gripper: usize,
    time: f32,
    samples: Vec<Sample>,
}

impl Walk<'_> {
    fn change(&mut self, step: usize, change: &Change, handover: Option<&Change>) {
        match change {
            Change::MoveBase { to, .. } => {
                if let Some(motion) = link_motion(self.tree, change, SAMPLE_S) {
                    for pose in motion.world_from_link.iter().skip(1) {
                        self.base = BasePose {
                            position: pose.translation.truncate(),
                            yaw: yaw_of(pose),
                        };
                        self.move_subtree(self.robot, *pose);
                        self.time += SAMPLE_S;
                        self.record(step);
                    }
                }
                self.base = *to;
                self.move_subtree(self.robot, to.world_from_base());
            }
            Change::SetJoint { link, from, to } => {
                let Some(l) = self.link_named(link) else {
                    return;
                };
                // A part the hand has already moved (it followed the handle) stays where it is.
                if (self.values[l] - to).abs() <= f32::EPSILON && (from - to).abs() > 0.0 {
                    return;
                }
                let samples = link_motion(self.tree, change, SAMPLE_S)
                    .map_or(1, |m| m.world_from_link.len().saturating_sub(1).max(1));
                for k in 1..=samples {
                    let v = from + (to - from) * k as f32 / samples as f32;
                    self.set_joint(l, v);
                    self.time += SAMPLE_S;
                    self.record(step);
                }
            }
            Change::Attach { .. } => self.attach(change),
            Change::ArmMotion {
                reach,
                retreat,
                part,
                grip_m,
                ..
            } => {
                let takes =
                    matches!(handover, Some(Change::Attach { to, .. }) if to == GRIPPER_LINK);
                let holding = handover.is_some() && !takes;
                let [_, on_handle, on_retreat] =
                    self.rig.finger_openings(*grip_m, holding, part.is_some());
                self.follow(step, reach);
                if let Some(attach) = handover {
                    // A place's fingers open on the object still held, a pick's close on it
                    // once it is.
                    if holding {
                        self.fingers_to(step, on_retreat);
                    }
                    self.attach(attach);
                    if takes {
                        self.fingers_to(step, on_retreat);
                    }
                }
                if let Some(part) = part
                    && let Some(l) = self.link_named(&part.link)
                {
                    self.fingers_to(step, on_handle);
                    for (q, &v) in part.along.iter().zip(&part.values) {
                        self.set_joint(l, v);
                        self.follow(step, std::slice::from_ref(q));
                    }
                    self.fingers_to(step, on_retreat);
                }
                self.follow(step, retreat);
            }
        }
    }

    /// Turns or slides link `l`'s joint to `v`, with what hangs from the link.
    fn set_joint(&mut self, l: usize, v: f32) {
        let link = &self.tree.links[l];
        let parent = self.parent[l].map_or(Affine3A::IDENTITY, |p| self.poses[p]);
        let pose = parent * link.parent_from_link * link.joint.motion(v);
        self.values[l] = v;
        self.move_subtree(l, pose);
    }

    /// The hand along `path`, with what it holds.
    fn follow(&mut self, step: usize, path: &[Vec<f32>]) {
        let root = self.base.world_from_base() * self.rig.base_from_root;
        for q in path {
            let dt = crate::arm::rrt::distance(q, &self.q) / ARM_SPEED;
            self.q.clone_from(q);
            let hand = self.rig.arm.tool_pose(&root, q);
            self.move_subtree(self.gripper, hand);
            self.time += dt;
            self.record(step);
        }
    }

    /// The fingers close or open to `opening` over `FINGER_SAMPLES` instants (none when they
    /// are there).
    fn fingers_to(&mut self, step: usize, opening: f32) {
        let from = self.opening;
        if (opening - from).abs() <= f32::EPSILON {
            return;
        }
        for k in 1..=FINGER_SAMPLES {
            self.opening = from + (opening - from) * k as f32 / FINGER_SAMPLES as f32;
            self.time += SAMPLE_S;
            self.record(step);
        }
    }

    /// `link` now hangs from `to` at `parent_from_link`.
    fn attach(&mut self, change: &Change) {
        let Change::Attach {
            link,
            to,
            parent_from_link,
            ..
        } = change
        else {
            return;
        };
        let (Some(l), Some(p)) = (self.link_named(link), self.link_named(to)) else {
            return;
        };
        self.parent[l] = Some(p);
        let pose = self.poses[p] * *parent_from_link;
        self.move_subtree(l, pose);
    }

    /// A link by its name, or a node's own link by the node's id.
    fn link_named(&self, name: &str) -> Option<usize> {
        let links = &self.tree.links;
        links
            .iter()
            .position(|l| l.name == name)
            .or_else(|| links.iter().position(|l| l.node.as_deref() == Some(name)))
    }

    /// Moves link `l` to `pose`, and everything hanging from it with it.
    fn move_subtree(&mut self, l: usize, pose: Affine3A) {
        let delta = pose * self.poses[l].inverse();
        for d in 0..self.poses.len() {
            if self.hangs_from(d, l) {
                self.poses[d] = delta * self.poses[d];
            }
        }
    }

    /// Whether `link` is `ancestor` or hangs from it now.
    fn hangs_from(&self, link: usize, ancestor: usize) -> bool {
        crate::base::parent_chain::descends_from(link, ancestor, |l| self.parent[l])
    }

    fn record(&mut self, step: usize) {
        let values = self.columns.iter().map(|c| self.value(*c)).collect();
        let held = (0..self.parent.len())
            .find(|&l| self.parent[l] == Some(self.gripper))
            .map(|l| self.tree.links[l].name.clone());
        self.samples.push(Sample {
            time: self.time,
            step,
            held,
            values,
        });
    }

    fn value(&self, column: Column) -> f32 {
        match column {
            Column::BaseX => self.base.position.x,
            Column::BaseY => self.base.position.y,
            Column::BaseYaw => self.base.yaw,
            Column::Arm(i) => self.q[i],
            Column::Finger(l) => self.rig.arm.links[l].joint.as_ref().map_or(0.0, |j| {
                j.limits.0 + self.opening * (j.limits.1 - j.limits.0)
            }),
            Column::Free { link, component } => {
                let (_, rotation, translation) = self.poses[link].to_scale_rotation_translation();
                let rotation = rotation.normalize();
                [
                    translation.x,
                    translation.y,
                    translation.z,
                    rotation.w,
                    rotation.x,
                    rotation.y,
                    rotation.z,
                ][component]
            }
            Column::Joint(l) => self.values[l],
        }
    }
}

impl Trajectory {
    /// `trajectory.csv`: a header (`time`, `step`, `held`, then the joints), one line a sample.
    pub fn csv(&self) -> String {
        let mut text = String::new();
        let _ = writeln!(text, "time,step,held,{}", self.names.join(","));
        for sample in &self.samples {
            let _ = write!(
                text,
                "{:.4},{},{}",
                sample.time,
                sample.step,
                sample.held.as_deref().unwrap_or("")
            );
            for v in &sample.values {
                let _ = write!(text, ",{v:.6}");
            }
            text.push('\n');
        }
        text
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::base::JointSpec;
    use crate::geometry::TriMesh;
    use crate::kinematics::tree::TreeLink;

    /// A planar two-link arm on a base at the origin, its hand stowed, and a cup where the
    /// hand reaches at `grasp`: the walk of a pick's reach, handover and retreat.
    #[test]
    fn a_picked_object_stays_until_the_reach_ends_then_moves_with_the_hand() {
        let rig = ArmRig::new(crate::arm::tests::two_link_arm(), 0.5);
        let cube = TriMesh::cuboid(Vec3::splat(-0.02), Vec3::splat(0.02));
        let root = rig.base_from_root;
        let grasp = vec![0.6, -0.9];
        let tool_at_grasp = rig.arm.tool_pose(&root, &grasp);
        let cup_pose = tool_at_grasp * Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.03));
        let fixed = JointSpec::FIXED;
        let tree = KinematicTree {
            links: vec![
                TreeLink::root(),
                TreeLink::body(
                    ROBOT_LINK,
                    "robot",
                    0,
                    fixed,
                    Affine3A::IDENTITY,
                    cube.clone(),
                ),
                TreeLink::body(
                    GRIPPER_LINK,
                    "robot",
                    1,
                    fixed,
                    rig.base_from_stowed_tool(),
                    cube.clone(),
                ),
                TreeLink::body("cup_1", "cup", 0, JointSpec::FLOATING, cup_pose, cube),
            ],
        };
        let halfway: Vec<f32> = rig
            .stow
            .iter()
            .zip(&grasp)
            .map(|(a, b)| 0.5 * (a + b))
            .collect();
        let changes = vec![
            Change::ArmMotion {
                part: None,
                what: "test".into(),
                reach: vec![halfway.clone(), grasp.clone()],
                retreat: vec![halfway.clone(), rig.stow.clone()],
                grip_m: None,
            },
            Change::Attach {
                link: "cup_1".into(),
                from: String::new(),
                to: GRIPPER_LINK.into(),
                parent_from_link: tool_at_grasp.inverse() * cup_pose,
            },
        ];
        let walk = trajectory(&tree, &rig, &[(0, &changes)]).expect("a robot");
        assert_eq!(
            walk.samples.len(),
            5,
            "the start, two reach and two retreat samples"
        );
        let column = |name: &str| walk.names.iter().position(|n| n == name).expect(name);
        let (x, z) = (column("cup_1_joint.x"), column("cup_1_joint.z"));
        let arm0 = column(&arm_joint_name(&rig, rig.arm.chain[0]));
        let cup_at = |k: usize| {
            let v = &walk.samples[k].values;
            Vec3::new(v[x], v[x + 1], v[z])
        };
        let expected = |q: &[f32]| {
            (rig.arm.tool_pose(&root, q) * (tool_at_grasp.inverse() * cup_pose)).translation
        };
        for k in 0..3 {
            assert!(
                cup_at(k).distance(cup_pose.translation.into()) < 1e-5,
                "sample {k}"
            );
            assert_eq!(walk.samples[k].held, None);
        }
        assert_eq!(walk.samples[2].values[arm0], grasp[0]);
        for (k, q) in [(3, &halfway), (4, &rig.stow)] {
            assert!(cup_at(k).distance(expected(q).into()) < 1e-5, "sample {k}");
            assert_eq!(walk.samples[k].held.as_deref(), Some("cup_1"));
        }
        // Time runs at the arm's speed: the last sample is the path's length later.
        let length: f32 = [&rig.stow, &halfway, &grasp, &halfway, &rig.stow]
            .windows(2)
            .map(|w| crate::arm::rrt::distance(w[0], w[1]))
            .sum();
        assert!((walk.samples[4].time - length / ARM_SPEED).abs() < 1e-4);
        let csv = walk.csv();
        assert_eq!(csv.lines().count(), 6);
        assert!(csv.starts_with("time,step,held,robot_x,robot_y,robot_yaw,"));
    }
}
