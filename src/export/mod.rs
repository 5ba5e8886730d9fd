//! Exports of the kinematic tree for simulators and tools: URDF with OBJ meshes, MJCF, glTF, and
//! the 2D occupancy layer in the ROS map_server format; the augmented geometry.

pub mod augmented;
pub mod mjcf;
pub mod obj;
pub mod occupancy;
pub mod scene_glb;
pub mod urdf;

use std::path::Path;

use crate::error::IsceneError;
use crate::io::write_sequence::write_text;
use crate::kinematics::tree::KinematicTree;

/// Writes the tree's exports into `dir` (a staged output folder); returns the paths written,
/// relative to `dir`, meshes summarised as `meshes/`.
pub fn write_tree_exports(
    dir: &Path,
    tree: &KinematicTree,
    name: &str,
) -> Result<Vec<String>, IsceneError> {
    let files = urdf::urdf_files(tree, name).map_err(|e| IsceneError::Internal(e.to_string()))?;
    std::fs::create_dir_all(dir.join(urdf::MESH_DIR)).map_err(|e| {
        IsceneError::io(
            format!("creating {}", dir.join(urdf::MESH_DIR).display()),
            e,
        )
    })?;
    for file in &files {
        write_text(&dir.join(&file.path), &file.text)?;
    }
    write_text(&dir.join("scene.xml"), &mjcf::mjcf_text(tree, name))?;
    let glb =
        scene_glb::scene_glb(tree).map_err(|e| IsceneError::Internal(format!("scene.glb: {e}")))?;
    std::fs::write(dir.join("scene.glb"), glb)
        .map_err(|e| IsceneError::io(format!("writing {}", dir.join("scene.glb").display()), e))?;
    Ok(vec![
        "scene.urdf".into(),
        "scene.xml".into(),
        "scene.glb".into(),
        format!("{}/", urdf::MESH_DIR),
    ])
}

/// Writes `augmented.ply` (`points`, their entities `entities`); returns its path.
pub fn write_augmented(
    dir: &Path,
    points: &[augmented::AugmentedPoint],
    entities: &[crate::panoptic::PanopticEntity],
) -> Result<String, IsceneError> {
    let classes: Vec<&str> = entities.iter().map(|e| e.class.as_str()).collect();
    let path = dir.join("augmented.ply");
    std::fs::write(&path, augmented::augmented_ply_bytes(points, &classes))
        .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))?;
    Ok("augmented.ply".into())
}

/// Writes `occupancy.pgm/.yaml` (the map layer from `map_points`, aligned frame) and
/// `occupancy_objects.pgm/.yaml` (plus the tree's objects projected); returns the paths.
pub fn write_occupancy(
    dir: &Path,
    map_points: &[glam::Vec3],
    tree: Option<&KinematicTree>,
) -> Result<Vec<String>, IsceneError> {
    let Some(grid) = occupancy::OccupancyGrid::from_map(map_points) else {
        return Ok(Vec::new());
    };
    let mut layers = vec![("occupancy", grid.clone())];
    if let Some(tree) = tree {
        let poses = tree.world_from_links();
        let classes = crate::classes::ClassTable::builtin();
        let objects: Vec<crate::geometry::TriMesh> = tree
            .links
            .iter()
            .zip(&poses)
            .filter(|(link, _)| !classes.is_layout(link.class.as_deref()))
            .filter_map(|(link, pose)| link.geometry.as_ref().map(|g| g.visual.transformed(pose)))
            .collect();
        layers.push(("occupancy_objects", grid.with_objects(&objects)));
    }
    let mut written = Vec::new();
    for (name, layer) in layers {
        let pgm = format!("{name}.pgm");
        std::fs::write(dir.join(&pgm), layer.pgm_bytes())
            .map_err(|e| IsceneError::io(format!("writing {}", dir.join(&pgm).display()), e))?;
        write_text(&dir.join(format!("{name}.yaml")), &layer.yaml_text(&pgm))?;
        written.push(pgm);
        written.push(format!("{name}.yaml"));
    }
    Ok(written)
}
