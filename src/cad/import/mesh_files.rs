//! Triangle meshes from the files model formats refer to: MuJoCo's legacy binary `.msh`, STL
//! (binary or ASCII) and OBJ, chosen by the file's extension.

use std::io::{BufReader, Cursor};
use std::path::Path;

use glam::Vec3;

use crate::geometry::TriMesh;

/// Why a mesh file could not be read. The message says what is wrong, not which file: the
/// caller names it.
#[derive(Debug, thiserror::Error)]
pub enum MeshFileError {
    #[error("cannot read: {0}")]
    Unreadable(#[from] std::io::Error),
    /// A format this reader does not read: the model may be valid, its mesh is not for us.
    #[error("not a mesh format read here (.msh, .stl or .obj)")]
    UnsupportedFormat,
    /// The file is broken, in words.
    #[error("{0}")]
    Malformed(String),
}

fn malformed(problem: impl Into<String>) -> MeshFileError {
    MeshFileError::Malformed(problem.into())
}

/// Reads the mesh file at `path` (in the file's units and frame).
pub fn read_mesh_file(path: &Path) -> Result<TriMesh, MeshFileError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let mesh = match extension.as_deref() {
        Some("msh") => msh_mesh(&std::fs::read(path)?)?,
        Some("stl") => stl_mesh(&mut BufReader::new(std::fs::File::open(path)?))?,
        Some("obj") => obj_mesh(&std::fs::read(path)?)?,
        _ => return Err(MeshFileError::UnsupportedFormat),
    };
    if mesh.triangles.is_empty() {
        return Err(malformed("the mesh has no triangles"));
    }
    if let Some(p) = mesh.positions.iter().find(|p| !p.is_finite()) {
        return Err(malformed(format!("a vertex is not a number: {p}")));
    }
    Ok(mesh)
}

/// MuJoCo's legacy binary mesh: four little-endian i32 counts (vertices, normals, texture
/// coordinates, faces), then the vertices (3 f32 each), normals (3 f32), texture coordinates
/// (2 f32) and faces (3 i32 each). Without faces, consecutive vertex triples are the triangles.
fn msh_mesh(bytes: &[u8]) -> Result<TriMesh, MeshFileError> {
    let count = |i: usize| -> Result<usize, MeshFileError> {
        let raw = bytes
            .get(4 * i..4 * i + 4)
            .ok_or_else(|| malformed("shorter than the 16-byte header of a .msh file"))?;
        let n = i32::from_le_bytes([raw[0], raw[1], raw[2], raw[3]]);
        usize::try_from(n).map_err(|_| malformed(format!("negative count {n} in the header")))
    };
    let (vertices, normals, texcoords, faces) = (count(0)?, count(1)?, count(2)?, count(3)?);
    let expected = 16 + 12 * vertices + 12 * normals + 8 * texcoords + 12 * faces;
    if bytes.len() != expected {
        return Err(malformed(format!(
            "{} bytes, but the header ({vertices} vertices, {normals} normals, {texcoords} \
             texture coordinates, {faces} faces) makes {expected}",
            bytes.len()
        )));
    }
    let word = |offset: usize| {
        [
            bytes[offset],
            bytes[offset + 1],
            bytes[offset + 2],
            bytes[offset + 3],
        ]
    };
    let positions: Vec<Vec3> = (0..vertices)
        .map(|v| {
            let at = 16 + 12 * v;
            Vec3::new(
                f32::from_le_bytes(word(at)),
                f32::from_le_bytes(word(at + 4)),
                f32::from_le_bytes(word(at + 8)),
            )
        })
        .collect();
    let faces_at = 16 + 12 * vertices + 12 * normals + 8 * texcoords;
    let triangles: Vec<[u32; 3]> = if faces == 0 {
        if vertices % 3 != 0 {
            return Err(malformed(format!(
                "no faces, and {vertices} vertices are not whole triangles"
            )));
        }
        (0..vertices as u32 / 3)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect()
    } else {
        (0..faces)
            .map(|f| {
                let at = faces_at + 12 * f;
                [0, 4, 8].map(|k| i32::from_le_bytes(word(at + k)))
            })
            .map(|t| {
                t.iter()
                    .all(|&i| i >= 0 && (i as usize) < vertices)
                    .then(|| t.map(|i| i as u32))
                    .ok_or_else(|| {
                        malformed(format!("a face {t:?} refers to a vertex that is not there"))
                    })
            })
            .collect::<Result<_, _>>()?
    };
    Ok(TriMesh {
        positions,
        triangles,
    })
}

