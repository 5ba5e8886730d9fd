//! What the rest test simulates and how it judges the outcome (the simulation itself is the
//! PhysicsValidation stage, with rapier).
//!
//! Every object a model replaced is a dynamic body, standing where the reconstruction put it,
//! whatever its joint in the tree: a table that would topple is as wrong as a cup that would
//! slide. The layout, what hangs on a wall and the objects no model replaced are static. Those
//! are made of what the map saw of them (`kinematics::link::observed_surface`), a surface seen
//! from one side, not a body of known shape and weight; every export fixes them too. A counter
//! seen from the front is a box 35 cm deep (7-Scenes redkitchen): as a dynamic body hundreds of
//! times a cup's weight it shook the cup on it off its edge, while MuJoCo, which has it fixed,
//! rests the cup to 0.02 mm. An
//! articulated object's doors and drawers are locked to it at their current values. After the
//! simulated time each object is judged by how far it moved and turned, and by how deep it
//! started inside anything else.

use glam::Affine3A;
use serde::Serialize;

use crate::classes::ClassTable;
use crate::kinematics::joint_sweep::{LinkSolids, link_penetration};
use crate::kinematics::tree::KinematicTree;

/// Simulated time of the rest test, seconds, and its fixed step.
pub const REST_SECONDS: f32 = 2.0;
pub const REST_STEP_S: f32 = 1.0 / 120.0;
/// Solver substeps per step: small round objects (cups, bowls) on a dynamic table jitter
/// without them.
pub const REST_SUBSTEPS: usize = 4;
/// An object that moves farther than this (metres) or tips more than this (degrees) is unstable.
pub const MAX_REST_DISPLACEMENT_M: f32 = 0.01;
pub const MAX_REST_TILT_DEG: f32 = 5.0;
/// Starting deeper than this (metres) inside another body is penetrating.
pub const MAX_START_PENETRATION_M: f32 = 0.01;

/// One simulated body: the links it carries (its own first) and whether it moves.
#[derive(Clone, Debug, PartialEq)]
pub struct RestBody {
    /// The object's contact-graph id, or `world` for the static body.
    pub name: String,
    pub links: Vec<usize>,
    pub dynamic: bool,
}

/// The bodies of the rest test: body 0 is static (the root, the layout, wall-hung objects, the
/// robot and what it holds, objects no model replaced, and everything locked to them), then one
/// dynamic body per other object.
pub fn rest_bodies(tree: &KinematicTree) -> Vec<RestBody> {
    let mut bodies = vec![RestBody {
        name: crate::kinematics::tree::ROOT_LINK.into(),
        links: Vec::new(),
        dynamic: false,
    }];
    let mut body_of: Vec<usize> = Vec::with_capacity(tree.links.len());
    for (i, link) in tree.links.iter().enumerate() {
        let own_link = link.node.as_deref() == Some(link.name.as_str());
        let parent_body = link.parent.map_or(0, |p| body_of[p]);
        let hangs_on_wall = link
            .parent
            .is_some_and(|p| tree.links[p].class.as_deref() == Some("wall"));
        // What the robot's gripper holds is held still with the robot (a link that is no node).
        let held = link
            .parent
            .is_some_and(|p| p != 0 && tree.links[p].node.is_none());
        let body = if own_link
            && link.modelled
            && !ClassTable::builtin().is_layout(link.class.as_deref())
            && !hangs_on_wall
            && !held
        {
            bodies.push(RestBody {
                name: link.name.clone(),
                links: Vec::new(),
                dynamic: true,
            });
            bodies.len() - 1
        } else {
            parent_body
        };
        bodies[body].links.push(i);
        body_of.push(body);
    }
    bodies
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Stable,
    Unstable,
    Penetrating,
}

/// The rest test's finding for one object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectVerdict {
    pub object: String,
    pub verdict: Verdict,
    pub displacement_m: f32,
    /// The whole turn, and how far the object's up axis tipped (degrees).
    pub rotation_deg: f32,
    pub tilt_deg: f32,
    /// The deepest the object started inside another body, metres, and that body's link.
    pub start_penetration_m: f32,
    pub penetrates: Option<String>,
    /// Why it is not stable, in words; `None` when it is.
    pub reason: Option<String>,
}

/// The deepest start penetration of each body into any other body (not static into static).
pub fn start_penetrations(tree: &KinematicTree, bodies: &[RestBody]) -> Vec<(f32, Option<usize>)> {
    let poses = tree.world_from_links();
    let solids: Vec<LinkSolids> = (0..tree.links.len())
        .map(|i| LinkSolids::of(tree, i))
        .collect();
    let mut deepest = vec![(0.0f32, None); bodies.len()];
    for (a, body_a) in bodies.iter().enumerate() {
        for (b, body_b) in bodies.iter().enumerate().skip(a + 1) {
            if !body_a.dynamic && !body_b.dynamic {
                continue;
            }
            for &la in &body_a.links {
                for &lb in &body_b.links {
                    let d = link_penetration(&solids[la], &poses[la], &solids[lb], &poses[lb]);
                    if d > deepest[a].0 {
                        deepest[a] = (d, Some(lb));
                    }
                    if d > deepest[b].0 {
                        deepest[b] = (d, Some(la));
                    }
                }
            }
        }
    }
    deepest
}

/// Judges one dynamic body from its pose before and after the rest and its start penetration.
pub fn judge(
    tree: &KinematicTree,
    body: &RestBody,
    before: Affine3A,
    after: Affine3A,
    start_penetration: (f32, Option<usize>),
) -> ObjectVerdict {
    let displacement_m = before.translation.distance(after.translation);
    let (_, r0, _) = before.to_scale_rotation_translation();
    let (_, r1, _) = after.to_scale_rotation_translation();
    let rotation_deg = r0.angle_between(r1).to_degrees();
    // How far it tipped: round objects may turn about the vertical without falling over.
    let tilt_deg = (r0 * glam::Vec3::Z)
        .angle_between(r1 * glam::Vec3::Z)
        .to_degrees();
    let (depth, with) = start_penetration;
    let penetrates = with.map(|l| tree.links[l].name.clone());
    let (verdict, reason) = if depth > MAX_START_PENETRATION_M {
        (
            Verdict::Penetrating,
            Some(format!(
                "starts {:.1} cm inside {}",
                depth * 100.0,
                penetrates.as_deref().unwrap_or("another body")
            )),
        )
    } else if displacement_m > MAX_REST_DISPLACEMENT_M || tilt_deg > MAX_REST_TILT_DEG {
        (
            Verdict::Unstable,
            Some(format!(
                "moved {:.1} cm and tipped {:.1} degrees in {REST_SECONDS} s at rest",
                displacement_m * 100.0,
                tilt_deg
            )),
        )
    } else {
        (Verdict::Stable, None)
    };
    ObjectVerdict {
        object: body.name.clone(),
        verdict,
        displacement_m,
        rotation_deg,
        tilt_deg,
        start_penetration_m: depth,
        penetrates,
        reason,
    }
}
