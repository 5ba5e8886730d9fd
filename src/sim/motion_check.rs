//! What a motion check simulates and how it judges the outcome (the simulation itself is
//! `systems::motion_physics`, with rapier), as `kinematics::rest_test` is for the rest test.
//!
//! The moving links (the robot's base with its gripper and what it holds, a door or drawer with
//! what stands on it, the arm's links) are driven along their paths among the rest test's bodies;
//! the objects near the paths are free to be pushed, tipped or knocked down, the rest hold still.
//! Afterwards each free object is judged by how far it moved and turned, and the arm by how deep
//! it went into the scene. Which objects are near a motion: `kinematics::motion_bounds`.

use glam::{Affine3A, Vec3};
use serde::Serialize;

use crate::arm::rig::ArmRig;
use crate::kinematics::joint_sweep::world_bounds;
use crate::kinematics::motion_bounds::{body_bounds, link_bounds, overlaps, swept_bounds};
use crate::kinematics::rest_test::{
    MAX_START_PENETRATION_M, RestBody, rest_bodies, start_penetrations,
};
use crate::kinematics::tree::KinematicTree;
use crate::sim::robot::{GRIPPER_LINK, ROBOT_LINK};

/// An object moved farther than this (metres) or turned more than `KNOCK_TURN_DEG` was knocked.
pub const KNOCK_DISTANCE_M: f32 = 0.01;
pub const KNOCK_TURN_DEG: f32 = 5.0;
/// After the motion the world runs on this long (seconds), so what was knocked has fallen.
pub const AFTERMATH_S: f32 = 0.5;
/// Objects within this distance (metres) of where the moving links pass are simulated, with
/// what stands on them; the others hold still.
const NEAR_M: f32 = 0.05;
/// The arm going deeper than this (metres) into the scene refuses the motion.
pub const MAX_ARM_DEPTH_M: f32 = 0.005;

/// An object the motion moved.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Knocked {
    pub object: String,
    pub moved_m: f32,
    pub turned_deg: f32,
}

/// How deep the arm went into the scene along a motion: rapier's deepest contact between one
/// of its links and a link of the scene (the robot's own and what moves with the hand left out).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ArmDepth {
    /// Metres; 0 when nothing of the arm came within rapier's contact distance.
    pub depth_m: f32,
    /// The arm's link and the scene's link of that contact.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_link: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub into: Option<String>,
}

/// What one motion did to the objects around it.
#[derive(Clone, Debug, Serialize)]
pub struct MotionCheck {
    /// The moving link (or the arm motion's phase).
    pub link: String,
    /// Simulated seconds: the motion and its aftermath.
    pub simulated_s: f32,
    /// The objects near its path, simulated as it passed.
    pub near: Vec<String>,
    /// Those it moved more than 1 cm or turned more than 5 degrees.
    pub knocked: Vec<Knocked>,
    /// For an arm's motion, how deep it went into the scene.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arm_depth: Option<ArmDepth>,
    /// Objects near the path that the last rest test found falling on their own: held still
    /// here and not judged (their fall is not the motion's doing; the rest test reports it).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub falls_at_rest: Vec<String>,
    pub wall_ms: f64,
}

impl MotionCheck {
    /// Why this motion refuses its action, if it does: it knocked something, or took the arm
    /// more than [`MAX_ARM_DEPTH_M`] into the scene.
    pub fn refusal(&self) -> Option<String> {
        if let Some(depth) = self
            .arm_depth
            .as_ref()
            .filter(|d| d.depth_m > MAX_ARM_DEPTH_M)
        {
            return Some(format!(
                "moving {} would take {} {:.1} mm into {} (simulated in rapier)",
                self.link,
                depth.arm_link.as_deref().unwrap_or("the arm"),
                1000.0 * depth.depth_m,
                depth.into.as_deref().unwrap_or("the scene"),
            ));
        }
        if self.knocked.is_empty() {
            return None;
        }
        let what = self
            .knocked
            .iter()
            .map(|k| {
                format!(
                    "{} ({:.1} cm, {:.0} degrees)",
                    k.object,
                    100.0 * k.moved_m,
                    k.turned_deg
                )
            })
            .collect::<Vec<_>>()
            .join(", ");
        Some(format!(
            "moving {} would knock {what} (simulated in rapier)",
            self.link
        ))
    }
}

