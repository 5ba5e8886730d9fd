//! Moving objects with the mouse: a left drag from a movable object (a cup, a chair, a box) to a
//! surface puts it there. It keeps its turn and is let go just above the point under the
//! pointer; rapier lets it fall and settle, everything else held still, so it lands flat on the
//! surface, or tips off an edge it was dropped over, and the viewer plays that fall back. It
//! then hangs from the link it rests on: the
//! support edge of the contact graph and the kinematic tree change (a cup dragged from the table
//! to the counter is the counter's child). While the button is held, a box shows where the object
//! would land (red where it would be refused). A drop that would sink it into something is refused
//! and changes nothing; otherwise the rest test runs on the new scene, and the panel (and the
//! physics layer) say whether it stands.

use bevy::prelude::*;
use glam::Affine3A;

use crate::components::{OrientedBox, SceneEntity};
use crate::geometry::mesh::box_corners;
use crate::kinematics::ray_pick::{pick_link, pick_link_where};
use crate::kinematics::rest_test::REST_STEP_S;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::Change;
use crate::sim::scene_view::SceneView;
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::physics_validation::settle_object;
use crate::systems::scene_graph::transform_of;
use crate::systems::simulation::apply_change;
use crate::viewer::interaction::{CLICK_SLOP_PX, PendingClicks, ray_through, scene_changed};
use crate::viewer::link_meshes::HIDDEN_CLASSES;
use crate::viewer::motion::{finish_motion, show_fall};
use crate::viewer::state::{PointerPosition, ViewerStatus};

/// A dropped object may touch what it lands on, not sink into anything deeper than this.
const DROP_TOLERANCE_M: f32 = 0.01;
/// The object is let go this high (metres) above the point under the pointer, so it starts
/// clear of the surface however the surface's facets lie.
const DROP_HEIGHT_M: f32 = 0.005;
/// Simulated seconds for a dropped object to come to rest.
const SETTLE_SECONDS: f32 = 1.5;

fn work_drags(world: &mut World) {
    let drags = std::mem::take(&mut world.resource_mut::<PendingClicks>().drags);
    for (from, to) in drags {
        let lines = drop_object(world, from, to);
        world.resource_mut::<ViewerStatus>().0 = lines;
    }
}

/// Where a drag from one pixel to another would put an object.
struct DropPlan {
    object: String,
    /// The object's own link.
    link: usize,
    /// The link under the pointer.
    target: usize,
    /// The link's world pose put down on the point under the pointer, keeping its turn.
    moved: Affine3A,
    /// How deep it would sit there inside what is around it, metres.
    sunk: f32,
}

impl DropPlan {
    fn refused(&self) -> Option<String> {
        (self.sunk > DROP_TOLERANCE_M).then(|| {
            format!(
                "refused: {} would sit {:.1} cm inside what is there",
                self.object,
                100.0 * self.sunk
            )
        })
    }
}

/// Why a drag has nothing to drop, or nowhere to drop it.
#[derive(Debug, thiserror::Error)]
enum NoDrop {
    #[error("nothing there to drag")]
    NothingThere,
    #[error("{0} stays where it is (its class is not movable)")]
    NotMovable(String),
    #[error("{0} has no link to move")]
    NoLink(String),
    #[error("nothing under the pointer to put {0} on")]
    NothingUnder(String),
    #[error("{0} has no mesh")]
    NoMesh(String),
}

/// The drop of the object hit by the ray `grab` onto the surface hit by the ray `put`, or why
/// there is none.
fn plan_drop(
    tree: &KinematicTree,
    view: &SceneView,
    grab: Ray3d,
    put: Ray3d,
) -> Result<DropPlan, NoDrop> {
    let Some((hit, _)) = pick_link(tree, grab.origin, *grab.direction, &HIDDEN_CLASSES) else {
        return Err(NoDrop::NothingThere);
    };
    let object = tree.links[hit].node.clone().unwrap_or_default();
    if !view.is_movable(&object) {
        return Err(NoDrop::NotMovable(object));
    }
    let Some(link) = view.node_link(&object) else {
        return Err(NoDrop::NoLink(object));
    };
    // The surface under the pointer, seen through the object itself and what it carries.
    let Some((target, distance)) = pick_link_where(tree, put.origin, *put.direction, |i| {
        !view.descends_from(i, link)
            && !HIDDEN_CLASSES.contains(&tree.links[i].class.as_deref().unwrap_or(""))
    }) else {
        return Err(NoDrop::NothingUnder(object));
    };
    let Some((lo, hi)) = view.local_bounds(link) else {
        return Err(NoDrop::NoMesh(object));
    };
    let point = put.origin + *put.direction * distance;
    let bottom = view.poses[link].transform_point3(((lo + hi) / 2.0).with_z(lo.z));
    let moved = Affine3A::from_translation(point - bottom) * view.poses[link];
    let sunk = view.overlap_at(link, moved, &[]);
    Ok(DropPlan {
        object,
        link,
        target,
        moved,
        sunk,
    })
}

