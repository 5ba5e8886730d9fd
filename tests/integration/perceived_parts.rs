//! Issue 36, section 2: a cabinet whose fronts differ from every model of the database the
//! reconstruction searches gets a model built from the doors and drawers perceived on it, and a
//! fridge hinged on the other side from the library's gets its door hinged where it is; both open
//! where the real ones do, in the reconstruction's own check and in MuJoCo.

use std::path::Path;

use glam::Vec3;
use iscene::cad::ParametricLibrary;
use iscene::cad::db::export::write_models;
use iscene::cad::library::builder::{BOARD, PartsBuilder};
use iscene::cad::model::CadModel;
use iscene::eval::evaluate_reconstruction;
use iscene::graph::ContactGraph;
use iscene::graph::parts::{PartJointType, PartSource};

use crate::common;

/// A cabinet of four drawers in two columns (no library model has drawers side by side), 0.8 x
/// 0.5 x 0.85 m on a plinth, with centred bars.
fn two_by_two_drawers() -> CadModel {
    let s = Vec3::new(0.8, 0.5, 0.85);
    let plinth = 0.08;
    let mut b = PartsBuilder::new([0.75, 0.74, 0.7]);
    b.carcass(
        Vec3::new(-0.5 * s.x, -0.5 * s.y + BOARD, plinth),
        Vec3::new(0.5 * s.x, 0.5 * s.y, s.z),
    )
    .slab(
        Vec3::new(-0.5 * s.x + 0.02, -0.5 * s.y + BOARD + 0.05, 0.0),
        Vec3::new(0.5 * s.x - 0.02, 0.5 * s.y, plinth),
    );
    let front = -0.5 * s.y + BOARD;
    let h = 0.5 * (s.z - plinth);
    let gap = 0.004;
    for row in 0..2 {
        for column in 0..2 {
            let x0 = -0.5 * s.x + 0.5 * s.x * column as f32;
            let z0 = plinth + h * row as f32;
            b.drawer(
                &format!("drawer_{row}{column}"),
                PartsBuilder::BODY,
                (x0 + gap, x0 + 0.5 * s.x - gap),
                (z0 + gap, z0 + h - gap),
                front,
                (0.25 * s.x - BOARD - 0.01, s.y - 3.0 * BOARD - 0.03),
                [0.2, 0.35, 0.55],
                [0.6, 0.6, 0.62],
            );
        }
    }
    b.finish("cabinet_2x2", "cabinet")
}

