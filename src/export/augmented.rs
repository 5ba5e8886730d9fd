//! The augmented geometry of Sivananda et al.: the map's surface with the segments of replaced
//! objects taken out and their CAD models' complete surfaces put in, as one point cloud
//! (`augmented.ply`) for planners that want the whole shape of what was seen from one side (a
//! table's far legs, a chair's back). In the aligned frame (z up, floor at z = 0), at the map's
//! voxel spacing; every point carries its entity (the index in `panoptic/entities.json` plus
//! one, 0 for none, as in `panoptic/surface_voxels.ply`), whether it comes from a model, and its
//! class's colour.

use std::collections::{HashMap, HashSet};

use glam::{Affine3A, IVec3, Mat4, Vec3};

use crate::cad::db::database::CadDatabase;
use crate::geometry::surface_points::surface_points;
use crate::graph::ContactGraph;
use crate::panoptic::PanopticEntity;
use crate::panoptic::panoptic_dir::class_color;

/// One point of the augmented geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AugmentedPoint {
    /// Aligned frame.
    pub position: Vec3,
    /// Index in the entity list plus one; 0 for surface no entity holds.
    pub entity: u32,
    /// On a CAD model's surface rather than the map's.
    pub from_model: bool,
}

/// The map's surface voxels (`surface_voxels`, world frame, each with its entity index plus
/// one) without those of replaced entities, plus the surfaces of the models the contact graph
/// places (closed, at `spacing`, one point per voxel cell), all in the aligned frame. Entities
/// whose model is not in `db` keep their segments.
pub fn augmented_points(
    surface_voxels: &[(Vec3, u32)],
    aligned_from_world: &Affine3A,
    entities: &[PanopticEntity],
    graph: &ContactGraph,
    db: &CadDatabase,
    spacing: f32,
) -> Vec<AugmentedPoint> {
    let index_of: HashMap<&str, u32> = entities
        .iter()
        .enumerate()
        .map(|(i, e)| (e.id.as_str(), i as u32 + 1))
        .collect();
    let models: Vec<(u32, Vec<Vec3>)> = graph
        .nodes
        .iter()
        .filter_map(|node| {
            let cad = node.cad.as_ref()?;
            let entity = *index_of.get(node.id.as_str())?;
            let model = db.get(&cad.model)?;
            let pose = Affine3A::from_mat4(Mat4::from_cols_array(&cad.world_from_model));
            let mesh = model.model.merged_mesh(&[]).transformed(&pose);
            Some((
                entity,
                thinned(surface_points(&mesh, spacing).points, spacing),
            ))
        })
        .collect();
    let replaced: HashSet<u32> = models.iter().map(|(e, _)| *e).collect();
    let map = surface_voxels
        .iter()
        .filter(|(_, e)| !replaced.contains(e))
        .map(|(p, e)| AugmentedPoint {
            position: aligned_from_world.transform_point3(*p),
            entity: *e,
            from_model: false,
        });
    let model_points = models.into_iter().flat_map(|(entity, points)| {
        points.into_iter().map(move |position| AugmentedPoint {
            position,
            entity,
            from_model: true,
        })
    });
    map.chain(model_points).collect()
}

/// The first point in every cell of a `spacing` grid, in input order.
fn thinned(points: Vec<Vec3>, spacing: f32) -> Vec<Vec3> {
    let mut seen: HashSet<IVec3> = HashSet::new();
    points
        .into_iter()
        .filter(|p| p.is_finite() && seen.insert((*p / spacing).floor().as_ivec3()))
        .collect()
}