/// Moves the object under the pixel `from` onto the surface under the pixel `to`, and shows it
/// falling the last bit and settling there; returns what happened, in words.
pub fn drop_object(world: &mut World, from: Vec2, to: Vec2) -> Vec<String> {
    let (Some(grab), Some(put)) = (ray_through(world, from), ray_through(world, to)) else {
        return vec!["no camera to drag through".into()];
    };
    finish_motion(world);
    let tree = match read_kinematic_tree(world) {
        Ok(tree) => tree,
        Err(why) => return vec![why.to_string()],
    };
    let view = SceneView::new(&tree);
    let plan = match plan_drop(&tree, &view, grab, put) {
        Ok(plan) => plan,
        Err(why) => return vec![why.to_string()],
    };
    if let Some(why) = plan.refused() {
        return vec![why];
    }
    let DropPlan {
        object,
        link,
        target,
        moved,
        ..
    } = plan;
    let was = view.support_of(&object).unwrap_or("nothing").to_string();
    let let_go = Affine3A::from_translation(Vec3::Z * DROP_HEIGHT_M) * moved;
    let fall = settle_object(&posed(&tree, link, let_go), link, SETTLE_SECONDS)
        .unwrap_or_else(|| vec![moved]);
    let settled = fall.last().copied().unwrap_or(moved);
    // It may have slid or tipped off what it was dropped on: it hangs from what it rests on.
    let support = support_under(&tree, &view, link, settled).unwrap_or(target);
    let change = Change::Attach {
        link: tree.links[link].name.clone(),
        from: tree.links[link]
            .parent
            .map_or(String::new(), |p| tree.links[p].name.clone()),
        to: tree.links[support].name.clone(),
        parent_from_link: view.poses[support].inverse() * settled,
    };
    apply_change(world, &change);
    show_fall(world, &tree.links[link].name, &fall, REST_STEP_S);
    // The node's box goes with it (the boxes and graph layers draw it).
    let motion = settled * view.poses[link].inverse();
    let turn = crate::sim::scene_view::yaw_of(&motion);
    let boxes = world
        .query::<(&SceneEntity, &mut OrientedBox)>()
        .iter_mut(world)
        .filter(|(id, _)| id.0 == object)
        .map(|(_, b)| b)
        .collect::<Vec<_>>();
    for mut b in boxes {
        b.0.center = motion.transform_point3(b.0.center);
        b.0.yaw += turn;
    }
    scene_changed(world);
    // The transforms are the tree's until the fall's first frame is drawn.
    let now = read_kinematic_tree(world)
        .ok()
        .and_then(|t| SceneView::new(&t).support_of(&object).map(str::to_string))
        .unwrap_or_else(|| "nothing".into());
    let mut lines = vec![format!("moved {object} onto {now} (it was on {was})")];
    let tilt = settled
        .matrix3
        .z_axis
        .angle_between(moved.matrix3.z_axis)
        .to_degrees();
    if tilt > 5.0 {
        lines.push(format!("it tipped {tilt:.0} degrees as it settled"));
    }
    lines
}

/// `tree` with the link `link` at the world pose `world_from_link`.
fn posed(tree: &KinematicTree, link: usize, world_from_link: Affine3A) -> KinematicTree {
    let mut posed = tree.clone();
    let parent = tree.links[link]
        .parent
        .map_or(Affine3A::IDENTITY, |p| tree.world_from_links()[p]);
    let joint = tree.links[link].joint.motion(tree.links[link].value);
    posed.links[link].parent_from_link = parent.inverse() * world_from_link * joint.inverse();
    posed
}

