//! What the contact graph knows, drawn over the scene: each node's gravity-aligned box, its
//! surface planes cut to the box, support edges from parent to child, and proximal pairs.

use bevy::prelude::*;

use crate::components::{OrientedBox, Panoptic, ProximalPairQuery, SceneEntity, SurfacePlanes};
use crate::geometry::{GravityBox, Plane};
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::HIDDEN_CLASSES;

const SUPPORT_COLOUR: Color = Color::srgb(1.0, 0.45, 0.0);
const PROXIMAL_COLOUR: Color = Color::srgb(0.1, 0.35, 1.0);
const BOX_COLOUR: Color = Color::srgb(0.1, 0.1, 0.1);
const UP_PLANE_COLOUR: Color = Color::srgb(0.0, 0.7, 0.2);
const DOWN_PLANE_COLOUR: Color = Color::srgb(0.85, 0.1, 0.1);
const UPRIGHT_PLANE_COLOUR: Color = Color::srgb(0.1, 0.3, 0.9);

/// A plane this close to level (|n . z|) is drawn as facing up or down.
const LEVEL_COS: f32 = 0.9;
/// Planes are cut from the box grown by this much (metres): a plane on a face still shows.
const SECTION_MARGIN_M: f32 = 0.01;
/// Length of the normal drawn from a plane's middle, metres.
const NORMAL_LENGTH_M: f32 = 0.12;

fn draw_boxes(
    layers: Res<ActiveLayers>,
    boxes: Query<&OrientedBox, With<SceneEntity>>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Boxes) {
        return;
    }
    for b in &boxes {
        draw_box(&mut gizmos, &b.0);
    }
}

fn draw_planes(
    layers: Res<ActiveLayers>,
    nodes: Query<(&OrientedBox, &SurfacePlanes, Option<&Panoptic>), With<SceneEntity>>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Planes) {
        return;
    }
    for (b, planes, panoptic) in &nodes {
        if panoptic.is_some_and(|p| HIDDEN_CLASSES.contains(&p.class.as_str())) {
            continue;
        }
        for plane in &planes.0 {
            draw_plane(&mut gizmos, &b.0, plane);
        }
    }
}

/// `plane` cut to `gravity_box`, hatched, with its normal; coloured by which way it faces.
pub fn draw_plane(gizmos: &mut Gizmos, gravity_box: &GravityBox, plane: &Plane) {
    let section = gravity_box.section(plane, SECTION_MARGIN_M);
    if section.is_empty() {
        return;
    }
    let colour = match plane.normal.z {
        z if z >= LEVEL_COS => UP_PLANE_COLOUR,
        z if z <= -LEVEL_COS => DOWN_PLANE_COLOUR,
        _ => UPRIGHT_PLANE_COLOUR,
    };
    gizmos.linestrip(section.iter().chain(section.first()).copied(), colour);
    // Hatching between opposite corners shows the plane as a surface, not a frame.
    let n = section.len();
    for i in 0..n / 2 {
        gizmos.line(section[i], section[i + n / 2], colour.with_alpha(0.5));
    }
    let middle = section.iter().copied().sum::<Vec3>() / n as f32;
    gizmos.arrow(middle, middle + plane.normal * NORMAL_LENGTH_M, colour);
}

/// A support edge from the parent's top centre to the child's bottom centre.
pub fn draw_support(gizmos: &mut Gizmos, parent: &GravityBox, child: &GravityBox) {
    let top = parent.center.with_z(parent.top_z());
    let bottom = child.center.with_z(child.bottom_z());
    gizmos.line(top, bottom, SUPPORT_COLOUR);
    gizmos.sphere(Isometry3d::from_translation(bottom), 0.03, SUPPORT_COLOUR);
}

/// A proximal pair, centre to centre.
pub fn draw_proximal(gizmos: &mut Gizmos, a: &GravityBox, b: &GravityBox) {
    gizmos.line(a.center, b.center, PROXIMAL_COLOUR);
}

/// A node's box.
pub fn draw_box(gizmos: &mut Gizmos, gravity_box: &GravityBox) {
    gizmos.cube(
        Transform::from_translation(gravity_box.center)
            .with_rotation(Quat::from_rotation_z(gravity_box.yaw))
            .with_scale(gravity_box.size),
        BOX_COLOUR,
    );
}

/// A node as the graph layer draws it: its box and support parent.
type GraphNodeView<'a> = (&'a OrientedBox, Option<&'a ChildOf>);

fn draw_graph(
    layers: Res<ActiveLayers>,
    nodes: Query<GraphNodeView, With<SceneEntity>>,
    pairs: Query<ProximalPairQuery>,
    mut gizmos: Gizmos,
) {
    if !layers.is_on(Layer::Graph) {
        return;
    }
    for (b, parent) in &nodes {
        if let Some((pb, _)) = parent.and_then(|p| nodes.get(p.parent()).ok()) {
            draw_support(&mut gizmos, &pb.0, &b.0);
        }
    }
    for (a, b) in &pairs {
        if let (Ok((ab, _)), Ok((bb, _))) = (nodes.get(a.0), nodes.get(b.0)) {
            draw_proximal(&mut gizmos, &ab.0, &bb.0);
        }
    }
}

pub struct GraphOverlaysPlugin;

impl Plugin for GraphOverlaysPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (draw_boxes, draw_planes, draw_graph));
    }
}
