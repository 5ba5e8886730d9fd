//! The arm's motions for a pick or a place: from its stowed configuration to a tool pose along a
//! straight last stretch, and back, with or without an object in the hand.
//!
//! A reach is the inverse kinematics of the target and of the pose a short way back along the
//! approach, a straight line of tool poses between them (each solved from the one before, so the
//! hand does not flip), and a planned path from the stowed configuration to the line's start.
//! A retreat lifts the hand straight up, then plans back to the stowed configuration. Every
//! configuration on the way is checked against the obstacles with a margin; the last stretch,
//! where the fingers close around the object or set it down, with a smaller one.

use glam::{Affine3A, Vec3};
use parry3d::shape::ConvexPolyhedron;

use crate::arm::collision::{Obstacles, Touching};
use crate::arm::ik::{IkSettings, solve};
use crate::arm::rig::ArmRig;
use crate::arm::rrt::{PlanError, densify, plan, segment_free};

/// Clearance kept from everything on the way, metres.
pub const TRANSIT_MARGIN_M: f32 = 0.02;
/// Clearance kept on the last stretch (a finger beside the object's support), metres.
pub const STRETCH_MARGIN_M: f32 = 0.004;
/// Spacing of the tool poses along a straight stretch, metres.
const STRETCH_STEP_M: f32 = 0.01;
/// The largest joint change between two poses of a straight stretch, radians: more is a flip.
const STRETCH_MAX_JUMP: f32 = 0.25;
/// How strongly a hand following a path keeps its joints towards the middle of their ranges
/// (`IkSettings::centering`).
const FOLLOW_CENTERING: f32 = 0.1;
/// How many other configurations at the target a reach tries when its last stretch fails from
/// the first.
const OTHER_TARGET_CONFIGURATIONS: usize = 4;
/// How high a retreat lifts the hand before it plans back, metres.
pub const LIFT_M: f32 = 0.1;

/// An object in the hand: its convex pieces in the tool's frame, and the obstacles it may touch
/// (by name): those it stood against where the hand took it, while it is lifted off them.
#[derive(Clone, Default)]
pub struct Held {
    pub pieces: Vec<ConvexPolyhedron>,
    pub beside: Vec<String>,
}

impl Held {
    /// The object lifted clear of what it stood against: it may touch nothing.
    pub fn lifted(&self) -> Held {
        Held {
            pieces: self.pieces.clone(),
            beside: Vec::new(),
        }
    }
}

/// A planned motion: the configurations (densified for execution) and the final one.
#[derive(Clone, Debug)]
pub struct ArmPath {
    pub configurations: Vec<Vec<f32>>,
}

impl ArmPath {
    pub fn last(&self) -> &[f32] {
        self.configurations.last().map_or(&[], |q| q)
    }
}

/// Why the arm cannot make a motion; the message is what a task's trace says was tried. A
/// `String` inside says what the arm touches, in words ([`describe`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ReachError {
    #[error("the target is out of the arm's reach")]
    OutOfReach,
    #[error("the arm reaches the target only touching something ({0})")]
    ReachesOnlyTouching(String),
    #[error("the straight approach is blocked or out of reach {before_cm:.0} cm before the target")]
    ApproachBlocked { before_cm: f32 },
    #[error("at the start of the approach {0}")]
    ApproachStartTouches(String),
    #[error("the arm's configuration before the motion is not clear: {0}")]
    StartNotClear(String),
    #[error("no path to the approach: {0}")]
    NoPathToApproach(PlanError),
    #[error("no way back")]
    NoWayBack,
    /// `why`: what blocks it where it stops (": panda_hand hits cup_2"), when known.
    #[error(
        "the hand's first way back is blocked or out of reach after {after_cm:.0} of \
         {of_cm:.0} cm{why}"
    )]
    FirstWayBackBlocked {
        after_cm: f32,
        of_cm: f32,
        why: String,
    },
    #[error(
        "the straight way back (up, or out of a container) is blocked or out of reach \
         after {after_cm:.0} of {of_cm:.0} cm{why}"
    )]
    WayBackBlocked {
        after_cm: f32,
        of_cm: f32,
        why: String,
    },
    #[error("after the lift {0}")]
    AfterLiftTouches(String),
    #[error("the stowed arm would touch something: {0}")]
    StowedTouches(String),
    #[error("no path back to the stowed arm: {0}")]
    NoPathToStow(PlanError),
}

