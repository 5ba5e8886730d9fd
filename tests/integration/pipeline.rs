//! The reconstruction app: its stage schedule, and the default run a newcomer starts with.

use crate::common;

use bevy::prelude::*;
use iscene::systems::{Reconstruct, ReconstructionStage};

#[test]
fn the_stage_schedule_builds_without_ambiguities_and_runs_in_order() {
    let mut app = App::new();
    app.add_plugins(iscene::ReconstructionPlugins);
    // A probe system per stage records the order the stages run in. It touches only `Order`, so
    // it may run on either side of a stage's exclusive systems (hence `ambiguous_with_all`).
    #[derive(Resource, Default)]
    struct Order(Vec<&'static str>);
    app.init_resource::<Order>();
    for stage in ReconstructionStage::ALL {
        app.add_systems(
            Reconstruct,
            (move |mut order: ResMut<Order>| order.0.push(stage.name()))
                .in_set(stage)
                .ambiguous_with_all(),
        );
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let seq = dir.path().join("seq");
    common::render_scene("office", &seq, 2, true);
    app.insert_resource(iscene::systems::ingest::InputSequence(
        iscene::io::Sequence::open(&seq).expect("sequence"),
    ));
    app.world_mut().run_schedule(Reconstruct);
    let order = &app.world().resource::<Order>().0;
    let expected: Vec<&str> = ReconstructionStage::ALL.iter().map(|s| s.name()).collect();
    assert_eq!(order, &expected);
    let report = app
        .world()
        .resource::<iscene::systems::ingest::IngestReport>();
    assert_eq!(report.frames, 2);
    // Without noise every pixel of a closed room has depth.
    assert!(
        report.valid_depth_fraction > 0.999,
        "{}",
        report.valid_depth_fraction
    );
    let seconds = app
        .world()
        .resource::<iscene::systems::stages::StageMarks>()
        .seconds();
    assert_eq!(
        seconds.len(),
        ReconstructionStage::ALL.len(),
        "every stage is timed"
    );
}

#[test]
fn a_bare_iscene_renders_the_builtin_kitchen_and_writes_its_output_folder() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (code, stdout, stderr) = common::iscene(&[], dir.path());
    assert_eq!(code, 0, "{stdout}{stderr}");
    let out = dir.path().join("out/kitchen");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("report.json")).expect("report.json"),
    )
    .expect("json");
    assert_eq!(report["ingest"]["frames"], 300);
    assert_eq!(report["rendered"], true);
    assert!(
        dir.path()
            .join("out/kitchen.sequence/frame-000299.depth.png")
            .is_file()
    );
    assert!(
        stdout.contains("ingest"),
        "summary lists stage times: {stdout}"
    );
    // What the kitchen's reconstruction found, as it was (tests/golden, common/golden.rs).
    common::golden::assert_json_matches(
        &out.join("contact_graph.json"),
        "kitchen/contact_graph.json",
        &[],
    );
    common::golden::assert_report_matches(&out.join("report.json"), "kitchen/report.json");
    // A second run reuses the rendering of the unchanged specification.
    let (code, stdout, stderr) =
        common::iscene(&["reconstruct", "--frames", "0:300:30"], dir.path());
    assert_eq!(code, 0, "{stdout}{stderr}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("report.json")).expect("report.json"),
    )
    .expect("json");
    assert_eq!(report["ingest"]["frames"], 10);
    let timings = report["timings"].as_array().expect("timings");
    assert!(
        !timings.iter().any(|t| t[0] == "render"),
        "the rendering was redone: {timings:?}"
    );
}

/// The four hand-written scenes rendered with realistic noise and reconstructed from every second
/// frame, the maps the contact-graph, CAD, export and arm tests share: what each found, as it
/// was (tests/golden, common/golden.rs). A refactoring that changes the office's, living room's
/// or bedroom's result shows here, not only the kitchen's.
#[test]
fn the_four_scenes_reconstruct_as_they_did() {
    for name in ["kitchen", "office", "living_room", "bedroom"] {
        let (_, out) = common::shared_noisy_map(name);
        common::golden::assert_json_matches(
            &out.join("contact_graph.json"),
            &format!("noisy_{name}/contact_graph.json"),
            &[],
        );
        common::golden::assert_report_matches(
            &out.join("report.json"),
            &format!("noisy_{name}/report.json"),
        );
    }
}

#[test]
fn seven_scenes_reconstructs_without_labels() {
    let input = common::shared_data("rgbd/7scenes-redkitchen");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("redkitchen");
    let args = [
        "reconstruct",
        input.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--segmentation",
        "none",
        "--frames",
        "0:1000:20",
    ];
    let (code, stdout, stderr) = common::iscene(&args, dir.path());
    assert_eq!(code, 0, "{stdout}{stderr}");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("report.json")).expect("report.json"),
    )
    .expect("json");
    assert_eq!(report["ingest"]["frames"], 50);
    assert_eq!(report["ingest"]["has_gravity"], true);
    common::golden::assert_json_matches(
        &out.join("contact_graph.json"),
        "redkitchen_0_1000_20/contact_graph.json",
        &[],
    );
    common::golden::assert_report_matches(
        &out.join("report.json"),
        "redkitchen_0_1000_20/report.json",
    );
    // The oracle needs labels a real sequence does not have.
    let (code, _, stderr) = common::iscene(
        &[
            "reconstruct",
            input.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        dir.path(),
    );
    assert_eq!(code, 2);
    assert!(stderr.contains("labels.json"), "{stderr}");
}
