//! The parametric CAD library on disk: regenerating it gives the committed files byte for byte,
//! and each .glb is a node tree of the model's parts with their joints.

use crate::common;

use iscene::cad::ParametricLibrary;
use iscene::cad::db::export::ModelMetadata;

#[test]
fn assets_cad_is_what_the_generator_writes() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("cad");
    let (code, stdout, stderr) = common::iscene(
        &["cad", "generate", "--into", out.to_str().expect("utf8")],
        &common::root(),
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    let generated = common::hash_tree(&out);
    let committed = common::hash_tree(&common::root().join("assets/cad"));
    assert_eq!(
        generated, committed,
        "assets/cad is stale: run `cargo run --release -- cad generate` and commit the result"
    );
}

#[test]
fn every_model_file_holds_its_parts_and_joints() {
    let dir = common::root().join("assets/cad");
    for entry in ParametricLibrary::entries() {
        let meta_text =
            std::fs::read_to_string(dir.join(format!("{}.json", entry.id))).expect("metadata");
        let meta: ModelMetadata = serde_json::from_str(&meta_text).expect("metadata parses");
        let model = entry.model();
        assert_eq!(meta.parts.len(), model.parts.len());
        let bytes = std::fs::read(dir.join(&meta.glb)).expect("glb");
        let gltf = gltf::Gltf::from_slice(&bytes).expect("valid glb");
        let names: Vec<String> = gltf
            .nodes()
            .filter_map(|n| n.name().map(str::to_owned))
            .collect();
        for part in &meta.parts {
            assert!(
                names.contains(&part.name),
                "{}: node {} missing",
                entry.id,
                part.name
            );
        }
        assert!(names.contains(&entry.id.to_string()));
        for node in gltf.nodes() {
            let Some(name) = node.name() else { continue };
            let Some(part) = meta.parts.iter().find(|p| p.name == name) else {
                continue;
            };
            // The node's children are exactly the parts whose parent it is.
            let mut children: Vec<String> = node
                .children()
                .filter_map(|c| c.name().map(str::to_owned))
                .collect();
            let mut expected: Vec<String> = meta
                .parts
                .iter()
                .filter(|p| p.parent.as_deref() == Some(name))
                .map(|p| p.name.clone())
                .collect();
            children.sort();
            expected.sort();
            assert_eq!(children, expected, "{}: children of {name}", entry.id);
            let extras = node
                .extras()
                .as_ref()
                .map(|r| r.get().to_string())
                .unwrap_or_default();
            let joint: serde_json::Value = serde_json::from_str(&extras).expect("joint extras");
            assert_eq!(
                joint["joint"]["kind"],
                serde_json::to_value(part.joint.kind).expect("kind"),
                "{}: {name}",
                entry.id
            );
        }
    }
}
