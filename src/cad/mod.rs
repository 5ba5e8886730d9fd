//! The CAD database and replacement:
//! - `model`, `model_parts`, `placed_solid`: what a model is (parts, joints, meshes), its moving
//!   parts, and a placed model as solids;
//! - `db`: the database on disk (index, load, write);
//! - `library`: the parametric generators of the built-in library;
//! - `import`: Sweet Home 3D catalogues, MJCF and URDF files, mesh files, into models;
//! - `replace`: the replacement stage (ranking, orientations, alignment, ICP, shape filters, the
//!   physical check, separation).

pub mod db;
pub mod import;
pub mod library;
pub mod model;
pub mod model_parts;
pub mod placed_solid;
pub mod replace;

pub use library::{ModelBuilder, ParametricLibrary};
pub use model::{CadModel, CadPart};
