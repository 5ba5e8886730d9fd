//! Carving the objects' meshes with the frames' free-space evidence (map/free_space.rs): the
//! run-on of tops and sides over a gap, which the TSDF's band behind grazing hits leaves, goes
//! before boxes are fitted and models aligned. Layout is left whole: a wall is seen past at its
//! openings, and its extent is surveyed from planes anyway.

use glam::Vec3;

use crate::classes::EntityKind;
use crate::error::InputError;
use crate::io::Sequence;
use crate::map::free_space::{FreeSpaceParams, Sightings, sequence_sightings};
use crate::panoptic::PanopticEntity;

fn is_object(e: &PanopticEntity) -> bool {
    e.kind != EntityKind::Layout
}

/// Removes from every object's mesh the vertices `sequence`'s frames saw past, and the
/// triangles using them.
pub fn carve_objects(
    entities: &mut [PanopticEntity],
    sequence: &Sequence,
    params: &FreeSpaceParams,
) -> Result<(), InputError> {
    let points: Vec<Vec3> = entities
        .iter()
        .filter(|e| is_object(e))
        .flat_map(|e| e.mesh.positions.iter().copied())
        .collect();
    let sightings = sequence_sightings(sequence, &points, params)?;
    carve_with(entities, &sightings, params);
    Ok(())
}

/// `sightings` holds the objects' vertices in entity order. An object whose every triangle
/// would go keeps its mesh (the evidence then says the segment is wrong, not where it ends).
fn carve_with(entities: &mut [PanopticEntity], sightings: &[Sightings], params: &FreeSpaceParams) {
    let mut offset = 0;
    for e in entities.iter_mut().filter(|e| is_object(e)) {
        let n = e.mesh.positions.len();
        let keep: Vec<bool> = sightings[offset..offset + n]
            .iter()
            .map(|s| !s.in_free_space(params))
            .collect();
        offset += n;
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
        };
        carve_with(&mut entities, &[seen_past; 3], &params);
        assert_eq!(entities[0].mesh, tri);
    }
}
