//! What the links of a scene folder's world are built of besides its contact graph: the CAD
//! models its placements name, and what the map saw of the objects no model replaced.

use std::collections::HashMap;
use std::path::Path;

use bevy::prelude::World;

use crate::cad::db::database::CadDatabase;
use crate::classes::EntityKind;
use crate::error::InputError;
use crate::geometry::TriMesh;
use crate::graph::ContactGraph;
use crate::panoptic::panoptic_dir::read_aligned_segment_meshes;
use crate::systems::kinematic_tree::{attach_segment_meshes, spawn_node_links};

pub struct SceneShapes {
    /// The library's models and the folder's own (`cad/`).
    pub models: CadDatabase,
    /// Segment meshes of the objects no model replaced, in the graph's frame, by node id (none
    /// for a ground truth, whose objects all have models).
    pub seen: HashMap<String, TriMesh>,
}

impl SceneShapes {
    /// The shapes of the scene in `dir`, whose contact graph is `graph`.
    pub fn read(dir: &Path, graph: &ContactGraph) -> Result<Self, InputError> {
        let unplaced: Vec<&str> = graph
            .nodes
            .iter()
            .filter(|n| n.cad.is_none() && n.kind != EntityKind::Layout)
            .map(|n| n.id.as_str())
            .collect();
        Ok(Self {
            models: CadDatabase::for_scene(dir)?,
            seen: read_aligned_segment_meshes(dir, &unplaced)?,
        })
    }

    /// Gives the entities of `graph` spawned in `world` their links.
    pub fn spawn_links(&self, world: &mut World, graph: &ContactGraph) {
        attach_segment_meshes(world, &self.seen);
        spawn_node_links(world, graph, Some(&self.models));
    }
}
