//! The CAD database the replacement stage matches against: every model pre-processed once into
//! what matching and alignment ask of it (box, dominant planes, a BVH for closest points).

use std::path::Path;

use glam::{Affine3A, Vec3};
use parry3d::query::PointQueryWithLocation;
use parry3d::shape::TrianglePointLocation;
use rayon::prelude::*;

use crate::cad::ParametricLibrary;
use crate::cad::db::load::read_database;
use crate::cad::library::{LibraryEntry, build_sized_model};
use crate::cad::model::CadModel;
use crate::error::InputError;
use crate::geometry::{Plane, TriMesh, plane::dominant_planes};
use crate::perception::fronts::{model_handles, placed_handle};
use crate::perception::handles::Handle;

/// The folder of a scene's output that holds the models it uses from a `--cad` database.
pub const SCENE_MODELS: &str = "cad";

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
#[derive(Clone)]
pub struct DatabaseModel {
    pub model: CadModel,
    /// How the parametric library built this model, for the models of
    /// [`CadDatabase::parametric`] and those built from them: such a model is built again to
    /// the size an object is fitted at (`cad::replace::sizing`) rather than stretched.
    pub built: Option<LibraryBuild>,
    /// All parts merged (closed doors and drawers).
    pub mesh: TriMesh,
    /// Dominant planes, largest area first.
    pub planes: Vec<Plane>,
    /// The vertices of each connected piece of the mesh: the convex primitives (boards, legs,
    /// cylinders) the model is built from, for contact queries.
    pub pieces: Vec<Vec<Vec3>>,
    /// The handles on an articulated model's front, model frame, as the perception would find
    /// them on it (`perception::fronts::model_handles`); none on a rigid model.
    pub handles: Vec<Handle>,
    shape: parry3d::shape::TriMesh,
}

/// A library entry and the size it built a model at.
#[derive(Clone, Copy)]
pub struct LibraryBuild {
    pub entry: &'static LibraryEntry,
    pub size: Vec3,
}

impl DatabaseModel {
    /// The library's model as it is (nominal size), which `CadDatabase::for_scene` can build
    /// again from its id alone.
    pub fn is_library_nominal(&self) -> bool {
        self.built
            .is_some_and(|b| b.size == b.entry.nominal_size && b.entry.id == self.model.id)
    }

    pub fn new(model: CadModel) -> Result<Self, DatabaseError> {
        let mesh = model.merged_mesh(&[]);
        let largest_face = {
            let s = model.size;
            (s.x * s.y).max(s.x * s.z).max(s.y * s.z)
        };
        let planes = dominant_planes(&mesh, MIN_PLANE_SHARE * largest_face, MAX_MODEL_PLANES)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let shape = parry_mesh(&mesh).map_err(|problem| DatabaseError::UnusableMesh {
            model: model.id.clone(),
            problem,
        })?;
        let pieces = mesh
            .connected_components()
            .into_iter()
            .map(|c| c.positions)
            .collect();
        let handles = if model.is_articulated() {
            model_handles(&model.merged_visual_mesh(&[]), model.size)
        } else {
            Vec::new()
        };
        Ok(Self {
            model,
            built: None,
            mesh,
            planes,
            pieces,
            handles,
            shape,
        })
    }

    /// Its handles carried into the world by `world_from_model` (scale included).
    pub fn placed_handles(&self, world_from_model: &Affine3A) -> Vec<Handle> {
        self.handles
            .iter()
            .map(|h| placed_handle(world_from_model, h))
            .collect()
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

/// A parry triangle mesh (with its BVH) of `mesh`.
pub fn parry_mesh(
    mesh: &TriMesh,
) -> Result<parry3d::shape::TriMesh, parry3d::shape::TriMeshBuilderError> {
    parry3d::shape::TriMesh::new(mesh.positions.clone(), mesh.triangles.clone())
}

/// Why models could not make a database.
#[derive(Debug, thiserror::Error)]
pub enum DatabaseError {
    #[error("model id {0:?} appears twice")]
    DuplicateId(String),
    #[error("model {model}: not a usable triangle mesh: {problem:?}")]
    UnusableMesh {
        model: String,
        problem: parry3d::shape::TriMeshBuilderError,
    },
}

/// The models replacement chooses from.
#[derive(Clone)]
pub struct CadDatabase {
    models: Vec<DatabaseModel>,
}

impl CadDatabase {
    /// Pre-processes `models` (in parallel); ids must be unique.
    pub fn from_models(models: Vec<CadModel>) -> Result<Self, DatabaseError> {
        let mut ids: Vec<&str> = models.iter().map(|m| m.id.as_str()).collect();
        ids.sort_unstable();
        if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
            return Err(DatabaseError::DuplicateId(w[0].to_string()));
        }
        let models = models
            .into_par_iter()
            .map(DatabaseModel::new)
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { models })
    }