/// Where a configuration touches something, in words.
pub fn describe(rig: &ArmRig, obstacles: &Obstacles, touch: &(usize, Touching)) -> String {
    let link = &rig.arm.links[touch.0].name;
    match &touch.1 {
        Touching::Obstacle(o) => format!("{link} hits {}", obstacles.items[*o].name),
        Touching::Link(l) => format!("{link} hits {}", rig.arm.links[*l].name),
        Touching::Held(o) => format!("the held object hits {}", obstacles.items[*o].name),
    }
}

/// What touches at `q` within `margin`, in words; `None` when free.
pub fn touching(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    obstacles: &Obstacles,
    held: &Held,
    q: &[f32],
    margin: f32,
) -> Option<String> {
    let poses = rig.arm.link_poses(world_from_root, q, 1.0);
    rig.collider
        .touching_holding(
            &poses,
            rig.arm.tool,
            &held.pieces,
            &held.beside,
            obstacles,
            margin,
        )
        .map(|t| describe(rig, obstacles, &t))
}

/// The arm's motion from `from` to the tool at `target`, the last `stretch` metres straight
/// along `approach`: checked against `transit` obstacles on the way and `near` ones (the
/// object being grasped left out) on the last stretch.
#[allow(clippy::too_many_arguments, reason = "one motion's whole problem")]
pub fn reach(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    target: &Affine3A,
    approach: Vec3,
    stretch: f32,
    transit: &Obstacles,
    near: &Obstacles,
    held: &Held,
) -> Result<ArmPath, ReachError> {
    let free_near = clear_of(rig, world_from_root, near, held, STRETCH_MARGIN_M);
    let q_target = solve(&rig.arm, world_from_root, target, from, &rig.ik, &free_near)
        .ok_or_else(|| why_no_ik(rig, world_from_root, target, from, near, held))?;
    let from_target = |q: &[f32]| {
        reach_configuration(
            rig,
            world_from_root,
            from,
            (q, target),
            approach,
            stretch,
            transit,
            near,
            held,
        )
    };
    let first = from_target(&q_target);
    if !matches!(
        first,
        Err(ReachError::ApproachBlocked { .. }
            | ReachError::ApproachStartTouches(_)
            | ReachError::NoPathToApproach(_))
    ) {
        return first;
    }
    // The same tool pose with the elbow or the wrist the other way may leave the last stretch
    // clear (a side grasp of a cup 6 cm over a table had link 6 under the hand), or start it
    // where the planner finds a way (a cup carried down into a cabinet's low board through
    // the narrow gap beside its open door).
    let others = distinct_configurations(
        rig,
        world_from_root,
        target,
        &free_near,
        vec![q_target],
        OTHER_TARGET_CONFIGURATIONS,
    );
    others
        .iter()
        .find_map(|q| from_target(q).ok())
        .map_or(first, Ok)
}

/// Configurations that put the tool at `target` clear of `near` obstacles, from up to `count`
/// seeded inverse kinematics runs, each different from those before.
pub fn configurations_at(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    target: &Affine3A,
    near: &Obstacles,
    count: usize,
) -> Vec<Vec<f32>> {
    let empty = Held::default();
    let free_near = clear_of(rig, world_from_root, near, &empty, STRETCH_MARGIN_M);
    distinct_configurations(rig, world_from_root, target, &free_near, Vec::new(), count)
}

