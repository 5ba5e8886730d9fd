//! The replay's scene at the clock's frame: the panoptic map grown to what the sensor had seen
//! (each segment's mesh cut to its revealed triangles, coloured by instance), the camera's
//! frustum and the trajectory so far, and the contact graph's boxes, planes and edges as their
//! nodes appear.

use bevy::asset::RenderAssetUsages;
use bevy::mesh::{Indices, PrimitiveTopology};
use bevy::prelude::*;

use crate::classes::ClassTable;
use crate::replay::Replay;
use crate::viewer::camera::spawn_orbit_camera;
use crate::viewer::graph_overlays::{draw_box, draw_plane, draw_proximal, draw_support};
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::{HIDDEN_CLASSES, instance_colour, sun};
use crate::viewer::timeline::{ClockUpdate, ReplayClock, ReplayCounts};

/// The replay being shown.
#[derive(Resource, Clone, Debug)]
pub struct ReplayData(pub Replay);

/// The entity showing segment `segment`, and how many of its triangles it shows.
#[derive(Component, Clone, Copy, Debug)]
struct SegmentMesh {
    segment: usize,
    shown: usize,
}

/// Floor and walls in one quiet colour: the objects are what the instance colours tell apart.
const LAYOUT_COLOUR: Color = Color::srgb(0.62, 0.6, 0.56);
const FRUSTUM_COLOUR: Color = Color::srgb(0.8, 0.05, 0.3);
const TRAJECTORY_COLOUR: Color = Color::srgb(0.35, 0.35, 0.4);
/// How far the frustum reaches from the camera, metres.
const FRUSTUM_DEPTH_M: f32 = 0.35;

/// The vertices of every segment (the triangles come as they are revealed), and the camera
/// framing the floor.
fn spawn_replay(
    mut commands: Commands,
    replay: Res<ReplayData>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    for (i, segment) in replay.0.segments.iter().enumerate() {
        if HIDDEN_CLASSES.contains(&segment.class.as_str()) {
            continue;
        }
        let positions: Vec<[f32; 3]> = segment
            .mesh
            .positions
            .iter()
            .map(|p| p.to_array())
            .collect();
        let normals: Vec<[f32; 3]> = segment
            .mesh
            .vertex_normals()
            .iter()
            .map(|n| n.to_array())
            .collect();
        let mesh = Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        )
        .with_inserted_attribute(Mesh::ATTRIBUTE_POSITION, positions)
        .with_inserted_attribute(Mesh::ATTRIBUTE_NORMAL, normals)
        // Hidden until revealed; one triangle keeps the index buffer from being empty.
        .with_inserted_indices(Indices::U32(
            segment
                .mesh
                .triangles
                .iter()
                .take(1)
                .flatten()
                .copied()
                .collect(),
        ));
        commands.spawn((
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: if ClassTable::builtin().is_layout(Some(&segment.class)) {
                    LAYOUT_COLOUR
                } else {
                    instance_colour(segment.instance)
                },
                perceptual_roughness: 0.8,
                // The map is a surface seen from one side; its back must not vanish.
                cull_mode: None,
                double_sided: true,
                ..default()
            })),
            Transform::IDENTITY,
            Visibility::Hidden,
            Name::new(format!("segment {}", segment.id)),
            SegmentMesh {
                segment: i,
                shown: 0,
            },
        ));
    }
    let floor = replay.0.nodes.iter().find(|n| n.class == "floor");
    let (centre, size) = floor.map_or((Vec3::ZERO, Vec2::splat(4.0)), |n| {
        (
            n.gravity_box.center.with_z(0.0),
            n.gravity_box.size.truncate(),
        )
    });
    spawn_orbit_camera(&mut commands, centre, size);
    commands.spawn(sun());
}

