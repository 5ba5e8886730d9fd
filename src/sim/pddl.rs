//! The task domain and a problem as PDDL (STRIPS with static predicates), the same operators the
//! planner grounds, so an outside planner (pyperplan in the tests) can check our plans.

use crate::sim::symbolic::{Fact, START_PLACE, SymbolicScene};

/// The domain: navigate, open, close, pick-on, pick-in, place-on, place-in; open and close need
/// the hand empty when `hand_works_parts` (an arm takes the handle).
pub fn domain(hand_works_parts: bool) -> String {
    let hand = if hand_works_parts {
        " (hand-empty)"
    } else {
        ""
    };
    format!(
        r#"(define (domain iscene)
  (:requirements :strips)
  (:predicates
    (robot-at ?p) (holding ?o) (hand-empty) (on ?o ?s) (inside ?o ?c)
    (is-open ?c) (is-closed ?c) (part-open ?d) (part-closed ?d) (clear ?o)
    (place ?p) (surface ?s) (container ?c) (part ?d ?c) (movable ?o) (picked-from ?o ?s ?p))
  (:action navigate
    :parameters (?from ?to)
    :precondition (and (robot-at ?from) (place ?to))
    :effect (and (robot-at ?to) (not (robot-at ?from))))
  (:action open
    :parameters (?c)
    :precondition (and (container ?c) (robot-at ?c) (is-closed ?c){hand})
    :effect (and (is-open ?c) (not (is-closed ?c))))
  (:action close
    :parameters (?c)
    :precondition (and (container ?c) (robot-at ?c) (is-open ?c){hand})
    :effect (and (is-closed ?c) (not (is-open ?c))))
  (:action open-part
    :parameters (?d ?c)
    :precondition (and (part ?d ?c) (robot-at ?c) (part-closed ?d){hand})
    :effect (and (part-open ?d) (not (part-closed ?d))))
  (:action close-part
    :parameters (?d ?c)
    :precondition (and (part ?d ?c) (robot-at ?c) (part-open ?d){hand})
    :effect (and (part-closed ?d) (not (part-open ?d))))
  (:action pick-on
    :parameters (?o ?s ?p)
    :precondition (and (picked-from ?o ?s ?p) (robot-at ?p) (on ?o ?s) (hand-empty) (clear ?o))
    :effect (and (holding ?o) (clear ?s) (not (on ?o ?s)) (not (hand-empty))))
  (:action pick-in
    :parameters (?o ?c)
    :precondition (and (movable ?o) (container ?c) (robot-at ?c) (inside ?o ?c) (is-open ?c)
                       (hand-empty) (clear ?o))
    :effect (and (holding ?o) (not (inside ?o ?c)) (not (hand-empty))))
  (:action place-on
    :parameters (?o ?s)
    :precondition (and (movable ?o) (surface ?s) (robot-at ?s) (holding ?o))
    :effect (and (on ?o ?s) (hand-empty) (not (holding ?o))))
  (:action place-in
    :parameters (?o ?c)
    :precondition (and (movable ?o) (container ?c) (robot-at ?c) (holding ?o) (is-open ?c))
    :effect (and (inside ?o ?c) (hand-empty) (not (holding ?o)))))
"#
    )
}

/// The problem of reaching `goal` from the scene's facts.
pub fn problem(name: &str, scene: &SymbolicScene, goal: &[Fact]) -> String {
    let mut objects: std::collections::BTreeSet<&str> = [START_PLACE].into_iter().collect();
    objects.extend(scene.movables.iter().map(String::as_str));
    objects.extend(scene.surfaces.iter().map(String::as_str));
    objects.extend(scene.places.iter().map(String::as_str));
    for (o, s) in scene.pick_places.keys() {
        objects.insert(o);
        objects.insert(s);
    }
    objects.extend(scene.parts.keys().map(String::as_str));
    let mut init: Vec<String> = scene.facts.iter().map(Fact::pddl).collect();
    // The doors and drawers the goal names, as the planner grounds them (`planner::ground`).
    init.extend(
        scene
            .parts
            .iter()
            .filter(|(link, _)| {
                goal.iter()
                    .any(|f| matches!(f, Fact::PartOpen(l) | Fact::PartClosed(l) if l == *link))
            })
            .map(|(link, (c, _))| format!("(part {link} {c})")),
    );
    init.extend(scene.places.iter().map(|p| format!("(place {p})")));
    init.extend(scene.surfaces.iter().map(|s| format!("(surface {s})")));
    init.extend(scene.containers.iter().map(|c| format!("(container {c})")));
    init.extend(scene.movables.iter().map(|o| format!("(movable {o})")));
    init.extend(
        scene
            .pick_places
            .iter()
            .map(|((o, s), p)| format!("(picked-from {o} {s} {p})")),
    );
    let goal: Vec<String> = goal.iter().map(Fact::pddl).collect();
    format!(
        "(define (problem {name})\n  (:domain iscene)\n  (:objects {})\n  (:init\n    {})\n  (:goal (and {})))\n",
        objects.into_iter().collect::<Vec<_>>().join(" "),
        init.join("\n    "),
        goal.join(" ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The operator `name` of `domain`, up to the next one.
    fn operator<'a>(domain: &'a str, name: &str) -> &'a str {
        let start = domain
            .find(&format!("(:action {name}\n"))
            .expect("operator");
        let rest = &domain[start + 1..];
        &domain[start..start + 1 + rest.find("(:action").unwrap_or(rest.len())]
    }

    #[test]
    fn open_and_close_need_the_hand_empty_only_when_the_hand_works_them() {
        for name in ["open", "close", "open-part", "close-part"] {
            assert!(!operator(&domain(false), name).contains("(hand-empty)"));
            assert!(operator(&domain(true), name).contains("(hand-empty))\n    :effect"));
        }
        // Nothing else changes.
        assert_eq!(
            domain(true)
                .replace(
                    " (hand-empty))\n    :effect (and (is-",
                    ")\n    :effect (and (is-"
                )
                .replace(
                    " (hand-empty))\n    :effect (and (part-",
                    ")\n    :effect (and (part-"
                ),
            domain(false)
        );
    }
}