/// Configurations that put the tool at `target` accepted by `free`, from up to `count` seeded
/// inverse kinematics runs from the stowed arm, each different from those before and from
/// `known` (which are not returned).
fn distinct_configurations(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    target: &Affine3A,
    free: &dyn Fn(&[f32]) -> bool,
    known: Vec<Vec<f32>>,
    count: usize,
) -> Vec<Vec<f32>> {
    let skip = known.len();
    let mut found = known;
    for seed in 0..count as u64 {
        let settings = IkSettings { seed, ..rig.ik };
        if let Some(q) = solve(
            &rig.arm,
            world_from_root,
            target,
            &rig.stow,
            &settings,
            &|q| {
                free(q)
                    && found
                        .iter()
                        .all(|f| crate::arm::rrt::distance(f, q) > STRETCH_MAX_JUMP)
            },
        ) {
            found.push(q);
        }
    }
    found.split_off(skip)
}

/// [`reach`] to a configuration already solved: `q_target` puts the tool at `target`.
#[allow(clippy::too_many_arguments, reason = "one motion's whole problem")]
pub fn reach_configuration(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    (q_target, target): (&[f32], &Affine3A),
    approach: Vec3,
    stretch: f32,
    transit: &Obstacles,
    near: &Obstacles,
    held: &Held,
) -> Result<ArmPath, ReachError> {
    let free_near = clear_of(rig, world_from_root, near, held, STRETCH_MARGIN_M);
    // The straight stretch, solved backwards from the target so it ends exactly there.
    let back = -approach * stretch;
    let mut line = straight_line(rig, world_from_root, q_target, target, back, &free_near)
        .map_err(|at| ReachError::ApproachBlocked {
            before_cm: 100.0 * at * stretch,
        })?;
    line.reverse();
    let start = line[0].clone();
    // What the held object stood against it may touch on the straight stretch only.
    let lifted = held.lifted();
    let free_transit = clear_of(rig, world_from_root, transit, &lifted, TRANSIT_MARGIN_M);
    if let Some(why) = touching(
        rig,
        world_from_root,
        transit,
        held,
        &start,
        TRANSIT_MARGIN_M,
    ) {
        return Err(ReachError::ApproachStartTouches(why));
    }
    let path = plan(
        from,
        &start,
        &rig.arm.limits_between(from, &start),
        &free_transit,
        &rig.plan,
    )
    .map_err(|e| match e {
        PlanError::StartInCollision => ReachError::StartNotClear(
            touching(rig, world_from_root, transit, held, from, TRANSIT_MARGIN_M)
                .unwrap_or_default(),
        ),
        other => ReachError::NoPathToApproach(other),
    })?;
    let mut configurations = densify(&path, rig.plan.resolution);
    configurations.extend(line.into_iter().skip(1));
    Ok(ArmPath { configurations })
}

/// Whether a configuration is within the limits and keeps `margin` from the obstacles.
fn clear_of<'a>(
    rig: &'a ArmRig,
    world_from_root: &'a Affine3A,
    obstacles: &'a Obstacles,
    held: &'a Held,
    margin: f32,
) -> impl Fn(&[f32]) -> bool + 'a {
    move |q: &[f32]| {
        rig.arm.within_limits(q)
            && touching(rig, world_from_root, obstacles, held, q, margin).is_none()
    }
}

/// The configurations that move the tool from `start` (at configuration `from`, included
/// first) straight by `offset` (world) in steps of `STRETCH_STEP_M`, each solved from the one
/// before and accepted by `free`; where it fails, the fraction of the way.
fn straight_line(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    start: &Affine3A,
    offset: Vec3,
    free: &dyn Fn(&[f32]) -> bool,
) -> Result<Vec<Vec<f32>>, f32> {
    let steps = (offset.length() / STRETCH_STEP_M).ceil().max(1.0) as usize;
    let poses: Vec<Affine3A> = (1..=steps)
        .map(|k| Affine3A::from_translation(offset * (k as f32 / steps as f32)) * *start)
        .collect();
    let mut line = vec![from.to_vec()];
    let single = IkSettings {
        restarts: 0,
        centering: FOLLOW_CENTERING,
        ..rig.ik
    };
    let along = along_poses(rig, world_from_root, from, &poses, &single, &|_, q| free(q))
        .map_err(|k| (k + 1) as f32 / steps as f32)?;
    line.extend(along);
    Ok(line)
}