/// The verdict on an object that started at `start` and ended at `end`: knocked when it moved
/// more than [`KNOCK_DISTANCE_M`] or turned more than [`KNOCK_TURN_DEG`].
pub fn knocked(object: &str, start: Affine3A, end: Affine3A) -> Option<Knocked> {
    let moved_m = end.translation.distance(start.translation);
    let turned_deg = glam::Quat::from_mat3a(&end.matrix3)
        .angle_between(glam::Quat::from_mat3a(&start.matrix3))
        .to_degrees();
    (moved_m > KNOCK_DISTANCE_M || turned_deg > KNOCK_TURN_DEG).then(|| Knocked {
        object: object.to_string(),
        moved_m,
        turned_deg,
    })
}

/// What moves in one check: links of the tree driven along world poses (each with what hangs
/// from it), and the arm's links, all at the same instants `REST_STEP_S` apart.
pub struct Movers<'a> {
    /// The motion in words, for the check's record.
    pub name: String,
    pub links: &'a [(usize, Vec<Affine3A>)],
    /// Moving links whose own collision pieces take no part (the gripper's stand-in hand).
    pub hidden: &'a [usize],
    /// Links whose bodies are simulated with their hollows (what the hand goes into).
    pub hollow: &'a [usize],
    /// Links whose bodies hold still, the arm's contacts with them measured (what the hand
    /// comes to take: it must not go into it).
    pub still: &'a [usize],
    /// Links whose bodies the moving links (not the arm) are set down on or lifted from: the
    /// held object touching its new or old support is the set-down or the lift, not a knock
    /// (pressing a kinematic body onto a free one that stands on the floor throws it about in
    /// rapier, where MuJoCo's replay of the same motion finds 0.1 mm).
    pub set_on: &'a [usize],
    /// Links of objects the last rest test found falling on their own (`FallsAtRest`): held
    /// still, as `still`, so that a fall that happens without the motion is not blamed on it.
    pub falling: &'a [usize],
    /// The arm and its links' world poses at each instant (`arm.1[k][l]`).
    pub arm: Option<(&'a ArmRig, &'a [Vec<Affine3A>])>,
}

impl<'a> Movers<'a> {
    /// Nothing moving yet, named `name`: the base the other fields are set on.
    pub fn named(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            links: &[],
            hidden: &[],
            hollow: &[],
            still: &[],
            set_on: &[],
            falling: &[],
            arm: None,
        }
    }

    /// How many instants the motion has.
    pub fn instants(&self) -> usize {
        self.arm
            .map(|(_, poses)| poses.len())
            .or(self.links.first().map(|(_, poses)| poses.len()))
            .unwrap_or(0)
    }
}

/// Whether link `l` of `tree` is the robot's own (its base, or the gripper that stands for the
/// stowed hand).
pub fn robot_link(tree: &KinematicTree, l: usize) -> bool {
    [ROBOT_LINK, GRIPPER_LINK].contains(&tree.links[l].name.as_str())
}

/// The rest test's bodies as one motion check takes them: which are free, which hold still, and
/// what each driven link carries.
#[derive(Debug)]
pub struct MotionBodies {
    /// The rest test's bodies less the moving links (and, for an arm's motion, the robot's own:
    /// its base is no obstacle to its arm, and its gripper is the arm's own hand now).
    pub bodies: Vec<RestBody>,
    /// Each link's world pose at the start.
    pub poses: Vec<Affine3A>,
    /// For each driven link (`movers.links[i]`), the links its body carries: its subtree less
    /// the hidden links.
    pub carried: Vec<Vec<bool>>,
    /// Dynamic bodies a driven link belongs to without moving itself (a door's cabinet), and
    /// what the hand sets its object on: they do not collide with the driven links.
    pub owners: Vec<usize>,
    /// Bodies near the paths, or standing on one that is (bodies come after their supports).
    pub near: Vec<bool>,
    /// Bodies that hold still: not near, starting too deep in something, held still by the
    /// movers or falling on their own.
    pub frozen: Vec<bool>,
    /// Bodies the last rest test found falling on their own.
    pub falling: Vec<bool>,
    /// Links of the fixed scene the arm comes near, and those held still: the contacts with the
    /// arm that its depth is measured on (the rest cannot be touched, and computing their
    /// contacts every step cost more than the whole check).
    pub touchable: Vec<usize>,
}

