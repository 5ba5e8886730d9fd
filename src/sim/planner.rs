//! The task planner: STRIPS operators for the robot's actions, grounded on the symbolic scene,
//! and A* with the admissible h_max heuristic, so the plan it returns is a shortest one (the
//! search is complete: it answers `None` only when no plan exists).
//!
//! The operators are exactly those `pddl` writes, so a PDDL planner finds plans of the same
//! length on the exported domain and problem.

use std::collections::{BinaryHeap, HashMap};

use crate::sim::actions::Action;
use crate::sim::symbolic::{Fact, START_PLACE, SymbolicScene};

/// One ground operator.
#[derive(Clone, Debug)]
pub struct GroundOperator {
    /// The PDDL name with its arguments: `(pick-in box_1 fridge_1)`.
    pub name: String,
    /// The robot action it stands for.
    pub action: Action,
    pub pre: Vec<usize>,
    pub add: Vec<usize>,
    pub del: Vec<usize>,
}

/// The ground problem: the fact table, the operators, the start and the goal.
pub struct GroundProblem {
    pub facts: Vec<Fact>,
    pub operators: Vec<GroundOperator>,
    pub init: Vec<usize>,
    pub goal: Vec<usize>,
}

/// A plan: the operators' names and the actions they stand for.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub steps: Vec<(String, Action)>,
    /// States the search expanded.
    pub expanded: usize,
    /// The facts that hold once the plan has run (where later goals are planned from).
    pub end: Vec<Fact>,
}

struct FactTable {
    facts: Vec<Fact>,
    index: HashMap<Fact, usize>,
}

impl FactTable {
    fn id(&mut self, f: Fact) -> usize {
        if let Some(&i) = self.index.get(&f) {
            return i;
        }
        self.facts.push(f.clone());
        self.index.insert(f, self.facts.len() - 1);
        self.facts.len() - 1
    }
}