fn stl_mesh(reader: &mut (impl std::io::Read + std::io::Seek)) -> Result<TriMesh, MeshFileError> {
    let stl = stl_io::read_stl(reader).map_err(|e| malformed(format!("not an STL file: {e}")))?;
    let positions = stl.vertices.iter().map(|v| Vec3::from(v.0)).collect();
    let triangles = stl
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    Ok(TriMesh {
        positions,
        triangles,
    })
}

/// Every group of an OBJ file as one mesh; materials are not read.
fn obj_mesh(bytes: &[u8]) -> Result<TriMesh, MeshFileError> {
    let (groups, _) = obj_groups(bytes, |_| Err(tobj::LoadError::OpenFileFailed))?;
    let mut mesh = TriMesh::default();
    for group in groups {
        mesh.append(&group.mesh);
    }
    Ok(mesh)
}

/// One group of an OBJ file, triangulated.
pub struct ObjGroup {
    pub name: String,
    pub mesh: TriMesh,
    /// Index into the materials [`obj_groups`] returns.
    pub material: Option<usize>,
}

/// The groups of an OBJ file, and the materials of its `mtllib` files, which `material_file`
/// reads (by the name the OBJ file gives). A face referring to a vertex that is not there is an
/// error.
pub fn obj_groups(
    bytes: &[u8],
    material_file: impl Fn(&Path) -> tobj::MTLLoadResult,
) -> Result<(Vec<ObjGroup>, Vec<tobj::Material>), MeshFileError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, materials) = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, material_file)
        .map_err(|e| malformed(format!("not an OBJ file: {e}")))?;
    let groups = models
        .into_iter()
        .map(|model| {
            let positions: Vec<Vec3> = model
                .mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect();
            let n = positions.len();
            let triangles = model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| {
                    t.iter()
                        .all(|&i| (i as usize) < n)
                        .then(|| [t[0], t[1], t[2]])
                        .ok_or_else(|| {
                            malformed(format!("group {:?} has a face out of range", model.name))
                        })
                })
                .collect::<Result<_, _>>()?;
            Ok(ObjGroup {
                name: model.name,
                mesh: TriMesh {
                    positions,
                    triangles,
                },
                material: model.mesh.material_id,
            })
        })
        .collect::<Result<Vec<_>, MeshFileError>>()?;
    Ok((groups, materials.unwrap_or_default()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn msh_bytes(counts: [i32; 4], floats: &[f32], faces: &[i32]) -> Vec<u8> {
        let mut bytes: Vec<u8> = counts.iter().flat_map(|c| c.to_le_bytes()).collect();
        bytes.extend(floats.iter().flat_map(|f| f.to_le_bytes()));
        bytes.extend(faces.iter().flat_map(|f| f.to_le_bytes()));
        bytes
    }

    #[test]
    fn msh_files_are_read_with_and_without_faces() {
        let triangle = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        let with_faces = msh_mesh(&msh_bytes([3, 0, 0, 1], &triangle, &[0, 2, 1])).expect("msh");
        assert_eq!(with_faces.triangles, vec![[0, 2, 1]]);
        assert_eq!(with_faces.positions[1], Vec3::X);
        // Normals and texture coordinates are skipped over.
        let mut floats = triangle.to_vec();
        floats.extend([0.0; 9 + 6]);
        let soup = msh_mesh(&msh_bytes([3, 3, 3, 0], &floats, &[])).expect("msh");
        assert_eq!(soup.triangles, vec![[0, 1, 2]]);
        assert!(msh_mesh(&msh_bytes([3, 0, 0, 1], &triangle, &[0, 2, 3])).is_err());
        let short = msh_mesh(&msh_bytes([4, 0, 0, 0], &triangle, &[])).expect_err("short");
        assert!(
            matches!(&short, MeshFileError::Malformed(why) if why.contains("makes")),
            "{short}"
        );
        assert!(matches!(
            read_mesh_file(Path::new("a.dae")),
            Err(MeshFileError::UnsupportedFormat)
        ));
    }

    #[test]
    fn stl_and_obj_give_the_same_triangle() {
        let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                     vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let stl = stl_mesh(&mut Cursor::new(ascii.as_bytes())).expect("stl");
        let obj = obj_mesh(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").expect("obj");
        assert_eq!(stl.triangles.len(), 1);
        assert_eq!(obj.triangles, vec![[0, 1, 2]]);
        let corners = |m: &TriMesh| m.triangles[0].map(|i| m.positions[i as usize]);
        assert_eq!(corners(&stl), corners(&obj));
    }
}
