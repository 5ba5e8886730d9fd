//! A pick or a place done by the robot's arm: grasps of the object from its box, the arm's
//! motions to them planned against the scene as it stands, and the motions as changes of the
//! trace. Each grasp is tried in turn; when none works, the action fails with what went wrong
//! for each.

use glam::{Affine3A, Vec3};

use crate::arm::collision::Obstacles;
use crate::arm::grasp::{Grasp, GraspKind, Hand, PREGRASP_M, finger_gap, grasps, most_level_first};
use crate::arm::reach::{ArmPath, Held, LIFT_M, ReachError, reach, retreat, retreat_through};
use crate::arm::rig::ArmRig;
use crate::sim::actions::arm_scene::{
    AroundObject, add_links, collision_pieces, held_pieces, standing_against, subtree,
};
use crate::sim::actions::look_ahead::LookAheadError;
use crate::sim::actions::{ActionError, Change, RobotInTree};
use crate::sim::robot::GRIPPER_LINK;
use crate::sim::scene_view::{SceneView, TOUCH_M};

/// Classes held by their rim when too wide for the fingers.
const VESSELS: [&str; 3] = ["cup", "bowl", "mug"];
/// A grasp whose approach is within 45 degrees of straight down comes from above; leaving an
/// object it set down in a container, its hand first rises this far (metres) over the object's
/// top.
const FROM_ABOVE_COS: f32 = 0.7;
const RISE_CLEAR_M: f32 = 0.01;
/// Fractions of that rise tried first, the open fingers kept clear of the object: less of a
/// rise keeps the hand lower under a container's ceiling.
const LESSER_RISES: [f32; 3] = [0.0, 0.25, 0.5];
/// At most this many grasps are tried per action (the best first).
const MAX_GRASPS: usize = 6;
/// Room between the object and a container's front where the hand starts carrying it in,
/// metres.
const INSERT_CLEARANCE_M: f32 = 0.03;

/// The grasps of node `id`'s link `link` at the world pose `world_from_link`, from the
/// collision pieces of the node's links (its own and its parts', such as a bottle's cap).
fn grasps_of(
    view: &SceneView,
    rig: &ArmRig,
    state: &RobotInTree,
    id: &str,
    link: usize,
    world_from_link: &Affine3A,
) -> Result<Vec<Grasp>, ActionError> {
    let node = &view.tree.links[link].node;
    let own: Vec<usize> = subtree(view, link)
        .into_iter()
        .filter(|&l| view.tree.links[l].node == *node)
        .collect();
    let link_from_world = view.poses[link].inverse();
    let points: Vec<Vec3> = collision_pieces(view, &own)
        .flat_map(|(_, piece, pose)| {
            let link_from_piece = link_from_world * pose;
            piece
                .positions
                .iter()
                .map(move |p| link_from_piece.transform_point3(*p))
        })
        .collect();
    if points.is_empty() {
        return Err(ActionError::NoGeometry(id.to_string()));
    }
    let rim = view.class_of(id).is_some_and(|c| VESSELS.contains(&c));
    let found = grasps(
        world_from_link,
        &points,
        Hand {
            opening: rig.max_opening,
            palm_depth: rig.palm_depth,
        },
        state.base.position,
        rim,
    );
    if found.is_empty() {
        return Err(ActionError::NoGrasp {
            object: id.to_string(),
            width_m: rig.max_opening,
        });
    }
    Ok(found)
}

