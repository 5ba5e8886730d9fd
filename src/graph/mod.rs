//! The contact graph: scene entities as nodes, support and proximal relations as edges.

pub mod contact_graph;

pub use contact_graph::{BoxJson, CadPlacement, ContactGraph, GraphEdge, GraphNode};
