//! Where the base goes for an action: a drive to a place that meets the action's goal (in
//! front of doors, within reach of an object or a free spot), on the grid of the scene as it
//! stands, and whether the robot reaches what it works on.

use glam::{Vec2, Vec3};

use crate::geometry::GravityBox;
use crate::sim::actions::{ActionError, Change, RobotInTree};
use crate::sim::navigation::{NavGoal, NavGrid};
use crate::sim::robot::{BasePose, ROBOT_LINK, RobotSpec};
use crate::sim::scene_view::SceneView;

/// The longest drive (metres) a pick or place makes on its own to get within reach.
pub(crate) const APPROACH_M: f32 = 4.0;

pub(super) fn navigate(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    to: &str,
) -> Result<Vec<Change>, ActionError> {
    let Some(own) = view.node_link(to) else {
        return Err(ActionError::NotInScene(to.to_string()));
    };
    let goal = nav_goal(view, robot, to, own);
    let (change, _) = drive(view, robot, state, &goal, f32::INFINITY)?
        .ok_or_else(|| ActionError::NoPath(to.to_string()))?;
    Ok(vec![change])
}

/// The base's drive from where it stands to the cheapest place that meets `goal`, if one is
/// no farther than `max_m` along the path: the move and the robot after it.
pub(crate) fn drive(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    goal: &NavGoal,
    max_m: f32,
) -> Result<Option<(Change, RobotInTree)>, ActionError> {
    let Some(path) = nav_grid(view)?
        .plan(state.base.position, goal, robot.radius)
        .filter(|p| p.length_m <= max_m)
    else {
        return Ok(None);
    };
    let end = *path.waypoints.last().unwrap_or(&state.base.position);
    let moved = RobotInTree {
        base: BasePose::facing(end, goal.target),
        ..state.clone()
    };
    let change = Change::MoveBase {
        from: state.base,
        to: moved.base,
        path_length_m: path.length_m,
        path: path.waypoints,
    };
    Ok(Some((change, moved)))
}

/// The last stretch before picking or placing: when node `id` is out of reach but a short drive
/// (at most `APPROACH_M`) brings it within reach (into an open fridge, along a table), the
/// base drives there first. Returns that drive (if any) and the robot after it.
pub(super) fn approach(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    id: &str,
) -> Result<(Vec<Change>, RobotInTree), ActionError> {
    let Err(out_of_reach) = within_reach(view, robot, state, id) else {
        return Ok((Vec::new(), state.clone()));
    };
    let (lo, hi) = view
        .node_bounds(id)
        .ok_or_else(|| ActionError::NotInScene(id.to_string()))?;
    let goal = NavGoal {
        target: ((lo + hi) / 2.0).truncate(),
        reach: robot.reach - 0.1,
        facing: None,
        keep_out: Vec::new(),
    };
    let (change, moved) = drive(view, robot, state, &goal, APPROACH_M)?.ok_or(out_of_reach)?;
    within_reach(view, robot, &moved, id)?;
    Ok((vec![change], moved))
}

/// A drive (if needed, at most `APPROACH_M`) to within reach of the point `target` on `what`.
pub(crate) fn approach_point(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    target: Vec2,
    what: &str,
) -> Result<(Vec<Change>, RobotInTree), ActionError> {
    if state.base.position.distance(target) <= robot.reach {
        return Ok((Vec::new(), state.clone()));
    }
    let goal = NavGoal {
        target,
        reach: robot.reach - 0.1,
        facing: None,
        keep_out: Vec::new(),
    };
    let (change, moved) = drive(view, robot, state, &goal, APPROACH_M)?
        .ok_or_else(|| ActionError::NoWayToSpot(what.to_string()))?;
    Ok((vec![change], moved))
}

/// The grid of the scene as it stands, without the robot and what it holds.
pub fn nav_grid(view: &SceneView) -> Result<NavGrid, ActionError> {
    let robot = view.link(ROBOT_LINK);
    let floor = view
        .nodes()
        .into_iter()
        .find(|n| view.class_of(n) == Some("floor"))
        .and_then(|n| view.node_link(n))
        .ok_or(ActionError::NoFloor)?;
    let obstacles: Vec<_> = (1..view.tree.links.len())
        .filter(|&l| {
            l != floor
                && robot.is_none_or(|r| !view.descends_from(l, r))
                && !matches!(view.tree.links[l].class.as_deref(), Some("ceiling"))
        })
        .map(|l| view.world_mesh(l))
        .collect();
    let grid = NavGrid::new(&view.world_mesh(floor), &obstacles).ok_or(ActionError::EmptyFloor)?;
    Ok(grid.with_walls(wall_segments(view)))
}

