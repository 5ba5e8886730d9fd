//! The contact-graph stage on a reconstructed room (issue 4's goal: a 30-entity scene under
//! 100 ms on 2 cores). Setup, untimed: render the office and map every third frame; then the
//! entities' meshes go through `build_contact_graph` (boxes, planes, supports, proximal pairs).

mod common;

use criterion::{Criterion, criterion_group, criterion_main};
use iscene::graph::build::{ContactGraphParams, build_contact_graph};

fn contact_graph(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let (found, meshes) = common::mapped_entities("office", dir.path());
    let entities = common::graph_entities(&found, &meshes);
    let params = ContactGraphParams::for_voxel(0.02, false);
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