/// The arm's pick of node `id` (link `link`, its obstacles `around`) from where the base
/// stands: reach, close, lift and stow with it. The object then hangs from the gripper (the
/// stowed hand) as the fingers hold it. The first grasp whose pick `then` accepts (the place
/// that follows plans with it), else the first that works; with `level_first`, the grasps
/// whose hand comes in most level are tried before the others.
#[allow(clippy::too_many_arguments, reason = "one action's whole problem")]
pub(super) fn pick_motion(
    view: &SceneView,
    rig: &ArmRig,
    state: &RobotInTree,
    (id, link): (&str, usize),
    around: &AroundObject,
    level_first: bool,
    then: &dyn Fn(&[Change]) -> Result<(), LookAheadError>,
) -> Result<Vec<Change>, ActionError> {
    let root = state.base.world_from_base() * rig.base_from_root;
    let (transit, near) = (&around.with_object, &around.grasped);
    let mut candidates = grasps_of(view, rig, state, id, link, &view.poses[link])?;
    let mut tried = MAX_GRASPS;
    if level_first {
        // The level ones first, and as many again: the others stay in the running.
        candidates = most_level_first(candidates);
        tried *= 2;
    }
    let from = view.support_of(id).map_or(String::new(), String::from);
    let support_links: Vec<String> = view
        .tree
        .links
        .iter()
        .filter(|l| l.node.as_deref() == Some(from.as_str()))
        .map(|l| l.name.clone())
        .collect();
    first_grasp_that_works(
        id,
        &format!("pick {id}"),
        &state.refused,
        candidates,
        tried,
        then,
        |_, grasp| {
            let to = reach(
                rig,
                &root,
                &rig.stow,
                &grasp.world_from_tool,
                grasp.approach,
                PREGRASP_M,
                transit,
                near,
                &Held::default(),
            )?;
            // Where the fingers closed: the tool as the arm put it, not as the grasp asked.
            let world_from_tool = rig.arm.tool_pose(&root, to.last());
            let scene = &around.without_object;
            let (held, lift) = standing_against(
                rig,
                held_pieces(view, &around.links, &world_from_tool),
                &world_from_tool,
                scene,
                &support_links,
            );
            let up = Vec3::Z * lift;
            let back = retreat(rig, &root, to.last(), up, scene, scene, &held)?;
            let in_hand = Change::Attach {
                link: id.to_string(),
                from: from.clone(),
                to: GRIPPER_LINK.into(),
                parent_from_link: world_from_tool.inverse() * view.poses[link],
            };
            Ok(GraspPlan {
                reach: to,
                retreat: back,
                attach: in_hand,
                grip_m: finger_gap(&held.pieces, rig.max_opening),
            })
        },
    )
}

/// One grasp's motion: the reach, the retreat, the object's attachment between them (to the
/// hand, or from it to where it is set down) and the fingers' gap on it.
struct GraspPlan {
    reach: ArmPath,
    retreat: ArmPath,
    attach: Change,
    grip_m: Option<f32>,
}

