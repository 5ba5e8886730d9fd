//! The symbolic state the task planner works on, read off the scene: where the robot is, what
//! it holds, what stands on or inside what, which containers and which of their other doors and
//! drawers are open; and goals parsed from text such as `cup_1 in microwave_1`, `microwave_1
//! closed` or `fridge_1 freezer open`.

use std::collections::{BTreeMap, BTreeSet};

use serde::Serialize;

use crate::sim::scene_view::SceneView;

/// The robot's place before its first navigation.
pub const START_PLACE: &str = "start";

/// One ground fact.
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Fact {
    /// The robot stands at place `0` (a node it navigated to, or `start`).
    RobotAt(String),
    Holding(String),
    HandEmpty,
    /// Object `0` stands on `1`.
    On(String, String),
    /// Object `0` is inside container `1`.
    Inside(String, String),
    IsOpen(String),
    IsClosed(String),
    /// A door or drawer of a container other than its main one (by its link's name,
    /// `fridge_1_freezer`) is open.
    PartOpen(String),
    PartClosed(String),
    /// Nothing stands on `0`.
    Clear(String),
}

impl Fact {
    /// The fact as a PDDL atom: `(inside box_1 microwave_1)`.
    pub fn pddl(&self) -> String {
        match self {
            Fact::RobotAt(p) => format!("(robot-at {p})"),
            Fact::Holding(o) => format!("(holding {o})"),
            Fact::HandEmpty => "(hand-empty)".into(),
            Fact::On(o, s) => format!("(on {o} {s})"),
            Fact::Inside(o, c) => format!("(inside {o} {c})"),
            Fact::IsOpen(c) => format!("(is-open {c})"),
            Fact::IsClosed(c) => format!("(is-closed {c})"),
            Fact::PartOpen(p) => format!("(part-open {p})"),
            Fact::PartClosed(p) => format!("(part-closed {p})"),
            Fact::Clear(o) => format!("(clear {o})"),
        }
    }
}

/// The scene's symbolic description: the objects by role, the static place each support's
/// objects are picked from, and the facts that hold now.
#[derive(Clone, Debug, Default)]
pub struct SymbolicScene {
    /// Movable objects (cups, boxes, chairs).
    pub movables: Vec<String>,
    /// Fixed non-layout nodes objects can be set down on.
    pub surfaces: Vec<String>,
    /// Nodes with doors or drawers.
    pub containers: Vec<String>,
    /// Each container's main part (the door or drawer its own `open` and `close` work), by
    /// part name (`door`): a goal naming it is the container's.
    pub main_parts: BTreeMap<String, String>,
    /// The containers' other doors and drawers: link name (`fridge_1_freezer`) to the
    /// container and the part's name (`freezer`).
    pub parts: BTreeMap<String, (String, String)>,
    /// Places the robot navigates to (every node it works at).
    pub places: Vec<String>,
    /// `(object, support)` to the place the robot picks it there from.
    pub pick_places: BTreeMap<(String, String), String>,
    pub facts: BTreeSet<Fact>,
    /// The robot's one hand opens and closes doors and drawers by their handles (an arm): it
    /// must be empty to do so. A base without an arm works them without its gripper.
    pub hand_works_parts: bool,
}

/// Reads the symbolic scene from `view`; `robot_at` is the robot's place (`start` before it
/// moved).
pub fn symbolic_scene(view: &SceneView, robot_at: &str, holding: Option<&str>) -> SymbolicScene {
    let mut s = SymbolicScene::default();
    let nodes = view.nodes();
    for n in &nodes {
        if view.is_layout(n) {
            continue;
        }
        if view.is_movable(n) {
            s.movables.push(n.to_string());
        } else {
            s.surfaces.push(n.to_string());
            if view.is_container(n) {
                s.containers.push(n.to_string());
            }
        }
    }
    // Where the robot stands to pick an object off its support: the support itself when it is
    // fixed furniture, the object itself when it stands on the floor (a chair), and for an
    // object on a movable one (a magazine on a chair) wherever that one is picked from.
    let place_of = |object: &str, support: &str| -> String {
        let mut o = object.to_string();
        let mut sup = support.to_string();
        loop {
            if view.is_layout(&sup) {
                return o;
            }
            if !view.is_movable(&sup) {
                return sup;
            }
            let Some(next) = view.support_of(&sup) else {
                return sup;
            };
            o = sup;
            sup = next.to_string();
        }
    };
    for o in &s.movables {
        // Any surface it may be set on, and where it stands now.
        let mut supports: Vec<String> = s.surfaces.clone();
        if let Some(now) = view.support_of(o)
            && !supports.iter().any(|x| x == now)
        {
            supports.push(now.to_string());
        }
        for sup in supports {
            let place = place_of(o, &sup);
            s.pick_places.insert((o.clone(), sup), place);
        }
    }
    let mut places: BTreeSet<String> = s.surfaces.iter().cloned().collect();
    places.extend(s.pick_places.values().cloned());
    s.places = places.into_iter().collect();

    s.facts.insert(Fact::RobotAt(robot_at.to_string()));
    match holding {
        Some(h) => {
            s.facts.insert(Fact::Holding(h.to_string()));
        }
        None => {
            s.facts.insert(Fact::HandEmpty);
        }
    }
    for o in &s.movables {
        if holding == Some(o.as_str()) {
            continue;
        }
        if let Some(sup) = view.support_of(o) {
            if view.is_inside(o, sup) {
                s.facts.insert(Fact::Inside(o.clone(), sup.to_string()));
            } else {
                s.facts.insert(Fact::On(o.clone(), sup.to_string()));
            }
        }
    }
    for n in nodes.iter().filter(|n| !view.is_layout(n)) {
        if !nodes.iter().any(|m| view.support_of(m) == Some(n)) {
            s.facts.insert(Fact::Clear(n.to_string()));
        }
    }
    for c in &s.containers {
        s.facts.insert(if view.is_open(c) {
            Fact::IsOpen(c.clone())
        } else {
            Fact::IsClosed(c.clone())
        });
        let prefix = format!("{c}_");
        for (k, joint) in view.moving_parts(c).into_iter().enumerate() {
            let link = &view.tree.links[joint].name;
            let Some(name) = link.strip_prefix(&prefix) else {
                continue;
            };
            if k == 0 {
                s.main_parts.insert(c.clone(), name.to_string());
                continue;
            }
            s.parts.insert(link.clone(), (c.clone(), name.to_string()));
            s.facts.insert(if view.is_part_open(joint) {
                Fact::PartOpen(link.clone())
            } else {
                Fact::PartClosed(link.clone())
            });
        }
    }
    s
}

