//! The map layer: the reconstruction itself, each panoptic segment's mesh as the mapper left it,
//! shown in place of the CAD models so what replaced what can be seen by switching back and
//! forth. It takes the meshes' two looks from the colour and segments layers: the colours the
//! sensor saw (replay/vertex_colours.rs, from the sequence the reconstruction read) or each
//! segment's instance colour. Only a reconstruction's folder has a map (its `panoptic/`); a
//! rendered sequence's `gt/` has none, and the layer then says so.

use std::path::Path;

use bevy::prelude::*;

use crate::base::ClassId;
use crate::error::IsceneError;
use crate::geometry::TriMesh;
use crate::panoptic::panoptic_dir::{read_index, read_segment_meshes};
use crate::replay::{read_report, reconstruction_sequence, vertex_colours};
use crate::viewer::layers::{ActiveLayers, Layer};
use crate::viewer::link_meshes::{
    HIDDEN_CLASSES, LinkMaterials, coloured_bevy_mesh, instance_colour, material,
};
use crate::viewer::state::ViewerStatus;

/// A map vertex no colour frame saw is drawn in this grey.
const UNSEEN_GREY: [u8; 3] = [150, 150, 150];
/// A vertex takes a frame's colour within this many voxels of the frame's depth there.
const COLOUR_TOLERANCE_VOXELS: f32 = 3.0;

/// One segment of the reconstructed map, in the contact graph's aligned frame.
#[derive(Clone, Debug)]
pub struct MapSegment {
    pub class: String,
    pub instance: u32,
    pub mesh: TriMesh,
    /// Per vertex, the colour the sensor saw there (8-bit sRGB); `None` where no colour frame
    /// saw it, and empty when the sequence could not be read.
    pub colours: Vec<Option<[u8; 3]>>,
}

/// The reconstructed map of the folder on view; empty when it has none.
#[derive(Resource, Clone, Debug, Default)]
pub struct MapSegments {
    pub segments: Vec<MapSegment>,
    /// Why the map has no sensor colours, when it has none.
    pub uncoloured_because: Option<String>,
}

/// The map of the reconstruction in `dir`: `panoptic/<id>.ply` moved into the aligned frame
/// report.json records, coloured from the sequence it read when that is still there. A folder
/// without `panoptic/entities.json` has no map.
pub fn read_map(dir: &Path) -> Result<MapSegments, IsceneError> {
    let panoptic = dir.join("panoptic");
    if !panoptic.join("entities.json").exists() {
        return Ok(MapSegments::default());
    }
    let facts = read_report(&dir.join("report.json"))?;
    let index = read_index(&panoptic)?;
    let meshes = read_segment_meshes(&panoptic, &index)?;
    // The colours come from the sequence's frames, in its world frame (before alignment).
    let vertices: Vec<glam::Vec3> = meshes.iter().flat_map(|m| m.positions.clone()).collect();
    let (mut colours, uncoloured_because) =
        match reconstruction_sequence(dir, &facts).and_then(|sequence| {
            let tolerance = COLOUR_TOLERANCE_VOXELS * index.voxel_size;
            Ok(vertex_colours(&vertices, &sequence, tolerance)?)
        }) {
            Ok(colours) => (colours, None),
            Err(why) => (Vec::new(), Some(why.to_string())),
        };
    let mut segments = Vec::with_capacity(meshes.len());
    for (e, mut mesh) in index.entities.iter().zip(meshes) {
        let own = if colours.is_empty() {
            Vec::new()
        } else {
            colours.drain(..mesh.positions.len()).collect()
        };
        for p in &mut mesh.positions {
            *p = facts.aligned_from_world.transform_point3(*p);
        }
        segments.push(MapSegment {
            class: e.class.clone(),
            instance: e.instance,
            mesh,
            colours: own,
        });
    }
    Ok(MapSegments {
        segments,
        uncoloured_because,
    })
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
    // The map is a surface seen from one side; its back faces show through its gaps.
    let two_sided = |colour: Color| StandardMaterial {
        double_sided: true,
        cull_mode: None,
        ..material(colour)
    };
    for segment in &map.segments {
        if HIDDEN_CLASSES.contains(&segment.class.as_str()) || segment.mesh.is_empty() {
            continue;
        }
        let colours = (!segment.colours.is_empty()).then(|| {
            segment
                .colours
                .iter()
                .map(|c| {
                    let [r, g, b] = c.unwrap_or(UNSEEN_GREY);
                    Color::srgb_u8(r, g, b).to_linear().to_f32_array()
                })
                .collect()
        });
        let segment_look = materials.add(two_sided(instance_colour(segment.instance)));
        // Without sensor colours both looks are the instance colour.
        let colour_look = if colours.is_some() {
            materials.add(two_sided(Color::WHITE))
        } else {
            segment_look.clone()
        };
        let current = if layers.is_on(Layer::Segments) {
            segment_look.clone()
        } else {
            colour_look.clone()
        };
        commands.spawn((
            Mesh3d(meshes.add(coloured_bevy_mesh(&segment.mesh, colours))),
            MeshMaterial3d(current),
            // The segments layer switches the map's look as it does the models'.
            LinkMaterials {
                colour: colour_look,
                segment: segment_look,
                class: Some(ClassId::new(&segment.class)),
            },
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
    mut map_meshes: Query<&mut Visibility, With<MapMesh>>,
    mut links: Query<(&LinkMaterials, &mut Visibility), Without<MapMesh>>,
) {
    if !layers.is_changed() {
        return;
    }
    let on = layers.is_on(Layer::Map) && !map.segments.is_empty();
    if layers.is_on(Layer::Map) {
        if map.segments.is_empty() {
            status.0 = vec!["no map here: only a reconstruction's folder has one".into()];
        } else if let Some(why) = map.uncoloured_because.as_ref()
            && !layers.is_on(Layer::Segments)
        {
            status.0 = vec![
                "the map is in instance colours: the sensor's colours could not be read".into(),
                why.clone(),
            ];
        }
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
