//! Setup shared by the benchmarks (untimed): a rendered scene mapped into entity meshes.

use std::path::Path;

use iscene::geometry::TriMesh;
use iscene::graph::build::GraphEntity;
use iscene::io::ply::read_mesh_ply;
use iscene::panoptic::PanopticEntity;
use iscene::panoptic::panoptic_dir::read_panoptic;
use iscene::pipeline::{ReconstructOptions, reconstruct};

/// Renders `scenes/<scene>.json`, maps every third frame at 2 cm with the oracle segmentation
/// into `dir/<scene>`, and returns the entities with their meshes.
pub fn mapped_entities(scene: &str, dir: &Path) -> (Vec<PanopticEntity>, Vec<TriMesh>) {
    let out = dir.join(scene);
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{scene}.json"));
    reconstruct(&ReconstructOptions {
        frames: Some((0, None, 3)),
        ..ReconstructOptions::new(spec, &out)
    })
    .expect("reconstruct");
    let (index, _) = read_panoptic(&out.join("panoptic")).expect("panoptic folder");
    let meshes = index
        .entities
        .iter()
        .map(|e| read_mesh_ply(&out.join("panoptic").join(format!("{}.ply", e.id))).expect("mesh"))
        .collect();
    (index.entities, meshes)
}

/// The contact graph's view of mapped entities.
pub fn graph_entities<'a>(
    found: &'a [PanopticEntity],
    meshes: &'a [TriMesh],
) -> Vec<GraphEntity<'a>> {
    found
        .iter()
        .zip(meshes)
        .map(|(e, mesh)| GraphEntity {
            id: &e.id,
            class: &e.class,
            kind: e.kind,
            mesh,
            sighted: &[],
        })
        .collect()
}
