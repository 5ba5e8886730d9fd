//! The complete CAD model that replaces the segment mesh: which model, where, and how well it fits.

use bevy::prelude::*;
use glam::Affine3A;

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
