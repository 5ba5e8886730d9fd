//! Ground truth of a synthetic world: the contact graph (support and proximal edges), instance
//! labels, and per-entity meshes, all as a reconstruction would ideally produce them.

use std::collections::BTreeMap;

use glam::{Mat4, Vec3};

use crate::cad::db::database::SCENE_MODELS;
use crate::cad::db::export::write_models;
use crate::cad::library::ParametricLibrary;
use crate::cad::model::CadModel;
use crate::cad::model_parts::model_parts;
use crate::classes::EntityKind;
use crate::geometry::plane::dominant_planes;
use crate::geometry::{GravityBox, TriMesh};
use crate::graph::proximal::{ProximalMargins, proximal_edges};
use crate::graph::{CadPlacement, ContactGraph, GraphEdge, GraphNode};
use crate::io::labels::{LabelEntry, Labels};
use crate::scene::world::{SceneWorld, Support};

/// Smallest surface, in square metres, that is listed as a plane of an object.
const MIN_PLANE_AREA: f32 = 0.01;
const MAX_PLANES: usize = 8;
/// Layout boxes are slabs this thick behind their surface.
const LAYOUT_THICKNESS: f32 = 0.1;

impl SceneWorld {
    pub fn labels(&self) -> Labels {
        Labels {
            instances: self
                .instances()
                .into_iter()
                .map(|(id, class, entity)| (id.to_string(), LabelEntry { class, entity }))
                .collect(),
        }
    }

    /// Every entity's mesh in the world frame with its colour, layout first.
    pub fn entity_meshes(&self) -> Vec<(String, TriMesh, [f32; 3])> {
        let layout = self
            .layout
            .iter()
            .map(|l| (l.id.clone(), l.mesh.clone(), l.color));
        let objects = self
            .objects
            .iter()
            .map(|o| (o.id.clone(), o.world_visual_mesh(), o.model.parts[0].color));
        layout.chain(objects).collect()
    }

    /// The models of the world that the parametric library does not hold as they are (library
    /// models built to another size, database models), one per id, sorted: written to
    /// `gt/cad` so that the ground truth, simulated or exported, stands on its own models.
    pub fn models_outside_library(&self) -> Vec<CadModel> {
        let mut models: Vec<CadModel> = Vec::new();
        for o in &self.objects {
            if ParametricLibrary::get(&o.model.id).is_none()
                && models.iter().all(|m| m.id != o.model.id)
            {
                models.push(o.model.clone());
            }
        }
        models.sort_by(|a, b| a.id.cmp(&b.id));
        models
    }

    /// Writes [`Self::models_outside_library`] as the CAD database `<gt>/cad` (nothing when
    /// there are none), which `CadDatabase::for_scene` reads back.
    pub fn write_own_models(&self, gt: &std::path::Path) -> Result<(), crate::error::IsceneError> {
        let own = self.models_outside_library();
        if !own.is_empty() {
            write_models(&gt.join(SCENE_MODELS), &own, "iscene render")?;
        }
        Ok(())
    }

    /// The layout entity's box: a slab of the room-facing rectangle, `LAYOUT_THICKNESS` deep behind it.
    fn layout_box(&self, index: usize) -> GravityBox {
        let l = &self.layout[index];
        let behind = -l.plane.normal * LAYOUT_THICKNESS;
        let points: Vec<Vec3> = l
            .mesh
            .positions
            .iter()
            .flat_map(|p| [*p, *p + behind])
            .collect();
        GravityBox::enclosing(&points, 0.0).unwrap_or(GravityBox {
            center: Vec3::ZERO,
            yaw: 0.0,
            size: Vec3::ZERO,
        })
    }

    /// The ground-truth contact graph in the schema of `contact_graph.json`.
    pub fn contact_graph(&self) -> ContactGraph {
        let mut nodes = Vec::new();
        let mut boxes = Vec::new();
        for (i, l) in self.layout.iter().enumerate() {
            let b = self.layout_box(i);
            boxes.push(b);
            nodes.push(GraphNode {
                id: l.id.clone(),
                class: l.class.into(),
                kind: EntityKind::Layout,
                bbox: b.into(),
                planes: vec![l.plane.to_array()],
                cad: None,
                joints: BTreeMap::new(),
                parts: Vec::new(),
            });
        }
        for o in &self.objects {
            let b = o.gravity_box();
            boxes.push(b);
            let planes = dominant_planes(&o.world_mesh(), MIN_PLANE_AREA, MAX_PLANES)
                .into_iter()
                .map(|(p, _)| p.to_array())
                .collect();
            nodes.push(GraphNode {
                id: o.id.clone(),
                class: o.class.clone(),
                kind: o.kind,
                bbox: b.into(),
                planes,
                cad: Some(CadPlacement {
                    model: o.model.id.clone(),
                    world_from_model: Mat4::from(o.world_from_model).to_cols_array(),
                    scale: 1.0,
                    alignment_error: 0.0,
                }),
                joints: o.joint_values.iter().cloned().collect(),
                parts: model_parts(&o.model, &o.world_from_model),
            });
        }
        let mut edges = Vec::new();
        for o in &self.objects {
            let parent = match &o.support {
                Support::Floor => "floor".to_string(),
                Support::OnObject(p) | Support::InObject(p) => self.objects[*p].id.clone(),
                Support::Wall(k) => format!("wall_{k}"),
            };
            edges.push(GraphEdge::Support {
                parent,
                child: o.id.clone(),
            });
        }
        let supports: Vec<(&str, &str)> = edges
            .iter()
            .filter_map(|e| match e {
                GraphEdge::Support { parent, child } => Some((parent.as_str(), child.as_str())),
                GraphEdge::Proximal { .. } => None,
            })
            .collect();
        let boxed: Vec<(&str, GravityBox, &str)> = nodes
            .iter()
            .zip(&boxes)
            .map(|(n, b)| (n.id.as_str(), *b, n.class.as_str()))
            .collect();
        let proximal = proximal_edges(&boxed, &supports, ProximalMargins::EXACT);
        edges.extend(proximal);
        ContactGraph { nodes, edges }
    }
}
