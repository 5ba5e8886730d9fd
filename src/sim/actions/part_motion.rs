//! A door or drawer worked by the arm: the hand takes the part's handle (found on its front as
//! the perception finds handles on a model), follows it along the joint's arc or line while the
//! part turns or slides with it, each pose solved from the one before, then lets go, backs off
//! and goes back to the stowed arm. The whole arm keeps clear of everything but the part; the
//! arm's links but the hand keep clear of the part too (the hand holds its handle).

use glam::{Affine3A, Mat3, Vec3};

use crate::arm::collision::Obstacles;
use crate::arm::grasp::{PREGRASP_M, finger_gap};
use crate::arm::reach::{
    ArmPath, Held, ReachError, STRETCH_MARGIN_M, configurations_at, describe, follow,
    reach_configuration, retreat_along,
};
use crate::arm::rig::ArmRig;
use crate::geometry::TriMesh;
use crate::geometry::surface_points::surface_points;
use crate::kinematics::JointKind;
use crate::perception::fronts::model_handles;
use crate::perception::handles::{Handle, HandleKind};
use crate::sim::actions::arm_scene::{add_links, held_pieces, scene_obstacles, subtree};
use crate::sim::actions::{ActionError, Change, PartFollow, RobotInTree};
use crate::sim::robot::RobotSpec;
use crate::sim::scene_view::{SceneView, closed_value};

/// How far the handle moves between two poses the hand follows, metres.
const FOLLOW_STEP_M: f32 = 0.01;
/// How far in from a handle's outer face the tool (between the fingertips) takes it: half the
/// handle's depth, at most this, metres.
const HANDLE_GRIP_M: f32 = 0.015;
/// Inverse kinematics runs for the ways the arm takes a handle (per grip).
const GRIP_CONFIGURATIONS: usize = 12;
/// How far the hand backs off a handle it lets go of before it plans back, metres: the planner
/// keeps 2 cm from everything, the open part included.
const LET_GO_M: [f32; 3] = [0.05, 0.1, 0.2];
/// A door opened as far as it goes may be let go of this many follow steps before the end,
/// and every so many steps before that while it is open enough.
const LET_GO_EVERY: usize = 5;

/// A way to take the handle: which of the grips, the arm's configuration there, the
/// configurations that follow the handle from it, and why they stop short of the end.
struct Way {
    grip: usize,
    q: Vec<f32>,
    along: Vec<Vec<f32>>,
    stopped: Option<String>,
}

/// The arm's work on a part: its motion, and the value the part ends at.
pub(super) struct PartWork {
    pub motion: Change,
    pub reached: f32,
}

/// Where the hand takes part `joint` of node `object`: the handle found on the part's front,
/// and the tool's pose in the part's frame there, as it is and turned a half turn about the
/// approach.
pub(super) fn part_grip(
    view: &SceneView,
    object: &str,
    joint: usize,
) -> Result<(Handle, [Affine3A; 2]), ActionError> {
    let tree = view.tree;
    let link = &tree.links[joint];
    let cannot = |why: String| ActionError::ArmCannot {
        what: format!("work {}", link.name),
        attempts: vec![why],
    };
    let own = view
        .node_link(object)
        .ok_or_else(|| ActionError::NotInScene(object.to_string()))?;
    // Models face -y; the part's front faces the same way when it is closed.
    let outward = view.poses[own]
        .transform_vector3(Vec3::NEG_Y)
        .with_z(0.0)
        .try_normalize()
        .ok_or_else(|| cannot(format!("{object}'s front is not vertical")))?;
    let closed = world_from_part(view, joint, closed_value(tree, joint));
    let closed_from_now = closed * view.poses[joint].inverse();
    let mut mesh = TriMesh::default();
    for &l in &subtree(view, joint) {
        mesh.append(&view.world_mesh(l).transformed(&closed_from_now));
    }
    let axis = (
        Vec3::from(closed.translation),
        closed
            .transform_vector3(link.joint.axis)
            .normalize_or_zero(),
    );
    let handle = part_handle(&mesh, outward, link.joint.kind, axis)
        .ok_or_else(|| cannot(format!("no handle found on {}", link.name)))?;
    let grasp = closed.inverse() * handle_grasp(&handle, outward);
    // The fingers are alike: the hand turned a half turn about its approach takes the handle
    // as well, and may keep the wrist away from its limits.
    let turned = grasp * Affine3A::from_rotation_z(std::f32::consts::PI);
    Ok((handle, [grasp, turned]))
}

