//! Scene entities out of the panoptic map: labels resolved to (class, instance), instances too
//! small dropped, floor and ceiling each one entity, a labelled mesh cut per entity.

use std::collections::BTreeMap;

use glam::{IVec3, Vec3};
use serde::{Deserialize, Serialize};

use crate::classes::{ClassInfo, ClassTable, EntityKind};
use crate::geometry::TriMesh;
use crate::geometry::plane::{Plane, fit_plane};
use crate::map::{SegmentLabel, TsdfMap, extract_mesh};
use crate::panoptic::face_pieces::Slab;
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

/// The labels of one (class, instance), with their surface voxels and vote support.
struct Group {
    labels: Vec<SegmentLabel>,
    voxels: usize,
    weighted_support: f32,
}

/// Moves group `from` into group `into`: its labels, voxels and vote support.
fn merge_group(
    groups: &mut BTreeMap<(ClassId, InstanceId), Group>,
    from: (ClassId, InstanceId),
    into: (ClassId, InstanceId),
) {
    let piece = groups.remove(&from).expect("the group to merge");
    let host = groups.get_mut(&into).expect("the group merged into");
    host.labels.extend(piece.labels);
    host.labels.sort_unstable();
    host.voxels += piece.voxels;
    host.weighted_support += piece.weighted_support;
}

/// A wall is a plane: wall instances whose voxels lie on the plane of a larger wall instance are
/// pieces of it (a wall seen in parts, a mask split by the segmenter) and join it.
fn merge_coplanar_walls(
    groups: &mut BTreeMap<(ClassId, InstanceId), Group>,
    wall: ClassId,
    voxels: &[(IVec3, SegmentLabel)],
    map: &TsdfMap,
    max_distance: f32,
) {
    let walls: Vec<(ClassId, InstanceId)> =
        groups.keys().filter(|(c, _)| *c == wall).copied().collect();
    if walls.len() < 2 {
        return;
    }
    let mut group_of_label: BTreeMap<SegmentLabel, usize> = BTreeMap::new();
    for (k, key) in walls.iter().enumerate() {
        for &l in &groups[key].labels {
            group_of_label.insert(l, k);
        }
    }
    let mut points: Vec<Vec<Vec3>> = vec![Vec::new(); walls.len()];
    for (v, l) in voxels {
        if let Some(&k) = group_of_label.get(l) {
            points[k].push(map.voxel_center(*v));
        }
    }
    // Largest first, so pieces join the wall they belong to, never the other way round.
    let mut order: Vec<usize> = (0..walls.len()).collect();
    order.sort_by_key(|&k| (std::cmp::Reverse(points[k].len()), walls[k]));
    let planes: Vec<Option<Plane>> = points.iter().map(|p| fit_plane(p)).collect();
    let mut kept: Vec<usize> = Vec::new();
    for &k in &order {
        let host = kept.iter().copied().find(|&h| {
            let (Some(a), Some(b)) = (planes[h], planes[k]) else {
                return false;
            };
            let on_plane = points[k]
                .iter()
                .filter(|p| a.signed_distance(**p).abs() < max_distance)
                .count();
            a.normal.dot(b.normal).abs() > 0.95 && on_plane * 5 >= points[k].len() * 4
        });
        match host {
            Some(h) => {
                merge_group(groups, walls[k], walls[h]);
            }
            None => kept.push(k),
        }
    }
}

/// The smallest and largest voxel index along each axis, leaving out `trim` of the voxels at
/// each end of each axis; `None` for no voxels.
fn voxel_bounds(voxels: &[IVec3], trim: f32) -> Option<(IVec3, IVec3)> {
    if voxels.is_empty() {
        return None;
    }
    let n = voxels.len();
    let cut = ((trim * n as f32) as usize).min((n - 1) / 2);
    let mut lo = IVec3::ZERO;
    let mut hi = IVec3::ZERO;
    for axis in 0..3 {
        let mut along: Vec<i32> = voxels.iter().map(|v| v[axis]).collect();
        along.sort_unstable();
        lo[axis] = along[cut];
        hi[axis] = along[n - 1 - cut];
    }
    Some((lo, hi))
}

