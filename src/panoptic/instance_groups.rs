//! Labels grouped into scene objects: wall instances on one plane join, and pieces of an object
//! that instance fusion kept apart join it (`absorb_fragments`).

use std::collections::BTreeMap;

use glam::{IVec3, Vec3};

use crate::geometry::plane::{Plane, fit_plane};
use crate::map::{SegmentLabel, TsdfMap};
use crate::panoptic::face_pieces::Slab;
use crate::panoptic::instances::{ClassId, InstanceId};

/// The labels of one (class, instance), with their surface voxels and vote support.
pub(super) struct Group {
    pub(super) labels: Vec<SegmentLabel>,
    pub(super) voxels: usize,
    pub(super) weighted_support: f32,
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
pub(super) fn merge_coplanar_walls(
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
///
/// A piece of a large class that `no_object_of_its_class` could be (its voxel box, in metres, is
/// smaller than any object of its class on two of its three sides) joins the larger instance of
/// its class it touches whatever its share: a dishwasher's kick plate (0.8 x 38 x 11 cm, 74
/// voxels against the dishwasher's 1426) stood as a second dishwasher in front of the first,
/// whose model the physical check then pushed 7 cm back. A front seen without its carcass is
/// too shallow on one side only, and stays.
#[allow(clippy::too_many_arguments, reason = "the rules of one merge")]
pub(super) fn absorb_fragments(
    groups: &mut BTreeMap<(ClassId, InstanceId), Group>,
    voxels: &[(IVec3, SegmentLabel)],
    is_object: impl Fn(ClassId) -> bool,
    is_large: impl Fn(ClassId) -> bool,
    may_be_foreign: impl Fn(ClassId, usize) -> bool,
    no_object_of_its_class: impl Fn(ClassId, Vec3) -> bool,
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
        let lone = is_large(small.0)
            && voxel_bounds(piece, 0.0).is_some_and(|(lo, hi)| {
                no_object_of_its_class(small.0, (hi - lo + IVec3::ONE).as_vec3() * voxel_size)
            });
        let fragment = lone || size as f32 <= share * largest[&small.0] as f32;
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
                (fragment && (size as f32 <= share * *n as f32 || (lone && *n > size)))
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `absorb_fragments` with a 5 % share and 2 cm voxels.
    fn absorb(
        groups: &mut BTreeMap<(ClassId, InstanceId), Group>,
        voxels: &[(IVec3, SegmentLabel)],
        is_object: impl Fn(ClassId) -> bool,
        is_large: impl Fn(ClassId) -> bool,
        may_be_foreign: impl Fn(ClassId, usize) -> bool,
    ) {
        absorb_fragments(
            groups,
            voxels,
            is_object,
            is_large,
            may_be_foreign,
            |_, _| false,
            0.05,
            0.02,
        );
    }

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
        absorb(&mut groups, &voxels, |c| c != 9, |_| false, |_, _| false);
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
        absorb(&mut groups, &voxels, |_| true, |c| c == 5, |_, _| false);
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
        absorb(&mut groups, &voxels, |_| true, |_| false, |_, _| false);
        assert!(groups.contains_key(&(5, 2)));
    }

    #[test]
    fn a_piece_no_object_of_its_class_could_be_joins_the_instance_it_touches_whatever_its_share() {
        // 2 cm voxels, class 5 (large): a dishwasher's front 60 x 80 cm (label 1, at y = 0), its
        // kick plate below it, 38 x 10 cm in the same plane (label 2, 7 % of the front's
        // voxels), and touching it another unit's front 54 x 80 cm seen without its carcass
        // (label 3). The class's least size is 45 x 50 x 75 cm.
        let mut voxels = Vec::new();
        for z in 5..45 {
            for x in 0..30 {
                voxels.push((IVec3::new(x, 0, z), 1));
            }
            for x in 30..57 {
                voxels.push((IVec3::new(x, 0, z), 3));
            }
        }
        for z in 0..5 {
            for x in 5..24 {
                voxels.push((IVec3::new(x, 0, z), 2));
            }
        }
        let count = |l: SegmentLabel| voxels.iter().filter(|(_, k)| *k == l).count();
        assert!(count(2) as f32 > 0.05 * count(1) as f32, "above the share");
        let least = Vec3::new(0.45, 0.5, 0.75);
        let no_dishwasher = |_: ClassId, e: Vec3| {
            let (short, long) = (e.x.min(e.y), e.x.max(e.y));
            [short < least.x, long < least.y, e.z < least.z]
                .iter()
                .filter(|&&u| u)
                .count()
                >= 2
        };
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
            no_dishwasher,
            0.05,
            0.02,
        );
        assert_eq!(groups[&(5, 1)].labels, vec![1, 2], "the kick plate joins");
        assert!(
            groups.contains_key(&(5, 3)),
            "a front too shallow on one side stays"
        );
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
        absorb(&mut groups, &voxels, |_| true, is_large, may_be_foreign);
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
