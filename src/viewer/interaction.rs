//! Clicking the scene: a left click (press and release without dragging) casts a ray from the
//! camera through the pointer; the door or drawer hit (or the main one of the object hit) opens
//! when closed and closes when open. The joint moves in the transform hierarchy, and the rest
//! test runs on the scene as it now stands; the panel shows what happened. A left drag is left
//! to `drag_drop`.

use bevy::prelude::*;
use bevy::window::CursorMoved;

use crate::kinematics::ray_pick::{joint_of_click, pick_link};
use crate::sim::actions::Change;
use crate::sim::scene_view::{SceneView, closed_value, open_value};
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::simulation::apply_change;
use crate::viewer::link_meshes::HIDDEN_CLASSES;
use crate::viewer::motion::{finish_motion, show_motion};
use crate::viewer::physics_layer::run_rest_test;
use crate::viewer::state::{PointerPosition, SceneRevision, ViewerStatus};

/// Clicks not yet worked, where the pointer was, and left drags (from, to) not yet dropped.
#[derive(Resource, Clone, Debug, Default)]
pub(crate) struct PendingClicks {
    pub(crate) pressed_at: Option<Vec2>,
    clicks: Vec<Vec2>,
    pub(crate) drags: Vec<(Vec2, Vec2)>,
}

/// A press and release farther apart than this (pixels) is a drag, not a click.
pub(crate) const CLICK_SLOP_PX: f32 = 5.0;

fn track_pointer(mut moved: MessageReader<CursorMoved>, mut pointer: ResMut<PointerPosition>) {
    if let Some(last) = moved.read().last() {
        pointer.0 = Some(last.position);
    }
}

fn collect_clicks(
    buttons: Res<ButtonInput<MouseButton>>,
    pointer: Res<PointerPosition>,
    mut pending: ResMut<PendingClicks>,
) {
    let Some(at) = pointer.0 else {
        return;
    };
    if buttons.just_pressed(MouseButton::Left) {
        pending.pressed_at = Some(at);
    }
    if buttons.just_released(MouseButton::Left)
        && let Some(from) = pending.pressed_at.take()
    {
        if from.distance(at) <= CLICK_SLOP_PX {
            pending.clicks.push(at);
        } else {
            pending.drags.push((from, at));
        }
    }
}

/// Works the joint under each pending click.
fn work_clicked_joints(world: &mut World) {
    let clicks = std::mem::take(&mut world.resource_mut::<PendingClicks>().clicks);
    for at in clicks {
        let lines = work_joint_at(world, at);
        world.resource_mut::<ViewerStatus>().0 = lines;
    }
}

/// The ray from the camera through the pixel `at`.
pub(crate) fn ray_through(world: &mut World, at: Vec2) -> Option<Ray3d> {
    world
        .query::<(&Camera, &GlobalTransform)>()
        .iter(world)
        .find_map(|(camera, transform)| camera.viewport_to_world(transform, at).ok())
}

/// The scene changed from the viewer: the layers that follow it rebuild, and the rest test
/// reruns on it (the panel shows its verdicts).
pub(crate) fn scene_changed(world: &mut World) {
    let revision = {
        let mut revision = world.resource_mut::<SceneRevision>();
        revision.0 += 1;
        revision.0
    };
    run_rest_test(world, revision);
}

/// Opens or closes the joint under the pixel `at`; returns what happened, in words.
pub fn work_joint_at(world: &mut World, at: Vec2) -> Vec<String> {
    let Some(ray) = ray_through(world, at) else {
        return vec!["no camera to click through".into()];
    };
    finish_motion(world);
    let tree = match read_kinematic_tree(world) {
        Ok(tree) => tree,
        Err(why) => return vec![why.to_string()],
    };
    let Some((hit, _)) = pick_link(&tree, ray.origin, *ray.direction, &HIDDEN_CLASSES) else {
        return vec!["nothing there".into()];
    };
    let view = SceneView::new(&tree);
    let object = tree.links[hit].node.clone().unwrap_or_default();
    let Some(part) = joint_of_click(&tree, hit).or_else(|| view.main_part(&object)) else {
        return vec![format!("{}: nothing to open", tree.links[hit].name)];
    };
    // Nearer its closed end than its open end: it opens; otherwise it closes.
    let (value, open, closed) = (
        tree.links[part].value,
        open_value(&tree, part),
        closed_value(&tree, part),
    );
    let opening = (value - closed).abs() <= (value - open).abs();
    let to = if opening { open } else { closed };
    let link = tree.links[part].name.clone();
    let change = Change::SetJoint {
        link: link.clone(),
        from: tree.links[part].value,
        to,
    };
    apply_change(world, &change);
    show_motion(world, &[change]);
    scene_changed(world);
    vec![format!(
        "{} {link} ({:.2} -> {to:.2})",
        if opening { "opened" } else { "closed" },
        value
    )]
}

pub struct InteractionPlugin;

impl Plugin for InteractionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<PointerPosition>()
            .init_resource::<ViewerStatus>()
            .init_resource::<SceneRevision>()
            .init_resource::<PendingClicks>()
            .add_systems(
                Update,
                (track_pointer, collect_clicks, work_clicked_joints).chain(),
            );
    }
}
