//! Moving objects with the mouse: a left drag from a movable object (a cup, a chair, a box) to a
//! surface puts it there. It keeps its turn and is let go just above the point under the
//! pointer; rapier lets it fall and settle, everything else held still, so it lands flat on the
//! surface, or tips off an edge it was dropped over. It then hangs from the link it rests on: the
//! support edge of the contact graph and the kinematic tree change (a cup dragged from the table
//! to the counter is the counter's child). A drop that would sink it into something is refused
//! and changes nothing; otherwise the rest test runs on the new scene, and the panel (and the
//! physics layer) say whether it stands.

use bevy::prelude::*;
use glam::Affine3A;

use crate::components::{OrientedBox, SceneEntity};
use crate::kinematics::ray_pick::{pick_link, pick_link_where};
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::Change;
use crate::sim::scene_view::SceneView;
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::physics_validation::settle_object;
use crate::systems::simulation::apply_change;
use crate::viewer::interaction::{PendingClicks, ViewerStatus, ray_through, scene_changed};
use crate::viewer::link_meshes::HIDDEN_CLASSES;
use crate::viewer::motion::finish_motion;

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

/// Moves the object under the pixel `from` onto the surface under the pixel `to`; returns what
/// happened, in words.
pub fn drop_object(world: &mut World, from: Vec2, to: Vec2) -> Vec<String> {
    let (Some(grab), Some(put)) = (ray_through(world, from), ray_through(world, to)) else {
        return vec!["no camera to drag through".into()];
    };
    finish_motion(world);
    let tree = match read_kinematic_tree(world) {
        Ok(tree) => tree,
        Err(why) => return vec![why],
    };
    let view = SceneView::new(&tree);
    let Some((hit, _)) = pick_link(&tree, grab.origin, *grab.direction, &HIDDEN_CLASSES) else {
        return vec!["nothing there to drag".into()];
    };
    let object = tree.links[hit].node.clone().unwrap_or_default();
    if !view.is_movable(&object) {
        return vec![format!(
            "{object} stays where it is (its class is not movable)"
        )];
    }
    let Some(link) = view.node_link(&object) else {
        return vec![format!("{object} has no link to move")];
    };
    // The surface under the pointer, seen through the object itself and what it carries.
    let Some((target, distance)) = pick_link_where(&tree, put.origin, *put.direction, |i| {
        !view.descends_from(i, link)
            && !HIDDEN_CLASSES.contains(&tree.links[i].class.as_deref().unwrap_or(""))
    }) else {
        return vec![format!("nothing under the pointer to put {object} on")];
    };
    let Some((lo, hi)) = view.local_bounds(link) else {
        return vec![format!("{object} has no mesh")];
    };
    let point = put.origin + *put.direction * distance;
    let bottom = view.poses[link].transform_point3(((lo + hi) / 2.0).with_z(lo.z));
    let shift = point - bottom;
    let moved = Affine3A::from_translation(shift) * view.poses[link];
    let sunk = view.overlap_at(link, moved, &[]);
    if sunk > DROP_TOLERANCE_M {
        return vec![format!(
            "refused: {object} would sit {:.1} cm inside what is there",
            100.0 * sunk
        )];
    }
    let was = view.support_of(&object).unwrap_or("nothing").to_string();
    let let_go = Affine3A::from_translation(Vec3::Z * DROP_HEIGHT_M) * moved;
    let settled = settle_object(&posed(&tree, link, let_go), link, SETTLE_SECONDS).unwrap_or(moved);
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
    let corners = (0..8).map(|i| {
        let pick = |bit: usize, a: f32, b: f32| if i & bit == 0 { a } else { b };
        world_from_link.transform_point3(Vec3::new(
            pick(1, lo.x, hi.x),
            pick(2, lo.y, hi.y),
            pick(4, lo.z, hi.z),
        ))
    });
    let (min, max) = corners.fold((Vec3::MAX, Vec3::MIN), |(a, b), c| (a.min(c), b.max(c)));
    let centre = ((min + max) / 2.0).with_z(min.z + 0.02);
    pick_link_where(tree, centre, Vec3::NEG_Z, |i| {
        !view.descends_from(i, link)
            && !HIDDEN_CLASSES.contains(&tree.links[i].class.as_deref().unwrap_or(""))
    })
    .map(|(hit, _)| hit)
}

pub struct DragDropPlugin;

impl Plugin for DragDropPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, work_drags);
    }
}
