//! The CAD database the replacement stage matches against: every model pre-processed once into
//! what matching and alignment ask of it (box, dominant planes, a BVH for closest points).

use glam::Vec3;
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TrianglePointLocation;
use rayon::prelude::*;

use crate::cad::ParametricLibrary;
use crate::cad::model::CadModel;
use crate::geometry::{Plane, TriMesh, plane::dominant_planes};

/// At most this many planes describe a model (the object side keeps as many).
pub const MAX_MODEL_PLANES: usize = 8;

/// A plane must carry this share of the model's largest box face to describe the model.
const MIN_PLANE_SHARE: f32 = 0.04;

/// The closest point of a model's surface to a query point, in the model frame.
#[derive(Clone, Copy, Debug)]
pub struct SurfacePoint {
    pub point: Vec3,
    /// The outward normal of the triangle when the closest point lies inside it; `None` on an
    /// edge or a vertex, where the direction to the query point is the only good normal.
    pub face_normal: Option<Vec3>,
}

/// One model, ready for matching: everything in its canonical frame (+z up, front -y, origin at
/// the bottom centre) at joint values zero.
pub struct DatabaseModel {
    pub model: CadModel,
    /// All parts merged (closed doors and drawers).
    pub mesh: TriMesh,
    /// Dominant planes, largest area first.
    pub planes: Vec<Plane>,
    /// The vertices of each connected piece of the mesh: the convex primitives (boards, legs,
    /// cylinders) the model is built from, for contact queries.
    pub pieces: Vec<Vec<Vec3>>,
    shape: parry3d::shape::TriMesh,
}

impl DatabaseModel {
    pub fn new(model: CadModel) -> Result<Self, String> {
        let mesh = model.merged_mesh(&[]);
        let largest_face = {
            let s = model.size;
            (s.x * s.y).max(s.x * s.z).max(s.y * s.z)
        };
        let planes = dominant_planes(&mesh, MIN_PLANE_SHARE * largest_face, MAX_MODEL_PLANES)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let shape = parry_mesh(&mesh).map_err(|e| format!("model {}: {e}", model.id))?;
        let pieces = connected_pieces(&mesh);
        Ok(Self {
            model,
            mesh,
            planes,
            pieces,
            shape,
        })
    }

    /// The closest point of the surface to `point` (model frame).
    pub fn closest(&self, point: Vec3) -> SurfacePoint {
        let (projection, (triangle, location)) = self
            .shape
            .project_local_point_and_get_location(point, false);
        let face_normal = match location {
            TrianglePointLocation::OnFace(..) => self.shape.triangle(triangle).normal(),
            _ => None,
        };
        SurfacePoint {
            point: projection.point,
            face_normal,
        }
    }
}

/// The vertices of each set of triangles connected through shared vertex indices.
fn connected_pieces(mesh: &TriMesh) -> Vec<Vec<Vec3>> {
    let n = mesh.positions.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for t in &mesh.triangles {
        let a = root(&mut parent, t[0] as usize);
        for &v in &t[1..] {
            let b = root(&mut parent, v as usize);
            parent[b] = a;
        }
    }
    let mut index_of_root = std::collections::HashMap::new();
    let mut pieces: Vec<Vec<Vec3>> = Vec::new();
    let used: std::collections::BTreeSet<usize> = mesh
        .triangles
        .iter()
        .flat_map(|t| t.iter().map(|&v| v as usize))
        .collect();
    for v in used {
        let r = root(&mut parent, v);
        let k = *index_of_root.entry(r).or_insert_with(|| {
            pieces.push(Vec::new());
            pieces.len() - 1
        });
        pieces[k].push(mesh.positions[v]);
    }
    pieces
}

/// A parry triangle mesh (with its BVH) of `mesh`.
pub fn parry_mesh(mesh: &TriMesh) -> Result<parry3d::shape::TriMesh, String> {
    parry3d::shape::TriMesh::new(mesh.positions.clone(), mesh.triangles.clone())
        .map_err(|e| format!("not a usable triangle mesh: {e:?}"))
}

/// The models replacement chooses from.
pub struct CadDatabase {
    models: Vec<DatabaseModel>,
}

impl CadDatabase {
    /// Pre-processes `models` (in parallel); ids must be unique.
    pub fn from_models(models: Vec<CadModel>) -> Result<Self, String> {
        let mut ids: Vec<&str> = models.iter().map(|m| m.id.as_str()).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("model id {:?} appears twice", w[0]));
        }
        let models = models
            .into_par_iter()
            .map(DatabaseModel::new)
            .collect::<Result<Vec<_>, String>>()?;
        Ok(Self { models })
    }

    /// The built-in parametric library at its nominal sizes.
    pub fn parametric() -> Self {
        let models = ParametricLibrary::entries()
            .iter()
            .map(|e| e.model())
            .collect();
        // The library is generated by code and tested to give proper meshes.
        Self::from_models(models).unwrap_or_else(|e| panic!("parametric library: {e}"))
    }

    pub fn models(&self) -> &[DatabaseModel] {
        &self.models
    }

    pub fn len(&self) -> usize {
        self.models.len()
    }

    pub fn is_empty(&self) -> bool {
        self.models.is_empty()
    }

    /// The models of `class` with their indices.
    pub fn of_class<'a>(
        &'a self,
        class: &'a str,
    ) -> impl Iterator<Item = (usize, &'a DatabaseModel)> + 'a {
        self.models
            .iter()
            .enumerate()
            .filter(move |(_, m)| m.model.class == class)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_points_lie_on_the_surface_with_outward_face_normals() {
        let db = CadDatabase::parametric();
        assert!(db.len() >= 30);
        let (_, table) = db
            .of_class("table")
            .find(|(_, m)| m.model.id == "table_01")
            .expect("table_01");
        let top = table.model.size.z;
        let above = table.closest(Vec3::new(0.1, 0.05, top + 0.2));
        assert!((above.point.z - top).abs() < 1e-4, "{:?}", above.point);
        let n = above.face_normal.expect("inside the top face");
        assert!(n.z > 0.99, "top normal {n}");
        // The table top is one of its planes, facing up at its height.
        assert!(
            table
                .planes
                .iter()
                .any(|p| p.normal.z > 0.99
                    && (p.signed_distance(Vec3::new(0.0, 0.0, top))).abs() < 1e-3),
            "{:?}",
            table.planes
        );
    }

    #[test]
    fn duplicate_ids_are_refused() {
        let m = ParametricLibrary::entries()[0].model();
        let err = CadDatabase::from_models(vec![m.clone(), m])
            .err()
            .expect("refused");
        assert!(err.contains("twice"), "{err}");
    }
}