/// Part `joint`'s world pose at joint value `v`, its parent where it stands in `view`.
pub(super) fn world_from_part(view: &SceneView, joint: usize, v: f32) -> Affine3A {
    let link = &view.tree.links[joint];
    let parent = link.parent.map_or(Affine3A::IDENTITY, |p| view.poses[p]);
    parent * link.parent_from_link * link.joint.motion(v)
}

/// The arm of the robot `state` takes the handle of node `object`'s part `joint` and moves the
/// part from its value to `to`. Stopping short of `to` (where the arm cannot follow further)
/// is accepted from `least` on, when given: a door opened as far as it goes.
pub(super) fn work_part(
    view: &SceneView,
    rig: &ArmRig,
    state: &RobotInTree,
    object: &str,
    joint: usize,
    to: f32,
    least: Option<f32>,
) -> Result<PartWork, ActionError> {
    let link = &view.tree.links[joint];
    let name = link.name.clone();
    let cannot = |why: String| ActionError::ArmCannot {
        what: format!("work {name}"),
        attempts: vec![why],
    };
    let from = link.value;
    let (handle, part_from_tools) = part_grip(view, object, joint)?;
    let part_links = subtree(view, joint);

    // The part's values the hand follows, each close enough to the one before.
    let at_start = world_from_part(view, joint, from);
    let step = match link.joint.kind {
        JointKind::Revolute => {
            let axis = at_start
                .transform_vector3(link.joint.axis)
                .normalize_or_zero();
            let handle_at = at_start.transform_point3(part_from_tools[0].translation.into());
            let radius = (handle_at - Vec3::from(at_start.translation))
                .reject_from(axis)
                .length();
            FOLLOW_STEP_M / radius.max(0.05)
        }
        _ => FOLLOW_STEP_M,
    };
    let steps = ((to - from).abs() / step).ceil() as usize;
    let values: Vec<f32> = (1..=steps)
        .map(|k| from + (to - from) * k as f32 / steps as f32)
        .collect();
    // Per way of holding the handle: the tool at the start, and along the path.
    let grips: Vec<(Affine3A, Vec<Affine3A>)> = part_from_tools
        .iter()
        .map(|part_from_tool| {
            let along = values
                .iter()
                .map(|&v| rigid(&(world_from_part(view, joint, v) * *part_from_tool)))
                .collect();
            (rigid(&(at_start * *part_from_tool)), along)
        })
        .collect();

    let still = scene_obstacles(view, &part_links);
    let part_at = |v: f32| {
        let mut obstacles = Obstacles::default();
        let moved = world_from_part(view, joint, v) * view.poses[joint].inverse();
        add_links(&mut obstacles, view, &part_links, &moved);
        obstacles
    };
    let with_part = |v: f32| {
        let mut all = still.clone();
        all.items.extend(part_at(v).items);
        all
    };
    let root = state.base.world_from_base() * rig.base_from_root;
    let parts: Vec<Obstacles> = values.iter().map(|&v| part_at(v)).collect();
    let hand = rig.arm.hand_links();
    let touching_at = |k: usize, q: &[f32]| {
        let poses = rig.arm.link_poses(&root, q, 1.0);
        rig.collider
            .touching(&poses, &still, STRETCH_MARGIN_M)
            .map(|t| describe(rig, &still, &t))
            .or_else(|| {
                rig.collider
                    .touching_obstacles(&poses, &parts[k], STRETCH_MARGIN_M, &hand)
                    .map(|t| describe(rig, &parts[k], &t))
            })
    };
    // Ways the arm takes the handle, each followed along the path as far as it goes (one at
    // a joint's limit goes nowhere); the farthest first, the first the arm gets to taken.
    let mut ways: Vec<Way> = grips
        .iter()
        .enumerate()
        .flat_map(|(g, (grip, _))| {
            configurations_at(rig, &root, grip, &still, GRIP_CONFIGURATIONS)
                .into_iter()
                .map(move |q| (g, q))
        })
        .map(|(g, q)| {
            let (along, stopped) = follow(rig, &root, &q, &grips[g].1, &touching_at);
            Way {
                grip: g,
                q,
                along,
                stopped,
            }
        })
        .collect();
    ways.sort_by_key(|w| std::cmp::Reverse(w.along.len()));
    if ways.is_empty() {
        return Err(cannot(format!(
            "no configuration of the arm takes {name}'s handle clear of everything else"
        )));
    }
    let mut why_not = Vec::new();
    let mut chosen = None;
    for Way {
        grip,
        q,
        along,
        stopped,
    } in ways
    {
        let grip = &grips[grip].0;
        let approach = grip.transform_vector3(Vec3::Z).normalize();
        let reached = along.len().checked_sub(1).map_or(from, |k| values[k]);
        if let Some(why) = &stopped {
            let enough = least.is_some_and(|l| (reached - from).abs() >= (l - from).abs());
            if !enough {
                why_not.push(format!(
                    "the hand follows {name} from {from:.2} to {reached:.2} of {to:.2}: {why}"
                ));
                continue;
            }
        }
        let there = match reach_configuration(
            rig,
            &root,
            &rig.stow,
            (&q, grip),
            approach,
            PREGRASP_M,
            &with_part(from),
            &still,
            &Held::default(),
        ) {
            Ok(there) => there,
            Err(why) => {
                why_not.push(why.to_string());
                continue;
            }
        };
        // Where the hand lets go: at the end, else (a door opened as far as it goes) earlier
        // on the way, as long as the part is open enough there. A door opened wide turns its
        // handle away from the base, and the hand behind it has no way back past it.
        let enough = |k: usize| {
            k + 1 == along.len()
                || least.is_some_and(|l| (values[k] - from).abs() >= (l - from).abs())
        };
        let mut cuts: Vec<usize> = (0..along.len())
            .rev()
            .step_by(LET_GO_EVERY)
            .take_while(|&k| enough(k))
            .collect();
        if along.is_empty() {
            cuts.push(usize::MAX);
        }
        for k in cuts {
            let (last, value) = match along.get(k) {
                Some(q) => (q.as_slice(), values[k]),
                None => (there.last(), from),
            };
            let part = part_at(value);
            match let_go(rig, &root, last, &still, &part, &with_part(value)) {
                Ok(back) => {
                    let along = along[..along.len().min(k.saturating_add(1))].to_vec();
                    // The fingers close round the handle (its pieces as the hand takes it).
                    let on_handle = held_pieces(view, &part_links, grip);
                    let grip_m = finger_gap(&on_handle.pieces, rig.max_opening);
                    chosen = Some((there, along, back, value, grip_m));
                    break;
                }
                Err(why) => why_not.push(format!("letting go at {value:.2}: {why}")),
            }
        }
        if chosen.is_some() {
            break;
        }
    }
    let Some((there, along, back, reached, grip_m)) = chosen else {
        return Err(ActionError::ArmCannot {
            what: format!("work {name}"),
            attempts: why_not,
        });
    };
    let kind = match handle.kind {
        HandleKind::Bar => "bar",
        HandleKind::Knob => "knob",
    };
    Ok(PartWork {
        motion: Change::ArmMotion {
            what: format!("{kind} handle of {name}"),
            reach: there.configurations,
            retreat: back.configurations,
            part: Some(PartFollow {
                link: name.clone(),
                values: values[..along.len()].to_vec(),
                along,
            }),
            grip_m,
        },
        reached,
    })
}

