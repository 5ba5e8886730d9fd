//! Proximal relations: entities whose boxes overlap or touch without one supporting the other.
//! Their meshes must not interpenetrate (the CAD stage's constraint). One rule for the ground
//! truth and the reconstruction, so the two are comparable.

use crate::geometry::GravityBox;
use crate::graph::GraphEdge;

/// Boxes closer than this (metres) count as touching.
pub const PROXIMAL_MARGIN: f32 = 0.02;

/// How close two boxes must be (metres) to count as touching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProximalMargins {
    /// Between two objects.
    pub objects: f32,
    /// Between an object and a wall.
    pub wall: f32,
}

impl ProximalMargins {
    /// For exact boxes (the ground truth): `PROXIMAL_MARGIN` everywhere.
    pub const EXACT: Self = Self {
        objects: PROXIMAL_MARGIN,
        wall: PROXIMAL_MARGIN,
    };
}

/// Proximal edges among `nodes` (id, box, class), in node order: boxes closer than the margin
/// for the pair, leaving out pairs related by a support edge in `supports` (parent, child).
/// Floor and ceiling only ever support; walls are proximal to what stands against them but not to
/// each other.
pub fn proximal_edges(
    nodes: &[(&str, GravityBox, &str)],
    supports: &[(&str, &str)],
    margins: ProximalMargins,
) -> Vec<GraphEdge> {
    let related = |a: &str, b: &str| {
        supports
            .iter()
            .any(|&(p, c)| (p == a && c == b) || (p == b && c == a))
    };
    let only_supports = |class: &str| class == "floor" || class == "ceiling";
    let mut edges = Vec::new();
    for (i, (a, box_a, class_a)) in nodes.iter().enumerate() {
        for (b, box_b, class_b) in &nodes[i + 1..] {
            if only_supports(class_a)
                || only_supports(class_b)
                || (*class_a == "wall" && *class_b == "wall")
                || related(a, b)
            {
                continue;
            }
            let margin = if *class_a == "wall" || *class_b == "wall" {
                margins.wall
            } else {
                margins.objects
            };
            if box_a.overlaps(box_b, margin) {
                edges.push(GraphEdge::Proximal {
                    a: a.to_string(),
                    b: b.to_string(),
                });
            }
        }
    }
    edges
}
