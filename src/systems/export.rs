//! The Export stage: the output folder's files, written from what the stages left in the world
//! into the staged folder that the caller commits whole (report.json, which holds every stage's
//! time, is written by the caller after the schedule). A world without an `ExportTarget` (a live
//! session's preview) writes nothing.

use std::path::PathBuf;

use bevy::prelude::*;

use crate::cad::db::export::write_scene_models;
use crate::error::IsceneError;
use crate::export::augmented::augmented_points;
use crate::export::{write_augmented, write_occupancy, write_tree_exports};
use crate::panoptic::panoptic_dir::{PanopticIndex, write_panoptic};
use crate::systems::cad_replacement::SceneModels;
use crate::systems::contact_graph::SceneGravity;
use crate::systems::kinematic_tree::SceneKinematicTree;
use crate::systems::panoptic_mapping::{MappingConfig, PanopticSurface};
use crate::systems::scene_nodes::SceneNodes;
use crate::systems::stages::record_failure;

/// The folder the Export stage writes into.
#[derive(Resource)]
pub struct ExportTarget(pub PathBuf);

/// The files the Export stage wrote, relative to the output folder, in the order written.
#[derive(Resource, Default)]
pub struct ExportedFiles(pub Vec<String>);

/// `panoptic/`: the index of entities and the labelled surface voxels.
fn export_panoptic(
    target: Res<ExportTarget>,
    config: Res<MappingConfig>,
    surface: Option<Res<PanopticSurface>>,
    mut files: ResMut<ExportedFiles>,
) -> Result<(), IsceneError> {
    let Some(surface) = surface else {
        return Ok(());
    };
    let index = PanopticIndex {
        voxel_size: config.params.voxel_size,
        fusion: config.params.fusion.name().into(),
        entities: surface.entities.clone(),
    };
    files.0.extend(write_panoptic(
        &target.0.join("panoptic"),
        &index,
        &surface.voxels,
    )?);
    Ok(())
}

/// `contact_graph.json`, and the models built for this scene (`cad/`) that its placements name.
fn export_contact_graph(
    target: Res<ExportTarget>,
    gravity: Option<Res<SceneGravity>>,
    nodes: SceneNodes,
    models: Option<Res<SceneModels>>,
    mut files: ResMut<ExportedFiles>,
) -> Result<(), IsceneError> {
    if gravity.is_none() {
        return Ok(());
    }
    let graph = nodes.contact_graph();
    crate::io::write_sequence::write_text(&target.0.join("contact_graph.json"), &graph.to_json())?;
    files.0.push("contact_graph.json".into());
    if let Some(models) = models {
        files
            .0
            .extend(write_scene_models(&target.0, &graph, &models.0)?);
    }
    Ok(())
}

/// URDF, MJCF and glTF of the kinematic tree, with their meshes.
fn export_kinematic_tree(
    target: Res<ExportTarget>,
    tree: Option<Res<SceneKinematicTree>>,
    mut files: ResMut<ExportedFiles>,
) -> Result<(), IsceneError> {
    if let Some(tree) = tree {
        files
            .0
            .extend(write_tree_exports(&target.0, &tree.0, "scene")?);
    }
    Ok(())
}

/// The gravity-aligned world's frame, once the ContactGraph stage has found it.
fn aligned_from_world(gravity: &SceneGravity) -> glam::Affine3A {
    gravity.0.aligned_from_world()
}

/// The 2D occupancy grid of the map and the kinematic tree, in the gravity-aligned world.
fn export_occupancy(
    target: Res<ExportTarget>,
    surface: Option<Res<PanopticSurface>>,
    gravity: Option<Res<SceneGravity>>,
    tree: Option<Res<SceneKinematicTree>>,
    mut files: ResMut<ExportedFiles>,
) -> Result<(), IsceneError> {
    let (Some(surface), Some(gravity)) = (surface, gravity) else {
        return Ok(());
    };
    let aligned_from_world = aligned_from_world(&gravity);
    let map_points: Vec<glam::Vec3> = surface
        .voxels
        .iter()
        .map(|(p, _)| aligned_from_world.transform_point3(*p))
        .collect();
    files.0.extend(write_occupancy(
        &target.0,
        &map_points,
        tree.as_ref().map(|t| &t.0),
    )?);
    Ok(())
}

/// The augmented point cloud: the map's surface with replaced segments swapped for their
/// models' surfaces, in the gravity-aligned world.
fn export_augmented_points(
    target: Res<ExportTarget>,
    config: Res<MappingConfig>,
    surface: Option<Res<PanopticSurface>>,
    gravity: Option<Res<SceneGravity>>,
    nodes: SceneNodes,
    models: Option<Res<SceneModels>>,
    mut files: ResMut<ExportedFiles>,
) -> Result<(), IsceneError> {
    let (Some(surface), Some(gravity), Some(models)) = (surface, gravity, models) else {
        return Ok(());
    };
    let points = augmented_points(
        &surface.voxels,
        &aligned_from_world(&gravity),
        &surface.entities,
        &nodes.contact_graph(),
        &models.0,
        config.params.voxel_size,
    );
    files
        .0
        .push(write_augmented(&target.0, &points, &surface.entities)?);
    Ok(())
}

/// Adds the Export stage's systems, one after the other in the order their files are listed.
pub struct ExportPlugin;

impl Plugin for ExportPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ExportedFiles>().add_systems(
            crate::systems::Reconstruct,
            (
                export_panoptic.pipe(record_failure),
                export_contact_graph.pipe(record_failure),
                export_kinematic_tree.pipe(record_failure),
                export_occupancy.pipe(record_failure),
                export_augmented_points.pipe(record_failure),
            )
                .chain()
                .run_if(resource_exists::<ExportTarget>)
                .in_set(crate::systems::ReconstructionStage::Export),
        );
    }
}
