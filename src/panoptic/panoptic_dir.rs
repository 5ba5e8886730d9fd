//! The `panoptic/` folder of a reconstruction: `entities.json` (one record per scene entity),
//! `<id>.ply` (its segment mesh) and `surface_voxels.ply` (every surface voxel centre with the
//! index of its entity plus one, 0 = none; what `iscene eval` scores).

use std::collections::HashMap;
use std::path::Path;

use glam::{Affine3A, Mat4, Vec3};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs_bw::writer::Writer;
use serde::{Deserialize, Serialize};

use crate::error::{InputError, IsceneError};
use crate::geometry::TriMesh;
use crate::io::ply::{mesh_ply_bytes, read_mesh_ply};
use crate::io::write_sequence::write_text;
use crate::panoptic::PanopticEntity;

#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PanopticIndex {
    pub voxel_size: f32,
    /// `joint` or `voxblox++`.
    pub fusion: String,
    pub entities: Vec<PanopticEntity>,
}

/// A colour per class name, stable across runs.
pub fn class_color(class: &str) -> [f32; 3] {
    let h = crate::base::stable_hash(0, class);
    [
        0.25 + 0.7 * ((h & 0xff) as f32 / 255.0),
        0.25 + 0.7 * (((h >> 8) & 0xff) as f32 / 255.0),
        0.25 + 0.7 * (((h >> 16) & 0xff) as f32 / 255.0),
    ]
}

pub fn write_panoptic(
    dir: &Path,
    index: &PanopticIndex,
    surface_voxels: &[(Vec3, u32)],
) -> Result<Vec<String>, IsceneError> {
    std::fs::create_dir_all(dir).map_err(|e| IsceneError::io(dir.display().to_string(), e))?;
    let mut written = Vec::new();
    for e in &index.entities {
        let bytes = mesh_ply_bytes(&e.mesh, class_color(&e.class))
            .map_err(|why| IsceneError::Internal(format!("PLY of {}: {why}", e.id)))?;
        let path = dir.join(format!("{}.ply", e.id));
        std::fs::write(&path, bytes)
            .map_err(|err| IsceneError::io(path.display().to_string(), err))?;
        written.push(format!("panoptic/{}.ply", e.id));
    }
    let path = dir.join("surface_voxels.ply");
    std::fs::write(&path, labelled_points_ply_bytes(surface_voxels)?)
        .map_err(|err| IsceneError::io(path.display().to_string(), err))?;
    write_text(
        &dir.join("entities.json"),
        &serde_json::to_string_pretty(index).map_err(|e| IsceneError::Internal(e.to_string()))?,
    )?;
    written.extend([
        "panoptic/surface_voxels.ply".into(),
        "panoptic/entities.json".into(),
    ]);
    Ok(written)
}

