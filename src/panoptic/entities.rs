//! Scene entities out of the panoptic map: labels resolved to (class, instance), instances too
//! small dropped, floor and ceiling each one entity, a labelled mesh cut per entity.

use std::collections::{BTreeMap, HashSet};

use glam::{IVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::classes::{ClassInfo, ClassTable, EntityKind};
use crate::geometry::TriMesh;
use crate::map::{SegmentLabel, TsdfMap, extract_mesh};
use crate::panoptic::instance_groups::{Group, absorb_fragments, merge_coplanar_walls};
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
    /// Entities with less surface than this (square metres, counted in surface voxels of the
    /// map's size, so a finer map keeps the same entities) are dropped...
    pub min_surface_area: f32,
    /// ...except small things (a class whose default size is below `small_object_size` metres in
    /// every direction: a cup far away is a dozen 2 cm voxels), which need this much...
    pub min_small_object_area: f32,
    pub small_object_size: f32,
    /// ...and layout with less than this (a wall is large; a small piece is a misassigned one).
    pub min_layout_area: f32,
    /// Metres: a wall instance whose voxels lie this close to a larger wall's plane joins it.
    pub coplanar_distance: f32,
    /// An instance with at most this share of the surface voxels of an instance of its class that
    /// it touches is a piece of it and joins it.
    pub fragment_share: f32,
}

impl Default for ExtractionParams {
    fn default() -> Self {
        Self {
            surface_band: 0.75,
            min_weight: 2.0,
            // 40, 12 and 400 voxels of 2 cm.
            min_surface_area: 0.016,
            min_small_object_area: 0.0048,
            small_object_size: 0.3,
            min_layout_area: 0.16,
            coplanar_distance: 0.05,
            fragment_share: 0.05,
        }
    }
}

impl ExtractionParams {
    /// Whether `class` is a small thing (`small_object_size`): a cup, a book, not furniture.
    pub fn is_small(&self, class: &ClassInfo) -> bool {
        class.size.max_element() < self.small_object_size
    }

    /// The fewest surface voxels of `voxel_size` metres an entity of `kind` needs to be kept
    /// (`small`: a small-object class).
    pub fn min_surface_voxels(&self, kind: EntityKind, small: bool, voxel_size: f32) -> usize {
        let area = match kind {
            EntityKind::Layout => self.min_layout_area,
            _ if small => self.min_small_object_area,
            _ => self.min_surface_area,
        };
        (area / (voxel_size * voxel_size)).round() as usize
    }
}

/// Surface voxels: observed voxels less than the band from the surface, and the nearer voxel of
/// every pair of neighbours the surface passes between when it is less than the band from it once
/// its sdf is divided by the sdf gradient's length: a projective sdf overstates the distance to a
/// surface seen obliquely by 1 / cos of the angle, and with the sdf alone a plane halfway between
/// voxel centres (the floor and ceiling of a noise-free render) all but vanished from the map.
/// Only the nearer voxel, so noisy surfaces, whose gradients are steep everywhere, do not
/// thicken.
pub fn surface_voxels(map: &TsdfMap, params: &ExtractionParams) -> Vec<(IVec3, SegmentLabel)> {
    let band = params.surface_band * map.voxel_size;
    let observed = |v: &crate::map::Voxel| v.weight() >= params.min_weight;
    let sdf = |key: IVec3| map.voxel(key).filter(|v| observed(v)).map(|v| v.sdf);
    let steps = [IVec3::X, IVec3::Y, IVec3::Z];
    let nearer_side_of_crossing = |key: IVec3, s: f32| {
        steps
            .iter()
            .flat_map(|&step| [key + step, key - step])
            .filter_map(sdf)
            .any(|n| (n < 0.0) != (s < 0.0) && s.abs() <= n.abs())
    };
    // |grad sdf| by central differences (one-sided where a neighbour is missing), clamped:
    // obliquity beyond 1 / cos(70 deg) is rare.
    let stretch = |key: IVec3, s: f32| {
        let gradient =
            Vec3::from_array(steps.map(|step| match (sdf(key + step), sdf(key - step)) {
                (Some(a), Some(b)) => 0.5 * (a - b),
                (Some(a), None) => a - s,
                (None, Some(b)) => s - b,
                (None, None) => 0.0,
            })) / map.voxel_size;
        gradient.length().clamp(1.0, MAX_SDF_STRETCH)
    };
    let mut out = Vec::new();
    for block in &map.blocks {
        for (i, v) in block.voxels().enumerate() {
            if !observed(&v) || v.sdf.abs() >= band * MAX_SDF_STRETCH {
                continue;
            }
            let key = block.key * crate::map::BLOCK_SIDE as i32 + crate::map::tsdf::voxel_local(i);
            if v.sdf.abs() < band
                || (nearer_side_of_crossing(key, v.sdf) && v.sdf.abs() < band * stretch(key, v.sdf))
            {
                out.push((key, v.label));
            }
        }
    }
    out
}

/// The most a projective sdf is taken to overstate the distance to the surface.
const MAX_SDF_STRETCH: f32 = 3.0;

/// Voxels this close (in voxels, along each axis) are one piece of a surface: a voxel missing
/// between two seen ones does not part them.
const PIECE_REACH: i32 = 2;