/// The hand's letting go of a handle with the arm at `last`: straight back off it, else
/// straight towards the base, else straight up, by each of [`LET_GO_M`] in turn, then back to
/// the stowed arm. On the straight stretch the arm keeps clear of the scene `still` and, but
/// for the hand that held it, of the `part`; from its end the plan keeps clear of everything
/// (`transit`).
fn let_go(
    rig: &ArmRig,
    root: &Affine3A,
    last: &[f32],
    still: &Obstacles,
    part: &Obstacles,
    transit: &Obstacles,
) -> Result<ArmPath, LetGoError> {
    let tool = rig.arm.tool_pose(root, last);
    let back = -tool.transform_vector3(Vec3::Z).normalize();
    let to_base = Vec3::from(root.translation - tool.translation)
        .with_z(0.0)
        .normalize_or_zero();
    let hand = rig.arm.hand_links();
    let not_hand: Vec<usize> = (0..rig.arm.links.len())
        .filter(|l| !hand.contains(l))
        .collect();
    // The hand may stay against the part it let go of, but not go into it: a finger no
    // deeper than it may press on what it grasps, the palm not at all (straight up, the finger
    // under a drawer's bar handle went 67 mm into it in rapier).
    let held_part = part.clone().grasped();
    let free_line = |q: &[f32]| {
        let poses = rig.arm.link_poses(root, q, 1.0);
        rig.arm.within_limits(q)
            && rig
                .collider
                .touching(&poses, still, STRETCH_MARGIN_M)
                .is_none()
            && rig
                .collider
                .touching_obstacles(&poses, part, STRETCH_MARGIN_M, &hand)
                .is_none()
            && rig
                .collider
                .touching_obstacles(&poses, &held_part, 0.0, &not_hand)
                .is_none()
    };
    let mut why = Vec::new();
    for distance in LET_GO_M {
        for (words, away) in [
            ("back", back),
            ("towards the base", to_base),
            ("up", Vec3::Z),
        ] {
            match retreat_along(
                rig,
                root,
                last,
                away * distance,
                &free_line,
                transit,
                &Held::default(),
            ) {
                Ok(path) => return Ok(path),
                Err(e) => why.push((format!("{words} {:.0} cm", 100.0 * distance), e)),
            }
        }
    }
    Err(LetGoError(why))
}

