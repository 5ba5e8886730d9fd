//! Carving the objects' meshes with the frames' evidence (map/free_space.rs): the run-on of tops
//! and sides over a gap, which the TSDF's band behind grazing hits leaves, and the wall behind a
//! gap that the map labelled as the object in front, go before boxes are fitted and models
//! aligned. Layout is left whole: a wall is seen past at its openings, and its extent is
//! surveyed from planes anyway.

use std::collections::BTreeMap;

use glam::Vec3;

use crate::classes::EntityKind;
use crate::error::InputError;
use crate::geometry::TriMesh;
use crate::io::Sequence;
use crate::map::free_space::{EntityLabels, FreeSpaceParams, Sightings, sequence_sightings};
use crate::panoptic::{PanopticEntity, PanopticMapper};

fn is_object(e: &PanopticEntity) -> bool {
    e.kind != EntityKind::Layout
}

/// Objects narrower than this (metres, across their widest horizontal side) keep the vertices
/// the frames' labels would carve when over a third of them would go (a half for larger ones).
pub const HAND_SIZED_EXTENT_M: f32 = 0.2;

fn horizontal_extent(mesh: &TriMesh) -> f32 {
    mesh.bounds()
        .map_or(0.0, |(lo, hi)| (hi - lo).truncate().max_element())
}

/// Removes from every object's mesh the vertices `sequence`'s frames saw past or, by the label
/// images `mapper` kept of them, saw as another entity's, and the triangles using them.
/// `entities` are the ones extracted from `mapper`'s map, whose frames are `sequence`'s.
pub fn carve_objects(
    entities: &mut [PanopticEntity],
    sequence: &Sequence,
    mapper: &PanopticMapper,
    params: &FreeSpaceParams,
) -> Result<(), InputError> {
    let points: Vec<Vec3> = entities
        .iter()
        .filter(|e| is_object(e))
        .flat_map(|e| e.mesh.positions.iter().copied())
        .collect();
    // Entities are numbered from 1 in slice order; 0 is none.
    let point_entity: Vec<u32> = entities
        .iter()
        .enumerate()
        .filter(|(_, e)| is_object(e))
        .flat_map(|(k, e)| std::iter::repeat_n(k as u32 + 1, e.mesh.positions.len()))
        .collect();
    let entity_of_label = entity_of_frame_label(entities, mapper);
    // A map of other frames than these has nothing to say about them.
    let labels = (mapper.frame_labels().len() == sequence.frames.len()).then_some(EntityLabels {
        frames: mapper.frame_labels(),
        entity_of_label: &entity_of_label,
        point_entity: &point_entity,
    });
    let sightings = sequence_sightings(sequence, &points, labels.as_ref(), params)?;
    carve_with(entities, &sightings, params);
    Ok(())
}

/// The entity (numbered from 1 in `entities`' order; 0 is none) each label of `mapper`'s frames
/// went to: labels merged since go where the label they merged into went.
pub(crate) fn entity_of_frame_label(
    entities: &[PanopticEntity],
    mapper: &PanopticMapper,
) -> Vec<u32> {
    let entity_of_map_label: BTreeMap<_, u32> = entities
        .iter()
        .enumerate()
        .flat_map(|(k, e)| e.labels.iter().map(move |&l| (l, k as u32 + 1)))
        .collect();
    (0..mapper.label_count())
        .map(|l| {
            let now = mapper.label_now(l);
            entity_of_map_label.get(&now).copied().unwrap_or(0)
        })
        .collect()
}

