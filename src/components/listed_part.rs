//! A moving part as `contact_graph.json` lists it (DESIGN.md, second round: `parts`): its joint,
//! the box of its front and its handle, in the aligned world frame at rest. The KinematicTree
//! stage puts it on the part's entity (the child of its object with the `ModelPart` and `Joint`),
//! and the contact graph read off the world lists it under the object's node.

use bevy::prelude::*;

use crate::graph::parts::PartJson;

#[derive(Component, Clone, Debug, PartialEq)]
pub struct ListedPart(pub PartJson);