/// Every way the hand tried to let go of a handle (a direction and a distance, in words), and
/// why each failed.
#[derive(Debug, thiserror::Error)]
#[error("{}", .0.iter().map(|(way, e)| format!("{way}: {e}")).collect::<Vec<_>>().join("; "))]
struct LetGoError(Vec<(String, ReachError)>);

/// The handle on a closed part's front (its `mesh` in the world, the front facing `outward`):
/// of those the perception finds, a door's farthest from its hinge (`axis`: a point and a
/// direction), a drawer's nearest the middle of its front.
fn part_handle(
    mesh: &TriMesh,
    outward: Vec3,
    kind: JointKind,
    axis: (Vec3, Vec3),
) -> Option<Handle> {
    // The canonical frame of a model: the front facing -y, the bottom centre at the origin.
    let right = Vec3::Z.cross(outward);
    let rotation = Mat3::from_cols(right, -outward, Vec3::Z).transpose();
    let turned = mesh.transformed(&Affine3A::from_mat3(rotation));
    let (lo, hi) = turned.bounds()?;
    let bottom = Vec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z);
    let canonical_from_world = Affine3A::from_translation(-bottom) * Affine3A::from_mat3(rotation);
    let world_from_canonical = canonical_from_world.inverse();
    let handles = model_handles(&mesh.transformed(&canonical_from_world), hi - lo);
    let middle = world_from_canonical.transform_point3(Vec3::new(0.0, 0.0, 0.5 * (hi.z - lo.z)));
    let from_hinge = |c: Vec3| (c - axis.0).reject_from(axis.1).length();
    handles
        .into_iter()
        .map(|h| crate::perception::fronts::placed_handle(&world_from_canonical, &h))
        .max_by(|a, b| {
            let score = |h: &Handle| match kind {
                JointKind::Revolute => from_hinge(h.center),
                _ => -h.center.distance(middle),
            };
            score(a).total_cmp(&score(b))
        })
}

/// The tool's pose taking `handle` on a front facing `outward`: coming straight in (the tool's
/// +z into the front), the fingers closing across a bar (along the front, square to it) or
/// across a knob horizontally, between the fingertips a little in from its outer face.
fn handle_grasp(handle: &Handle, outward: Vec3) -> Affine3A {
    let z = -outward;
    let across = match handle.kind {
        HandleKind::Bar => z.cross(handle.axis).try_normalize(),
        HandleKind::Knob => None,
    };
    let y = across.unwrap_or_else(|| Vec3::Z.cross(z).normalize());
    let x = y.cross(z);
    let center = handle.center - outward * (0.5 * handle.depth).min(HANDLE_GRIP_M);
    Affine3A::from_mat3_translation(Mat3::from_cols(x, y, z), center)
}