/// The configurations that put the tool on `poses` in turn, each solved from the one before
/// (the first from `from`), accepted by `free(k, q)` for pose `k` and no flip away from the one
/// before; where it fails, the index of the pose.
fn along_poses(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    poses: &[Affine3A],
    single: &IkSettings,
    free: &dyn Fn(usize, &[f32]) -> bool,
) -> Result<Vec<Vec<f32>>, usize> {
    let mut along: Vec<Vec<f32>> = Vec::with_capacity(poses.len());
    for (k, pose) in poses.iter().enumerate() {
        let previous = along.last().map_or(from, |q| q.as_slice());
        let q = solve(&rig.arm, world_from_root, pose, previous, single, &|q| {
            free(k, q)
        })
        .filter(|q| crate::arm::rrt::distance(q, previous) <= STRETCH_MAX_JUMP)
        .ok_or(k)?;
        along.push(q);
    }
    Ok(along)
}

/// The arm keeping the tool on `poses` in turn from `from` (the tool at the first pose's
/// predecessor): a hand on a handle that turns or slides with its door or drawer. Each pose is
/// solved from the one before; `touching_at(k, q)` says what the arm touches at pose `k` in
/// configuration `q` (`None` when clear). Returns the configurations of the poses it follows,
/// and, where it stops short of the last, why.
pub fn follow(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    poses: &[Affine3A],
    touching_at: &dyn Fn(usize, &[f32]) -> Option<String>,
) -> (Vec<Vec<f32>>, Option<String>) {
    let free = |k: usize, q: &[f32]| rig.arm.within_limits(q) && touching_at(k, q).is_none();
    let single = IkSettings {
        restarts: 0,
        centering: FOLLOW_CENTERING,
        ..rig.ik
    };
    match along_poses(rig, world_from_root, from, poses, &single, &free) {
        Ok(along) => (along, None),
        Err(k) => {
            let along = along_poses(rig, world_from_root, from, &poses[..k], &single, &free)
                .unwrap_or_default();
            let previous = along.last().map_or(from, |q| q.as_slice());
            let why = match solve(
                &rig.arm,
                world_from_root,
                &poses[k],
                previous,
                &single,
                &|_| true,
            ) {
                None => "the hand's next pose is out of the arm's reach".to_string(),
                Some(q) if crate::arm::rrt::distance(&q, previous) > STRETCH_MAX_JUMP => {
                    "the arm would have to flip to follow".to_string()
                }
                Some(q) => touching_at(k, &q)
                    .unwrap_or_else(|| "no configuration follows the hand".to_string()),
            };
            (along, Some(why))
        }
    }
}

/// Why no collision-free configuration puts the tool at `target`: out of reach, or what the
/// arm touches in a configuration that reaches it.
fn why_no_ik(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    target: &Affine3A,
    from: &[f32],
    near: &Obstacles,
    held: &Held,
) -> ReachError {
    match solve(&rig.arm, world_from_root, target, from, &rig.ik, &|_| true) {
        None => ReachError::OutOfReach,
        Some(q) => ReachError::ReachesOnlyTouching(
            touching(rig, world_from_root, near, held, &q, STRETCH_MARGIN_M).unwrap_or_default(),
        ),
    }
}

/// The arm's motion from `from` (the tool at a grasp or a release) straight along `away`
/// (a vector in the world: up `LIFT_M` off a surface, back out of a container's front), then
/// back to the stowed configuration, against `near` obstacles on the straight stretch and
/// `transit` ones after it.
#[allow(clippy::too_many_arguments, reason = "one motion's whole problem")]
pub fn retreat(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    away: Vec3,
    transit: &Obstacles,
    near: &Obstacles,
    held: &Held,
) -> Result<ArmPath, ReachError> {
    retreat_through(rig, world_from_root, from, &[away], transit, near, held)
}

