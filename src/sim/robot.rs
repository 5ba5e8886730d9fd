//! The simulated robot: a round mobile base with a gripper on top of it, described by the
//! figures the actions check (footprint, reach, gripper height) and the meshes its links get.

use glam::{Affine3A, Vec2, Vec3};
use serde::{Deserialize, Serialize};

use crate::arm::rig::ArmRig;
use crate::geometry::TriMesh;

/// The robot's base link name in the kinematic tree and the exports.
pub const ROBOT_LINK: &str = "robot";
/// The gripper link (a child of the base); a held object rides on it.
pub const GRIPPER_LINK: &str = "robot_gripper";

/// What the actions need to know about the robot; the defaults are a Fetch-sized base.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RobotSpec {
    /// Radius of the round base's footprint, metres (navigation keeps this far from obstacles).
    pub radius: f32,
    /// Height of the base column, metres; with an arm, where its root rides when stowed.
    pub height: f32,
    /// Horizontal distance from the base's centre the gripper reaches, metres.
    pub reach: f32,
    /// The highest point the gripper reaches, metres above the floor.
    pub max_reach_height: f32,
    /// With an arm: the lowest and highest height of its root on a lift, metres above the
    /// floor (holding `height`); the column is as high as the lowest. `None`: a fixed column.
    pub lift: Option<[f32; 2]>,
}

impl Default for RobotSpec {
    fn default() -> Self {
        Self {
            radius: 0.25,
            height: 1.1,
            reach: 1.0,
            max_reach_height: 1.8,
            lift: None,
        }
    }
}

/// Where the robot stands: the base centre on the floor and its heading about +z.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BasePose {
    pub position: Vec2,
    /// Radians from +x.
    pub yaw: f32,
}

impl BasePose {
    pub fn world_from_base(&self) -> Affine3A {
        Affine3A::from_rotation_translation(
            glam::Quat::from_rotation_z(self.yaw),
            self.position.extend(0.0),
        )
    }

    /// Facing `target` from `position`.
    pub fn facing(position: Vec2, target: Vec2) -> Self {
        let d = target - position;
        Self {
            position,
            yaw: d.y.atan2(d.x),
        }
    }
}

impl RobotSpec {
    /// A base carrying an arm (the Panda) on a lift, stowed at table height. On the kitchen's
    /// ground truth a fixed 0.6 m column left the bottle on the counter (its neck at 1.15 m)
    /// out of reach and 0.75 m reached all seven picks and places tried, but not the handles
    /// of the doors under the counter (39-48 cm up), which a 0.45 m column did: the lift
    /// takes the root from 0.4 to 1.1 m (Stretch's lift travels 1.1 m, Fetch's torso 0.39 m).
    /// The base's own reach stays 1 m (it stands where it works a fridge's door), the picks
    /// and places stepping closer when the arm needs it.
    pub const ARM_BASE: RobotSpec = RobotSpec {
        radius: 0.25,
        height: 0.75,
        reach: 1.0,
        max_reach_height: 1.6,
        lift: Some([0.4, 1.1]),
    };

    /// Height of the base's column: the lift's lowest, else `height`.
    pub fn column_height(&self) -> f32 {
        self.lift.map_or(self.height, |[lo, _]| lo)
    }

    /// The lift's travel from `height`, where the stowed arm's root rides (`Arm::on_lift`).
    pub fn lift_travel(&self) -> Option<(f32, f32)> {
        self.lift
            .map(|[lo, hi]| (lo - self.height, hi - self.height))
    }

    /// `arm` as this base carries it: on its lift, if it has one.
    pub fn mount(&self, arm: ArmRig) -> ArmRig {
        match self.lift_travel() {
            Some(range) => arm.on_lift(range),
            None => arm,
        }
    }

    /// The base's mesh in its frame: a column standing on the floor, a centimetre narrower
    /// than the footprint so that touching clearance is not contact.
    pub fn base_mesh(&self) -> TriMesh {
        TriMesh::cylinder(Vec3::ZERO, self.radius - 0.01, self.column_height(), 16)
    }

    /// The gripper's frame in the base's: on top of the column. A held object rides on it,
    /// inside the base's footprint, so it never sweeps into furniture the base clears.
    pub fn base_from_gripper(&self) -> Affine3A {
        Affine3A::from_translation(Vec3::new(0.0, 0.0, self.height + 0.02))
    }

    /// The gripper's mesh in its frame: a plate just below the held object.
    pub fn gripper_mesh(&self) -> TriMesh {
        let r = 0.5 * self.radius;
        TriMesh::cuboid(Vec3::new(-r, -r, -0.02), Vec3::new(r, r, -0.001))
    }
}
