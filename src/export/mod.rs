//! Exports of the kinematic tree for simulators and tools: URDF with OBJ meshes, MJCF, glTF, and
//! the 2D occupancy layer in the ROS map_server format.

pub mod mjcf;
pub mod obj;
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
    let files = urdf::urdf_files(tree, name).map_err(IsceneError::Internal)?;
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
    Ok(vec![
        "scene.urdf".into(),
        "scene.xml".into(),
        format!("{}/", urdf::MESH_DIR),
    ])
}
