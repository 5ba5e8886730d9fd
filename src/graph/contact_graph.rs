//! `contact_graph.json` of DESIGN.md: the data types, their checks and their file form.

use std::collections::{BTreeMap, HashSet};
use std::path::Path;

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::classes::EntityKind;
use crate::error::InputError;
use crate::geometry::GravityBox;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxJson {
    pub center: [f32; 3],
    pub yaw: f32,
    pub size: [f32; 3],
}

impl From<GravityBox> for BoxJson {
    fn from(b: GravityBox) -> Self {
        Self {
            center: b.center.to_array(),
            yaw: b.yaw,
            size: b.size.to_array(),
        }
    }
}

impl From<&BoxJson> for GravityBox {
    fn from(b: &BoxJson) -> Self {
        GravityBox {
            center: Vec3::from_array(b.center),
            yaw: b.yaw,
            size: Vec3::from_array(b.size),
        }
    }
}

/// Which CAD model replaces the entity and where it stands.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CadPlacement {
    pub model: String,
    /// Column-major 4x4.
    pub world_from_model: [f32; 16],
    pub scale: f32,
    pub alignment_error: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraphNode {
    pub id: String,
    pub class: String,
    pub kind: EntityKind,
    #[serde(rename = "box")]
    pub bbox: BoxJson,
    /// `[nx, ny, nz, d]` with `n . x + d = 0`, world frame.
    pub planes: Vec<[f32; 4]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cad: Option<CadPlacement>,
    /// Joint values of the CAD model's moving parts, by part name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joints: BTreeMap<String, f32>,
    /// Its doors and drawers with their joints, world frame.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub parts: Vec<crate::graph::parts::PartJson>,
}

#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum GraphEdge {
    /// `parent` holds `child` up against gravity (or, for a wall, carries it).
    Support { parent: String, child: String },
    /// Boxes overlap or touch without support: the meshes must not interpenetrate.
    Proximal { a: String, b: String },
}

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactGraph {
    pub nodes: Vec<GraphNode>,
    pub edges: Vec<GraphEdge>,
}

/// What makes a contact graph malformed, whatever its schema allows.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum GraphError {
    #[error("nodes: {0} nodes, more than the {MAX_NODES} a room's graph may have")]
    TooManyNodes(usize),
    #[error("nodes: duplicate id {0:?}")]
    DuplicateId(String),
    /// An id that cannot name the files made for it (`file_name::check_file_name`'s reason).
    #[error("nodes: {0}")]
    BadId(crate::file_name::FileNameError),
    #[error("node {0:?}: NaN or infinite number in its box or planes")]
    NotFinite(String),
    #[error("edges: unknown node {0:?}")]
    UnknownNode(String),
    #[error("edges: {0:?} has two support parents")]
    TwoParents(String),
    #[error("edges: support cycle through {0:?}")]
    SupportCycle(String),
    #[error("edges: {0:?} stands on a stack of more than {MAX_SUPPORT_DEPTH} objects")]
    TooDeep(String),
}

/// The most nodes a contact graph read from a file may have.
pub const MAX_NODES: usize = 2000;
/// The tallest stack of objects on one another a graph may describe (the kinematic tree follows
/// it, and its exports recurse along it).
pub const MAX_SUPPORT_DEPTH: usize = 32;

impl ContactGraph {
    pub fn node(&self, id: &str) -> Option<&GraphNode> {
        self.nodes.iter().find(|n| n.id == id)
    }

    /// The supporting parent of `id`, if any.
    pub fn parent_of(&self, id: &str) -> Option<&str> {
        self.edges.iter().find_map(|e| match e {
            GraphEdge::Support { parent, child } if child == id => Some(parent.as_str()),
            _ => None,
        })
    }

    pub fn support_edges(&self) -> impl Iterator<Item = (&str, &str)> {
        self.edges.iter().filter_map(|e| match e {
            GraphEdge::Support { parent, child } => Some((parent.as_str(), child.as_str())),
            GraphEdge::Proximal { .. } => None,
        })
    }

    /// Checks what the schema cannot: unique ids, edges between known nodes, at most one support
    /// parent per node, no support cycles, finite numbers.
    pub fn check(&self) -> Result<(), GraphError> {
        if self.nodes.len() > MAX_NODES {
            return Err(GraphError::TooManyNodes(self.nodes.len()));
        }
        let mut ids = HashSet::new();
        for n in &self.nodes {
            if !ids.insert(n.id.as_str()) {
                return Err(GraphError::DuplicateId(n.id.clone()));
            }
            crate::file_name::check_file_name(&n.id).map_err(GraphError::BadId)?;
            let finite = n
                .bbox
                .center
                .iter()
                .chain(&n.bbox.size)
                .all(|v| v.is_finite())
                && n.bbox.yaw.is_finite();
            if !finite || n.planes.iter().flatten().any(|v| !v.is_finite()) {
                return Err(GraphError::NotFinite(n.id.clone()));
            }
        }
        let mut children = HashSet::new();
        for e in &self.edges {
            let (a, b) = match e {
                GraphEdge::Support { parent, child } => (parent, child),
                GraphEdge::Proximal { a, b } => (a, b),
            };
            for id in [a, b] {
                if !ids.contains(id.as_str()) {
                    return Err(GraphError::UnknownNode(id.clone()));
                }
            }
            if let GraphEdge::Support { child, .. } = e
                && !children.insert(child.as_str())
            {
                return Err(GraphError::TwoParents(child.clone()));
            }
        }
        let parents: std::collections::HashMap<&str, &str> =
            self.support_edges().map(|(p, c)| (c, p)).collect();
        for n in &self.nodes {
            let mut current = n.id.as_str();
            for depth in 0..=self.nodes.len() {
                match parents.get(current) {
                    Some(p) => current = p,
                    None => break,
                }
                if current == n.id {
                    return Err(GraphError::SupportCycle(n.id.clone()));
                }
                if depth >= MAX_SUPPORT_DEPTH {
                    return Err(GraphError::TooDeep(n.id.clone()));
                }
            }
        }
        Ok(())
    }

    pub fn load(path: &Path) -> Result<ContactGraph, InputError> {
        let text = std::fs::read_to_string(path).map_err(|e| InputError::io(path, &e))?;
        let graph: ContactGraph = serde_json::from_str(&text)
            .map_err(|e| InputError::invalid(path, format!("invalid contact graph: {e}")))?;
        graph
            .check()
            .map_err(|e| InputError::invalid(path, e.to_string()))?;
        Ok(graph)
    }

    pub fn to_json(&self) -> String {
        // Plain data of strings and finite floats cannot fail to serialise.
        serde_json::to_string_pretty(self).unwrap_or_default()
    }
}
