//! The contact graph built from the ground-truth meshes of every rendered scene is the scene's own
//! graph: every support parent and every proximal pair.

use std::collections::BTreeSet;
use std::path::Path;

use crate::common;

use iscene::eval::evaluate_reconstruction;
use iscene::graph::build::{ContactGraphParams, GraphEntity, build_contact_graph};
use iscene::graph::{ContactGraph, GraphEdge};
use iscene::scene::{SceneSpec, SceneWorld};

type Pairs = BTreeSet<(String, String)>;

/// Support edges as (parent, child), proximal pairs with their ids in order.
fn edge_sets(g: &ContactGraph) -> (Pairs, Pairs) {
    let mut support = BTreeSet::new();
    let mut proximal = BTreeSet::new();
    for e in &g.edges {
        match e {
            GraphEdge::Support { parent, child } => {
                support.insert((parent.clone(), child.clone()));
            }
            GraphEdge::Proximal { a, b } => {
                proximal.insert((a.clone().min(b.clone()), a.clone().max(b.clone())));
            }
        }
    }
    (support, proximal)
}

#[test]
fn the_graph_of_ground_truth_meshes_is_the_scenes_graph() {
    let mut failures = Vec::new();
    for name in ["kitchen", "office", "living_room", "bedroom"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.json"));
        let text = std::fs::read_to_string(&path).expect("scene file");
        let spec = SceneSpec::parse(&text, &path).expect("spec");
        let world = SceneWorld::from_spec(&spec, &path).expect("world");
        let truth = world.contact_graph();
        let meshes = world.entity_meshes();
        let entities: Vec<GraphEntity> = meshes
            .iter()
            .map(|(id, mesh, _)| {
                let node = truth.node(id).expect("every mesh is a node");
                GraphEntity {
                    id,
                    class: &node.class,
                    kind: node.kind,
                    mesh,
                    sighted: &[],
                }
            })
            .collect();
        let built = build_contact_graph(&entities, &ContactGraphParams::default());
        built.check().expect("a valid graph");
        let (support, proximal) = edge_sets(&built);
        let (true_support, true_proximal) = edge_sets(&truth);
        for e in true_support.difference(&support) {
            failures.push(format!("{name}: missing support {e:?} (parent, child)"));
        }
        for e in support.difference(&true_support) {
            failures.push(format!("{name}: wrong support {e:?}"));
        }
        for e in true_proximal.difference(&proximal) {
            failures.push(format!("{name}: missing proximal {e:?}"));
        }
        for e in proximal.difference(&true_proximal) {
            failures.push(format!("{name}: extra proximal {e:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The kitchen through the whole pipeline with realistic depth and segmentation noise, every
/// second frame: every seen entity is found and every support parent is right (the wall cabinet
/// on its wall, the microwave on its cabinet, cups and the bowl on the table); oriented boxes
/// reach issue 4's mAP@0.5 bar. What remains of the edit distance is proximal pairs: the fridge
/// 5.4 cm off its wall touches it in the map, two cabinets 1.8 cm off it are seen 3 to 5 cm off
/// (measured on this run: box mAP 1.00, GED 3, all proximal).
#[test]
fn the_kitchens_contact_graph_has_every_support_right() {
    let (seq, out) = common::shared_noisy_map("kitchen");
    ContactGraph::load(&out.join("contact_graph.json")).expect("a valid contact_graph.json");
    let eval = evaluate_reconstruction(&out, &seq).expect("eval");
    let contact = eval.contact_graph.expect("contact-graph metrics");
    eprintln!(
        "obb mAP {:.3}, GED {:?}, unseen {:?}",
        contact.obb_map50, contact.ged, contact.unseen_truth
    );
    assert_eq!(
        contact.unseen_truth,
        ["box_1"],
        "only the box in the closed fridge is unseen"
    );
    assert_eq!(
        contact.ged.parts.nodes, 0,
        "every seen entity found, none extra"
    );
    assert_eq!(contact.ged.parts.support, 0, "every support parent right");
    assert!(
        contact.ged.parts.proximal <= 3,
        "proximal edits {}",
        contact.ged.parts.proximal
    );
    assert!(contact.obb_map50 >= 0.8, "box mAP {:.3}", contact.obb_map50);
}

/// Issue 4's bar: every scene rendered without noise and mapped with ground-truth segmentation
/// (every second frame, 2 cm voxels, the default) gets the scene's own contact graph, every
/// entity, support parent and proximal pair, and boxes at mAP@0.5 >= 0.8. The map alone cannot
/// do it: its boxes end at a voxel column, and furniture 0.8, 1.8 and 3.8 cm off a wall all
/// measured 2.9 cm off (3, 0, 0 and 2 proximal edits before the frames' outlines, README).
/// Noise-free depth is measured as such (`map::depth_precision`), so the objects' boxes are
/// fitted to their silhouettes in the frames (`panoptic::sighted`).
#[test]
fn clean_renders_get_the_scenes_own_contact_graph() {
    let mut failures = Vec::new();
    for name in ["kitchen", "office", "living_room", "bedroom"] {
        let dir = tempfile::tempdir().expect("tempdir");
        let (seq, out) = common::render_and_map_every_second_frame(name, dir.path(), true, 0.02);
        let eval = evaluate_reconstruction(&out, &seq).expect("eval");
        let contact = eval.contact_graph.expect("contact-graph metrics");
        eprintln!(
            "{name}: PQ {:.3}, obb mAP {:.3}, GED {:?}, unseen {:?}",
            eval.panoptic.pq, contact.obb_map50, contact.ged, contact.unseen_truth
        );
        if contact.ged.cost != 0 {
            failures.push(format!("{name}: edits {:?}", contact.ged.parts));
        }
        if contact.obb_map50 < 0.8 {
            failures.push(format!("{name}: box mAP {:.3}", contact.obb_map50));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
