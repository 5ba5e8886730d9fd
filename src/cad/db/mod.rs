//! The CAD database on disk: its index and model files, read and written.

pub mod database;
pub mod export;
pub mod load;
