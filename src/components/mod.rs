//! ECS components: the vocabulary of a scene entity.
//!
//! A scene entity (a piece of layout or an object) carries its `SceneEntity` id and `Panoptic`
//! identity, its `OrientedBox`, `SurfacePlanes`, `SegmentMesh` from the panoptic map, the
//! `SightedOutline` precise frames measured of it, the `ObservedSurface` the contact graph kept
//! of it, the `PerceivedFront` of a door or drawer unit, the CAD stages' `CadCandidates`,
//! `CadAlignments` or `ShapeRejection`, once replaced
//! its `CadModel`, and in the kinematic tree its `LinkBody`; each moving
//! part of its model is a child entity with a `ModelPart`, a `LinkBody`, a `Joint` and the
//! `ListedPart` the contact graph lists it as. Support
//! is Bevy's `ChildOf`: the parent supports the child, and the child's `Joint` says how it may
//! move relative to it. A robot with an arm has a `RobotArmLink` entity per link of the arm.
//! A proximal pair is an entity of its own, related to both ends (`ProximalEndA`,
//! `ProximalEndB`).

pub mod cad_candidates;
pub mod cad_model;
pub mod joint;
pub mod link_body;
pub mod listed_part;
pub mod model_part;
pub mod observed_surface;
pub mod oriented_box;
pub mod panoptic;
pub mod perceived_front;
pub mod proximal;
pub mod robot_arm_link;
pub mod segment_mesh;
pub mod sighted_outline;
pub mod surface_planes;

pub use cad_candidates::{CadAlignments, CadCandidates, ShapeRejection};
pub use cad_model::CadModel;
pub use joint::Joint;
pub use link_body::LinkBody;
pub use listed_part::ListedPart;
pub use model_part::ModelPart;
pub use observed_surface::{CounterBody, ObservedSurface};
pub use oriented_box::OrientedBox;
pub use panoptic::{Panoptic, SceneEntity};
pub use perceived_front::PerceivedFront;
pub use proximal::{
    ProximalEndA, ProximalEndB, ProximalPairQuery, ProximalPairsAsA, ProximalPairsAsB,
    proximal_partners,
};
pub use robot_arm_link::RobotArmLink;
pub use segment_mesh::SegmentMesh;
pub use sighted_outline::SightedOutline;
pub use surface_planes::SurfacePlanes;
