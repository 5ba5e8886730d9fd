//! The integration tests, one module per area, in one test binary.
//!
//! One binary rather than one per file: each test binary links the whole Bevy and rapier stack,
//! and on CI's two cores those thirteen links and builds were minutes of the test budget. Every
//! test uses its own temporary folder, so tests from different files may run side by side.

mod common;

mod arm;
mod bad_input;
mod batch;
mod cad_import;
mod cad_library;
mod cad_replacement;
mod contact_graph;
mod exports;
mod fuzz_corpora;
mod gravity;
mod held_out;
mod hostile_input;
mod layers;
mod live;
mod model_import;
mod onnx;
mod panoptic;
mod perceived_parts;
mod pipeline;
mod readers;
mod render_ground_truth;
mod simulation;
mod viewer;
