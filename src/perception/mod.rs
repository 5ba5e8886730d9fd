//! Perceiving how furniture opens from what the camera saw (issue 36): the handles and knobs on
//! an object's front and the motion of the part each belongs to. Bevy-free; uses only geometry.

pub mod handles;
