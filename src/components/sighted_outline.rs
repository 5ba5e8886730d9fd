//! What precise depth frames measured of the entity's outline (`panoptic::sighted`): the points
//! on its silhouette, one list per frame that saw it, world frame. Empty for layout and
//! whenever the depth is too noisy to place an edge within a voxel.

use bevy::prelude::*;

#[derive(Component, Clone, Debug, Default, PartialEq)]
pub struct SightedOutline(pub Vec<Vec<Vec3>>);
