//! CAD replacement on rendered scenes with realistic depth and segmentation noise (issue 5's
//! bar): the replacing model has the right class for >= 95% of seen objects, the yaw of objects
//! whose front matters is within 15 degrees for >= 90% of them, the mean alignment error is at
//! most 2 cm, articulated objects get articulated models, every support between two placed
//! objects passes the area test, nothing reaches over 1 cm into the floor or a wall, and models
//! interpenetrate by at most 1 cm with none reported in conflict. The kitchen's two cabinets in
//! a row come out of the map overlapping by 17 cm (their shared top's labels bleed into each
//! other); the physical check shrinks both back to the middle of the overlap.

use std::collections::BTreeMap;
use std::path::Path;

use crate::common;

use iscene::cad::ParametricLibrary;
use iscene::cad::library::library_model_id;
use iscene::classes::EntityKind;
use iscene::eval::evaluate_reconstruction;
use iscene::graph::ContactGraph;
use iscene::pipeline::AlignMethod;

#[test]
fn every_scene_gets_models_of_the_right_class_facing_the_right_way() {
    let failures: Vec<String> = ["kitchen", "office", "living_room", "bedroom"]
        .iter()
        .flat_map(|name| {
            let (seq, out) = common::shared_noisy_map(name);
            issue_bar(name, &seq, &out)
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The ICP route of Sivananda et al. (`--align icp`) on the same rendered sequences meets the
/// same bar: the kitchen (articulated models) and the bedroom (its 2 m wardrobe, the farthest
/// from any model's proportions). Office and living room pass too (README), but each scene costs
/// a mapping run, and the clean CI run is at its time limit.
#[test]
fn the_icp_route_meets_the_same_bar() {
    let failures: Vec<String> = ["kitchen", "bedroom"]
        .iter()
        .flat_map(|name| {
            let (seq, _) = common::shared_noisy_map(name);
            let out = Path::new(env!("CARGO_TARGET_TMPDIR"))
                .join("icp_maps")
                .join(name);
            common::map_every_second_frame_aligning(&seq, &out, None, AlignMethod::Icp);
            let report = read_json(&out.join("report.json"));
            assert_eq!(report["cad"]["align_method"], "icp");
            issue_bar(name, &seq, &out)
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

fn read_json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("readable")).expect("JSON")
}

/// What falls short of issue 5's bar in the reconstruction `out` of the sequence `seq`.
fn issue_bar(name: &str, seq: &Path, out: &Path) -> Vec<String> {
    let mut failures = Vec::new();
    let eval = evaluate_reconstruction(out, seq).expect("eval");
    let cad = eval.cad.expect("CAD metrics: the stage placed models");
    eprintln!(
        "{name}: class {:.3}, yaw {:?}, mean AE {:?} m, same model {:.3}",
        cad.class_accuracy, cad.yaw_accuracy, cad.mean_alignment_error_m, cad.model_accuracy
    );
    if cad.class_accuracy < 0.95 {
        failures.push(format!("{name}: class accuracy {:.3}", cad.class_accuracy));
    }
    match cad.yaw_accuracy {
        Some(y) if y >= 0.9 => {}
        other => failures.push(format!("{name}: yaw accuracy {other:?}")),
    }
    match cad.mean_alignment_error_m {
        Some(e) if e <= 0.02 => {}
        other => failures.push(format!("{name}: mean AE {other:?}")),
    }
    if cad.supports_passing != cad.supports_tested {
        failures.push(format!(
            "{name}: {} of {} supports pass the area test",
            cad.supports_passing, cad.supports_tested
        ));
    }
    match cad.max_layout_penetration_m {
        Some(d) if d <= 0.01 => {}
        other => failures.push(format!("{name}: into the layout by {other:?} m")),
    }
    let report = read_json(&out.join("report.json"));
    let conflicted = report["cad"]["conflicted"]
        .as_array()
        .expect("cad.conflicted")
        .len();
    eprintln!(
        "{name}: deepest interpenetration {:?} m, conflicts reported for {conflicted} objects",
        cad.max_penetration_m
    );
    match cad.max_penetration_m {
        Some(d) if d <= 0.01 && conflicted == 0 => {}
        other => failures.push(format!(
            "{name}: models interpenetrate by {other:?} m, {conflicted} in conflict"
        )),
    }
    let graph = ContactGraph::load(&out.join("contact_graph.json")).expect("graph");
    let objects = graph
        .nodes
        .iter()
        .filter(|n| n.kind != EntityKind::Layout)
        .count();
    let mut placed = BTreeMap::new();
    for node in &graph.nodes {
        let Some(c) = &node.cad else { continue };
        // A door or drawer unit no library model's handles agree with gets a model built from
        // its perceived parts (issue 36): articulated, of its class.
        if c.model.starts_with("perceived_") {
            if node.kind != EntityKind::Articulated || node.parts.is_empty() {
                failures.push(format!("{name}: {} got {} without parts", node.id, c.model));
            }
            placed.insert(node.id.clone(), c.model.clone());
            continue;
        }
        let entry = ParametricLibrary::get(library_model_id(&c.model))
            .unwrap_or_else(|| panic!("{name}: {} got {}, not a library model", node.id, c.model));
        assert_eq!(
            entry.class, node.class,
            "{name}: {} got {}",
            node.id, c.model
        );
        let articulated = entry.model().is_articulated();
        if articulated != (node.kind == EntityKind::Articulated) {
            failures.push(format!(
                "{name}: {} ({:?}) got {}",
                node.id, node.kind, c.model
            ));
        }
        placed.insert(node.id.clone(), c.model.clone());
    }
    if placed.len() != objects {
        failures.push(format!(
            "{name}: {} of {objects} objects placed",
            placed.len()
        ));
    }
    failures
}

/// The augmented geometry of Sivananda et al. (issue 5, step 6): `augmented.ply` holds the map's
/// surface voxels except those of replaced objects, and each replaced object's model surface
/// instead, complete down to the plane it stands on.
#[test]
fn the_augmented_geometry_swaps_replaced_segments_for_model_surfaces() {
    let (_, out) = common::shared_noisy_map("kitchen");
    let (index, voxels) = iscene::panoptic::panoptic_dir::read_panoptic(&out.join("panoptic"))
        .expect("panoptic folder");
    let graph = ContactGraph::load(&out.join("contact_graph.json")).expect("graph");
    let points = read_augmented(&out.join("augmented.ply"));
    let mut replaced = 0;
    for (i, entity) in index.entities.iter().enumerate() {
        let label = i as u32 + 1;
        let node = graph.node(&entity.id).expect("a node per entity");
        let seen = voxels.iter().filter(|(_, e)| *e == label).count();
        let map = points.iter().filter(|p| p.1 == label && !p.2).count();
        let model: Vec<[f32; 3]> = points
            .iter()
            .filter(|p| p.1 == label && p.2)
            .map(|p| p.0)
            .collect();
        match &node.cad {
            Some(_) => {
                replaced += 1;
                assert_eq!(map, 0, "{}: its segment stays", entity.id);
                assert!(
                    model.len() >= 50,
                    "{}: {} model points",
                    entity.id,
                    model.len()
                );
                // The model reaches down to the box's bottom (its support), unseen or not.
                let bottom = node.bbox.center[2] - 0.5 * node.bbox.size[2];
                let lowest = model.iter().map(|p| p[2]).fold(f32::MAX, f32::min);
                assert!(
                    (lowest - bottom).abs() < 0.03,
                    "{}: {lowest} vs {bottom}",
                    entity.id
                );
            }
            None => {
                assert_eq!(map, seen, "{}: its segment", entity.id);
                assert!(model.is_empty(), "{}", entity.id);
            }
        }
    }
    assert!(replaced >= 10, "{replaced} replaced");
    let unlabelled = voxels.iter().filter(|(_, e)| *e == 0).count();
    assert_eq!(points.iter().filter(|p| p.1 == 0).count(), unlabelled);
}

/// The points of `augmented.ply`: position, entity, from a model.
fn read_augmented(path: &Path) -> Vec<([f32; 3], u32, bool)> {
    use ply_rs_bw::ply::{DefaultElement, Property};
    let file = std::fs::File::open(path).expect("augmented.ply");
    let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
        .read_ply(&mut std::io::BufReader::new(file))
        .expect("a PLY file");
    ply.payload["vertex"]
        .iter()
        .map(|v| {
            let float = |k: &str| match v[k] {
                Property::Float(x) => x,
                ref other => panic!("{k}: {other:?}"),
            };
            let entity = match v["entity"] {
                Property::UInt(e) => e,
                ref other => panic!("entity: {other:?}"),
            };
            let from_model = matches!(v["from_model"], Property::UChar(1));
            ([float("x"), float("y"), float("z")], entity, from_model)
        })
        .collect()
}
