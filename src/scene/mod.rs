//! Synthetic scenes: the JSON specification and the world it describes, with its ground truth.

pub mod generate;
pub mod ground_truth;
pub mod overlap;
pub mod placement;
pub mod render_sequence;
pub mod spec;
pub mod world;

pub use render_sequence::{RenderOptions, RenderSummary, render_sequence};
pub use spec::SceneSpec;
pub use world::{SceneWorld, Support};

/// The built-in kitchen's ground-truth contact graph, for unit tests.
#[cfg(test)]
pub fn kitchen_contact_graph() -> crate::graph::ContactGraph {
    let path = std::path::Path::new("kitchen.json");
    let spec = SceneSpec::parse(include_str!("../../scenes/kitchen.json"), path).expect("spec");
    SceneWorld::from_spec(&spec, path)
        .expect("world")
        .contact_graph()
}