/// The four drawers of a cabinet no library model has are perceived, built and opened, and a
/// fridge hinged on its right (the library's on its left) gets a door hinged on its right: the
/// reconstruction (built-in library only) lists four perceived drawers sliding out into the room,
/// each with its handle, the articulation metric finds each of the truth's parts, the fridge's
/// hinge included, and MuJoCo opens every part of the exported scene to its limits without it
/// meeting anything.
#[test]
fn a_cabinet_no_model_fits_gets_a_model_of_its_perceived_drawers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fridge = ParametricLibrary::get("fridge_01")
        .expect("fridge")
        .model()
        .mirrored("fridge_hinged_right".into());
    write_models(
        &dir.path().join("mine"),
        &[two_by_two_drawers(), fridge],
        "test",
    )
    .expect("database");
    let spec = r#"{"name": "drawers_side_by_side", "seed": 5, "cad": ["mine"],
        "room": {"size": [4, 3.5, 2.6]},
        "objects": [
          {"id": "cabinet_1", "class": "cabinet", "model": "cabinet_2x2", "position": [2.0, 0.3], "yaw_deg": 180},
          {"id": "fridge_1", "class": "fridge", "model": "fridge_hinged_right", "position": [3.2, 0.4], "yaw_deg": 180},
          {"id": "table_1", "class": "table", "position": [2.0, 2.2]}]}"#;
    std::fs::write(dir.path().join("spec.json"), spec).expect("write");
    let (code, _, err) = common::iscene(
        &["render", "spec.json", "--out", "seq", "--frames", "60"],
        dir.path(),
    );
    assert_eq!(code, 0, "{err}");
    let (seq, out) = (dir.path().join("seq"), dir.path().join("out"));
    common::map_every_second_frame(&seq, &out, None);

    let graph = ContactGraph::load(&out.join("contact_graph.json")).expect("graph");
    let cabinet = graph
        .nodes
        .iter()
        .find(|n| n.class == "cabinet")
        .expect("a cabinet");
    let model = cabinet.cad.as_ref().map(|c| c.model.as_str());
    assert_eq!(model, Some(format!("perceived_{}", cabinet.id).as_str()));
    assert_eq!(cabinet.parts.len(), 4, "{:?}", cabinet.parts);
    for part in &cabinet.parts {
        assert_eq!(part.source, PartSource::Perceived, "{part:?}");
        assert_eq!(part.joint.kind, PartJointType::Prismatic, "{part:?}");
        // The wall is at y = 0: the drawers slide out along +y.
        assert!(part.axis().dot(Vec3::Y) > 0.97, "{part:?}");
        assert!(part.handle.is_some(), "{part:?}");
    }
    // The model is the scene's own: its files are beside the reconstruction.
    let id = model.expect("model");
    assert!(out.join(format!("cad/{id}.json")).exists());

    let eval = evaluate_reconstruction(&out, &seq).expect("eval");
    let scores = eval.articulation.expect("articulation");
    assert_eq!(scores.len(), 5, "{scores:?}");
    let parts: Vec<String> = graph
        .nodes
        .iter()
        .flat_map(|n| n.parts.iter().map(move |p| format!("{}/{}", n.id, p.name)))
        .collect();
    // Every part of the truth is reproduced: type, axis, hinge line within 5 cm, side and range.
    // (Precision is not asserted: with this seed's label noise a sliver of the fridge's side is
    // segmented apart, 8 cm wide, and gets a fridge model of its own, whose two doors stand for
    // nothing; that is segmentation's, issue 35.)
    assert!(
        eval.articulation_recall.is_some_and(|r| r >= 0.99),
        "precision {:?}, predicted {parts:?}: {scores:?}",
        eval.articulation_precision
    );

    // The fridge: the library's model mirrored, or one built from its perceived door.
    let fridge = graph
        .nodes
        .iter()
        .find(|n| n.class == "fridge")
        .expect("a fridge");
    let model = fridge.cad.as_ref().map_or("", |c| c.model.as_str());
    assert!(
        model.ends_with(".mirrored") || model.starts_with("perceived_"),
        "{model}"
    );

    mujoco_opens_every_part_of(&out, &cabinet.id);
    mujoco_opens_every_part_of(&out, &fridge.id);
}

/// MuJoCo loads `scene.xml` of `dir` and turns or slides every joint of `node` to both its
/// limits without its parts meeting anything they did not meet closed.
pub(crate) fn mujoco_opens_every_part_of(dir: &Path, node: &str) {
    let python = common::validator(".venv-validators/bin/python");
    let mujoco_rest = common::validator("tests/external/mujoco_rest.py");
    let (code, stdout, stderr) = common::run_tool(&python, &[&mujoco_rest, &dir.join("scene.xml")]);
    assert_eq!(code, 0, "MuJoCo: {stderr}");
    let result = common::json_line(&stdout);
    let hits: Vec<&serde_json::Value> = result["limit_overlaps"]
        .as_array()
        .expect("limit_overlaps")
        .iter()
        .filter(|o| o.to_string().contains(node))
        .collect();
    assert!(
        hits.is_empty(),
        "{node}'s parts meet others when open: {hits:?}"
    );
    assert!(
        result["joints"].as_u64().is_some_and(|n| n >= 4),
        "{result}"
    );
}
