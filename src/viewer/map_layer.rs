//! The map layer: the reconstruction itself, each panoptic segment's mesh as the mapper left it
//! in its instance colour, shown in place of the CAD models so what replaced what can be seen
//! by switching back and forth. Only a reconstruction's folder has a map (its `panoptic/`); a
//! rendered sequence's `gt/` has none, and the layer then says so.

use std::path::Path;

use bevy::prelude::*;

use crate::error::IsceneError;
use crate::geometry::TriMesh;
use crate::io::panoptic_dir::{read_index, read_segment_meshes};
use crate::replay::read_report;
use crate::viewer::interaction::ViewerStatus;
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::{HIDDEN_CLASSES, LinkMaterials, bevy_mesh, instance_colour};

/// One segment of the reconstructed map, in the contact graph's aligned frame.
#[derive(Clone, Debug)]
pub struct MapSegment {
    pub class: String,
    pub instance: u32,
    pub mesh: TriMesh,
}

/// The reconstructed map of the folder on view; empty when it has none.
#[derive(Resource, Clone, Debug, Default)]
pub struct MapSegments(pub Vec<MapSegment>);

/// The map of the reconstruction in `dir`: `panoptic/<id>.ply` moved into the aligned frame
/// report.json records. A folder without `panoptic/entities.json` has no map.
pub fn read_map(dir: &Path) -> Result<MapSegments, IsceneError> {
    let panoptic = dir.join("panoptic");
    if !panoptic.join("entities.json").exists() {
        return Ok(MapSegments::default());
    }
    let aligned_from_world = read_report(&dir.join("report.json"))?.aligned_from_world;
    let index = read_index(&panoptic)?;
    let meshes = read_segment_meshes(&panoptic, &index)?;
    Ok(MapSegments(
        index
            .entities
            .iter()
            .zip(meshes)
            .map(|(e, mut mesh)| {
                for p in &mut mesh.positions {
                    *p = aligned_from_world.transform_point3(*p);
                }
                MapSegment {
                    class: e.class.clone(),
                    instance: e.instance,
                    mesh,
                }
            })
            .collect(),
    ))
}

/// A segment mesh of the map.
#[derive(Component)]
struct MapMesh;

fn spawn_map_meshes(
    mut commands: Commands,
    map: Res<MapSegments>,
    layers: Res<ActiveLayers>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    let shown = if layers.is_on(Layer::Map) {
        Visibility::Inherited
    } else {
        Visibility::Hidden
    };
    for segment in &map.0 {
        if HIDDEN_CLASSES.contains(&segment.class.as_str()) || segment.mesh.is_empty() {
            continue;
        }
        commands.spawn((
            Mesh3d(meshes.add(bevy_mesh(&segment.mesh))),
            MeshMaterial3d(materials.add(StandardMaterial {
                base_color: instance_colour(segment.instance),
                perceptual_roughness: 0.8,
                // The map is a surface seen from one side; its back faces show through gaps.
                double_sided: true,
                cull_mode: None,
                ..default()
            })),
            Transform::IDENTITY,
            shown,
            MapMesh,
        ));
    }
}

/// With the map layer on, the map shows and the scene's models hide (the robot stays).
fn show_map(
    layers: Res<ActiveLayers>,
    map: Res<MapSegments>,
    mut status: ResMut<ViewerStatus>,
    mut map_meshes: Query<&mut Visibility, (With<MapMesh>, Without<LinkMaterials>)>,
    mut links: Query<(&LinkMaterials, &mut Visibility), Without<MapMesh>>,
) {
    if !layers.is_changed() {
        return;
    }
    let on = layers.is_on(Layer::Map) && !map.0.is_empty();
    if layers.is_on(Layer::Map) && map.0.is_empty() {
        status.0 = vec!["no map here: only a reconstruction's folder has one".into()];
    }
    for mut v in &mut map_meshes {
        v.set_if_neq(if on {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        });
    }
    for (looks, mut v) in &mut links {
        v.set_if_neq(looks.visibility(on));
    }
}

pub struct MapLayerPlugin;

impl Plugin for MapLayerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<MapSegments>()
            .add_systems(Startup, spawn_map_meshes)
            .add_systems(Update, show_map);
    }
}
