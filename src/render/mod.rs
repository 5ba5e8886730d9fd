//! A CPU renderer of RGB-D sequences with ground truth: colour, 16-bit depth and instance labels
//! of a synthetic world along a camera path, with Kinect-like depth noise.

pub mod noise;
pub mod pose_noise;
pub mod raster;
pub mod render_scene;
pub mod shading;
pub mod trajectory;

pub use noise::{DepthNoise, NoiseSettings};
pub use raster::{RasterFrame, rasterize};
pub use render_scene::RenderScene;
