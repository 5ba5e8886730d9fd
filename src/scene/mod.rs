//! Synthetic scenes: the JSON specification and the world it describes, with its ground truth.

pub mod ground_truth;
pub mod placement;
pub mod spec;
pub mod world;

pub use spec::SceneSpec;
pub use world::{SceneWorld, Support};