/// Distances (metres) from the middle of the handle's path at which the base may stand, and
/// the directions tried around it.
const STAND_DISTANCES_M: [f32; 4] = [0.3, 0.45, 0.6, 0.75];
const STAND_DIRECTIONS: usize = 16;
/// The base stands this far (metres) beyond the footprint of what the part sweeps below its
/// top, and the part's surface is sampled this finely.
const SWEEP_CLEARANCE_M: f32 = 0.05;
const SWEEP_SAMPLE_M: f32 = 0.05;
/// The least gap (metres) between a part where the arm leaves it and the arm stowed over the
/// base: the planner's margin on the way.
const STOWED_CLEARANCE_M: f32 = crate::arm::reach::TRANSIT_MARGIN_M;
/// At most this many places to stand are tried.
const MAX_STANDS: usize = 6;
/// The handle stays within this fraction of the arm's span from its shoulder.
const COMFORTABLE_SPAN: f32 = 0.85;

/// Where the base may stand (x, y) for the arm to move part `joint` of `object` from its value
/// to `to`, best first: around the middle of the handle's path, in front of the object, out
/// of the part's way to `to`, where the arm's shoulder is comfortably within reach of the
/// handle at the start, the middle and the end of the path. Those out of the part's way on to
/// `farthest` (a part opened as far as it goes) come first, so that it can open farther; then
/// those nearest to the handle's whole path.
pub(super) fn places_to_stand(
    view: &SceneView,
    rig: &ArmRig,
    robot: &RobotSpec,
    object: &str,
    joint: usize,
    (to, farthest): (f32, f32),
) -> Result<Vec<glam::Vec2>, ActionError> {
    let (_, [part_from_tool, _]) = part_grip(view, object, joint)?;
    let from = view.tree.links[joint].value;
    let handle_at =
        |v: f32| Vec3::from((world_from_part(view, joint, v) * part_from_tool).translation);
    let path = [handle_at(from), handle_at(0.5 * (from + to)), handle_at(to)];
    let closed = handle_at(closed_value(view.tree, joint));
    let own = view
        .node_link(object)
        .ok_or_else(|| ActionError::NotInScene(object.to_string()))?;
    let outward = view.poses[own]
        .transform_vector3(Vec3::NEG_Y)
        .truncate()
        .normalize_or_zero();
    // The shoulder (the chain's second joint past the lift, if any) over the base, how far a
    // lift takes it up or down, and how far the tool gets from it.
    let lift = rig.arm.lift();
    let first = lift.map_or(0, |i| i + 1);
    let shoulder_link = rig.arm.chain.get(first + 1).copied().unwrap_or(0);
    let stowed = rig.stowed_link_poses();
    let shoulder = Vec3::from(stowed[shoulder_link].translation);
    let (down, up) = lift.map_or((0.0, 0.0), |i| rig.arm.limits()[i]);
    let (low, high) = path.iter().fold((f32::MAX, f32::MIN), |(lo, hi), h| {
        (lo.min(h.z), hi.max(h.z))
    });
    let rise = (0.5 * (low + high) - shoulder.z).clamp(down, up);
    let span = arm_span(rig, shoulder_link);
    let middle = path[1].truncate();
    // The part misses the base's column all the way, and where the arm leaves it, the arm
    // folded over the base: a microwave's door on a counter swings above the column, and
    // stopped part of the way closed it stood a centimetre from the stowed fingers.
    let (top, out) = rig.stowed_envelope();
    let column = |end: f32| swept_footprint(view, joint, end, robot.height);
    let points = part_points(view, joint);
    let over_column = |end: f32| part_footprint(view, joint, &points, &[end], top);
    let (swept, swept_on) = (column(to), column(farthest));
    let (left, left_on) = (over_column(to), over_column(farthest));
    let clear_of = |(swept, left): (&[glam::Vec2], &[glam::Vec2]), p: glam::Vec2| {
        swept
            .iter()
            .all(|s| s.distance(p) > robot.radius + SWEEP_CLEARANCE_M)
            && left
                .iter()
                .all(|s| s.distance(p) > out + STOWED_CLEARANCE_M)
    };
    let mut places: Vec<((bool, bool, f32), glam::Vec2)> = STAND_DISTANCES_M
        .iter()
        .flat_map(|&d| {
            (0..STAND_DIRECTIONS).map(move |k| {
                let angle = std::f32::consts::TAU * k as f32 / STAND_DIRECTIONS as f32;
                middle + glam::Vec2::from_angle(angle) * d
            })
        })
        .filter(|p| (*p - closed.truncate()).dot(outward) >= robot.radius + 0.1)
        .filter(|p| clear_of((&swept, &left), *p))
        .filter_map(|p| {
            let reach_from = |over: Vec3| path.iter().map(|h| h.distance(over)).fold(0.0, f32::max);
            let (stowed, lifted) = (
                reach_from(shoulder + p.extend(0.0)),
                reach_from(shoulder + p.extend(rise)),
            );
            let comfortable = COMFORTABLE_SPAN * span;
            // Where the arm works at its stowed height first, as without a lift.
            (lifted <= comfortable).then_some((
                (
                    stowed > comfortable,
                    !clear_of((&swept_on, &left_on), p),
                    stowed,
                ),
                p,
            ))
        })
        .collect();
    places.sort_by(|a, b| {
        let ((a_lifts, a_swept, a_reach), (b_lifts, b_swept, b_reach)) = (a.0, b.0);
        (a_lifts, a_swept)
            .cmp(&(b_lifts, b_swept))
            .then(a_reach.total_cmp(&b_reach))
    });
    Ok(places
        .into_iter()
        .take(MAX_STANDS)
        .map(|(_, p)| p)
        .collect())
}

