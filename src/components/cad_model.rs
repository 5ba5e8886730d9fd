//! The complete CAD model that replaces the segment mesh: which model, where, and how well it fits.

use bevy::prelude::*;
use glam::Affine3A;

#[derive(Component, Clone, Debug, PartialEq)]
pub struct CadModel {
    /// Id in the CAD database (`table_01`).
    pub model: String,
    pub world_from_model: Affine3A,
    pub scale: f32,
    /// RMS distance from the segment mesh to the aligned model, metres.
    pub alignment_error: f32,
}
