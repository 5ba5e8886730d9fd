//! Plain geometric types shared by every stage: triangle meshes, gravity-aligned boxes, planes.

pub mod clusters;
pub mod convex_depth;
pub mod gravity_box;
pub mod mesh;
pub mod mesh_topology;
pub mod min_area_rect;
pub mod pinhole;
pub mod plane;
pub mod point_triangle;
pub mod principal_axis;
pub mod ransac;
pub mod surface_points;

pub use gravity_box::GravityBox;
pub use mesh::TriMesh;
pub use pinhole::Pinhole;
pub use plane::Plane;
