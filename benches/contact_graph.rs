//! The contact-graph stage on a reconstructed room (issue 4's goal: a 30-entity scene under
//! 100 ms on 2 cores). Setup, untimed: render the office and map every third frame; then the
//! entities' meshes go through `build_contact_graph` (boxes, planes, supports, proximal pairs).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use iscene::graph::build::{ContactGraphParams, GraphEntity, build_contact_graph};
use iscene::io::panoptic_dir::read_panoptic;
use iscene::io::ply::read_mesh_ply;
use iscene::panoptic::InstanceFusion;
use iscene::pipeline::{ReconstructOptions, SegmentationChoice, reconstruct};

fn contact_graph(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("office");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/office.json");
    reconstruct(&ReconstructOptions {
        input: Some(spec),
        out: out.clone(),
        frames: Some((0, None, 3)),
        voxel: 0.02,
        segmentation: SegmentationChoice::Oracle,
        fusion: InstanceFusion::Joint,
        estimate_gravity: false,
        progress: false,
    })
    .expect("reconstruct the office");
    let (index, _) = read_panoptic(&out.join("panoptic")).expect("panoptic folder");
    let meshes: Vec<_> = index
        .entities
        .iter()
        .map(|e| read_mesh_ply(&out.join("panoptic").join(format!("{}.ply", e.id))).expect("mesh"))
        .collect();
    let entities: Vec<GraphEntity> = index
        .entities
        .iter()
        .zip(&meshes)
        .map(|(e, mesh)| GraphEntity {
            id: &e.id,
            class: &e.class,
            kind: e.kind,
            mesh,
        })
        .collect();
    let params = ContactGraphParams::for_voxel(0.02);
    let name = format!("contact_graph_office_{}_entities", entities.len());
    c.bench_function(&name, |b| {
        b.iter(|| build_contact_graph(&entities, &params))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = contact_graph
}
criterion_main!(benches);