/// Whether `voxels` hold a connected piece (voxels within `PIECE_REACH` of each other) of at
/// least `min` voxels. Stops at the first piece that large, so a compact object costs `min`
/// voxels' search.
fn has_piece_of(voxels: &[IVec3], min: usize) -> bool {
    let cells: HashSet<IVec3> = voxels.iter().copied().collect();
    let mut seen: HashSet<IVec3> = HashSet::new();
    for &start in voxels {
        if !seen.insert(start) {
            continue;
        }
        let mut stack = vec![start];
        let mut size = 0;
        while let Some(v) = stack.pop() {
            size += 1;
            if size >= min {
                return true;
            }
            for dz in -PIECE_REACH..=PIECE_REACH {
                for dy in -PIECE_REACH..=PIECE_REACH {
                    for dx in -PIECE_REACH..=PIECE_REACH {
                        let w = v + IVec3::new(dx, dy, dz);
                        if cells.contains(&w) && seen.insert(w) {
                            stack.push(w);
                        }
                    }
                }
            }
        }
    }
    min == 0
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
    if let Some(wall) = classes.id("wall") {
        merge_coplanar_walls(&mut groups, wall, &voxels, map, params.coplanar_distance);
    }
    let is_object = |c: ClassId| {
        table
            .get(classes.name(c))
            .is_some_and(|info| info.kind != EntityKind::Layout)
    };
    // Faces are pieces of furniture and appliances, not of cups and books (a book lying on
    // another is a slab too).
    let is_large = |c: ClassId| {
        table
            .get(classes.name(c))
            .is_some_and(|info| !params.is_small(info))
    };
    // A mislabelled piece of another class's object: large fixed furniture (not movable) that
    // would be kept as an entity.
    let may_be_foreign = |c: ClassId, voxels: usize| {
        table.get(classes.name(c)).is_some_and(|info| {
            !info.movable
                && !params.is_small(info)
                && voxels >= params.min_surface_voxels(info.kind, false, map.voxel_size)
        })
    };
    // Smaller than the class's least size on two of its sides (horizontal ones sorted, the
    // height): no object of the class, only a piece of one.
    let no_object_of_its_class = |c: ClassId, extent: glam::Vec3| {
        table.get(classes.name(c)).is_some_and(|info| {
            let least = info.size_min;
            let (short, long) = (extent.x.min(extent.y), extent.x.max(extent.y));
            let under = [
                short < least.x.min(least.y),
                long < least.x.max(least.y),
                extent.z < least.z,
            ];
            under.iter().filter(|&&u| u).count() >= 2
        })
    };
    absorb_fragments(
        &mut groups,
        &voxels,
        is_object,
        is_large,
        may_be_foreign,
        no_object_of_its_class,
        params.fragment_share,
        map.voxel_size,
    );
    let mut voxels_by_label: BTreeMap<SegmentLabel, Vec<IVec3>> = BTreeMap::new();
    for (v, l) in &voxels {
        voxels_by_label.entry(*l).or_default().push(*v);
    }
    let mut entities: Vec<PanopticEntity> = Vec::new();
    let mut per_class_count: BTreeMap<String, usize> = BTreeMap::new();
    for ((class_id, instance), g) in groups {
        let class = classes.name(class_id).to_string();
        let info = table.get(&class);
        let kind = info.map_or(EntityKind::Rigid, |c| c.kind);
        let small = info.is_some_and(|c| params.is_small(c));
        let min_voxels = params.min_surface_voxels(kind, small, map.voxel_size);
        if g.voxels < min_voxels {
            continue;
        }
        // An object is one surface: labels scattered in specks over a room are noise, however
        // many voxels they add up to. (A wall is a plane seen in parts, and stays.)
        let object_voxels = || {
            g.labels
                .iter()
                .filter_map(|l| voxels_by_label.get(l))
                .flatten()
                .copied()
                .collect::<Vec<IVec3>>()
        };
        if kind != EntityKind::Layout && !has_piece_of(&object_voxels(), min_voxels) {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specks_scattered_over_a_room_hold_no_piece_an_object_needs() {
        // 40 voxels as one 8 x 5 patch, and as 20 pairs 5 voxels apart.
        let patch: Vec<IVec3> = (0..8)
            .flat_map(|x| (0..5).map(move |y| IVec3::new(x, y, 0)))
            .collect();
        assert!(has_piece_of(&patch, 40));
        assert!(!has_piece_of(&patch, 41));
        let specks: Vec<IVec3> = (0..20)
            .flat_map(|i| [IVec3::new(5 * i, 0, 0), IVec3::new(5 * i + 1, 0, 0)])
            .collect();
        assert!(has_piece_of(&specks, 2));
        assert!(!has_piece_of(&specks, 3));
        // A gap of one missing voxel does not part a surface.
        let gapped: Vec<IVec3> = (0..40).map(|i| IVec3::new(2 * i, 0, 0)).collect();
        assert!(has_piece_of(&gapped, 40));
    }

    #[test]
    fn the_smallest_entity_kept_has_the_same_area_at_any_voxel_size() {
        let params = ExtractionParams::default();
        let rigid = |voxel| params.min_surface_voxels(EntityKind::Rigid, false, voxel);
        let small = |voxel| params.min_surface_voxels(EntityKind::Rigid, true, voxel);
        let layout = |voxel| params.min_surface_voxels(EntityKind::Layout, false, voxel);
        assert_eq!((rigid(0.02), small(0.02), layout(0.02)), (40, 12, 400));
        assert_eq!((rigid(0.01), small(0.01), layout(0.01)), (160, 48, 1600));
        // A book's 14-voxel fragment at 1 cm (office, 2026-11-24) is 3.5 voxels' area at 2 cm,
        // where it was always dropped: it is dropped at 1 cm too.
        assert!(14 < small(0.01));
    }
}
