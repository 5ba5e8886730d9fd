//! Reads a CAD database folder (what `iscene cad generate` and `iscene cad import` write): the
//! ids in `index.json`, each model's parts and joints from `<id>.json` and their meshes from the
//! nodes of `<id>.glb` named after the parts.

use std::path::Path;

use crate::cad::db::export::{DatabaseIndex, ModelMetadata, visual_node_name};
use crate::cad::model::{CadModel, CadPart};
use crate::error::InputError;
use crate::file_name::check_file_name;
use crate::geometry::TriMesh;
use glam::{Affine3A, Mat4, Vec3};

/// The index of the database folder `dir`.
pub fn read_index(dir: &Path) -> Result<DatabaseIndex, InputError> {
    let index_path = dir.join("index.json");
    let text = std::fs::read_to_string(&index_path).map_err(|e| InputError::io(&index_path, &e))?;
    let index: DatabaseIndex = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(&index_path, format!("not a CAD database index: {e}")))?;
    for entry in &index.models {
        check_file_name(&entry.id)
            .map_err(|e| InputError::invalid(&index_path, format!("models: {e}")))?;
    }
    Ok(index)
}

/// Every model of the database folder `dir`, in the order of its index.
pub fn read_database(dir: &Path) -> Result<Vec<CadModel>, InputError> {
    read_index(dir)?
        .models
        .iter()
        .map(|entry| read_model(dir, &entry.id))
        .collect()
}

/// The model `id` of the database folder `dir`.
pub fn read_model(dir: &Path, id: &str) -> Result<CadModel, InputError> {
    check_file_name(id).map_err(|e| InputError::invalid(dir, e.to_string()))?;
    let meta_path = dir.join(format!("{id}.json"));
    let text = std::fs::read_to_string(&meta_path).map_err(|e| InputError::io(&meta_path, &e))?;
    let meta: ModelMetadata = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(&meta_path, format!("not model metadata: {e}")))?;
    if meta.id != id {
        return Err(InputError::invalid(
            &meta_path,
            format!("holds model {:?}, not {id:?}", meta.id),
        ));
    }
    check_file_name(&meta.glb).map_err(|e| InputError::invalid(&meta_path, format!("glb: {e}")))?;
    let glb_path = dir.join(&meta.glb);
    let bytes = std::fs::read(&glb_path).map_err(|e| InputError::io(&glb_path, &e))?;
    let meshes = part_meshes(&bytes).map_err(|e| InputError::invalid(&glb_path, e))?;
    let mut parts: Vec<CadPart> = Vec::with_capacity(meta.parts.len());
    for part in &meta.parts {
        let parent = match &part.parent {
            None => None,
            Some(name) => Some(parts.iter().position(|p| &p.name == name).ok_or_else(|| {
                InputError::invalid(
                    &meta_path,
                    format!("part {} comes before its parent {name}", part.name),
                )
            })?),
        };
        let mesh = meshes
            .iter()
            .find(|(name, _)| *name == part.name)
            .map(|(_, m)| m.clone())
            .ok_or_else(|| {
                InputError::invalid(&glb_path, format!("no node with part {}'s mesh", part.name))
            })?;
        let parent_from_part = Affine3A::from_mat4(Mat4::from_cols_array(&part.parent_from_part));
        if !parent_from_part.is_finite() {
            return Err(InputError::invalid(
                &meta_path,
                format!("part {}: pose is not finite", part.name),
            ));
        }
        // A part's pose is rigid: a singular or scaled one would break every later transform.
        let r = parent_from_part.matrix3;
        let deviation = (r.transpose() * r - glam::Mat3A::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |a, v| a.max(v.abs()));
        if deviation > 1e-3 || r.determinant() < 0.0 {
            return Err(InputError::invalid(
                &meta_path,
                format!(
                    "part {}: pose is not a rotation and a translation",
                    part.name
                ),
            ));
        }
        // The part's look, where it has one of its own, is its node's child of that name.
        let visual_name = visual_node_name(&part.name);
        let visual = meshes
            .iter()
            .find(|(name, _)| *name == visual_name)
            .map(|(_, m)| m.clone());
        if part.visual_triangles.is_some() != visual.is_some() {
            return Err(InputError::invalid(
                &glb_path,
                format!(
                    "part {}: node {visual_name} does not match the metadata",
                    part.name
                ),
            ));
        }
        check_file_name(&part.name)
            .map_err(|e| InputError::invalid(&meta_path, format!("part: {e}")))?;
        part.joint.check().map_err(|e| {
            InputError::invalid(&meta_path, format!("part {}: joint: {e}", part.name))
        })?;
        parts.push(CadPart {
            name: part.name.clone(),
            parent,
            parent_from_part,
            joint: part.joint,
            mesh,
            visual,
            color: part.color,
        });
    }
    if parts.first().is_none_or(|p| p.parent.is_some()) {
        return Err(InputError::invalid(
            &meta_path,
            "the first part must be the root",
        ));
    }
    let size = Vec3::from_array(meta.size);
    if !(size.is_finite() && size.min_element() > 0.0) {
        return Err(InputError::invalid(
            &meta_path,
            format!("size {size} is not positive"),
        ));
    }
    Ok(CadModel {
        id: meta.id,
        class: meta.class,
        size,
        parts,
    })
}