/// The share of an object's voxels left out at each end of its box when a piece of another class
/// is tested for lying inside it: a label's stray voxels far from the object (a few dozen of
/// 11k in a procedural room) would stretch its box over anything.
const HOST_BOUNDS_TRIM: f32 = 0.01;

/// Whether box `inner` lies within box `outer` grown by `slack` voxels on every side.
fn encloses(outer: (IVec3, IVec3), inner: (IVec3, IVec3), slack: i32) -> bool {
    inner.0.cmpge(outer.0 - IVec3::splat(slack)).all()
        && inner.1.cmple(outer.1 + IVec3::splat(slack)).all()
}

/// A piece of an object that instance fusion kept apart joins the instance of its class it
/// touches (surface voxels 26-adjacent): a small piece (a patch of the oven's top under an
/// instance of its own) when it has at most `share` of that instance's voxels, and a slab of a
/// large class lying over a face of it (a cabinet's front, `face_pieces`; within two voxels)
/// whatever its size. Two objects of one class that touch are both whole, neither much smaller
/// than the other nor a face of it. Layout is left alone (a wall's corner touches the next
/// wall).
///
/// A piece that `may_be_foreign` (large fixed furniture, big enough to be kept as an entity of
/// its own: a smaller one is dropped anyway) may also join a large object of another class: when
/// it has at most `share` of that object's voxels and lies within the object's voxel box (one
/// voxel of slack). That is the segmenter's noise labelling a patch of a shelf's back as
/// cabinet, or a patch of a bed as sofa: no cabinet stands inside a shelf's outline. A movable
/// object inside a large one (a box on a shelf, a cup in a cabinet) is a thing of its own.
fn absorb_fragments(
    groups: &mut BTreeMap<(ClassId, InstanceId), Group>,
    voxels: &[(IVec3, SegmentLabel)],
    is_object: impl Fn(ClassId) -> bool,
    is_large: impl Fn(ClassId) -> bool,
    may_be_foreign: impl Fn(ClassId, usize) -> bool,
    share: f32,
    voxel_size: f32,
) {
    let mut group_of_label: BTreeMap<SegmentLabel, (ClassId, InstanceId)> = BTreeMap::new();
    for (key, g) in groups.iter().filter(|(k, _)| is_object(k.0)) {
        for &l in &g.labels {
            group_of_label.insert(l, *key);
        }
    }
    let group_at: std::collections::HashMap<IVec3, (ClassId, InstanceId)> = voxels
        .iter()
        .filter_map(|(v, l)| group_of_label.get(l).map(|k| (*v, *k)))
        .collect();
    let mut voxels_of: BTreeMap<(ClassId, InstanceId), Vec<IVec3>> = BTreeMap::new();
    for (v, l) in voxels {
        if let Some(k) = group_of_label.get(l) {
            voxels_of.entry(*k).or_default().push(*v);
        }
    }
    // Only a group this small next to the largest of its class can be a fragment at all.
    let mut largest: BTreeMap<ClassId, usize> = BTreeMap::new();
    for (k, g) in groups.iter() {
        let n = largest.entry(k.0).or_default();
        *n = (*n).max(g.voxels);
    }
    // Smallest first, each into the largest same-class instance it touches that is big enough.
    let mut order: Vec<(ClassId, InstanceId)> =
        groups.keys().copied().filter(|k| is_object(k.0)).collect();
    order.sort_by_key(|k| (groups[k].voxels, *k));
    // A fragment already absorbed answers for its host.
    let mut host_of: BTreeMap<(ClassId, InstanceId), (ClassId, InstanceId)> = BTreeMap::new();
    let resolve = |host_of: &BTreeMap<_, _>, mut k: (ClassId, InstanceId)| {
        while let Some(&h) = host_of.get(&k) {
            k = h;
        }
        k
    };
    let no_voxels = Vec::new();
    let voxels_in = |k: &(ClassId, InstanceId)| voxels_of.get(k).unwrap_or(&no_voxels);
    for small in order {
        let size = groups[&small].voxels;
        let piece = voxels_in(&small);
        let fragment = size as f32 <= share * largest[&small.0] as f32;
        let slab = is_large(small.0)
            .then(|| Slab::of(piece, voxel_size))
            .flatten();
        let foreign = may_be_foreign(small.0, size);
        if !fragment && slab.is_none() && !foreign {
            continue;
        }
        // A front stands a little proud of its carcass: a voxel may lie between them.
        let reach = if slab.is_some() { 2 } else { 1 };
        let mut touching: BTreeMap<(ClassId, InstanceId), usize> = BTreeMap::new();
        let mut touching_foreign: BTreeMap<(ClassId, InstanceId), usize> = BTreeMap::new();
        for v in piece {
            for dz in -reach..=reach {
                for dy in -reach..=reach {
                    for dx in -reach..=reach {
                        if let Some(&other) = group_at.get(&(*v + IVec3::new(dx, dy, dz))) {
                            let other = resolve(&host_of, other);
                            if other.0 == small.0 && other != small {
                                touching.insert(other, groups[&other].voxels);
                            } else if foreign && other.0 != small.0 && is_large(other.0) {
                                touching_foreign.insert(other, groups[&other].voxels);
                            }
                        }
                    }
                }
            }
        }
        let same_class_host = touching
            .into_iter()
            .filter(|(k, n)| {
                (fragment && size as f32 <= share * *n as f32)
                    || slab.is_some_and(|s| s.lies_on_face_of(piece, voxels_in(k), voxel_size))
            })
            .max_by_key(|(k, n)| (*n, std::cmp::Reverse(*k)))
            .map(|(k, _)| k);
        let host = same_class_host.or_else(|| {
            let piece_bounds = voxel_bounds(piece, 0.0)?;
            touching_foreign
                .into_iter()
                .filter(|(k, n)| {
                    size as f32 <= share * *n as f32
                        && voxel_bounds(voxels_in(k), HOST_BOUNDS_TRIM)
                            .is_some_and(|b| encloses(b, piece_bounds, 1))
                })
                .max_by_key(|(k, n)| (*n, std::cmp::Reverse(*k)))
                .map(|(k, _)| k)
        });
        if let Some(host) = host {
            merge_group(groups, small, host);
            host_of.insert(small, host);
            let grown = groups[&host].voxels;
            largest.entry(host.0).and_modify(|n| *n = (*n).max(grown));
        }
    }
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
    absorb_fragments(
        &mut groups,
        &voxels,
        is_object,
        is_large,
        may_be_foreign,
        params.fragment_share,
        map.voxel_size,
    );
    let mut entities: Vec<PanopticEntity> = Vec::new();
    let mut per_class_count: BTreeMap<String, usize> = BTreeMap::new();
    for ((class_id, instance), g) in groups {
        let class = classes.name(class_id).to_string();
        let info = table.get(&class);
        let kind = info.map_or(EntityKind::Rigid, |c| c.kind);
        let small = info.is_some_and(|c| params.is_small(c));
        if g.voxels < params.min_surface_voxels(kind, small, map.voxel_size) {
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

    fn group(labels: &[SegmentLabel], voxels: usize) -> Group {
        Group {
            labels: labels.to_vec(),
            voxels,
            weighted_support: voxels as f32,
        }
    }

    #[test]
    fn a_small_piece_touching_an_instance_of_its_class_joins_it() {
        // Class 1: a 10x10 patch (label 1), a 2-voxel piece touching it (label 2), and a twin
        // patch touching it (label 3). Class 2: a piece touching the patch (label 4). Layout
        // class 9: a piece touching a large wall (labels 5, 6).
        let mut voxels = Vec::new();
        for y in 0..10 {
            for x in 0..10 {
                voxels.push((IVec3::new(x, y, 0), 1));
                voxels.push((IVec3::new(x + 10, y, 0), 3));
                voxels.push((IVec3::new(x, y, 5), 6));
            }
        }
        voxels.extend([
            (IVec3::new(0, 10, 0), 2),
            (IVec3::new(1, 10, 0), 2),
            (IVec3::new(2, 10, 0), 4),
            (IVec3::new(0, 10, 5), 5),
        ]);
        let mut groups = BTreeMap::from([
            ((1, 1), group(&[1], 100)),
            ((1, 2), group(&[2], 2)),
            ((1, 3), group(&[3], 100)),
            ((2, 4), group(&[4], 1)),
            ((9, 5), group(&[5], 1)),
            ((9, 6), group(&[6], 100)),
        ]);
        absorb_fragments(
            &mut groups,
            &voxels,
            |c| c != 9,
            |_| false,
            |_, _| false,
            0.05,
            0.02,
        );
        assert_eq!(groups[&(1, 1)].labels, vec![1, 2], "the piece joins");
        assert_eq!(groups[&(1, 1)].voxels, 102);
        assert!(groups.contains_key(&(1, 3)), "a touching twin stays whole");
        assert!(groups.contains_key(&(2, 4)), "another class stays");
        assert!(groups.contains_key(&(9, 5)), "layout is left alone");
    }

    #[test]
    fn a_cabinet_s_front_kept_apart_joins_its_carcass_and_a_neighbour_seen_from_the_front_does_not()
    {
        // 2 cm voxels, class 5 (a large class): a carcass 60 x 56 x 86 cm seen without its front
        // (label 1), its front a slab one voxel in front of it (label 2), and the front of the
        // next cabinet beside it (label 3).
        let mut voxels = Vec::new();
        for x in 0..=30 {
            for y in 0..=28 {
                for z in 0..=43 {
                    let side = x == 0 || x == 30 || y == 28 || z == 0 || z == 43;
                    if side {
                        voxels.push((IVec3::new(x, y, z), 1));
                    }
                }
            }
        }
        for x in 1..=29 {
            for z in 1..=42 {
                voxels.push((IVec3::new(x, -2, z), 2));
                voxels.push((IVec3::new(x + 31, -2, z), 3));
            }
        }
        let count = |l: SegmentLabel| voxels.iter().filter(|(_, k)| *k == l).count();
        let mut groups = BTreeMap::from([
            ((5, 1), group(&[1], count(1))),
            ((5, 2), group(&[2], count(2))),
            ((5, 3), group(&[3], count(3))),
        ]);
        absorb_fragments(
            &mut groups,
            &voxels,
            |_| true,
            |c| c == 5,
            |_, _| false,
            0.05,
            0.02,
        );
        assert_eq!(
            groups[&(5, 1)].labels,
            vec![1, 2],
            "the front joins its carcass"
        );
        assert!(
            groups.contains_key(&(5, 3)),
            "the neighbour's front stays its own"
        );
        // A small class's slabs are left as they are.
        let mut groups = BTreeMap::from([
            ((5, 1), group(&[1], count(1))),
            ((5, 2), group(&[2], count(2))),
        ]);
        absorb_fragments(
            &mut groups,
            &voxels,
            |_| true,
            |_| false,
            |_, _| false,
            0.05,
            0.02,
        );
        assert!(groups.contains_key(&(5, 2)));
    }

    #[test]
    fn a_patch_of_fixed_furniture_inside_another_class_s_object_joins_it() {
        // Class 1, a shelf (label 1): its back at y = 20, sides at x = 0 and 50, bottom at
        // z = 0. Class 2, cabinet (fixed): a patch on the back inside the shelf (label 2) and a
        // patch outside beside it, touching its side (label 3). Class 3, a cup (small, label
        // 4), and class 4, a box (large but movable, label 5), both standing on the bottom.
        let mut voxels = Vec::new();
        for x in 0..=50 {
            for y in 0..=20 {
                for z in 0..=90 {
                    let shell = y == 20 || x == 0 || x == 50 || z == 0;
                    if shell {
                        voxels.push((IVec3::new(x, y, z), 1));
                    }
                }
            }
        }
        for x in 10..=20 {
            for z in 10..=20 {
                voxels.push((IVec3::new(x, 19, z), 2));
            }
        }
        for x in 51..=60 {
            for z in 0..=10 {
                voxels.push((IVec3::new(x, 10, z), 3));
            }
        }
        // A few stray shelf voxels past the cabinet beside it: the shelf's box is not theirs.
        for x in 61..=65 {
            voxels.push((IVec3::new(x, 10, 5), 1));
        }
        for x in 20..=22 {
            for y in 10..=12 {
                voxels.push((IVec3::new(x, y, 1), 4));
            }
        }
        for x in 30..=40 {
            for y in 5..=15 {
                voxels.push((IVec3::new(x, y, 1), 5));
            }
        }
        let count = |l: SegmentLabel| voxels.iter().filter(|(_, k)| *k == l).count();
        let mut groups = BTreeMap::from([
            ((1, 1), group(&[1], count(1))),
            ((2, 2), group(&[2], count(2))),
            ((2, 3), group(&[3], count(3))),
            ((3, 4), group(&[4], count(4))),
            ((4, 5), group(&[5], count(5))),
        ]);
        assert!(
            count(2) * 20 <= count(1),
            "the patch has at most 5 % of the shelf"
        );
        let is_large = |c: ClassId| c != 3;
        let may_be_foreign = |c: ClassId, _voxels: usize| c <= 2;
        absorb_fragments(
            &mut groups,
            &voxels,
            |_| true,
            is_large,
            may_be_foreign,
            0.05,
            0.02,
        );
        assert_eq!(
            groups[&(1, 1)].labels,
            vec![1, 2],
            "the patch joins the shelf"
        );
        assert!(
            groups.contains_key(&(2, 3)),
            "a cabinet beside the shelf stays"
        );
        assert!(groups.contains_key(&(3, 4)), "a cup inside stays");
        assert!(groups.contains_key(&(4, 5)), "a box inside stays");
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

    #[test]
    fn a_piece_on_a_larger_walls_plane_joins_it_and_the_opposite_wall_stays() {
        let map = TsdfMap::new(0.02);
        let mut voxels = Vec::new();
        // Wall instance 1 (label 1): the plane x = 0, 2 m wide. Instance 2 (label 2): a piece of
        // the same plane beside it. Instance 3 (label 3): the parallel wall at x = 4 m.
        for y in 0..100 {
            for z in 0..50 {
                voxels.push((IVec3::new(0, y, z), 1));
                if y < 30 {
                    voxels.push((IVec3::new(1, y + 110, z), 2));
                    voxels.push((IVec3::new(200, y, z), 3));
                }
            }
        }
        let mut groups = BTreeMap::from([
            ((7, 1), group(&[1], 5000)),
            ((7, 2), group(&[2], 1500)),
            ((7, 3), group(&[3], 1500)),
            ((2, 4), group(&[4], 10)),
        ]);
        merge_coplanar_walls(&mut groups, 7, &voxels, &map, 0.05);
        assert_eq!(groups.len(), 3);
        assert_eq!(groups[&(7, 1)].labels, vec![1, 2]);
        assert_eq!(groups[&(7, 1)].voxels, 6500);
        assert_eq!(groups[&(7, 3)].labels, vec![3]);
        assert!(groups.contains_key(&(2, 4)), "other classes are untouched");
    }
}
