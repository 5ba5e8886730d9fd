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
}