/// The link right under the lowest point of `link` at the pose `world_from_link`: a ray down
/// from just above it, through the object itself and what it carries.
fn support_under(
    tree: &KinematicTree,
    view: &SceneView,
    link: usize,
    world_from_link: Affine3A,
) -> Option<usize> {
    let (lo, hi) = view.local_bounds(link)?;
    let corners = box_corners(lo, hi).map(|c| world_from_link.transform_point3(c));
    let (min, max) = corners
        .into_iter()
        .fold((Vec3::MAX, Vec3::MIN), |(a, b), c| (a.min(c), b.max(c)));
    let centre = ((min + max) / 2.0).with_z(min.z + 0.02);
    pick_link_where(tree, centre, Vec3::NEG_Z, |i| {
        !view.descends_from(i, link)
            && !HIDDEN_CLASSES.contains(&tree.links[i].class.as_deref().unwrap_or(""))
    })
    .map(|(hit, _)| hit)
}

/// A drag under way: where it began, the scene as it stood then (it does not change while the
/// button is held), and the box where the object would land if let go now.
#[derive(Resource, Default)]
pub struct DragPreview {
    from: Option<Vec2>,
    at: Option<Vec2>,
    tree: Option<KinematicTree>,
    /// The object and its box at the drop pose (a unit cube's transform), `refused` when the
    /// drop would sink it into something.
    pub ghost: Option<DropGhost>,
}

#[derive(Clone, Debug)]
pub struct DropGhost {
    pub object: String,
    pub world_from_cube: Transform,
    pub refused: bool,
}

const GHOST_COLOUR: Color = Color::srgb(0.1, 0.75, 0.3);
const REFUSED_GHOST_COLOUR: Color = Color::srgb(0.9, 0.1, 0.1);

/// While a left drag is held, works out where the object under its start would land under the
/// pointer, and says so in the panel.
fn preview_drag(world: &mut World) {
    let from = world.resource::<PendingClicks>().pressed_at;
    let held = world
        .resource::<ButtonInput<MouseButton>>()
        .pressed(MouseButton::Left);
    let pointer = world.resource::<PointerPosition>().0;
    let (Some(from), Some(at), true) = (from, pointer, held) else {
        if world.resource::<DragPreview>().from.is_some() {
            *world.resource_mut::<DragPreview>() = DragPreview::default();
        }
        return;
    };
    if from.distance(at) <= CLICK_SLOP_PX || world.resource::<DragPreview>().at == Some(at) {
        return;
    }
    if world.resource::<DragPreview>().from != Some(from) {
        finish_motion(world);
        let tree = read_kinematic_tree(world).ok();
        *world.resource_mut::<DragPreview>() = DragPreview {
            from: Some(from),
            tree,
            ..default()
        };
    }
    let (Some(grab), Some(put)) = (ray_through(world, from), ray_through(world, at)) else {
        return;
    };
    let mut preview = world.resource_mut::<DragPreview>();
    preview.at = Some(at);
    let Some(tree) = &preview.tree else {
        return;
    };
    let view = SceneView::new(tree);
    let (ghost, line) = match plan_drop(tree, &view, grab, put) {
        Ok(plan) => {
            let onto = tree.links[plan.target]
                .node
                .clone()
                .unwrap_or_else(|| tree.links[plan.target].name.clone());
            let line = plan
                .refused()
                .unwrap_or_else(|| format!("drop {} onto {onto}", plan.object));
            let ghost = view.local_bounds(plan.link).map(|(lo, hi)| DropGhost {
                object: plan.object.clone(),
                world_from_cube: transform_of(
                    plan.moved
                        * Affine3A::from_scale_rotation_translation(
                            hi - lo,
                            Quat::IDENTITY,
                            (lo + hi) / 2.0,
                        ),
                ),
                refused: plan.refused().is_some(),
            });
            (ghost, line)
        }
        Err(why) => (None, why.to_string()),
    };
    preview.ghost = ghost;
    let mut status = world.resource_mut::<ViewerStatus>();
    if status.0 != [line.clone()] {
        status.0 = vec![line];
    }
}

/// The landing box of the drag under way: green, or red where it would be refused.
fn draw_ghost(preview: Res<DragPreview>, mut gizmos: Gizmos) {
    if let Some(ghost) = &preview.ghost {
        let colour = if ghost.refused {
            REFUSED_GHOST_COLOUR
        } else {
            GHOST_COLOUR
        };
        gizmos.cube(ghost.world_from_cube, colour);
    }
}

pub struct DragDropPlugin;

impl Plugin for DragDropPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<DragPreview>()
            .add_systems(Update, (preview_drag, work_drags, draw_ghost).chain());
    }
}
