//! The pinhole camera model with OpenCV conventions (x right, y down, z forward; integer pixel
//! coordinates are pixel centres).

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Pinhole {
    pub width: u32,
    pub height: u32,
    pub fx: f32,
    pub fy: f32,
    pub cx: f32,
    pub cy: f32,
}

impl Pinhole {
    /// The Kinect-like camera the renderer uses: 640x480, 525 px focal length.
    pub const KINECT: Pinhole = Pinhole {
        width: 640,
        height: 480,
        fx: 525.0,
        fy: 525.0,
        cx: 319.5,
        cy: 239.5,
    };

    /// Pixel coordinates of `point_in_camera` (which must have z > 0).
    pub fn project(&self, point_in_camera: Vec3) -> Vec2 {
        Vec2::new(
            self.fx * point_in_camera.x / point_in_camera.z + self.cx,
            self.fy * point_in_camera.y / point_in_camera.z + self.cy,
        )
    }

    /// The camera-frame point at pixel `(u, v)` whose depth (z) is `depth`.
    pub fn unproject(&self, u: f32, v: f32, depth: f32) -> Vec3 {
        Vec3::new(
            (u - self.cx) / self.fx * depth,
            (v - self.cy) / self.fy * depth,
            depth,
        )
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}
