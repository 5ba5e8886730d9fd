//! The benchmark's pick and place in a room: an object chosen from the contact graph, a goal
//! planned and simulated with the arm.

use std::path::Path;

use bevy::prelude::*;
use serde::Serialize;

use super::{SimulateOptions, simulate};
use crate::error::IsceneError;
use crate::graph::ContactGraph;
use crate::graph::GraphEdge;
use crate::io::write_sequence::write_text;
use crate::sim::actions::Action;

/// A room's pick and place with the arm: what was moved where, whether it worked, and the
/// seconds its pick and place steps took (planning, motion checks and rest tests).
#[derive(Clone, Debug, Serialize)]
pub struct PickPlaceTrial {
    pub object: String,
    pub surface: String,
    pub success: bool,
    pub seconds: f64,
}

/// Classes whose open top holds things at a working height: the benchmark's pick and place
/// takes from and puts onto these first (a shelf's lower boards come after).
const TOP_CLASSES: [&str; 6] = [
    "table",
    "desk",
    "counter",
    "nightstand",
    "dresser",
    "sideboard",
];

/// Classes a parallel gripper is made for (a book lying flat offers it no side narrower than a
/// hand): the benchmark's pick and place takes one of these first.
const HANDY_CLASSES: [&str; 5] = ["cup", "mug", "bottle", "bowl", "can"];

/// The benchmark's task for a room: a movable object standing on something other than the
/// floor goes onto another surface, planned from the goal `"OBJECT on SURFACE"` with the arm of
/// `robot` on the scene in `dir`. Cups, mugs, bottles, bowls and cans on tables, desks and
/// counters come first, then other objects there, then the rest, each by id; the surface is
/// the first other one, tables, desks and counters first. The simulation's
/// output goes to `out`, its task beside it (`out` with `.task.json`). `None` when the room has
/// no such object and surface, or the planner finds no plan.
pub fn pick_and_place_trial(
    dir: &Path,
    robot: &Path,
    out: &Path,
) -> Result<Option<PickPlaceTrial>, IsceneError> {
    let graph = ContactGraph::load(&dir.join("contact_graph.json"))?;
    let classes = crate::classes::ClassTable::builtin();
    let is_layout = |id: &str| {
        graph
            .node(id)
            .is_none_or(|n| n.kind == crate::classes::EntityKind::Layout)
    };
    let supports: Vec<(&str, &str)> = graph
        .edges
        .iter()
        .filter_map(|e| match e {
            GraphEdge::Support { parent, child } => Some((parent.as_str(), child.as_str())),
            _ => None,
        })
        .collect();
    let on_top = |id: &str| {
        graph
            .node(id)
            .is_some_and(|n| TOP_CLASSES.contains(&n.class.as_str()))
    };
    let mut objects: Vec<(&str, &str)> = supports
        .iter()
        .filter(|(parent, child)| {
            !is_layout(parent)
                && graph
                    .node(child)
                    .and_then(|n| classes.get(&n.class))
                    .is_some_and(|c| c.movable)
        })
        .map(|&(parent, child)| (child, parent))
        .collect();
    let handy = |id: &str| {
        graph
            .node(id)
            .is_some_and(|n| HANDY_CLASSES.contains(&n.class.as_str()))
    };
    objects.sort_by_key(|&(object, support)| (!on_top(support), !handy(object), object));
    let mut surfaces: Vec<&str> = supports
        .iter()
        .map(|(parent, _)| *parent)
        .chain(
            graph
                .nodes
                .iter()
                .filter(|n| TOP_CLASSES.contains(&n.class.as_str()))
                .map(|n| n.id.as_str()),
        )
        .filter(|id| !is_layout(id))
        .collect();
    surfaces.sort_by_key(|&id| (!on_top(id), id));
    surfaces.dedup();
    let Some((object, surface)) = objects.iter().find_map(|&(object, support)| {
        let onto = surfaces
            .iter()
            .find(|s| **s != support && !objects.iter().any(|(o, _)| o == *s))?;
        Some((object.to_string(), onto.to_string()))
    }) else {
        return Ok(None);
    };
    let task = out.with_extension("task.json");
    write_text(
        &task,
        &serde_json::json!({ "goals": [format!("{object} on {surface}")] }).to_string(),
    )?;
    let summary = match simulate(&SimulateOptions {
        dir: dir.to_path_buf(),
        task,
        out: out.to_path_buf(),
        force: true,
        robot: Some(robot.to_path_buf()),
    }) {
        Ok(summary) => summary,
        Err(IsceneError::Input(e)) => {
            tracing::warn!("no pick and place in {}: {e}", dir.display());
            return Ok(None);
        }
        Err(other) => return Err(other),
    };
    let seconds = summary
        .steps
        .iter()
        .filter(|s| {
            matches!(
                s.action,
                Action::Pick { .. } | Action::PlaceOn { .. } | Action::PlaceIn { .. }
            )
        })
        .map(|s| s.wall_ms / 1e3)
        .sum();
    Ok(Some(PickPlaceTrial {
        object,
        surface,
        success: summary.success,
        seconds,
    }))
}