/// `sightings` holds the objects' vertices in entity order. An object whose every triangle
/// would go keeps its mesh (the evidence then says the segment is wrong, not where it ends).
fn carve_with(entities: &mut [PanopticEntity], sightings: &[Sightings], params: &FreeSpaceParams) {
    let mut offset = 0;
    for e in entities.iter_mut().filter(|e| is_object(e)) {
        let n = e.mesh.positions.len();
        let seen = &sightings[offset..offset + n];
        offset += n;
        let labelled_other = seen
            .iter()
            .filter(|s| !s.in_free_space(params) && s.labelled_other(params))
            .count();
        // When the frames saw most of an object as something else, they disagree with the map
        // about what it is, not about where it ends (a cup half hidden behind a monitor, its
        // sliver under the monitor's bleeding mask): it keeps those vertices. A hand-sized
        // object is mostly the rim of its mask, so a third is already too much to lose (that
        // cup at every second frame: 28 of 61, and no model left; a lone bottle's rim under a
        // bleeding label: 15 to 35 %).
        let by_labels = if horizontal_extent(&e.mesh) >= HAND_SIZED_EXTENT_M {
            2 * labelled_other <= n
        } else {
            3 * labelled_other <= n
        };
        let keep: Vec<bool> = seen
            .iter()
            .map(|s| {
                let goes = s.in_free_space(params) || (by_labels && s.labelled_other(params));
                !goes
            })
            .collect();
        let carved = e.mesh.with_vertices(&keep);
        if !carved.triangles.is_empty() {
            e.mesh = carved;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;

    fn entity(id: &str, kind: EntityKind, mesh: TriMesh) -> PanopticEntity {
        PanopticEntity {
            id: id.into(),
            class: id.split('_').next().unwrap_or(id).into(),
            kind,
            instance: 1,
            score: 1.0,
            surface_voxels: mesh.positions.len(),
            labels: Vec::new(),
            mesh,
        }
    }

    /// Two triangles sharing an edge; the vertex only the second uses was seen past: the second
    /// triangle goes. The wall before it, with no sightings counted, is left alone.
    #[test]
    fn vertices_seen_past_go_with_their_triangles_and_layout_stays() {
        let quad = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        let mut entities = vec![
            entity("wall_0", EntityKind::Layout, quad.clone()),
            entity("cabinet_1", EntityKind::Rigid, quad.clone()),
        ];
        let params = FreeSpaceParams::for_voxel(0.02);
        // Ten frames with 1 cm of noise each (units: micrometres, square millimetres).
        let on_surface = Sightings {
            seen: 10,
            residual_sum: 0,
            variance_sum: 10 * 100,
            ..Sightings::default()
        };
        let seen_past = Sightings {
            residual_sum: 10 * 50_000,
            ..on_surface
        };
        carve_with(
            &mut entities,
            &[on_surface, on_surface, on_surface, seen_past],
            &params,
        );
        assert_eq!(entities[0].mesh, quad);
        assert_eq!(entities[1].mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(
            entities[1].mesh.positions,
            vec![Vec3::ZERO, Vec3::X, Vec3::Y]
        );
    }

    /// Six frames saw a vertex on the surface: mostly as its own entity's, or mostly as another's.
    fn own_and_anothers() -> (Sightings, Sightings) {
        let own = Sightings {
            seen: 6,
            variance_sum: 6 * 100,
            own_label: 5,
            other_label: 1,
            ..Sightings::default()
        };
        let anothers = Sightings {
            own_label: 2,
            other_label: 4,
            ..own
        };
        (own, anothers)
    }

    /// A vertex on the surface, but where most frames that saw it saw another entity: it goes.
    #[test]
    fn vertices_the_frames_saw_as_anothers_go() {
        let quad = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        let mut entities = vec![entity("shelf_1", EntityKind::Rigid, quad)];
        let params = FreeSpaceParams::for_voxel(0.02);
        let (own, wall) = own_and_anothers();
        carve_with(&mut entities, &[own, own, own, wall], &params);
        assert_eq!(entities[0].mesh.triangles, vec![[0, 1, 2]]);
    }

    /// A strip of three squares `side` metres wide (8 vertices, 6 triangles); the frames saw
    /// its last 3 vertices as another entity's. A 1 m strip loses them (3 of 8 is under half);
    /// a 10 cm one (a cup's size, mostly the rim of its mask) keeps them (over a third).
    #[test]
    fn a_hand_sized_object_keeps_a_third_of_its_vertices_seen_as_anothers() {
        let strip = |side: f32| TriMesh {
            positions: (0..8)
                .map(|k| {
                    Vec3::new(
                        (k / 2) as f32 * side / 3.0,
                        (k % 2) as f32 * side / 3.0,
                        0.0,
                    )
                })
                .collect(),
            triangles: (0..3)
                .flat_map(|i| {
                    [
                        [2 * i, 2 * i + 2, 2 * i + 1],
                        [2 * i + 2, 2 * i + 3, 2 * i + 1],
                    ]
                })
                .collect(),
        };
        let params = FreeSpaceParams::for_voxel(0.02);
        let (own, anothers) = own_and_anothers();
        let seen = [own, own, own, own, own, anothers, anothers, anothers];
        let mut entities = vec![
            entity("shelf_1", EntityKind::Rigid, strip(1.0)),
            entity("cup_1", EntityKind::Rigid, strip(0.1)),
        ];
        carve_with(&mut entities, &[seen, seen].concat(), &params);
        assert_eq!(entities[0].mesh.triangles.len(), 3);
        // Whole (reindexed in the order the triangles use the vertices).
        assert_eq!(entities[1].mesh.triangles.len(), 6);
        assert_eq!(entities[1].mesh.positions.len(), 8);
    }

    /// Every vertex seen past: the mesh stays whole.
    #[test]
    fn an_object_seen_past_everywhere_keeps_its_mesh() {
        let tri = TriMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 2]],
        };
        let mut entities = vec![entity("cup_1", EntityKind::Rigid, tri.clone())];
        let params = FreeSpaceParams::for_voxel(0.02);
        let seen_past = Sightings {
            seen: 10,
            residual_sum: 10 * 100_000,
            variance_sum: 10 * 100,
            ..Sightings::default()
        };
        carve_with(&mut entities, &[seen_past; 3], &params);
        assert_eq!(entities[0].mesh, tri);
    }
}