/// Why a model's .glb holds no part meshes this reader can use.
#[derive(Debug, thiserror::Error)]
enum GlbError {
    #[error("not a glTF binary: {0}")]
    NotGltf(#[from] gltf::Error),
    #[error("no binary chunk")]
    NoBinaryChunk,
    #[error("node {0}: no positions")]
    NoPositions(String),
    #[error("node {0}: no indices")]
    NoIndices(String),
    #[error("node {0}: indices are not triangles of its vertices")]
    NotTriangles(String),
}

/// The mesh of every named node of a .glb, in the node's own frame.
fn part_meshes(bytes: &[u8]) -> Result<Vec<(String, TriMesh)>, GlbError> {
    let gltf = gltf::Gltf::from_slice(bytes)?;
    let blob = gltf.blob.as_deref().ok_or(GlbError::NoBinaryChunk)?;
    let mut out = Vec::new();
    for node in gltf.nodes() {
        let (Some(name), Some(mesh)) = (node.name(), node.mesh()) else {
            continue;
        };
        let mut part = TriMesh::default();
        for primitive in mesh.primitives() {
            let reader = primitive.reader(|b| (b.index() == 0).then_some(blob));
            let positions: Vec<Vec3> = reader
                .read_positions()
                .ok_or_else(|| GlbError::NoPositions(name.to_string()))?
                .map(Vec3::from_array)
                .collect();
            let indices: Vec<u32> = reader
                .read_indices()
                .ok_or_else(|| GlbError::NoIndices(name.to_string()))?
                .into_u32()
                .collect();
            if !indices.len().is_multiple_of(3)
                || indices.iter().any(|&i| i as usize >= positions.len())
            {
                return Err(GlbError::NotTriangles(name.to_string()));
            }
            part.append(&TriMesh {
                positions,
                triangles: indices
                    .chunks_exact(3)
                    .map(|t| [t[0], t[1], t[2]])
                    .collect(),
            });
        }
        out.push((name.to_string(), part));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::ParametricLibrary;

    #[test]
    fn a_written_database_reads_back_as_the_same_models() {
        let dir = tempfile::tempdir().expect("tempdir");
        let models: Vec<CadModel> = ["fridge_01", "chair_01", "cabinet_02"]
            .iter()
            .map(|id| ParametricLibrary::get(id).expect(id).model())
            .collect();
        crate::cad::db::export::write_models(dir.path(), &models, "test").expect("write");
        let read = read_database(dir.path()).expect("read");
        assert_eq!(read.len(), models.len());
        for (a, b) in models.iter().zip(&read) {
            assert_eq!(a.id, b.id);
            assert_eq!(a.class, b.class);
            assert_eq!(a.parts.len(), b.parts.len());
            for (p, q) in a.parts.iter().zip(&b.parts) {
                assert_eq!((&p.name, p.parent, p.joint), (&q.name, q.parent, q.joint));
                assert_eq!(p.mesh, q.mesh);
                assert!(p.parent_from_part.abs_diff_eq(q.parent_from_part, 1e-6));
            }
        }
    }

    #[test]
    fn a_broken_database_names_the_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        std::fs::write(dir.path().join("index.json"), r#"{"models":[{"id":"x"}]}"#).expect("w");
        let err = read_database(dir.path())
            .expect_err("x.json is missing")
            .to_string();
        assert!(err.contains("x.json"), "{err}");
        std::fs::write(dir.path().join("index.json"), "{").expect("w");
        let err = read_database(dir.path())
            .expect_err("bad index")
            .to_string();
        assert!(err.contains("index.json"), "{err}");
    }
}
