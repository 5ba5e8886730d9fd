//! Perceiving how furniture opens from what the camera saw (issue 36): the handles and knobs on
//! an object's front, the motion of the part each belongs to, and how far a CAD model's handles
//! agree with the perceived ones. Bevy-free; uses geometry, the map's median and the contact
//! graph's surface sampling.

pub mod front_marks;
pub mod front_texture;
pub mod fronts;
pub mod handles;
pub mod open_doors;
pub mod open_drawers;
pub mod parts;