impl MotionBodies {
    /// The bodies of `tree` for `movers`, whose arm (if any) sweeps the world box `arm_swept`.
    pub fn new(tree: &KinematicTree, movers: &Movers, arm_swept: (Vec3, Vec3)) -> Self {
        let n = tree.links.len();
        let moving: Vec<bool> = (0..n)
            .map(|i| movers.links.iter().any(|(l, _)| tree.descends_from(i, *l)))
            .collect();
        let mut bodies = rest_bodies(tree);
        let owners: Vec<usize> = (0..bodies.len())
            .filter(|&b| {
                let links = &bodies[b].links;
                bodies[b].dynamic
                    && !moving[links[0]]
                    && (movers.links.iter().any(|(l, _)| links.contains(l))
                        || movers.set_on.iter().any(|l| links.contains(l)))
            })
            .collect();
        let left_out = |l: usize| moving[l] || (movers.arm.is_some() && robot_link(tree, l));
        for body in &mut bodies {
            body.links.retain(|&l| !left_out(l));
        }
        let poses = tree.world_from_links();
        let carried: Vec<Vec<bool>> = movers
            .links
            .iter()
            .map(|(l, _)| {
                (0..n)
                    .map(|i| tree.descends_from(i, *l) && !movers.hidden.contains(&i))
                    .collect()
            })
            .collect();
        let swept = movers
            .links
            .iter()
            .zip(&carried)
            .map(|((l, path), under)| swept_bounds(tree, under, &poses, *l, path))
            .fold(arm_swept, |(a, b), (lo, hi)| (a.min(lo), b.max(hi)));
        let near = near_bodies(tree, &bodies, &moving, &poses, swept);
        let penetrations = start_penetrations(tree, &bodies);
        let holds = |b: usize, links: &[usize]| bodies[b].links.iter().any(|l| links.contains(l));
        let falling: Vec<bool> = (0..bodies.len())
            .map(|b| holds(b, movers.falling))
            .collect();
        let frozen = (0..bodies.len())
            .map(|b| {
                !near[b]
                    || penetrations[b].0 > MAX_START_PENETRATION_M
                    || falling[b]
                    || holds(b, movers.still)
            })
            .collect();
        let touchable = match movers.arm {
            Some(_) => bodies[0]
                .links
                .iter()
                .copied()
                .filter(|&l| {
                    link_bounds(tree, l).is_some_and(|(lo, hi)| {
                        overlaps(world_bounds(&poses[l], lo, hi), arm_swept, NEAR_M)
                    })
                })
                .chain(movers.still.iter().copied())
                .chain(movers.falling.iter().copied())
                .collect(),
            None => Vec::new(),
        };
        Self {
            bodies,
            poses,
            carried,
            owners,
            near,
            frozen,
            falling,
            touchable,
        }
    }

    /// The names of the bodies `keep` picks, in body order.
    pub fn names(&self, keep: impl Fn(usize) -> bool) -> Vec<String> {
        (0..self.bodies.len())
            .filter(|&b| keep(b))
            .map(|b| self.bodies[b].name.clone())
            .collect()
    }
}

/// Which of `bodies` are near the world box `swept`, or stand on a body that is.
fn near_bodies(
    tree: &KinematicTree,
    bodies: &[RestBody],
    moving: &[bool],
    poses: &[Affine3A],
    swept: (Vec3, Vec3),
) -> Vec<bool> {
    let mut body_of = vec![0; tree.links.len()];
    for (b, body) in bodies.iter().enumerate() {
        for &l in &body.links {
            body_of[l] = b;
        }
    }
    let mut near = vec![false; bodies.len()];
    for (b, body) in bodies.iter().enumerate() {
        let Some(&first) = body.links.first() else {
            continue;
        };
        let on_near = tree.links[first]
            .parent
            .is_some_and(|p| !moving[p] && near[body_of[p]]);
        near[b] = body.dynamic
            && (on_near
                || body_bounds(tree, &body.links, poses)
                    .is_some_and(|(lo, hi)| overlaps((lo, hi), swept, NEAR_M)));
    }
    near
}