/// Why one grasp's motion does not plan: the arm's reach or retreat, or where the object would
/// end up.
#[derive(Debug, thiserror::Error)]
enum GraspFailure {
    #[error(transparent)]
    Reach(#[from] ReachError),
    #[error(transparent)]
    Action(#[from] ActionError),
}

/// The arm's motion with the first of `candidates` (at most `tried` of them, those whose motion
/// the simulation `refused` left out) for which `plan` (given the grasp and its index) finds a
/// reach, a retreat and where the object ends up, and whose changes `then` accepts; else the
/// first that `plan` finds; else `what` fails with each grasp's reason.
fn first_grasp_that_works(
    id: &str,
    what: &str,
    refused: &[String],
    candidates: Vec<Grasp>,
    tried: usize,
    then: &dyn Fn(&[Change]) -> Result<(), LookAheadError>,
    plan: impl Fn(usize, &Grasp) -> Result<GraspPlan, GraspFailure>,
) -> Result<Vec<Change>, ActionError> {
    let (mut first, mut attempts) = (None, Vec::new());
    let mut not_refused = Vec::new();
    for (i, grasp) in candidates.into_iter().enumerate() {
        let label = grasp_label(&grasp);
        if refused.contains(&format!("{label} of {id}")) {
            attempts.push(format!("{label}: refused by the simulation in rapier"));
        } else {
            not_refused.push((i, grasp));
        }
    }
    for (i, grasp) in not_refused.into_iter().take(tried) {
        let label = grasp_label(&grasp);
        match plan(i, &grasp) {
            Ok(planned) => {
                let motion = Change::ArmMotion {
                    what: format!("{label} of {id}"),
                    reach: planned.reach.configurations,
                    retreat: planned.retreat.configurations,
                    part: None,
                    grip_m: planned.grip_m,
                };
                let changes = vec![motion, planned.attach];
                match then(&changes) {
                    Ok(()) => return Ok(changes),
                    Err(why) => {
                        tracing::debug!("{label} of {id}: {why}");
                        first.get_or_insert(changes);
                    }
                }
            }
            Err(why) => {
                tracing::debug!("{label} of {id} does not plan: {why}");
                attempts.push(format!("{label}: {why}"));
            }
        }
    }
    first.ok_or_else(|| ActionError::ArmCannot {
        what: what.to_string(),
        attempts,
    })
}

/// The arm's placing of the held node `id` (link `link`) at `world_from_link` on or in `host`:
/// reach with it, open, lift and stow. The hand keeps the grasp it picked the object with; the
/// object may stand turned about its vertical axis (by a half turn, or any eighth of one for
/// a round vessel or a bottle) where the spot has room for it that way, `ignore` left out of
/// that check. The last stretch comes down from above, or along `inward` (a horizontal
/// direction in the world, and how far) into a container through its front. The motion and
/// the object's attachment to `host`.
#[allow(clippy::too_many_arguments, reason = "one action's whole problem")]
pub(super) fn place_motion(
    view: &SceneView,
    rig: &ArmRig,
    state: &RobotInTree,
    (id, link): (&str, usize),
    around: &AroundObject,
    (host, world_from_link): (&str, &Affine3A),
    inward: Option<(Vec3, f32)>,
    ignore: &[usize],
) -> Result<Vec<Change>, ActionError> {
    let root = state.base.world_from_base() * rig.base_from_root;
    let scene = &around.without_object;
    let gripper = view
        .link(GRIPPER_LINK)
        .ok_or_else(|| ActionError::NotHolding(id.to_string()))?;
    // How the fingers hold it, and the object in the hand as the tool's pieces.
    let link_from_tool = view.poses[link].inverse() * view.poses[gripper];
    let held = held_pieces(view, &around.links, &view.poses[gripper]);
    let grip_m = finger_gap(&held.pieces, rig.max_opening);
    let spots = turned_spots(view, id, link, world_from_link, ignore);
    let candidates = spots
        .iter()
        .map(|spot| held_grasp(*spot * link_from_tool))
        .collect();
    first_grasp_that_works(
        id,
        &format!("place {id}"),
        &state.refused,
        candidates,
        MAX_GRASPS,
        &|_| Ok(()),
        |i, grasp| {
            let spot = spots[i];
            // The object at its new place, for the way back.
            let moved = spot * view.poses[link].inverse();
            let mut placed = scene.clone();
            add_links(&mut placed, view, &around.links, &moved);
            // Set down from above (or carried in through a container's front), so the object
            // never drags over its support, and released 5 mm over it (beyond the last
            // stretch's margin): it drops onto it.
            let release = Affine3A::from_translation(Vec3::Z * 0.005) * grasp.world_from_tool;
            let to = reach(
                rig,
                &root,
                &rig.stow,
                &release,
                inward.map_or(-Vec3::Z, |(d, _)| d),
                inward.map_or(PREGRASP_M, |(_, length)| length),
                scene,
                scene,
                &held,
            )?;
            // Out of the grasp: back along the hand's approach off a surface (up from a top
            // grasp; straight up would drag a side grasp's fingers along a bottle's height),
            // back out of a container's front.
            let aways = match inward {
                None => vec![-grasp.approach * LIFT_M],
                // A hand that came down on it (fingers in a cup's rim, around a bottle's neck)
                // rises off it before it backs out: straight out, the fingers went through
                // the cup's wall (12 mm in MuJoCo's replay).
                Some((d, length)) if grasp.approach.z < -FROM_ABOVE_COS => {
                    let top = view.local_bounds(link).map_or(0.0, |(_, hi)| {
                        (moved * view.poses[link]).translation.z + hi.z
                    });
                    let rise = (top - grasp.world_from_tool.translation.z + RISE_CLEAR_M).max(0.0);
                    vec![Vec3::Z * rise, -d * length]
                }
                Some((d, length)) => vec![-d * length],
            };
            // Out of a container the fingers leave the object as they may touch it, no more.
            let mut near = scene.clone();
            let mut set_down = Obstacles::default();
            if inward.is_some() {
                add_links(&mut set_down, view, &around.links, &moved);
                near.items.extend(set_down.clone().grasped().items);
            }
            // Out with less of a rise (none first) where the open fingers clear the object
            // all the way, no finger touching it (a leaning rim grasp's inner finger rides
            // near a bowl's rim): rising the whole way first, the hand over a bowl in a
            // microwave met its ceiling.
            let straight_out = match (inward, aways.as_slice()) {
                (Some((d, length)), [rise, _]) => {
                    let mut clear = scene.clone();
                    clear.items.extend(set_down.items);
                    LESSER_RISES.iter().find_map(|fraction| {
                        let ways = [*rise * *fraction, -d * length];
                        let ways = if *fraction > 0.0 {
                            &ways[..]
                        } else {
                            &ways[1..]
                        };
                        retreat_through(
                            rig,
                            &root,
                            to.last(),
                            ways,
                            &placed,
                            &clear,
                            &Held::default(),
                        )
                        .inspect_err(|e| tracing::debug!("out after {fraction} of the rise: {e}"))
                        .ok()
                    })
                }
                _ => None,
            };
            let back = match straight_out {
                Some(back) => back,
                None => retreat_through(
                    rig,
                    &root,
                    to.last(),
                    &aways,
                    &placed,
                    &near,
                    &Held::default(),
                )?,
            };
            let attach = super::attach(view, link, host, spot)?
                .pop()
                .expect("one attachment");
            Ok(GraspPlan {
                reach: to,
                retreat: back,
                attach,
                grip_m,
            })
        },
    )
}

/// The grasp the hand holds an object by, the tool at `world_from_tool` once it is set down.
fn held_grasp(world_from_tool: Affine3A) -> Grasp {
    Grasp {
        kind: GraspKind::Held,
        world_from_tool,
        approach: world_from_tool.transform_vector3(Vec3::Z).normalize(),
        width: 0.0,
    }
}

/// `spot` and the same spot with the object turned about its vertical axis through its middle,
/// where it has room that way: by a half turn (a box's footprint is the same), or by every
/// eighth of a turn for a round vessel or a bottle.
fn turned_spots(
    view: &SceneView,
    id: &str,
    link: usize,
    spot: &Affine3A,
    ignore: &[usize],
) -> Vec<Affine3A> {
    let round = view
        .class_of(id)
        .is_some_and(|c| VESSELS.contains(&c) || c == "bottle");
    let turns: &[f32] = if round {
        &[0.0, 4.0, 2.0, 6.0, 1.0, 7.0, 3.0, 5.0]
    } else {
        &[0.0, 4.0]
    };
    let (lo, hi) = view.local_bounds(link).unwrap_or_default();
    let middle = spot.transform_point3(0.5 * (lo + hi));
    turns
        .iter()
        .map(|eighths| {
            let turn = Affine3A::from_translation(middle)
                * Affine3A::from_rotation_z(eighths * std::f32::consts::FRAC_PI_4)
                * Affine3A::from_translation(-middle);
            turn * *spot
        })
        .filter(|s| s == spot || view.overlap_at(link, *s, ignore) <= TOUCH_M)
        .collect()
}

/// A grasp in words: its kind, where the tool goes and which way the hand comes in.
fn grasp_label(grasp: &Grasp) -> String {
    let at = grasp.world_from_tool.translation;
    let d = grasp.approach;
    let from = if d.z < -0.9 {
        "from above".to_string()
    } else if d.z < -0.1 {
        format!("along ({:+.1}, {:+.1}) pitched down", d.x, d.y)
    } else {
        format!("along ({:+.1}, {:+.1})", d.x, d.y)
    };
    format!(
        "{} grasp at ({:.2}, {:.2}, {:.2}) {from}",
        format!("{:?}", grasp.kind).to_lowercase(),
        at.x,
        at.y,
        at.z
    )
}

/// The way into the container whose body is link `container` for object `link` set down at
/// `spot`: the inward direction (its frame's +y, the front facing -y) and the distance from
/// where the object is clear of the front to the spot.
pub(super) fn way_in(
    view: &SceneView,
    container: usize,
    link: usize,
    spot: &Affine3A,
) -> Option<(Vec3, f32)> {
    let (clo, _) = view.local_bounds(container)?;
    let (olo, ohi) = view.local_bounds(link)?;
    let pose = view.poses[container];
    let inward = pose.transform_vector3(Vec3::Y).normalize();
    let depth = pose.inverse().transform_point3(spot.translation.into()).y - clo.y;
    let half = 0.5 * (ohi - olo).truncate().max_element();
    Some((inward, depth.max(0.0) + half + INSERT_CLEARANCE_M))
}
