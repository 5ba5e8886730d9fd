//! The objects a task adds to the scene (`"add"`: what the camera could not see, such as a box
//! inside a closed fridge), each placed where the simulator itself would put it.

use bevy::prelude::*;
use glam::Affine3A;

use super::scene_shapes::SceneShapes;
use crate::base::InvalidValue;
use crate::graph::ContactGraph;
use crate::graph::GraphEdge;
use crate::sim::scene_view::SceneView;
use crate::sim::task::AddedObject;
use crate::systems::kinematic_tree::read_kinematic_tree;
use crate::systems::scene_graph::spawn_contact_graph;
use crate::systems::simulation::SimulationPlugin;

/// `graph` with the task's added objects, each put where the simulator's own placing puts a held
/// object: the first free spot inside the container (`"in"`, its lowest level with room, centred,
/// then towards the front) or on the surface (`"on"`), supported by it. One at a time, so each
/// sees the ones before it.
pub(super) fn add_unseen_objects(
    mut graph: ContactGraph,
    adds: &[AddedObject],
    shapes: &SceneShapes,
) -> Result<ContactGraph, InvalidValue> {
    let db = &shapes.models;
    for (i, added) in adds.iter().enumerate() {
        let at = |problem: String| InvalidValue::at(format!("add[{i}] ({})", added.id), problem);
        let (host, inside) = added.host().map_err(|e| at(e.to_string()))?;
        if graph.node(&added.id).is_some() {
            return Err(at("the scene already has a node of this id".into()));
        }
        let class = crate::classes::ClassTable::builtin()
            .get(&added.class)
            .ok_or_else(|| at(format!("unknown class {:?}", added.class)))?;
        if !class.movable {
            return Err(at(format!(
                "{} objects do not move; add a movable one",
                added.class
            )));
        }
        let model = db.get(&added.model).ok_or_else(|| {
            at(format!(
                "no model {:?} in the scene's models or the library",
                added.model
            ))
        })?;
        let Some(parent) = graph.node(host) else {
            return Err(at(format!("the scene has no node {host:?}")));
        };
        // Provisionally at the top centre of the host's box; the placing moves it.
        let parent_box = crate::geometry::GravityBox::from(&parent.bbox);
        let top = parent_box.center + Vec3::Z * parent_box.size.z / 2.0;
        let world_from_model =
            Affine3A::from_rotation_translation(Quat::from_rotation_z(parent_box.yaw), top);
        graph.nodes.push(node_of_model(
            &added.id,
            &added.class,
            class.kind,
            &model.model,
            world_from_model,
        ));
        graph.edges.push(GraphEdge::Support {
            parent: host.to_string(),
            child: added.id.clone(),
        });
        let mut app = App::new();
        app.add_plugins(SimulationPlugin);
        spawn_contact_graph(app.world_mut(), &graph).map_err(|e| at(e.to_string()))?;
        shapes.spawn_links(app.world_mut(), &graph);
        let tree = read_kinematic_tree(app.world_mut()).map_err(|e| at(e.to_string()))?;
        let view = SceneView::new(&tree);
        let link = view
            .node_link(&added.id)
            .ok_or_else(|| at("its model built no link".into()))?;
        let spot = if inside {
            if !view.is_container(host) {
                return Err(at(format!("{host} is not a container")));
            }
            view.spot_in(link, host, &[])
                .ok_or_else(|| at(format!("{} does not fit in {host}", added.model)))?
        } else {
            if view.is_layout(host) && !matches!(host_class(&graph, host), Some("floor")) {
                return Err(at(format!("{host} is not a surface to put things on")));
            }
            let centre = top.truncate();
            view.spot_on(link, host, centre, &[])
                .ok_or_else(|| at(format!("no free spot on {host} for {}", added.model)))?
        };
        // The link's frame need not be the model's: move the model as the link moves.
        let link_from_model = view.poses[link].inverse() * world_from_model;
        let placed = spot * link_from_model;
        let node = graph.nodes.last_mut().expect("just added");
        *node = node_of_model(&added.id, &added.class, class.kind, &model.model, placed);
    }
    Ok(graph)
}

fn host_class<'a>(graph: &'a ContactGraph, id: &str) -> Option<&'a str> {
    graph.node(id).map(|n| n.class.as_str())
}

/// A node for `model` standing at `world_from_model` (the model's origin is the bottom centre of
/// its box).
fn node_of_model(
    id: &str,
    class: &str,
    kind: crate::classes::EntityKind,
    model: &crate::cad::model::CadModel,
    world_from_model: Affine3A,
) -> crate::graph::GraphNode {
    let (_, rotation, _) = world_from_model.to_scale_rotation_translation();
    let centre = world_from_model.transform_point3(Vec3::Z * model.size.z / 2.0);
    crate::graph::GraphNode {
        id: id.to_string(),
        class: class.to_string(),
        kind,
        bbox: crate::graph::BoxJson {
            center: centre.to_array(),
            yaw: rotation.to_euler(EulerRot::ZYX).0,
            size: model.size.to_array(),
        },
        planes: Vec::new(),
        cad: Some(crate::graph::CadPlacement {
            model: model.id.clone(),
            world_from_model: Mat4::from(world_from_model).to_cols_array(),
            scale: 1.0,
            alignment_error: 0.0,
        }),
        joints: Default::default(),
        parts: Vec::new(),
    }
}