/// Grounds the operators of `scene` (the domain `pddl::domain` writes) for `goal`.
pub fn ground(scene: &SymbolicScene, goal: &[Fact]) -> GroundProblem {
    let mut t = FactTable {
        facts: Vec::new(),
        index: HashMap::new(),
    };
    let mut ops = Vec::new();
    let mut op = |t: &mut FactTable,
                  name: String,
                  action: Action,
                  pre: Vec<Fact>,
                  add: Vec<Fact>,
                  del: Vec<Fact>| {
        ops.push(GroundOperator {
            name,
            action,
            pre: pre.into_iter().map(|f| t.id(f)).collect(),
            add: add.into_iter().map(|f| t.id(f)).collect(),
            del: del.into_iter().map(|f| t.id(f)).collect(),
        });
    };
    let at = |p: &str| Fact::RobotAt(p.to_string());
    let mut origins: Vec<&str> = vec![START_PLACE];
    origins.extend(scene.places.iter().map(String::as_str));
    for from in &origins {
        for to in &scene.places {
            if from == to {
                continue;
            }
            op(
                &mut t,
                format!("(navigate {from} {to})"),
                Action::Navigate { to: to.clone() },
                vec![at(from)],
                vec![at(to)],
                vec![at(from)],
            );
        }
    }
    // With an arm the hand works the handle, so it must be empty.
    let hand = |mut pre: Vec<Fact>| {
        if scene.hand_works_parts {
            pre.push(Fact::HandEmpty);
        }
        pre
    };
    // Each container's main part, as the container's own open and close, and its other doors
    // and drawers, those the goal names only: nothing else needs them open or closed, and each
    // one ungoaled would double the states the search may visit. Per part: the operators'
    // names, the container, the part's name, and its open and closed facts.
    let mains = scene.containers.iter().map(|c| {
        (
            (format!("(open {c})"), format!("(close {c})")),
            c,
            None,
            (Fact::IsOpen(c.clone()), Fact::IsClosed(c.clone())),
        )
    });
    let others = scene
        .parts
        .iter()
        .map(|(link, (c, name))| {
            (
                (
                    format!("(open-part {link} {c})"),
                    format!("(close-part {link} {c})"),
                ),
                c,
                Some(name.clone()),
                (Fact::PartOpen(link.clone()), Fact::PartClosed(link.clone())),
            )
        })
        .filter(|(_, _, _, (open, closed))| goal.contains(open) || goal.contains(closed));
    for ((open_name, close_name), c, part, (open, closed)) in mains.chain(others) {
        op(
            &mut t,
            open_name,
            Action::Open {
                object: c.clone(),
                part: part.clone(),
                value: None,
            },
            hand(vec![at(c), closed.clone()]),
            vec![open.clone()],
            vec![closed.clone()],
        );
        op(
            &mut t,
            close_name,
            Action::Close {
                object: c.clone(),
                part,
            },
            hand(vec![at(c), open.clone()]),
            vec![closed],
            vec![open],
        );
    }
    for ((o, s), p) in &scene.pick_places {
        let (on, clear_o, clear_s) = (
            Fact::On(o.clone(), s.clone()),
            Fact::Clear(o.clone()),
            Fact::Clear(s.clone()),
        );
        op(
            &mut t,
            format!("(pick-on {o} {s} {p})"),
            Action::Pick { object: o.clone() },
            vec![at(p), on.clone(), Fact::HandEmpty, clear_o],
            vec![Fact::Holding(o.clone()), clear_s],
            vec![on, Fact::HandEmpty],
        );
    }
    for o in &scene.movables {
        for s in &scene.surfaces {
            let on = Fact::On(o.clone(), s.clone());
            op(
                &mut t,
                format!("(place-on {o} {s})"),
                Action::PlaceOn {
                    object: o.clone(),
                    surface: s.clone(),
                },
                vec![at(s), Fact::Holding(o.clone())],
                vec![on, Fact::HandEmpty],
                vec![Fact::Holding(o.clone())],
            );
        }
        for c in &scene.containers {
            let inside = Fact::Inside(o.clone(), c.clone());
            let open = Fact::IsOpen(c.clone());
            op(
                &mut t,
                format!("(pick-in {o} {c})"),
                Action::Pick { object: o.clone() },
                vec![
                    at(c),
                    inside.clone(),
                    open.clone(),
                    Fact::HandEmpty,
                    Fact::Clear(o.clone()),
                ],
                vec![Fact::Holding(o.clone())],
                vec![inside.clone(), Fact::HandEmpty],
            );
            op(
                &mut t,
                format!("(place-in {o} {c})"),
                Action::PlaceIn {
                    object: o.clone(),
                    container: c.clone(),
                },
                vec![at(c), Fact::Holding(o.clone()), open],
                vec![inside, Fact::HandEmpty],
                vec![Fact::Holding(o.clone())],
            );
        }
    }
    let init: Vec<usize> = scene.facts.iter().map(|f| t.id(f.clone())).collect();
    let goal: Vec<usize> = goal.iter().map(|f| t.id(f.clone())).collect();
    GroundProblem {
        facts: t.facts,
        operators: ops,
        init,
        goal,
    }
}

/// A state: one bit per fact.
type State = Vec<u64>;

fn has(s: &State, f: usize) -> bool {
    s[f / 64] >> (f % 64) & 1 == 1
}

fn set(s: &mut State, f: usize, on: bool) {
    if on {
        s[f / 64] |= 1 << (f % 64);
    } else {
        s[f / 64] &= !(1 << (f % 64));
    }
}