/// [`retreat`] by the straight stretches `aways` in turn (a hand whose fingers are in a cup
/// rises off it before it backs out of the cabinet).
pub fn retreat_through(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    aways: &[Vec3],
    transit: &Obstacles,
    near: &Obstacles,
    held: &Held,
) -> Result<ArmPath, ReachError> {
    let free_near = clear_of(rig, world_from_root, near, held, STRETCH_MARGIN_M);
    let (last, rest) = aways.split_last().ok_or(ReachError::NoWayBack)?;
    // What blocks the tool `at` a fraction of `away` from configuration `q`, in words.
    let why = |q: &[f32], away: Vec3, at: f32| {
        let tool = rig.arm.tool_pose(world_from_root, q);
        let stopped = Affine3A::from_translation(away * at) * tool;
        format!(
            ": {}",
            why_no_ik(rig, world_from_root, &stopped, q, near, held)
        )
    };
    let mut start = from.to_vec();
    let mut lines = Vec::new();
    for away in rest {
        let tool = rig.arm.tool_pose(world_from_root, &start);
        let line = straight_line(rig, world_from_root, &start, &tool, *away, &free_near).map_err(
            |at| ReachError::FirstWayBackBlocked {
                after_cm: 100.0 * away.length() * at,
                of_cm: 100.0 * away.length(),
                why: why(&start, *away, at),
            },
        )?;
        start = line.last().expect("not empty").clone();
        lines.extend(line.into_iter().skip(usize::from(!lines.is_empty())));
    }
    let mut path = retreat_along(
        rig,
        world_from_root,
        &start,
        *last,
        &free_near,
        transit,
        held,
    )
    .map_err(|e| match e {
        ReachError::WayBackBlocked {
            after_cm, of_cm, ..
        } => ReachError::WayBackBlocked {
            after_cm,
            of_cm,
            why: why(&start, *last, after_cm / of_cm.max(1e-6)),
        },
        other => other,
    })?;
    if !lines.is_empty() {
        lines.extend(path.configurations.into_iter().skip(1));
        path.configurations = lines;
    }
    Ok(path)
}

/// [`retreat`] with the straight stretch accepted by `free_line` instead of a clearance from
/// obstacles: a hand letting go of a handle may stay near it, the rest of the arm may not.
pub fn retreat_along(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    from: &[f32],
    away: Vec3,
    free_line: &dyn Fn(&[f32]) -> bool,
    transit: &Obstacles,
    held: &Held,
) -> Result<ArmPath, ReachError> {
    let tool = rig.arm.tool_pose(world_from_root, from);
    let line = straight_line(rig, world_from_root, from, &tool, away, free_line).map_err(|at| {
        ReachError::WayBackBlocked {
            after_cm: 100.0 * away.length() * at,
            of_cm: 100.0 * away.length(),
            why: String::new(),
        }
    })?;
    let top = line.last().expect("not empty").clone();
    // What the held object stood against it may touch on the straight stretch only.
    let lifted = held.lifted();
    let free_transit = clear_of(rig, world_from_root, transit, &lifted, TRANSIT_MARGIN_M);
    let path = plan(
        &top,
        &rig.stow,
        &rig.arm.limits_between(&top, &rig.stow),
        &free_transit,
        &rig.plan,
    )
    .map_err(|e| match e {
        PlanError::StartInCollision => ReachError::AfterLiftTouches(
            touching(
                rig,
                world_from_root,
                transit,
                &lifted,
                &top,
                TRANSIT_MARGIN_M,
            )
            .unwrap_or_default(),
        ),
        PlanError::GoalInCollision => ReachError::StowedTouches(
            touching(
                rig,
                world_from_root,
                transit,
                held,
                &rig.stow,
                TRANSIT_MARGIN_M,
            )
            .unwrap_or_default(),
        ),
        other => ReachError::NoPathToStow(other),
    })?;
    let mut configurations = line;
    configurations.extend(densify(&path, rig.plan.resolution).into_iter().skip(1));
    Ok(ArmPath { configurations })
}

