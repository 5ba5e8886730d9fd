//! Scene entities out of the panoptic map: labels resolved to (class, instance), instances too
//! small dropped, floor and ceiling each one entity, a labelled mesh cut per entity.

use std::collections::BTreeMap;

use glam::{IVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::classes::{ClassTable, EntityKind};
use crate::geometry::TriMesh;
use crate::map::{SegmentLabel, TsdfMap, extract_mesh};
use crate::panoptic::instances::{ClassId, InstanceCounts, InstanceId};

/// The class names the mapper knows, with their ids (the class table's order).
pub struct ClassIds {
    names: Vec<String>,
}

impl ClassIds {
    pub fn builtin() -> Self {
        Self {
            names: ClassTable::builtin().names().map(String::from).collect(),
        }
    }

    pub fn id(&self, name: &str) -> Option<ClassId> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| i as ClassId)
    }

    pub fn name(&self, id: ClassId) -> &str {
        &self.names[id as usize]
    }
}

/// One scene entity of the panoptic map.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PanopticEntity {
    /// `floor`, `ceiling`, `wall_<n>`, or `<class>_<n>`.
    pub id: String,
    pub class: String,
    pub kind: EntityKind,
    pub instance: InstanceId,
    /// Confidence in [0, 1]: the share of its labels' votes that agree with its class and instance.
    pub score: f32,
    pub surface_voxels: usize,
    pub labels: Vec<SegmentLabel>,
    #[serde(skip)]
    pub mesh: TriMesh,
}

/// Entities, and every surface voxel with the index of its entity plus one (0 = none).
pub struct PanopticScene {
    pub entities: Vec<PanopticEntity>,
    pub surface_voxels: Vec<(Vec3, u32)>,
}

#[derive(Clone, Copy, Debug)]
pub struct ExtractionParams {
    /// A voxel is on the surface when |sdf| is below this many voxel sizes.
    pub surface_band: f32,
    /// Voxels observed with less weight than this are left out.
    pub min_weight: f32,
    /// Entities with fewer surface voxels are dropped...
    pub min_surface_voxels: usize,
    /// ...and layout with fewer than this (a wall is large; a small piece is a misassigned one).
    pub min_layout_voxels: usize,
}

impl Default for ExtractionParams {
    fn default() -> Self {
        Self {
            surface_band: 0.75,
            min_weight: 2.0,
            min_surface_voxels: 25,
            min_layout_voxels: 400,
        }
    }
}

/// Surface voxels: observed, within the band around the zero crossing.
pub fn surface_voxels(map: &TsdfMap, params: &ExtractionParams) -> Vec<(IVec3, SegmentLabel)> {
    let band = params.surface_band * map.voxel_size;
    let mut out = Vec::new();
    for block in &map.blocks {
        for (i, v) in block.voxels.iter().enumerate() {
            if v.weight >= params.min_weight && v.sdf.abs() < band {
                let local = crate::map::tsdf::voxel_local(i);
                out.push((block.key * crate::map::BLOCK_SIDE as i32 + local, v.label));
            }
        }
    }
    out
}

pub fn extract_entities(
    map: &TsdfMap,
    instances: &InstanceCounts,
    classes: &ClassIds,
    params: &ExtractionParams,
) -> PanopticScene {
    let table = ClassTable::builtin();
    let voxels = surface_voxels(map, params);
    let mut voxels_of_label: BTreeMap<SegmentLabel, usize> = BTreeMap::new();
    for (_, l) in &voxels {
        *voxels_of_label.entry(*l).or_default() += 1;
    }
    // Group labels by (class, instance); layout floor and ceiling are one entity each.
    struct Group {
        labels: Vec<SegmentLabel>,
        voxels: usize,
        weighted_support: f32,
    }
    let mut groups: BTreeMap<(ClassId, InstanceId), Group> = BTreeMap::new();
    for (&l, &n) in voxels_of_label.iter().filter(|(l, _)| **l != 0) {
        let Some(identity) = instances.identity(l) else {
            continue;
        };
        let class = classes.name(identity.class);
        let instance = if class == "floor" || class == "ceiling" {
            0
        } else {
            identity.instance
        };
        let g = groups.entry((identity.class, instance)).or_insert(Group {
            labels: Vec::new(),
            voxels: 0,
            weighted_support: 0.0,
        });
        g.labels.push(l);
        g.voxels += n;
        g.weighted_support += identity.support * n as f32;
    }
    let mut entities: Vec<PanopticEntity> = Vec::new();
    let mut per_class_count: BTreeMap<String, usize> = BTreeMap::new();
    for ((class_id, instance), g) in groups {
        let class = classes.name(class_id).to_string();
        let kind = table.get(&class).map_or(EntityKind::Rigid, |c| c.kind);
        let min = match kind {
            EntityKind::Layout => params.min_layout_voxels,
            _ => params.min_surface_voxels,
        };
        if g.voxels < min {
            continue;
        }
        let n = per_class_count.entry(class.clone()).or_default();
        let id = match class.as_str() {
            "floor" | "ceiling" => class.clone(),
            "wall" => format!("wall_{n}"),
            _ => format!("{class}_{}", *n + 1),
        };
        *n += 1;
        entities.push(PanopticEntity {
            id,
            class,
            kind,
            instance,
            score: g.weighted_support / g.voxels as f32,
            surface_voxels: g.voxels,
            labels: g.labels,
            mesh: TriMesh::default(),
        });
    }
    let mut entity_of_label: BTreeMap<SegmentLabel, u32> = BTreeMap::new();
    for (k, e) in entities.iter().enumerate() {
        for &l in &e.labels {
            entity_of_label.insert(l, k as u32 + 1);
        }
    }
    let meshes = extract_mesh(map, params.min_weight).split(entities.len(), |l| {
        entity_of_label.get(&l).map(|&e| e as usize - 1)
    });
    for (e, mesh) in entities.iter_mut().zip(meshes) {
        e.mesh = mesh;
    }
    let surface_voxels = voxels
        .into_iter()
        .map(|(v, l)| {
            (
                map.voxel_center(v),
                entity_of_label.get(&l).copied().unwrap_or(0),
            )
        })
        .collect();
    PanopticScene {
        entities,
        surface_voxels,
    }
}
