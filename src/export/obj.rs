//! Wavefront OBJ text of a triangle mesh (what URDF consumers and MuJoCo load).

use std::fmt::Write;

use crate::geometry::TriMesh;

/// `v` and `f` lines (1-based indices), micrometre precision, no normals or materials.
pub fn obj_text(mesh: &TriMesh) -> String {
    let mut text = String::with_capacity(32 * (mesh.positions.len() + mesh.triangles.len()));
    for p in &mesh.positions {
        let _ = writeln!(text, "v {:.6} {:.6} {:.6}", p.x, p.y, p.z);
    }
    for t in &mesh.triangles {
        let _ = writeln!(text, "f {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_box_has_eight_vertices_and_twelve_faces() {
        let text = obj_text(&TriMesh::cuboid(Vec3::ZERO, Vec3::ONE));
        assert_eq!(text.lines().filter(|l| l.starts_with("v ")).count(), 8);
        assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 12);
        assert!(text.lines().any(|l| l == "f 1 3 4"));
    }
}