fn labelled_points_ply_bytes(points: &[(Vec3, u32)]) -> Result<Vec<u8>, IsceneError> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.push(
        "surface voxels of the panoptic map; entity = index in entities.json + 1, 0 = none".into(),
    );
    let mut vertex = ElementDef::new("vertex".into());
    for name in ["x", "y", "z"] {
        vertex.properties.add(PropertyDef::new(
            name.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    vertex.properties.add(PropertyDef::new(
        "entity".into(),
        PropertyType::Scalar(ScalarType::UInt),
    ));
    ply.header.elements.add(vertex);
    let vertices = points
        .iter()
        .map(|(p, e)| {
            let mut v = DefaultElement::new();
            v.insert("x".into(), Property::Float(p.x));
            v.insert("y".into(), Property::Float(p.y));
            v.insert("z".into(), Property::Float(p.z));
            v.insert("entity".into(), Property::UInt(*e));
            v
        })
        .collect();
    ply.payload.insert("vertex".into(), vertices);
    let mut bytes = Vec::new();
    Writer::new()
        .write_ply(&mut bytes, &mut ply)
        .map_err(|e| IsceneError::Internal(e.to_string()))?;
    Ok(bytes)
}

/// Reads `entities.json` of a reconstruction's `panoptic/` folder.
pub fn read_index(dir: &Path) -> Result<PanopticIndex, InputError> {
    let index_path = dir.join("entities.json");
    let text = std::fs::read_to_string(&index_path).map_err(|e| InputError::io(&index_path, &e))?;
    let index: PanopticIndex = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(&index_path, format!("not a panoptic index: {e}")))?;
    for entity in &index.entities {
        crate::file_name::check_file_name(&entity.id)
            .map_err(|e| InputError::invalid(&index_path, format!("entities: {e}")))?;
    }
    Ok(index)
}

/// Reads every entity's segment mesh (`<id>.ply`) of a `panoptic/` folder, in the index's order.
pub fn read_segment_meshes(dir: &Path, index: &PanopticIndex) -> Result<Vec<TriMesh>, InputError> {
    index
        .entities
        .iter()
        .map(|e| read_mesh_ply(&dir.join(format!("{}.ply", e.id))))
        .collect()
}

/// The segment meshes of the entities `ids` that a reconstruction's folder `dir` holds
/// (`panoptic/<id>.ply`), moved into the aligned frame of its contact graph (`report.json`'s
/// `gravity.aligned_from_world`): what the map saw of them, exactly as the reconstruction built
/// its objects of it. A folder without a map (a ground truth) holds none.
pub fn read_aligned_segment_meshes(
    dir: &Path,
    ids: &[&str],
) -> Result<HashMap<String, TriMesh>, InputError> {
    let panoptic = dir.join("panoptic");
    if ids.is_empty() || !panoptic.join("entities.json").exists() {
        return Ok(HashMap::new());
    }
    let index = read_index(&panoptic)?;
    let report_path = dir.join("report.json");
    let text =
        std::fs::read_to_string(&report_path).map_err(|e| InputError::io(&report_path, &e))?;
    let report: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(&report_path, format!("not JSON: {e}")))?;
    let aligned_from_world = aligned_from_world_in(&report, &report_path)?;
    let mut meshes = HashMap::new();
    for e in index
        .entities
        .iter()
        .filter(|e| ids.contains(&e.id.as_str()))
    {
        let mesh = read_mesh_ply(&panoptic.join(format!("{}.ply", e.id)))?;
        meshes.insert(e.id.clone(), mesh.transformed(&aligned_from_world));
    }
    Ok(meshes)
}

/// `gravity.aligned_from_world` of a reconstruction's report.json (`report`, read from `path`):
/// the frame its contact graph is in, from the sequence's world frame its map is in. Identity
/// when the report has none.
pub fn aligned_from_world_in(
    report: &serde_json::Value,
    path: &Path,
) -> Result<Affine3A, InputError> {
    match &report["gravity"]["aligned_from_world"] {
        serde_json::Value::Null => Ok(Affine3A::IDENTITY),
        value => {
            let m: [f32; 16] = serde_json::from_value(value.clone()).map_err(|e| {
                InputError::invalid(path, format!("gravity.aligned_from_world: {e}"))
            })?;
            if m.iter().any(|x| !x.is_finite()) {
                return Err(InputError::invalid(
                    path,
                    "gravity.aligned_from_world is not finite",
                ));
            }
            Ok(Affine3A::from_mat4(Mat4::from_cols_array(&m)))
        }
    }
}

/// Reads `entities.json` and `surface_voxels.ply` of a reconstruction's `panoptic/` folder.
pub fn read_panoptic(dir: &Path) -> Result<(PanopticIndex, Vec<(Vec3, u32)>), InputError> {
    let index = read_index(dir)?;
    let path = dir.join("surface_voxels.ply");
    let file = std::fs::File::open(&path).map_err(|e| InputError::io(&path, &e))?;
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut std::io::BufReader::new(file))
        .map_err(|e| InputError::invalid(&path, format!("not a PLY point set: {e}")))?;
    let mut points = Vec::new();
    for v in ply
        .payload
        .get("vertex")
        .map(Vec::as_slice)
        .unwrap_or_default()
    {
        let (
            Some(Property::Float(x)),
            Some(Property::Float(y)),
            Some(Property::Float(z)),
            Some(Property::UInt(e)),
        ) = (v.get("x"), v.get("y"), v.get("z"), v.get("entity"))
        else {
            return Err(InputError::invalid(
                &path,
                "vertex without float x, y, z and uint entity",
            ));
        };
        if *e as usize > index.entities.len() || !(x.is_finite() && y.is_finite() && z.is_finite())
        {
            return Err(InputError::invalid(
                &path,
                format!("bad voxel ({x}, {y}, {z}) entity {e}"),
            ));
        }
        points.push((Vec3::new(*x, *y, *z), *e));
    }
    Ok((index, points))
}