/// Whether every step of `path` keeps `margin` from the obstacles (what an executed motion is
/// checked against).
pub fn path_clear(
    rig: &ArmRig,
    world_from_root: &Affine3A,
    path: &[Vec<f32>],
    obstacles: &Obstacles,
    held: &Held,
    margin: f32,
) -> bool {
    let clear = clear_of(rig, world_from_root, obstacles, held, margin);
    path.windows(2)
        .all(|w| segment_free(&w[0], &w[1], &clear, rig.plan.resolution / 4.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::ik::{IkSettings, solve};
    use crate::arm::tests::two_link_arm;
    use crate::geometry::TriMesh;

    /// A held cube 1 mm into a neighbour touches it, unless the neighbour is one it stood
    /// against (`Held::beside`); another obstacle it touches still counts.
    #[test]
    fn the_held_object_may_touch_what_it_stood_against() {
        let rig = ArmRig::new(two_link_arm(), 0.5);
        let root = rig.base_from_root;
        let q = vec![0.0, 0.0];
        let tool = rig.arm.tool_pose(&root, &q);
        let cube = |half: f32| TriMesh::cuboid(Vec3::splat(-half), Vec3::splat(half));
        let hull =
            |mesh: &TriMesh| ConvexPolyhedron::from_convex_hull(&mesh.positions).expect("a hull");
        let mut held = Held {
            pieces: vec![hull(&cube(0.03))],
            beside: Vec::new(),
        };
        let mut scene = Obstacles::default();
        // 1 mm into the held cube along the tool's y, in the world.
        let beside = tool * Affine3A::from_translation(Vec3::new(0.0, 0.059, 0.0));
        scene.add("cup_6", &cube(0.03), &beside);
        let touch = |held: &Held, scene: &Obstacles| touching(&rig, &root, scene, held, &q, 0.004);
        assert_eq!(
            touch(&held, &scene).as_deref(),
            Some("the held object hits cup_6")
        );
        held.beside = vec!["cup_6".into()];
        assert_eq!(touch(&held, &scene), None);
        let other = tool * Affine3A::from_translation(Vec3::new(0.0, -0.059, 0.0));
        scene.add("bowl_1", &cube(0.03), &other);
        assert!(touch(&held, &scene).is_some_and(|t| t.contains("bowl_1")));
    }

    #[test]
    fn an_arm_on_a_lift_reaches_above_its_plane_and_travels_as_before() {
        let fixed = ArmRig::new(two_link_arm(), 0.5);
        let lifted = ArmRig::new(two_link_arm(), 0.5).on_lift((-0.3, 0.4));
        assert_eq!(lifted.arm.dof(), 3);
        assert_eq!(lifted.arm.lift(), Some(0));
        assert_eq!(fixed.arm.lift(), None);
        // Stowed, every link is where it was; the lift link stands at the old root.
        let (before, after) = (fixed.stowed_link_poses(), lifted.stowed_link_poses());
        assert_eq!(after.len(), before.len() + 1);
        for (a, b) in before.iter().zip(&after[1..]) {
            assert!(a.abs_diff_eq(*b, 1e-6), "{a:?} {b:?}");
        }
        let (mast_link, mast_length) = lifted.mast().expect("a mast");
        assert!(mast_link == 0 && (mast_length - 0.7).abs() < 1e-5);
        // The planar arm reaches a point 0.25 m above its plane only on the lift.
        let settings = IkSettings {
            orientation: false,
            ..IkSettings::default()
        };
        let target = Affine3A::from_translation(Vec3::new(1.2, 0.7, 0.75));
        let reach = |rig: &ArmRig| {
            solve(
                &rig.arm,
                &rig.base_from_root,
                &target,
                &rig.stow,
                &settings,
                &|_| true,
            )
        };
        assert!(reach(&fixed).is_none());
        let q = reach(&lifted).expect("reached on the lift");
        assert!((q[0] - 0.25).abs() < 1e-3, "{q:?}");
        let tool = lifted.arm.tool_pose(&lifted.base_from_root, &q).translation;
        assert!((Vec3::from(tool) - Vec3::new(1.2, 0.7, 0.75)).length() < 1e-3);
    }
}
