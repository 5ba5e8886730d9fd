//! The entity's mesh as the panoptic map saw it (partial, noisy), world frame.

use bevy::prelude::*;

use crate::geometry::TriMesh;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct SegmentMesh(pub TriMesh);