/// The room's walls as segments on the floor: each wall's least box around its surface, along
/// its longer side through the middle of its thickness (a wall at any angle).
fn wall_segments(view: &SceneView) -> Vec<(Vec2, Vec2)> {
    (0..view.tree.links.len())
        .filter(|&l| view.tree.links[l].class.as_deref() == Some("wall"))
        .filter_map(|l| {
            let wall = GravityBox::minimal(&view.world_mesh(l).positions)?;
            let along = Vec2::from_angle(wall.yaw);
            let half = if wall.size.x >= wall.size.y {
                along * 0.5 * wall.size.x
            } else {
                along.perp() * 0.5 * wall.size.y
            };
            let centre = wall.center.truncate();
            Some((centre - half, centre + half))
        })
        .collect()
}

/// Where the base must go to work on node `id`: in front of its doors, out of their swing,
/// when it has any; anywhere within reach of its centre otherwise.
pub(super) fn nav_goal(view: &SceneView, robot: &RobotSpec, id: &str, own: usize) -> NavGoal {
    let world_from_node = view.poses[own];
    let bounds = view.body_mesh_in_node(id).bounds();
    let Some((lo, hi)) = bounds else {
        return NavGoal {
            target: world_from_node.translation.truncate(),
            reach: robot.reach,
            facing: None,
            keep_out: Vec::new(),
        };
    };
    if !view.is_container(id) {
        // Reach its nearest side: the centre, from up to half its smaller side farther out.
        let centre = world_from_node.transform_point3((lo + hi) / 2.0).truncate();
        let half = ((hi - lo).truncate() / 2.0).min_element();
        return NavGoal {
            target: centre,
            reach: robot.reach + half,
            facing: None,
            keep_out: Vec::new(),
        };
    }
    let front = world_from_node
        .transform_point3(Vec3::new((lo.x + hi.x) / 2.0, lo.y, (lo.z + hi.z) / 2.0))
        .truncate();
    let facing = world_from_node
        .transform_vector3(-Vec3::Y)
        .truncate()
        .normalize_or_zero();
    // Doors on vertical hinges sweep a disc about the hinge as wide as the door.
    let keep_out = view
        .moving_parts(id)
        .into_iter()
        .filter(|&j| {
            let l = &view.tree.links[j];
            l.joint.kind == crate::kinematics::JointKind::Revolute
                && view.poses[j].transform_vector3(l.joint.axis).z.abs() > 0.9
        })
        .filter_map(|j| {
            let (dlo, dhi) = view.local_bounds(j)?;
            let hinge = view.poses[j].translation.truncate();
            let radius = [dlo.x, dhi.x]
                .iter()
                .flat_map(|x| [dlo.y, dhi.y].map(|y| Vec2::new(*x, y).length()))
                .fold(0.0f32, f32::max);
            Some((hinge, radius + robot.radius))
        })
        .collect();
    NavGoal {
        target: front,
        reach: robot.reach,
        facing: Some(facing),
        keep_out,
    }
}

/// Whether the base reaches node `id`: its nearest point within the robot's reach and its
/// lowest point below the highest the gripper reaches.
pub(super) fn within_reach(
    view: &SceneView,
    robot: &RobotSpec,
    state: &RobotInTree,
    id: &str,
) -> Result<(), ActionError> {
    let (lo, hi) = view
        .node_bounds(id)
        .ok_or_else(|| ActionError::NotInScene(id.to_string()))?;
    let p = state.base.position;
    let nearest = p.clamp(lo.truncate(), hi.truncate());
    let d = nearest.distance(p);
    if d > robot.reach {
        return Err(ActionError::BeyondReach {
            object: id.to_string(),
            distance_m: d,
            reach_m: robot.reach,
        });
    }
    if lo.z > robot.max_reach_height {
        return Err(ActionError::AboveReach(id.to_string()));
    }
    Ok(())
}
