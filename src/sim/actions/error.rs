//! Why an action cannot be done.

/// Why an action cannot be done: the precondition that fails. The message is the trace's
/// `failed_precondition`; a planner can match on the kind (an object the scene lacks, a closed
/// container, something out of reach) to try another way.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ActionError {
    #[error("the scene has no robot")]
    NoRobot,
    #[error("{0} is not in the scene")]
    NotInScene(String),
    #[error("{0} is not a surface of the scene")]
    NotASurface(String),
    #[error("no free spot on {0}")]
    NoFreeSpot(String),
    #[error("{0} is not a container")]
    NotAContainer(String),
    #[error("{0} is closed")]
    Closed(String),
    #[error("{object} does not fit in {container}")]
    DoesNotFit { object: String, container: String },
    #[error("no place near {0} to work its doors from")]
    NoPlaceToWorkDoors(String),
    #[error("{part} would hit {hit} at {at:.2}")]
    WouldHit { part: String, hit: String, at: f32 },
    #[error("{part} hits {hit} at {at:.2} before it is open")]
    HitsBeforeOpen { part: String, hit: String, at: f32 },
    #[error("no path for the base to {0}")]
    NoPath(String),
    #[error("no way to get within reach of the free spot on {0}")]
    NoWayToSpot(String),
    #[error("the scene has no floor to drive on")]
    NoFloor,
    #[error("the floor is empty")]
    EmptyFloor,
    #[error("{0} has no door or drawer")]
    NotArticulated(String),
    #[error("{object} has no part {part}")]
    NoSuchPart { object: String, part: String },
    #[error("{object} is {distance_m:.2} m from the robot, beyond its reach of {reach_m:.2} m")]
    BeyondReach {
        object: String,
        distance_m: f32,
        reach_m: f32,
    },
    #[error("{0} is above the robot's reach")]
    AboveReach(String),
    #[error("the robot holds {held}, not {object}")]
    HoldsAnother { held: String, object: String },
    #[error("the robot does not hold {0}")]
    NotHolding(String),
    #[error("the robot already holds {0}")]
    AlreadyHolding(String),
    #[error("{0} is not movable")]
    NotMovable(String),
    #[error("{top} stands on {object}")]
    StandsOn { top: String, object: String },
    #[error("{object} is inside {container}, which is closed")]
    InsideClosed { object: String, container: String },
    #[error("{0} has no geometry")]
    NoGeometry(String),
    #[error("the robot holds {0}")]
    Holds(String),
    #[error("{0} stands on nothing")]
    StandsOnNothing(String),
    #[error("a push needs a direction and a positive distance")]
    BadPush,
    #[error("{object} would run into something after {after_m:.2} m")]
    WouldRunInto { object: String, after_m: f32 },
    #[error("{object} would slide off {support}")]
    WouldSlideOff { object: String, support: String },
    #[error("{object} has no side narrower than the gripper's {width_m:.3} m")]
    NoGrasp { object: String, width_m: f32 },
    #[error("the arm cannot {what}: {}", attempts.join("; "))]
    ArmCannot { what: String, attempts: Vec<String> },
}

/// The arm's failures from several places (base poses, spots), each reason with its place, and
/// the first reason the base got to none of them.
#[derive(Default)]
pub(super) struct ArmTries {
    what: String,
    attempts: Vec<String>,
    unreached: Option<ActionError>,
}

impl ArmTries {
    /// The base could not get to a place; the first such reason is kept.
    pub fn unreached(&mut self, e: ActionError) {
        self.unreached.get_or_insert(e);
    }

    /// The arm's failure from the place `at` (in words) is recorded; any other error is not the
    /// arm's and comes back.
    pub fn failed(&mut self, at: &str, e: ActionError) -> Result<(), ActionError> {
        match e {
            ActionError::ArmCannot { what, attempts } => {
                self.what = what;
                self.attempts
                    .extend(attempts.into_iter().map(|r| format!("{at}, {r}")));
                Ok(())
            }
            other => Err(other),
        }
    }

    /// Why nothing worked: the base's reason when the arm was tried nowhere, else the arm's
    /// attempts at `what` (the failures' own words when `None`).
    pub fn error(self, what: Option<String>) -> ActionError {
        match self.unreached {
            Some(e) if self.attempts.is_empty() => e,
            _ => ActionError::ArmCannot {
                what: what.unwrap_or(self.what),
                attempts: self.attempts,
            },
        }
    }
}
