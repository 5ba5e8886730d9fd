//! Writes the parametric library to disk: one .glb per model (node tree = parts) plus its metadata.

use std::path::Path;

use glam::{Affine3A, Mat4};
use serde::{Deserialize, Serialize};

use crate::base::JointSpec;
use crate::cad::db::database::{CadDatabase, SCENE_MODELS};
use crate::cad::library::ParametricLibrary;
use crate::cad::model::CadModel;
use crate::error::IsceneError;
use crate::graph::ContactGraph;
use crate::io::atomic::write_file_atomically;
use crate::io::gltf_write::{GlbError, GltfNode, glb_bytes, nest};

/// The metadata file `<id>.json` beside `<id>.glb`.
#[derive(Debug, Serialize, Deserialize)]
pub struct ModelMetadata {
    pub id: String,
    pub class: String,
    /// Canonical frame convention, spelled out for tools that read the file alone.
    pub frame: String,
    pub size: [f32; 3],
    pub glb: String,
    pub parts: Vec<PartMetadata>,
}

#[derive(Debug, Serialize, Deserialize)]
pub struct PartMetadata {
    pub name: String,
    pub parent: Option<String>,
    /// Column-major 4x4 pose of the part's frame in its parent's frame at joint value zero.
    pub parent_from_part: [f32; 16],
    pub joint: JointSpec,
    pub color: [f32; 3],
    pub vertices: usize,
    pub triangles: usize,
    /// Triangles of its own visual mesh (node `<name>.visual` under the part's node), when it
    /// has one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visual_triangles: Option<usize>,
}

/// The .glb node holding part `part`'s visual mesh, a child of the part's node.
pub fn visual_node_name(part: &str) -> String {
    format!("{part}.visual")
}

pub const CANONICAL_FRAME: &str =
    "metres; +z up; front faces -y; origin at the bottom centre of the closed bounding box";

pub fn metadata(model: &CadModel) -> ModelMetadata {
    ModelMetadata {
        id: model.id.clone(),
        class: model.class.clone(),
        frame: CANONICAL_FRAME.into(),
        size: model.size.to_array(),
        glb: format!("{}.glb", model.id),
        parts: model
            .parts
            .iter()
            .map(|p| PartMetadata {
                name: p.name.clone(),
                parent: p
                    .parent
                    .and_then(|i| model.parts.get(i))
                    .map(|q| q.name.clone()),
                parent_from_part: Mat4::from(p.parent_from_part).to_cols_array(),
                joint: p.joint,
                color: p.color,
                vertices: p.mesh.positions.len(),
                triangles: p.mesh.triangles.len(),
                visual_triangles: p.visual.as_ref().map(|v| v.triangles.len()),
            })
            .collect(),
    }
}

/// The model as a glTF node tree: a node per part under its parent, joints in the nodes' extras.
pub fn model_glb(model: &CadModel) -> Result<Vec<u8>, GlbError> {
    let nodes: Vec<GltfNode> = model
        .parts
        .iter()
        .map(|p| {
            let mut node = GltfNode::new(p.name.clone());
            let (_, rotation, translation) =
                Affine3A::to_scale_rotation_translation(&p.parent_from_part);
            node.rotation = rotation;
            node.translation = translation;
            node.mesh = Some((p.mesh.clone(), p.color));
            if let Some(visual) = &p.visual {
                let mut child = GltfNode::new(visual_node_name(&p.name));
                child.mesh = Some((visual.clone(), p.color));
                node.children.push(child);
            }
            node.extras = serde_json::to_value(p.joint)
                .ok()
                .map(|j| serde_json::json!({ "joint": j }));
            node
        })
        .collect();
    let mut root = GltfNode::new(model.id.clone());
    root.extras = Some(serde_json::json!({ "class": model.class, "size": model.size.to_array() }));
    root.children = nest(nodes, |i| model.parts[i].parent.unwrap_or(0))
        .into_iter()
        .collect();
    glb_bytes(&root, "z_up")
}

/// Writes every model of the library, plus `index.json`, into `dir`.
pub fn write_library(dir: &Path) -> Result<usize, IsceneError> {
    let models: Vec<CadModel> = ParametricLibrary::entries()
        .iter()
        .map(|e| e.model())
        .collect();
    write_models(dir, &models, "iscene cad generate")
}