/// A goal of a task that is not one the planner reads.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum GoalError {
    #[error("goal {goal:?}: {id} is not a {role} of the scene")]
    Unknown {
        goal: String,
        id: String,
        role: &'static str,
    },
    #[error("goal {goal:?}: {container} has no door or drawer {part:?} (it has: {known})")]
    UnknownPart {
        goal: String,
        container: String,
        part: String,
        known: String,
    },
    #[error(
        "goal {0:?} is not one of: A on B, A in B, A open, A closed, A PART open, A PART closed, \
         holding A, robot at P"
    )]
    NotAGoal(String),
}

/// Parses one goal: `A on B`, `A in B`, `A open`, `A closed`, `A PART open`, `A PART closed`
/// (a door or drawer of container A by its name: `fridge_1 freezer open`), `holding A`, `robot
/// at P`.
pub fn parse_goal(text: &str, scene: &SymbolicScene) -> Result<Fact, GoalError> {
    let words: Vec<&str> = text.split_whitespace().collect();
    let known = |id: &str, among: &[String], role: &'static str| {
        if among.iter().any(|x| x == id) {
            Ok(id.to_string())
        } else {
            Err(GoalError::Unknown {
                goal: text.to_string(),
                id: id.to_string(),
                role,
            })
        }
    };
    match words.as_slice() {
        [o, "on", s] => Ok(Fact::On(
            known(o, &scene.movables, "movable object")?,
            known(s, &scene.surfaces, "surface")?,
        )),
        [o, "in", c] => Ok(Fact::Inside(
            known(o, &scene.movables, "movable object")?,
            known(c, &scene.containers, "container")?,
        )),
        [c, "open"] => Ok(Fact::IsOpen(known(c, &scene.containers, "container")?)),
        [c, "closed"] => Ok(Fact::IsClosed(known(c, &scene.containers, "container")?)),
        [c, part, state @ ("open" | "closed")] => {
            let c = known(c, &scene.containers, "container")?;
            let open = *state == "open";
            if scene.main_parts.get(&c).is_some_and(|m| m == part) {
                return Ok(if open {
                    Fact::IsOpen(c)
                } else {
                    Fact::IsClosed(c)
                });
            }
            let link = format!("{c}_{part}");
            if !scene.parts.contains_key(&link) {
                let known: Vec<&str> = scene
                    .main_parts
                    .get(&c)
                    .into_iter()
                    .chain(
                        scene
                            .parts
                            .values()
                            .filter(|(o, _)| *o == c)
                            .map(|(_, p)| p),
                    )
                    .map(String::as_str)
                    .collect();
                return Err(GoalError::UnknownPart {
                    goal: text.to_string(),
                    container: c,
                    part: part.to_string(),
                    known: known.join(", "),
                });
            }
            Ok(if open {
                Fact::PartOpen(link)
            } else {
                Fact::PartClosed(link)
            })
        }
        ["holding", o] => Ok(Fact::Holding(known(o, &scene.movables, "movable object")?)),
        ["robot", "at", p] => Ok(Fact::RobotAt(known(p, &scene.places, "place")?)),
        _ => Err(GoalError::NotAGoal(text.to_string())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_goal_names_a_door_or_drawer_by_its_container_and_name() {
        let mut scene = SymbolicScene {
            containers: vec!["fridge_1".into()],
            ..Default::default()
        };
        scene.main_parts.insert("fridge_1".into(), "door".into());
        scene.parts.insert(
            "fridge_1_freezer".into(),
            ("fridge_1".into(), "freezer".into()),
        );
        assert_eq!(
            parse_goal("fridge_1 freezer open", &scene),
            Ok(Fact::PartOpen("fridge_1_freezer".into()))
        );
        assert_eq!(
            parse_goal("fridge_1  freezer closed", &scene),
            Ok(Fact::PartClosed("fridge_1_freezer".into()))
        );
        // The main part is the container's own open and close.
        assert_eq!(
            parse_goal("fridge_1 door open", &scene),
            Ok(Fact::IsOpen("fridge_1".into()))
        );
        let wrong = parse_goal("fridge_1 shelf open", &scene).expect_err("no shelf");
        assert_eq!(
            wrong.to_string(),
            "goal \"fridge_1 shelf open\": fridge_1 has no door or drawer \"shelf\" (it has: door, \
             freezer)"
        );
        assert!(matches!(
            parse_goal("oven_1 door open", &scene),
            Err(GoalError::Unknown { .. })
        ));
        assert!(matches!(
            parse_goal("fridge_1 freezer ajar", &scene),
            Err(GoalError::NotAGoal(_))
        ));
    }
}
