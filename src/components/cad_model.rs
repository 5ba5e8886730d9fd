//! The complete CAD model that replaces the segment mesh: which model, where, and how well it fits.

use bevy::prelude::*;
use glam::{Affine3A, Mat4};

use crate::graph::CadPlacement;

#[derive(Component, Clone, Debug, PartialEq)]
pub struct CadModel {
    /// Id in the CAD database (`table_01`).
    pub model: String,
    /// Rotation, per-axis scale and translation of the model; the entity's own frame (its
    /// `Transform` in the tree) is the rigid part of it, so children are never sheared.
    pub world_from_model: Affine3A,
    /// The geometric mean of the per-axis scale.
    pub scale: f32,
    /// RMS distance from the observed surface to the placed model, metres.
    pub alignment_error: f32,
}

/// A node's `cad` in contact_graph.json, as its entity holds it.
impl From<&CadPlacement> for CadModel {
    fn from(c: &CadPlacement) -> Self {
        CadModel {
            model: c.model.clone(),
            world_from_model: Affine3A::from_mat4(Mat4::from_cols_array(&c.world_from_model)),
            scale: c.scale,
            alignment_error: c.alignment_error,
        }
    }
}

/// The entity's model as contact_graph.json lists it (a column-major matrix).
impl From<&CadModel> for CadPlacement {
    fn from(c: &CadModel) -> Self {
        CadPlacement {
            model: c.model.clone(),
            world_from_model: Mat4::from(c.world_from_model).to_cols_array(),
            scale: c.scale,
            alignment_error: c.alignment_error,
        }
    }
}
