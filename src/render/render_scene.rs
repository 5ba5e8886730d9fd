//! A world flattened into triangles the rasteriser can walk: world-space corners, instance id,
//! colour and normal per triangle.

use glam::Vec3;

/// How a triangle's colour is computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Surface {
    Plain,
    /// A tiled floor: the colour alternates on a 0.5 m grid.
    FloorTiles,
}

#[derive(Clone, Debug, Default)]
pub struct RenderScene {
    pub corners: Vec<[Vec3; 3]>,
    pub normals: Vec<Vec3>,
    pub instances: Vec<u16>,
    pub colors: Vec<[f32; 3]>,
    pub surfaces: Vec<Surface>,
}

impl RenderScene {
    /// Adds the triangles of `mesh` with one instance id, colour and surface.
    pub fn push_mesh(
        &mut self,
        mesh: &crate::geometry::TriMesh,
        instance: u16,
        color: [f32; 3],
        surface: Surface,
    ) {
        for i in 0..mesh.triangles.len() {
            let normal = mesh.face_normal(i);
            if normal == Vec3::ZERO {
                continue;
            }
            self.corners.push(mesh.triangle(i));
            self.normals.push(normal);
            self.instances.push(instance);
            self.colors.push(color);
            self.surfaces.push(surface);
        }
    }

    pub fn len(&self) -> usize {
        self.corners.len()
    }

    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }
}
