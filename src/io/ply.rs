//! Triangle meshes as binary PLY (vertex x, y, z, red, green, blue; face vertex_indices).

use std::path::Path;

use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{
    Addable, DefaultElement, ElementDef, Encoding, Ply, Property, PropertyDef, PropertyType,
    ScalarType,
};
use ply_rs_bw::writer::Writer;

use crate::error::InputError;
use crate::geometry::TriMesh;

/// The mesh as binary little-endian PLY with one colour (0..1) on every vertex.
pub fn mesh_ply_bytes(mesh: &TriMesh, color: [f32; 3]) -> std::io::Result<Vec<u8>> {
    let mut ply = Ply::<DefaultElement>::new();
    ply.header.encoding = Encoding::BinaryLittleEndian;
    ply.header.comments.push("written by iscene".into());
    let mut vertex = ElementDef::new("vertex".into());
    for name in ["x", "y", "z"] {
        vertex.properties.add(PropertyDef::new(
            name.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    for name in ["red", "green", "blue"] {
        vertex.properties.add(PropertyDef::new(
            name.into(),
            PropertyType::Scalar(ScalarType::UChar),
        ));
    }
    ply.header.elements.add(vertex);
    let mut face = ElementDef::new("face".into());
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    ply.header.elements.add(face);
    let rgb = color.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8);
    let vertices = mesh
        .positions
        .iter()
        .map(|p| {
            let mut v = DefaultElement::new();
            v.insert("x".into(), Property::Float(p.x));
            v.insert("y".into(), Property::Float(p.y));
            v.insert("z".into(), Property::Float(p.z));
            v.insert("red".into(), Property::UChar(rgb[0]));
            v.insert("green".into(), Property::UChar(rgb[1]));
            v.insert("blue".into(), Property::UChar(rgb[2]));
            v
        })
        .collect();
    ply.payload.insert("vertex".into(), vertices);
    let faces = mesh
        .triangles
        .iter()
        .map(|t| {
            let mut f = DefaultElement::new();
            f.insert(
                "vertex_indices".into(),
                Property::ListInt(t.iter().map(|&i| i as i32).collect()),
            );
            f
        })
        .collect();
    ply.payload.insert("face".into(), faces);
    let mut bytes = Vec::new();
    Writer::new().write_ply(&mut bytes, &mut ply)?;
    Ok(bytes)
}

/// Reads the triangles of a PLY mesh file (polygons are fanned into triangles).
pub fn read_mesh_ply(path: &Path) -> Result<TriMesh, InputError> {
    let file = std::fs::File::open(path).map_err(|e| InputError::io(path, &e))?;
    let mut reader = std::io::BufReader::new(file);
    let ply = Parser::<DefaultElement>::new()
        .read_ply(&mut reader)
        .map_err(|e| InputError::invalid(path, format!("not a PLY mesh: {e}")))?;
    let scalar = |v: &DefaultElement, key: &str| -> Option<f32> {
        match v.get(key)? {
            Property::Float(x) => Some(*x),
            Property::Double(x) => Some(*x as f32),
            _ => None,
        }
    };
    let mut mesh = TriMesh::default();
    for v in ply
        .payload
        .get("vertex")
        .map(Vec::as_slice)
        .unwrap_or_default()
    {
        let (Some(x), Some(y), Some(z)) = (scalar(v, "x"), scalar(v, "y"), scalar(v, "z")) else {
            return Err(InputError::invalid(path, "vertex without float x, y, z"));
        };
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(InputError::invalid(
                path,
                "vertex with a NaN or infinite coordinate",
            ));
        }
        mesh.positions.push(Vec3::new(x, y, z));
    }
    let n = mesh.positions.len() as u32;
    for f in ply
        .payload
        .get("face")
        .map(Vec::as_slice)
        .unwrap_or_default()
    {
        let indices: Vec<u32> = match f.get("vertex_indices").or_else(|| f.get("vertex_index")) {
            Some(Property::ListInt(l)) => l.iter().map(|&i| i as u32).collect(),
            Some(Property::ListUInt(l)) => l.clone(),
            _ => {
                return Err(InputError::invalid(
                    path,
                    "face without an integer vertex_indices list",
                ));
            }
        };
        if indices.iter().any(|&i| i >= n) {
            return Err(InputError::invalid(
                path,
                format!("face index out of range (mesh has {n} vertices)"),
            ));
        }
        for k in 1..indices.len().saturating_sub(1) {
            mesh.triangles
                .push([indices[0], indices[k], indices[k + 1]]);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_round_trip_keeps_the_mesh() {
        let mesh = TriMesh::cuboid(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("box.ply");
        std::fs::write(&path, mesh_ply_bytes(&mesh, [0.5, 0.5, 0.5]).expect("ply")).expect("write");
        assert_eq!(read_mesh_ply(&path).expect("read"), mesh);
    }
}