    /// The built-in parametric library at its nominal sizes.
    pub fn parametric() -> Self {
        let models = ParametricLibrary::entries()
            .iter()
            .map(|e| e.model())
            .collect();
        // The library is generated by code and tested to give proper meshes.
        let mut db =
            Self::from_models(models).unwrap_or_else(|e| panic!("parametric library: {e}"));
        for m in &mut db.models {
            m.built = ParametricLibrary::get(&m.model.id).map(|entry| LibraryBuild {
                entry,
                size: entry.nominal_size,
            });
        }
        db
    }

    /// This database with the library models built to size that `graph`'s placements name and
    /// it lacks (`library::build_sized_model`): a graph whose models were written elsewhere, or
    /// not yet (a live session's preview), still gives its links their meshes.
    pub fn with_sized_models_of(&self, graph: &crate::graph::ContactGraph) -> Self {
        self.with_sized_models(
            graph
                .nodes
                .iter()
                .filter_map(|n| n.cad.as_ref())
                .map(|c| c.model.as_str()),
        )
    }

    /// This database with the library models built to size that `ids` name and it lacks (a
    /// task may add `box_01.120x70x100`, the library's box built to 12 x 7 x 10 cm).
    pub fn with_sized_models<'a>(&self, ids: impl IntoIterator<Item = &'a str>) -> Self {
        let missing: Vec<DatabaseModel> = ids
            .into_iter()
            .filter(|id| self.get(id).is_none())
            .filter_map(build_sized_model)
            .filter_map(|m| {
                let id = m.id.clone();
                DatabaseModel::new(m)
                    .inspect_err(|e| {
                        tracing::warn!("model {id} is left out: its parts do not build ({e})")
                    })
                    .ok()
            })
            .collect();
        self.with_models(missing)
    }

    /// This database with `extra` added (models whose ids it already has are left out).
    pub fn with_models(&self, extra: impl IntoIterator<Item = DatabaseModel>) -> Self {
        let mut db = self.clone();
        for m in extra {
            if db.get(&m.model.id).is_none() {
                db.models.push(m);
            }
        }
        db
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

    /// The models of the database folder `dir` (`iscene cad import`, `iscene cad generate`).
    pub fn from_folder(dir: &Path) -> Result<Self, InputError> {
        let models = read_database(dir)?;
        if models.is_empty() {
            return Err(InputError::invalid(
                dir.join("index.json"),
                "the database holds no models",
            ));
        }
        Self::from_models(models).map_err(|e| InputError::invalid(dir, e.to_string()))
    }

    /// The models a reconstructed scene folder can refer to: the parametric library and the
    /// models the reconstruction copied into `<dir>/cad` from the database it was given.
    pub fn for_scene(dir: &Path) -> Result<Self, InputError> {
        let mut models: Vec<CadModel> = ParametricLibrary::entries()
            .iter()
            .map(|e| e.model())
            .collect();
        let own = dir.join(SCENE_MODELS);
        if own.join("index.json").exists() {
            let copied = read_database(&own)?;
            models.retain(|m| copied.iter().all(|c| c.id != m.id));
            models.extend(copied);
        }
        Self::from_models(models).map_err(|e| InputError::invalid(&own, e.to_string()))
    }

    /// The model with id `id`.
    pub fn get(&self, id: &str) -> Option<&DatabaseModel> {
        self.models.iter().find(|m| m.model.id == id)
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
        assert!(matches!(err, DatabaseError::DuplicateId(_)), "{err}");
        assert!(err.to_string().contains("twice"), "{err}");
    }
}
