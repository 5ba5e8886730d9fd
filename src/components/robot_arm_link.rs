//! A link of the robot's arm as an entity of the world.

use bevy::prelude::*;

/// Link `0` of the robot's arm (an index into the arm's links), a child of the robot's base
/// entity at its pose for the arm's configuration. The arm is part of the world, and the motion
/// check drives these entities as rapier's kinematic bodies; it is no link of the scene's
/// kinematic tree (the exports describe the room, the trace and the trajectory the robot).
#[derive(Component, Clone, Copy, Debug, PartialEq, Eq)]
pub struct RobotArmLink(pub usize);