/// h_max: the costliest goal fact, each fact costing the cheapest way to make it with every
/// precondition at its own cost (admissible).
fn h_max(p: &GroundProblem, s: &State) -> Option<u32> {
    let mut cost: Vec<u32> = (0..p.facts.len())
        .map(|f| if has(s, f) { 0 } else { u32::MAX })
        .collect();
    loop {
        let mut changed = false;
        for op in &p.operators {
            let c = op.pre.iter().map(|&f| cost[f]).max().unwrap_or(0);
            if c == u32::MAX {
                continue;
            }
            for &f in &op.add {
                if c + 1 < cost[f] {
                    cost[f] = c + 1;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    let h = p.goal.iter().map(|&f| cost[f]).max().unwrap_or(0);
    (h != u32::MAX).then_some(h)
}

/// A shortest plan for `problem`, or `None` when the goal cannot be reached; `max_expanded`
/// bounds the search (`None` past it too).
pub fn plan(problem: &GroundProblem, max_expanded: usize) -> Option<Plan> {
    let words = problem.facts.len().div_ceil(64).max(1);
    let mut start = vec![0u64; words];
    for &f in &problem.init {
        set(&mut start, f, true);
    }
    let is_goal = |s: &State| problem.goal.iter().all(|&f| has(s, f));
    // Open entries (f, g, state id), smallest f first; each state keeps its parent and the
    // operator that made it, for the plan.
    let mut states: Vec<(State, Option<(usize, usize)>)> = vec![(start.clone(), None)];
    let mut best_g: HashMap<State, u32> = HashMap::from([(start.clone(), 0)]);
    let mut open = BinaryHeap::new();
    let h0 = h_max(problem, &start)?;
    open.push(std::cmp::Reverse((h0, 0u32, 0usize)));
    let mut expanded = 0;
    while let Some(std::cmp::Reverse((_, g, id))) = open.pop() {
        let state = states[id].0.clone();
        // A stale entry: the state was reached more cheaply since.
        if best_g.get(&state).is_some_and(|&b| b < g) {
            continue;
        }
        if is_goal(&state) {
            let mut steps = Vec::new();
            let mut at = id;
            while let Some((parent, op)) = states[at].1 {
                let o = &problem.operators[op];
                steps.push((o.name.clone(), o.action.clone()));
                at = parent;
            }
            steps.reverse();
            let end = (0..problem.facts.len())
                .filter(|&f| has(&state, f))
                .map(|f| problem.facts[f].clone())
                .collect();
            return Some(Plan {
                steps,
                expanded,
                end,
            });
        }
        expanded += 1;
        if expanded > max_expanded {
            return None;
        }
        for (k, op) in problem.operators.iter().enumerate() {
            if !op.pre.iter().all(|&f| has(&state, f)) {
                continue;
            }
            let mut next = state.clone();
            for &f in &op.del {
                set(&mut next, f, false);
            }
            for &f in &op.add {
                set(&mut next, f, true);
            }
            let g2 = g + 1;
            if best_g.get(&next).is_some_and(|&b| b <= g2) {
                continue;
            }
            let Some(h) = h_max(problem, &next) else {
                continue;
            };
            best_g.insert(next.clone(), g2);
            states.push((next, Some((id, k))));
            open.push(std::cmp::Reverse((g2 + h, g2, states.len() - 1)));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fridge with a box inside and a microwave, both closed; a table with a cup.
    fn kitchen() -> SymbolicScene {
        let s = |x: &str| x.to_string();
        let mut scene = SymbolicScene {
            movables: vec![s("box_1"), s("cup_1")],
            surfaces: vec![s("fridge_1"), s("microwave_1"), s("table_1")],
            containers: vec![s("fridge_1"), s("microwave_1")],
            places: vec![s("fridge_1"), s("microwave_1"), s("table_1")],
            ..Default::default()
        };
        for o in ["box_1", "cup_1"] {
            for sup in ["fridge_1", "microwave_1", "table_1"] {
                scene.pick_places.insert((s(o), s(sup)), s(sup));
            }
        }
        scene.facts = [
            Fact::RobotAt(s(START_PLACE)),
            Fact::HandEmpty,
            Fact::Inside(s("box_1"), s("fridge_1")),
            Fact::On(s("cup_1"), s("table_1")),
            Fact::IsClosed(s("fridge_1")),
            Fact::IsClosed(s("microwave_1")),
            Fact::Clear(s("box_1")),
            Fact::Clear(s("cup_1")),
        ]
        .into_iter()
        .collect();
        scene
    }

    /// The fridge-to-microwave task's goal: the box in the microwave, both doors closed.
    fn box_in_the_closed_microwave() -> [Fact; 3] {
        [
            Fact::Inside("box_1".into(), "microwave_1".into()),
            Fact::IsClosed("microwave_1".into()),
            Fact::IsClosed("fridge_1".into()),
        ]
    }

    /// The kitchen with a freezer drawer under the fridge's door, shut.
    fn kitchen_with_a_freezer() -> SymbolicScene {
        let mut scene = kitchen();
        scene.main_parts.insert("fridge_1".into(), "door".into());
        scene.parts.insert(
            "fridge_1_freezer".into(),
            ("fridge_1".into(), "freezer".into()),
        );
        scene
            .facts
            .insert(Fact::PartClosed("fridge_1_freezer".into()));
        scene
    }

    #[test]
    fn a_part_the_goal_names_opens_by_its_own_operator_and_the_plan_ends_where_it_says() {
        let scene = kitchen_with_a_freezer();
        let open = Fact::PartOpen("fridge_1_freezer".into());
        let p = plan(&ground(&scene, std::slice::from_ref(&open)), 1000).expect("plan");
        let names: Vec<&str> = p.steps.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "(navigate start fridge_1)",
                "(open-part fridge_1_freezer fridge_1)"
            ]
        );
        assert_eq!(
            p.steps[1].1,
            Action::Open {
                object: "fridge_1".into(),
                part: Some("freezer".into()),
                value: None,
            }
        );
        // The end state: the drawer open, the fridge's door as it was, the robot at the fridge.
        assert!(p.end.contains(&open));
        assert!(!p.end.contains(&Fact::PartClosed("fridge_1_freezer".into())));
        assert!(p.end.contains(&Fact::IsClosed("fridge_1".into())));
        assert!(p.end.contains(&Fact::RobotAt("fridge_1".into())));
        // Shut again from there: one step.
        let from = SymbolicScene {
            facts: p.end.iter().cloned().collect(),
            ..scene.clone()
        };
        let shut = Fact::PartClosed("fridge_1_freezer".into());
        let again = plan(&ground(&from, &[shut]), 1000).expect("plan");
        assert_eq!(again.steps.len(), 1, "{:?}", again.steps);
        // A goal that does not name the drawer grounds no operator for it.
        let ops = ground(&scene, &box_in_the_closed_microwave()).operators;
        assert!(!ops.iter().any(|o| o.name.contains("-part")));
    }

    #[test]
    fn the_fridge_to_microwave_task_takes_eight_steps() {
        let scene = kitchen();
        let goal = box_in_the_closed_microwave();
        let p = plan(&ground(&scene, &goal), 100_000).expect("plan");
        let names: Vec<&str> = p.steps.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names.len(), 8, "{names:?}");
        assert_eq!(names[0], "(navigate start fridge_1)");
        assert!(names.contains(&"(pick-in box_1 fridge_1)"), "{names:?}");
        assert!(names.contains(&"(place-in box_1 microwave_1)"), "{names:?}");
    }

    #[test]
    fn an_arm_opens_and_closes_only_with_its_hand_empty() {
        let scene = SymbolicScene {
            hand_works_parts: true,
            ..kitchen()
        };
        let goal = box_in_the_closed_microwave();
        let p = plan(&ground(&scene, &goal), 100_000).expect("plan");
        let names: Vec<&str> = p.steps.iter().map(|(n, _)| n.as_str()).collect();
        // Both doors opened before the pick (the microwave's first, on the way), the fridge
        // closed after the place: two steps more than with the base's door action.
        assert_eq!(names.len(), 10, "{names:?}");
        let mut holding = false;
        for name in &names {
            holding = (holding || name.starts_with("(pick")) && !name.starts_with("(place");
            assert!(
                !(holding && (name.starts_with("(open") || name.starts_with("(close"))),
                "{name} with the box in the hand: {names:?}"
            );
        }
    }

    #[test]
    fn a_goal_no_action_makes_has_no_plan() {
        let scene = kitchen();
        // Holding two things at once.
        let goal = [Fact::Holding("box_1".into()), Fact::Holding("cup_1".into())];
        assert!(plan(&ground(&scene, &goal), 100_000).is_none());
    }

    #[test]
    fn a_goal_that_already_holds_needs_no_step() {
        let scene = kitchen();
        let p = plan(&ground(&scene, &[Fact::HandEmpty]), 10).expect("plan");
        assert!(p.steps.is_empty());
    }
}
