//! The contact graph: scene entities as nodes, support and proximal relations as edges.

pub mod build;
pub mod contact_graph;
pub mod counters;
pub mod entity_shape;
pub mod floor_units;
pub mod gravity;
pub mod layout_plane;
pub mod parts;
pub mod proximal;
pub mod sighted_extent;
pub mod sparse_ends;
pub mod support;

pub use contact_graph::{BoxJson, CadPlacement, ContactGraph, GraphEdge, GraphError, GraphNode};
