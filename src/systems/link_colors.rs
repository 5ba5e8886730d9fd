//! Part of the KinematicTree stage: every link takes the colour the camera saw on its surface
//! (`map::seen_color`), so the exported twin (URDF, MJCF, glTF) and the viewer look like the
//! room. A model's door takes the colour seen on that door, its carcass the colour seen on the
//! carcass; a link the camera did not see enough of keeps its model's colour.

use std::collections::{HashMap, HashSet};
use std::sync::Arc;

use bevy::prelude::*;
use rayon::prelude::*;

use crate::components::LinkBody;
use crate::geometry::surface_points::surface_points;
use crate::kinematics::link::LinkGeometry;
use crate::kinematics::tree::KinematicTree;
use crate::map::SegmentLabel;
use crate::map::seen_color::seen_color;
use crate::systems::contact_graph::SceneGravity;
use crate::systems::panoptic_mapping::{PanopticMap, PanopticSurface};

/// Surface samples per link lie this many voxels apart: finer adds nothing, as the map holds
/// one colour per voxel.
const SAMPLE_SPACING_VOXELS: f32 = 2.0;

/// Gives the links of `tree` (read off `world`, `entities[l]` holding link `l`) the colours the
/// map saw on their surfaces, in the tree and on the entities' link bodies alike. An object's
/// links read only its own voxels (its entity's segment labels); an object the map did not
/// extract (a counter found from geometry) reads any surface voxel at its links. Does nothing
/// without a map (a scene read from a folder).
pub fn paint_links_as_seen(world: &mut World, tree: &mut KinematicTree, entities: &[Entity]) {
    let (Some(map), Some(gravity)) = (
        world.get_resource::<PanopticMap>(),
        world.get_resource::<SceneGravity>(),
    ) else {
        return;
    };
    let tsdf = &map.0.tsdf;
    let map_from_aligned = gravity.0.aligned_from_world().inverse();
    let labels: HashMap<&str, HashSet<SegmentLabel>> = world
        .get_resource::<PanopticSurface>()
        .map(|s| {
            s.entities
                .iter()
                .map(|e| (e.id.as_str(), e.labels.iter().copied().collect()))
                .collect()
        })
        .unwrap_or_default();
    let poses = tree.world_from_links();
    let spacing = SAMPLE_SPACING_VOXELS * tsdf.voxel_size;
    let painted: Vec<Option<Arc<LinkGeometry>>> = tree
        .links
        .par_iter()
        .zip(&poses)
        .map(|(link, pose)| {
            let geometry = link.geometry.as_ref()?;
            let own = link.node.as_deref().and_then(|id| labels.get(id));
            let map_from_link = map_from_aligned * *pose;
            let samples = surface_points(&geometry.visual, spacing).points;
            let color = seen_color(
                tsdf,
                samples.iter().map(|p| map_from_link.transform_point3(*p)),
                |label| own.is_none_or(|own| own.contains(&label)),
            )?;
            Some(Arc::new(LinkGeometry {
                color,
                ..(**geometry).clone()
            }))
        })
        .collect();
    for ((link, entity), geometry) in tree.links.iter_mut().zip(entities).zip(painted) {
        if let Some(geometry) = geometry {
            world.entity_mut(*entity).insert(LinkBody(geometry.clone()));
            link.geometry = Some(geometry);
        }
    }
}