/// `points` as binary little-endian PLY: x, y, z, entity, from_model (0 or 1), red, green, blue
/// (the entity's class colour, grey for none). `classes` is each entity's class, in order.
/// Written by hand rather than through ply-rs: one fixed record per point, and a scene has
/// hundreds of thousands of them.
pub fn augmented_ply_bytes(points: &[AugmentedPoint], classes: &[&str]) -> Vec<u8> {
    let header = format!(
        "ply\nformat binary_little_endian 1.0\n\
         comment augmented geometry: map surface minus replaced segments plus CAD model surfaces\n\
         comment aligned frame (z up, floor at 0); entity = index in panoptic/entities.json + 1, 0 = none\n\
         element vertex {}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uint entity\nproperty uchar from_model\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         end_header\n",
        points.len()
    );
    let colors: Vec<[u8; 3]> = classes
        .iter()
        .map(|c| class_color(c).map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8))
        .collect();
    let mut bytes = Vec::with_capacity(header.len() + points.len() * 20);
    bytes.extend_from_slice(header.as_bytes());
    for p in points {
        let rgb = (p.entity as usize)
            .checked_sub(1)
            .and_then(|i| colors.get(i))
            .copied()
            .unwrap_or([128; 3]);
        for v in p.position.to_array() {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        bytes.extend_from_slice(&p.entity.to_le_bytes());
        bytes.push(u8::from(p.from_model));
        bytes.extend_from_slice(&rgb);
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::classes::EntityKind;
    use crate::geometry::GravityBox;
    use crate::graph::{CadPlacement, ContactGraph, GraphNode};

    #[test]
    fn replaced_segments_give_way_to_their_model_surfaces() {
        let db = CadDatabase::parametric();
        let (_, table) = db.of_class("table").next().expect("a table");
        let entity = |id: &str, class: &str| PanopticEntity {
            id: id.into(),
            class: class.into(),
            kind: EntityKind::Rigid,
            instance: 0,
            score: 1.0,
            surface_voxels: 0,
            labels: Vec::new(),
            mesh: Default::default(),
        };
        let entities = vec![
            entity("floor", "floor"),
            entity("table_1", "table"),
            entity("cup_1", "cup"),
        ];
        // The map: floor voxels, the table's seen top, a cup, and unlabelled clutter; the world
        // frame is the aligned one shifted by 1 m in x.
        let mut voxels: Vec<(Vec3, u32)> = (0..10)
            .map(|i| (Vec3::new(i as f32 * 0.1, 0.0, 0.0), 1))
            .collect();
        voxels.extend((0..5).map(|i| (Vec3::new(i as f32 * 0.1, 0.1, 0.75), 2)));
        voxels.push((Vec3::new(0.2, 0.2, 0.8), 3));
        voxels.push((Vec3::new(3.0, 3.0, 1.0), 0));
        let aligned_from_world = Affine3A::from_translation(Vec3::new(-1.0, 0.0, 0.0));
        let mut graph = ContactGraph::default();
        for e in &entities {
            graph.nodes.push(GraphNode {
                id: e.id.clone(),
                class: e.class.clone(),
                kind: e.kind,
                bbox: GravityBox {
                    center: Vec3::ZERO,
                    yaw: 0.0,
                    size: Vec3::ONE,
                }
                .into(),
                planes: Vec::new(),
                cad: None,
                joints: Default::default(),
                parts: Vec::new(),
            });
        }
        let pose = Affine3A::from_translation(Vec3::new(0.5, 0.5, 0.0));
        graph.nodes[1].cad = Some(CadPlacement {
            model: table.model.id.clone(),
            world_from_model: Mat4::from(pose).to_cols_array(),
            scale: 1.0,
            alignment_error: 0.0,
        });
        let points = augmented_points(&voxels, &aligned_from_world, &entities, &graph, &db, 0.02);
        // The table's segment is gone; floor, cup and clutter stay, moved into the aligned frame.
        assert!(points.iter().all(|p| p.entity != 2 || p.from_model));
        assert_eq!(points.iter().filter(|p| !p.from_model).count(), 12);
        assert!(points.contains(&AugmentedPoint {
            position: Vec3::new(2.0, 3.0, 1.0),
            entity: 0,
            from_model: false
        }));
        // The model's surface is in, complete (down to its feet on the floor), one point per
        // 2 cm cell, within the model's box at its pose.
        let model: Vec<Vec3> = points
            .iter()
            .filter(|p| p.from_model)
            .map(|p| p.position)
            .collect();
        assert!(model.len() > 1000, "{}", model.len());
        let (lo, hi) = table.mesh.bounds().expect("bounds");
        let (lo, hi) = (pose.transform_point3(lo), pose.transform_point3(hi));
        assert!(
            model
                .iter()
                .all(|p| p.cmpge(lo - 1e-4).all() && p.cmple(hi + 1e-4).all())
        );
        assert!(model.iter().any(|p| p.z < 0.01) && model.iter().any(|p| p.z > hi.z - 0.01));
        let cells: HashSet<IVec3> = model
            .iter()
            .map(|p| (*p / 0.02).floor().as_ivec3())
            .collect();
        assert_eq!(cells.len(), model.len());
        let classes: Vec<&str> = entities.iter().map(|e| e.class.as_str()).collect();
        // ply-rs reads back what was written by hand.
        let bytes = augmented_ply_bytes(&points, &classes);
        let ply = ply_rs_bw::parser::Parser::<ply_rs_bw::ply::DefaultElement>::new()
            .read_ply(&mut bytes.as_slice())
            .expect("a PLY file");
        let vertices = &ply.payload["vertex"];
        assert_eq!(vertices.len(), points.len());
        let last = vertices.last().expect("points");
        assert_eq!(last["from_model"], ply_rs_bw::ply::Property::UChar(1));
        assert_eq!(last["entity"], ply_rs_bw::ply::Property::UInt(2));
        assert_eq!(
            last["x"],
            ply_rs_bw::ply::Property::Float(points.last().expect("points").position.x)
        );
    }
}