/// How far the tool gets from the origin of the arm's link `shoulder`, over random
/// configurations (seeded).
fn arm_span(rig: &ArmRig, shoulder: usize) -> f32 {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
    // The lift held (it moves the shoulder and the tool alike).
    let limits = rig.arm.limits_between(&rig.stow, &rig.stow);
    (0..200)
        .map(|_| {
            let q = crate::arm::random_configuration(&limits, &mut rng);
            let poses = rig.arm.link_poses(&Affine3A::IDENTITY, &q, 0.0);
            Vec3::from(poses[rig.arm.tool].translation - poses[shoulder].translation).length()
        })
        .fold(0.0, f32::max)
}

/// `pose` without its scale: a model's frame may be scaled to the object's size, and a part
/// turning in it carries the tool's frame through that scale.
fn rigid(pose: &Affine3A) -> Affine3A {
    let z = Vec3::from(pose.matrix3.z_axis).normalize();
    let y = Vec3::from(pose.matrix3.y_axis).reject_from(z).normalize();
    Affine3A::from_mat3_translation(Mat3::from_cols(y.cross(z), y, z), pose.translation.into())
}

/// The points (x, y) of part `joint`'s surface below `height` as it moves from its value to
/// `to`, every [`SWEEP_SAMPLE_M`] along its path.
fn swept_footprint(view: &SceneView, joint: usize, to: f32, height: f32) -> Vec<glam::Vec2> {
    let link = &view.tree.links[joint];
    let from = link.value;
    let points = part_points(view, joint);
    let reach = points.iter().map(|p| p.length()).fold(0.1, f32::max);
    let step = match link.joint.kind {
        JointKind::Revolute => SWEEP_SAMPLE_M / reach,
        _ => SWEEP_SAMPLE_M,
    };
    let steps = ((to - from).abs() / step).ceil() as usize;
    let values: Vec<f32> = (0..=steps)
        .map(|k| from + (to - from) * k as f32 / steps.max(1) as f32)
        .collect();
    part_footprint(view, joint, &points, &values, height)
}

/// The points (x, y) below `height` of part `joint`'s surface `points` (in its frame, as
/// [`part_points`] gives them) with its joint at each of `values`.
fn part_footprint(
    view: &SceneView,
    joint: usize,
    points: &[Vec3],
    values: &[f32],
    height: f32,
) -> Vec<glam::Vec2> {
    values
        .iter()
        .flat_map(|&v| {
            let at = world_from_part(view, joint, v);
            points
                .iter()
                .map(move |p| at.transform_point3(*p))
                .filter(|p| p.z < height)
                .map(|p| p.truncate())
        })
        .collect()
}

/// Points every [`SWEEP_SAMPLE_M`] on the surface of part `joint` and what it carries, in the
/// part's frame.
fn part_points(view: &SceneView, joint: usize) -> Vec<Vec3> {
    let now_from_world = view.poses[joint].inverse();
    let mut surface = TriMesh::default();
    for &l in &subtree(view, joint) {
        surface.append(&view.world_mesh(l).transformed(&now_from_world));
    }
    surface_points(&surface, SWEEP_SAMPLE_M).points
}