/// Cuts every segment's mesh to the triangles revealed by the clock's frame.
fn grow_map(
    clock: Res<ReplayClock>,
    replay: Res<ReplayData>,
    mut segments: Query<(&mut SegmentMesh, &Mesh3d, &mut Visibility)>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut counts: ResMut<ReplayCounts>,
) {
    let frame = clock.shown();
    let mut seen_segments = 0;
    for (mut shown, handle, mut visibility) in &mut segments {
        let segment = &replay.0.segments[shown.segment];
        let revealed = segment.revealed_by(frame);
        seen_segments += usize::from(revealed > 0);
        if revealed == shown.shown {
            continue;
        }
        if revealed > 0
            && let Some(mut mesh) = meshes.get_mut(&handle.0)
        {
            let indices = segment.mesh.triangles[..revealed]
                .iter()
                .flatten()
                .copied()
                .collect();
            mesh.insert_indices(Indices::U32(indices));
        }
        shown.shown = revealed;
        // An empty index buffer is kept out of the renderer: nothing revealed stays hidden.
        visibility.set_if_neq(if revealed == 0 {
            Visibility::Hidden
        } else {
            Visibility::Inherited
        });
    }
    let appeared = replay
        .0
        .nodes
        .iter()
        .filter(|n| n.appears_at <= frame)
        .count();
    let text = format!(
        "map: {seen_segments} of {} segments seen; graph: {appeared} of {} nodes, {} support edges",
        segments.iter().count(),
        replay.0.nodes.len(),
        replay.0.support_edges_at(frame).len()
    );
    if counts.0 != text {
        counts.0 = text;
    }
}

/// The camera's frustum at the clock's frame and the path it came along.
fn draw_camera(clock: Res<ReplayClock>, replay: Res<ReplayData>, mut gizmos: Gizmos) {
    let replay = &replay.0;
    let frame = clock.shown() as usize;
    let Some(pose) = replay.aligned_from_camera.get(frame) else {
        return;
    };
    let path = replay.aligned_from_camera[..=frame]
        .iter()
        .map(|p| Vec3::from(p.translation));
    gizmos.linestrip(path, TRAJECTORY_COLOUR);
    let c = &replay.camera;
    let (w, h) = (c.width as f32 - 0.5, c.height as f32 - 0.5);
    let corners = [(-0.5, -0.5), (w, -0.5), (w, h), (-0.5, h)]
        .map(|(u, v)| pose.transform_point3(c.unproject(u, v, FRUSTUM_DEPTH_M)));
    let eye = Vec3::from(pose.translation);
    for corner in corners {
        gizmos.line(eye, corner, FRUSTUM_COLOUR);
    }
    gizmos.linestrip(corners.iter().chain(&corners[..1]).copied(), FRUSTUM_COLOUR);
    // The image's top edge, marked: which way is up in the picture.
    let up_mark =
        (corners[0] + corners[1]) / 2.0 + (corners[0] - corners[3]).normalize_or_zero() * 0.05;
    gizmos.line(corners[0], up_mark, FRUSTUM_COLOUR);
    gizmos.line(up_mark, corners[1], FRUSTUM_COLOUR);
}

/// The graph's nodes that have appeared: boxes, planes, support and proximal edges.
fn draw_graph_so_far(
    clock: Res<ReplayClock>,
    replay: Res<ReplayData>,
    layers: Res<ActiveLayers>,
    mut gizmos: Gizmos,
) {
    let replay = &replay.0;
    let frame = clock.shown();
    let appeared = |i: usize| replay.nodes[i].appears_at <= frame;
    for (i, node) in replay.nodes.iter().enumerate() {
        if !appeared(i) || HIDDEN_CLASSES.contains(&node.class.as_str()) {
            continue;
        }
        if layers.is_on(Layer::Boxes) {
            draw_box(&mut gizmos, &node.gravity_box);
        }
        if layers.is_on(Layer::Planes) {
            for plane in &node.planes {
                draw_plane(&mut gizmos, &node.gravity_box, plane);
            }
        }
    }
    if layers.is_on(Layer::Graph) {
        for (parent, child) in replay.support_edges_at(frame) {
            draw_support(
                &mut gizmos,
                &replay.nodes[parent].gravity_box,
                &replay.nodes[child].gravity_box,
            );
        }
        for &(a, b) in &replay.proximal {
            if appeared(a) && appeared(b) {
                draw_proximal(
                    &mut gizmos,
                    &replay.nodes[a].gravity_box,
                    &replay.nodes[b].gravity_box,
                );
            }
        }
    }
}

pub struct ReplayScenePlugin;

impl Plugin for ReplayScenePlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, spawn_replay).add_systems(
            Update,
            (grow_map, draw_camera, draw_graph_so_far).after(ClockUpdate),
        );
    }
}
