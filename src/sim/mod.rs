//! The reconstructed scene as a world a robot acts in: the robot, navigation on the occupancy
//! layer, actions with their preconditions and effects on the kinematic tree, the symbolic state
//! and the task planner over it, and its PDDL export. Bevy-free; `systems::simulation` runs it
//! in the ECS.

pub mod actions;
pub mod arm_phases;
pub mod graph_sync;
pub mod motion_check;
pub mod motion_path;
pub mod navigation;
pub mod pddl;
pub mod planner;
pub mod replay;
pub mod robot;
pub mod scene_view;
pub mod symbolic;
pub mod task;
pub mod trajectory;