/// `index.json` of a database folder: the models it holds. Fields in alphabetical order, as
/// the files have always been written.
#[derive(Debug, Serialize, Deserialize)]
pub struct DatabaseIndex {
    pub generator: String,
    pub models: Vec<IndexEntry>,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct IndexEntry {
    pub articulated: bool,
    pub class: String,
    pub id: String,
}

impl IndexEntry {
    pub fn of(model: &CadModel) -> Self {
        Self {
            articulated: model.is_articulated(),
            class: model.class.clone(),
            id: model.id.clone(),
        }
    }
}

/// Writes `models` into the database folder `dir`: `<id>.glb` and `<id>.json` per model and
/// `index.json` listing them (what [`crate::cad::db::load::read_database`] reads back).
pub fn write_models(
    dir: &Path,
    models: &[CadModel],
    generator: &str,
) -> Result<usize, IsceneError> {
    let files = models
        .iter()
        .map(model_file_bytes)
        .collect::<Result<Vec<_>, _>>()?;
    write_model_files(dir, files)?;
    write_index(dir, models.iter().map(IndexEntry::of).collect(), generator)
}

/// `<id>.glb` and `<id>.json` of `model`: names and bytes, made in memory so that a model that
/// fails leaves nothing written.
pub fn model_file_bytes(model: &CadModel) -> Result<[(String, Vec<u8>); 2], IsceneError> {
    let glb =
        model_glb(model).map_err(|e| IsceneError::Internal(format!("{}: glTF: {e}", model.id)))?;
    let json = serde_json::to_vec_pretty(&metadata(model))
        .map_err(|e| IsceneError::Internal(e.to_string()))?;
    Ok([
        (format!("{}.glb", model.id), glb),
        (format!("{}.json", model.id), json),
    ])
}

/// Writes models' files (from [`model_file_bytes`]) into `dir`, created when missing.
pub fn write_model_files(
    dir: &Path,
    files: Vec<[(String, Vec<u8>); 2]>,
) -> Result<(), IsceneError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| IsceneError::io(format!("creating {}", dir.display()), e))?;
    for (name, bytes) in files.into_iter().flatten() {
        write_file_atomically(&dir.join(name), &bytes)?;
    }
    Ok(())
}

/// Writes `index.json` listing `models` into `dir`; returns how many it lists.
pub fn write_index(
    dir: &Path,
    models: Vec<IndexEntry>,
    generator: &str,
) -> Result<usize, IsceneError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| IsceneError::io(format!("creating {}", dir.display()), e))?;
    let count = models.len();
    let index = DatabaseIndex {
        generator: generator.to_string(),
        models,
    };
    let json =
        serde_json::to_vec_pretty(&index).map_err(|e| IsceneError::Internal(e.to_string()))?;
    write_file_atomically(&dir.join("index.json"), &json)?;
    Ok(count)
}

/// Writes the models `graph` uses from `db` that `CadDatabase::for_scene` cannot build from the
/// parametric library (models of a `--cad` database, library models built to an object's size)
/// into `<scene_dir>/cad`, so that the scene folder alone gives its links their meshes; returns
/// the files written (none when every model is the library's as it is).
pub fn write_scene_models(
    scene_dir: &Path,
    graph: &ContactGraph,
    db: &CadDatabase,
) -> Result<Vec<String>, IsceneError> {
    let mut used: Vec<CadModel> = Vec::new();
    for node in &graph.nodes {
        let Some(model) = node.cad.as_ref().and_then(|c| db.get(&c.model)) else {
            continue;
        };
        if !model.is_library_nominal() && used.iter().all(|m| m.id != model.model.id) {
            used.push(model.model.clone());
        }
    }
    if used.is_empty() {
        return Ok(Vec::new());
    }
    used.sort_by(|a, b| a.id.cmp(&b.id));
    write_models(&scene_dir.join(SCENE_MODELS), &used, "iscene reconstruct")?;
    let mut files: Vec<String> = used
        .iter()
        .flat_map(|m| {
            [
                format!("{SCENE_MODELS}/{}.glb", m.id),
                format!("{SCENE_MODELS}/{}.json", m.id),
            ]
        })
        .collect();
    files.push(format!("{SCENE_MODELS}/index.json"));
    Ok(files)
}
