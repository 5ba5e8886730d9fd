//! Perceiving how furniture opens from what the camera saw (issue 36): the handles and knobs on
//! an object's front and the motion of the part each belongs to. Bevy-free; uses geometry and the map's median.

pub mod handles;
