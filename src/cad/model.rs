//! A CAD model: rigid parts in a tree joined by fixed, revolute or prismatic joints.

use glam::{Affine3A, Vec3};
use serde::{Deserialize, Serialize};

use crate::base::JointSpec;
use crate::geometry::TriMesh;

/// One rigid part. Its mesh is in the part's own frame, which is also its joint frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CadPart {
    /// Unique within the model: `body`, `door`, `door_left`, `drawer_1`, ...
    pub name: String,
    /// Index of the parent part; `None` only for the root part (index 0).
    pub parent: Option<usize>,
    /// The part's frame in its parent's frame at joint value zero.
    pub parent_from_part: Affine3A,
    pub joint: JointSpec,
    /// What the part collides and is matched as.
    pub mesh: TriMesh,
    /// What it looks like, where that is not its collision mesh: an imported model's visual
    /// geometry (a LIBERO cabinet's panels and handles, where it collides as boxes). `None`:
    /// the mesh is both.
    pub visual: Option<TriMesh>,
    /// Linear RGB base colour in 0..1.
    pub color: [f32; 3],
}

impl CadPart {
    /// The mesh it is drawn with.
    pub fn visual_mesh(&self) -> &TriMesh {
        self.visual.as_ref().unwrap_or(&self.mesh)
    }
}

/// A complete model in the canonical frame: +z up, front facing -y, metres, the origin at the
/// centre of the bottom of its bounding box at joint values zero (closed doors and drawers).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CadModel {
    /// `<class>_<variant>`, e.g. `chair_03`.
    pub id: String,
    pub class: String,
    /// Size of the bounding box with every joint at zero.
    pub size: Vec3,
    /// Parts in topological order: a parent comes before its children.
    pub parts: Vec<CadPart>,
}

impl CadModel {
    /// Each part's pose in the model frame for the given joint values (missing values are zero;
    /// values are clamped to the joint limits).
    pub fn model_from_parts(&self, joint_values: &[(String, f32)]) -> Vec<Affine3A> {
        let mut poses: Vec<Affine3A> = Vec::with_capacity(self.parts.len());
        for part in &self.parts {
            let value = joint_values
                .iter()
                .find(|(name, _)| *name == part.name)
                .map_or(0.0, |(_, v)| *v);
            let parent_pose = part
                .parent
                .and_then(|p| poses.get(p).copied())
                .unwrap_or(Affine3A::IDENTITY);
            poses.push(
                parent_pose * part.parent_from_part * part.joint.motion(part.joint.clamp(value)),
            );
        }
        poses
    }

    /// All parts merged into one mesh in the model frame at the given joint values.
    pub fn merged_mesh(&self, joint_values: &[(String, f32)]) -> TriMesh {
        let mut merged = TriMesh::default();
        for (part, model_from_part) in self.parts.iter().zip(self.model_from_parts(joint_values)) {
            merged.append(&part.mesh.transformed(&model_from_part));
        }
        merged
    }

    /// All parts' visual meshes merged in the model frame at the given joint values: what a
    /// camera sees of the model.
    pub fn merged_visual_mesh(&self, joint_values: &[(String, f32)]) -> TriMesh {
        let mut merged = TriMesh::default();
        for (part, model_from_part) in self.parts.iter().zip(self.model_from_parts(joint_values)) {
            merged.append(&part.visual_mesh().transformed(&model_from_part));
        }
        merged
    }

    /// Parts that move (revolute or prismatic joints).
    pub fn movable_parts(&self) -> impl Iterator<Item = &CadPart> {
        self.parts.iter().filter(|p| p.joint.limits.is_some())
    }

    pub fn is_articulated(&self) -> bool {
        self.movable_parts().next().is_some()
    }

    /// Whether a door of it turns about a vertical hinge at one side: mirroring it moves the
    /// hinge to the other side.
    pub fn has_side_hinges(&self) -> bool {
        self.parts
            .iter()
            .any(|p| p.joint.kind == crate::base::JointKind::Revolute && p.joint.axis.z.abs() > 0.9)
    }

    /// The model mirrored across its x = 0 plane (left and right swapped, seen from the front),
    /// as `id`: the same box, its side hinges on the other sides. Every frame is conjugated by
    /// the mirror `M` (`M A M`), meshes mirrored with their triangles turned back outwards; a
    /// hinge axis `a` becomes `-M a` (a mirror turns a right-handed rotation into a left-handed
    /// one), a slide axis `M a`.
    pub fn mirrored(&self, id: String) -> CadModel {
        let m = Affine3A::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let mirror_mesh = |mesh: &TriMesh| TriMesh {
            positions: mesh
                .positions
                .iter()
                .map(|p| p * Vec3::new(-1.0, 1.0, 1.0))
                .collect(),
            triangles: mesh
                .triangles
                .iter()
                .map(|[a, b, c]| [*a, *c, *b])
                .collect(),
        };
        let parts = self
            .parts
            .iter()
            .map(|p| {
                let axis = m.transform_vector3(p.joint.axis);
                let axis = match p.joint.kind {
                    crate::base::JointKind::Revolute => -axis,
                    _ => axis,
                };
                CadPart {
                    name: p.name.clone(),
                    parent: p.parent,
                    parent_from_part: m * p.parent_from_part * m,
                    joint: JointSpec { axis, ..p.joint },
                    mesh: mirror_mesh(&p.mesh),
                    visual: p.visual.as_ref().map(mirror_mesh),
                    color: p.color,
                }
            })
            .collect();
        CadModel {
            id,
            class: self.class.clone(),
            size: self.size,
            parts,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::ParametricLibrary;

    #[test]
    fn a_mirrored_model_opens_as_the_mirror_image_of_the_model() {
        for id in ["fridge_01", "cabinet_03", "microwave_02"] {
            let model = ParametricLibrary::get(id).expect("model").model();
            assert!(model.has_side_hinges(), "{id}");
            let mirrored = model.mirrored(format!("{id}.mirrored"));
            // Every joint half open.
            let values: Vec<(String, f32)> = model
                .parts
                .iter()
                .filter_map(|p| Some((p.name.clone(), 0.5 * p.joint.limits?.1)))
                .collect();
            let (a, b) = (model.merged_mesh(&values), mirrored.merged_mesh(&values));
            assert_eq!(a.positions.len(), b.positions.len());
            for (p, q) in a.positions.iter().zip(&b.positions) {
                assert!(
                    (*p * Vec3::new(-1.0, 1.0, 1.0) - *q).length() < 1e-5,
                    "{id}: {p} {q}"
                );
            }
            assert_eq!(mirrored.size, model.size);
        }
    }
}
