//! The replacement stage: every object's model chosen, oriented, aligned and checked
//! (Han et al., Sect. 4; the ICP route and shape filters of Sivananda et al.).

pub mod alignment;
pub mod height_fit;
pub mod icp;
pub mod matching;
pub mod observed_objects;
pub mod on_holder;
pub mod orientation;
pub mod physical_check;
pub mod placement_verdict;
pub mod replacement;
pub mod separation;
pub mod shape_filter;
pub mod sizing;
pub mod snapping;
pub mod synthesis;
