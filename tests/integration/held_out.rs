//! Held-out truth: procedural rooms (`iscene generate`), specifications naming CAD databases
//! the library does not hold, the overlap rule, and the benchmark over a range of seeds with
//! bounds on every metric of `iscene eval`. No test here is tied to one room: each runs over a
//! range of seeds.

use std::path::Path;

use iscene::render::noise::NoiseChoice;
use iscene::scene::generate::{
    GenerateOptions, MAX_OBJECTS, MIN_OBJECTS, RoomStyle, doors_open_freely, generate,
    unseen_objects,
};
use iscene::scene::{SceneSpec, SceneWorld};

use crate::common::{iscene, listing, shared_data};

const SEEDS: std::ops::Range<u64> = 0..12;

fn options(seed: u64) -> GenerateOptions {
    GenerateOptions {
        seed,
        style: RoomStyle::Any,
        cad: Vec::new(),
        noise: NoiseChoice::Realistic,
        frames: 300,
    }
}

/// The world of a generated specification, written to `dir` and read back as a user would.
fn generated_world(dir: &Path, seed: u64) -> (SceneSpec, SceneWorld) {
    let path = dir.join(format!("room_{seed}.json"));
    let generated = generate(&options(seed), &path).expect("generated");
    iscene::scene::generate::write_generated(&path, &generated.json).expect("written");
    let spec = SceneSpec::load(&path).expect("a generated specification is valid");
    let world = SceneWorld::from_spec(&spec, &path).expect("and describes a world");
    (spec, world)
}

#[test]
fn generated_rooms_are_valid_seen_free_to_open_and_differ_by_seed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut styles = std::collections::BTreeSet::new();
    let mut open_joints = 0;
    let mut articulated = 0;
    let mut texts = std::collections::BTreeSet::new();
    for seed in SEEDS {
        let (spec, world) = generated_world(dir.path(), seed);
        styles.insert(spec.name.split('_').nth(1).unwrap_or("").to_string());
        let n = world.objects.len();
        assert!(
            (MIN_OBJECTS..=MAX_OBJECTS).contains(&n),
            "seed {seed}: {n} objects"
        );
        assert!(
            unseen_objects(&world, 300).is_empty(),
            "seed {seed}: objects the default path never sees"
        );
        for (i, o) in world.objects.iter().enumerate() {
            assert!(
                doors_open_freely(&world, i),
                "seed {seed}: a door or drawer of {} (or one opening onto it) cannot open all the way",
                o.id
            );
            if o.model.is_articulated() {
                articulated += 1;
            }
        }
        open_joints += spec.objects.iter().filter(|o| !o.joints.is_empty()).count();
        // Furniture on the floor stands on it and inside the room (checked by the world), and
        // what stands against a wall faces into the room: its front (-y) points away from the
        // nearest wall.
        for o in &world.objects {
            if o.support != iscene::scene::Support::Floor
                || !matches!(o.class.as_str(), "fridge" | "oven" | "dishwasher" | "shelf")
            {
                continue;
            }
            let front = o.world_from_model.transform_vector3(-glam::Vec3::Y);
            let p = o.world_from_model.translation;
            let room = world.room_size;
            let inward = [
                (p.y, glam::Vec3::Y),
                (room.x - p.x, -glam::Vec3::X),
                (room.y - p.y, -glam::Vec3::Y),
                (p.x, glam::Vec3::X),
            ]
            .into_iter()
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, n)| n)
            .expect("four walls");
            assert!(
                front.dot(inward) > 0.9,
                "seed {seed}: {} faces {front}, not into the room",
                o.id
            );
        }
        let text =
            std::fs::read_to_string(dir.path().join(format!("room_{seed}.json"))).expect("spec");
        let again = generate(&options(seed), &dir.path().join("again.json")).expect("again");
        assert_eq!(
            serde_json::to_string_pretty(&again.json).expect("json") + "\n",
            text,
            "seed {seed}: the same seed gives the same room"
        );
        texts.insert(text);
    }
    assert_eq!(texts.len(), SEEDS.count(), "every seed gives its own room");
    assert!(styles.len() >= 3, "styles over the seeds: {styles:?}");
    assert!(
        articulated >= SEEDS.count(),
        "{articulated} articulated objects"
    );
    assert!(
        open_joints >= 3,
        "{open_joints} objects left with a door or drawer open"
    );
}

#[test]
fn generate_refuses_to_write_over_what_it_did_not_write() {
    let dir = tempfile::tempdir().expect("tempdir");
    let user_file = dir.path().join("notes.json");
    std::fs::write(&user_file, "{\"mine\": true}").expect("write");
    let cwd = dir.path();
    let (code, _, err) = iscene(&["generate", "--seed", "1", "--out", "notes.json"], cwd);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("notes.json"), "{err}");
    assert_eq!(
        std::fs::read_to_string(&user_file).expect("kept"),
        "{\"mine\": true}"
    );
    let (code, _, err) = iscene(&["generate", "--seed", "1", "--out", "."], cwd);
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = iscene(
        &[
            "generate",
            "--seed",
            "1",
            "--out",
            "a.json",
            "--cad",
            "no_such_db",
        ],
        cwd,
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no_such_db"), "{err}");
    assert!(!cwd.join("a.json").exists());
    // An earlier generated specification is replaced.
    let (code, _, err) = iscene(&["generate", "--seed", "1", "--out", "room.json"], cwd);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = iscene(&["generate", "--seed", "2", "--out", "room.json"], cwd);
    assert_eq!(code, 0, "{err}");
    let names: Vec<String> = listing(cwd).into_iter().map(|(n, _)| n).collect();
    assert_eq!(names, ["notes.json", "room.json"], "no temporary file left");
}

#[test]
fn overlapping_objects_are_refused_naming_both() {
    let dir = tempfile::tempdir().expect("tempdir");
    let spec = dir.path().join("overlap.json");
    // A 1.6 m bed at x 2.5 reaches x 1.7; a 0.8 m shelf at x 1.35 reaches 1.75: 5 cm.
    std::fs::write(
        &spec,
        r#"{"name": "overlap", "room": {"size": [5, 4, 2.6]}, "objects": [
            {"id": "bed_1", "class": "bed", "model": "bed_01", "position": [2.5, 2.9]},
            {"id": "shelf_1", "class": "shelf", "model": "shelf_01", "position": [1.35, 3.7]}]}"#,
    )
    .expect("write");
    let (code, _, err) = iscene(
        &["render", "overlap.json", "--out", "seq", "--frames", "2"],
        dir.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("bed_1") && err.contains("shelf_1") && err.contains("overlap.json"),
        "{err}"
    );
    assert!(!dir.path().join("seq").exists());
    // Moved apart by a centimetre it renders.
    let text = std::fs::read_to_string(&spec)
        .expect("spec")
        .replace("[1.35, 3.7]", "[1.29, 3.7]");
    std::fs::write(&spec, text).expect("write");
    let (code, _, err) = iscene(
        &["render", "overlap.json", "--out", "seq", "--frames", "2"],
        dir.path(),
    );
    assert_eq!(code, 0, "{err}");
}

/// Imports the LIBERO models of the shared data into `db`.
fn libero_database(db: &Path) {
    let source = shared_data("cad/libero/articulated_objects");
    let (code, _, err) = iscene(
        &[
            "cad",
            "import",
            "mjcf",
            source.to_str().expect("utf-8"),
            "--into",
            db.to_str().expect("utf-8"),
        ],
        Path::new("."),
    );
    assert_eq!(code, 0, "{err}");
}

#[test]
fn specifications_draw_models_of_their_cad_databases_with_their_joints() {
    let dir = tempfile::tempdir().expect("tempdir");
    libero_database(&dir.path().join("libero"));
    let spec = r#"{"name": "with_libero", "seed": 3, "cad": ["libero"], "room": {"size": [4, 3.5, 2.6]},
        "objects": [
          {"id": "cabinet_1", "class": "cabinet", "model": "mjcf_wooden_cabinet", "position": [1.5, 3.0], "joints": {"cabinet_top": 0.1}},
          {"id": "fridge_1", "class": "fridge", "model": "mjcf_short_fridge", "position": [3.0, 3.0]},
          {"id": "table_1", "class": "table", "position": [2, 1.3]}]}"#;
    std::fs::write(dir.path().join("spec.json"), spec).expect("write");
    let (code, _, err) = iscene(
        &["render", "spec.json", "--out", "seq", "--frames", "4"],
        dir.path(),
    );
    assert_eq!(code, 0, "{err}");
    let graph = iscene::graph::ContactGraph::load(&dir.path().join("seq/gt/contact_graph.json"))
        .expect("truth graph");
    let cabinet = graph
        .nodes
        .iter()
        .find(|n| n.id == "cabinet_1")
        .expect("cabinet");
    assert_eq!(
        cabinet.cad.as_ref().map(|c| c.model.as_str()),
        Some("mjcf_wooden_cabinet")
    );
    assert_eq!(cabinet.joints.get("cabinet_top"), Some(&0.1));
    assert_eq!(cabinet.parts.len(), 3, "three drawers: {:?}", cabinet.parts);
    let fridge = graph
        .nodes
        .iter()
        .find(|n| n.id == "fridge_1")
        .expect("fridge");
    assert!(
        fridge
            .parts
            .iter()
            .any(|p| p.joint.kind == iscene::graph::parts::PartJointType::Revolute),
        "the fridge's door is a hinge"
    );

    // Bad input names the file and the key, and leaves nothing behind.
    let cases = [
        (spec.replace("\"libero\"", "\"nowhere\""), "nowhere"),
        (
            spec.replace("mjcf_short_fridge", "mjcf_no_such_model"),
            "objects[1].model",
        ),
        (
            spec.replace("\"cabinet_top\": 0.1", "\"door\": 0.3"),
            "objects[0].joints.door",
        ),
        (
            spec.replace(
                "\"position\": [3.0, 3.0]",
                "\"position\": [3.0, 3.0], \"size\": [1, 1, 1]",
            ),
            "objects[1].size",
        ),
    ];
    for (text, key) in cases {
        std::fs::write(dir.path().join("bad.json"), &text).expect("write");
        let (code, _, err) = iscene(
            &["render", "bad.json", "--out", "bad_seq", "--frames", "2"],
            dir.path(),
        );
        assert_eq!(code, 2, "{key}: {err}");
        assert!(err.contains(key), "{key}: {err}");
        assert!(!dir.path().join("bad_seq").exists(), "{key}");
    }
}

#[test]
fn generated_rooms_use_the_databases_they_are_given() {
    let dir = tempfile::tempdir().expect("tempdir");
    libero_database(&dir.path().join("libero"));
    let mut used = 0;
    for seed in 0..6 {
        let path = dir.path().join(format!("room_{seed}.json"));
        let options = GenerateOptions {
            cad: vec![dir.path().join("libero")],
            style: RoomStyle::Kitchen,
            ..options(seed)
        };
        let generated = generate(&options, &path).expect("generated");
        iscene::scene::generate::write_generated(&path, &generated.json).expect("written");
        let spec = SceneSpec::load(&path).expect("valid, with its databases");
        assert_eq!(spec.cad, ["libero"], "named relative to the specification");
        used += spec
            .objects
            .iter()
            .filter(|o| o.model.as_deref().is_some_and(|m| m.starts_with("mjcf_")))
            .count();
    }
    assert!(used >= 3, "{used} LIBERO models in six kitchens");
}

/// `benchmark --cad DB --unseen`: the rooms draw the database's models, the reconstruction
/// searches only its own library, and each room records that it did.
#[test]
fn an_unseen_database_is_drawn_from_but_never_searched() {
    let dir = tempfile::tempdir().expect("tempdir");
    libero_database(&dir.path().join("libero"));
    let (code, _, err) = iscene(
        &["benchmark", "--seeds", "0:1", "--unseen", "--out", "b"],
        dir.path(),
    );
    assert_eq!(code, 2, "--unseen needs --cad: {err}");
    let args = [
        "benchmark",
        "--seeds",
        "0:2",
        "--style",
        "kitchen",
        "--frames",
        "20",
        "--cad",
        "libero",
        "--unseen",
        "--out",
        "bench",
    ];
    let (code, _, err) = iscene(&args, dir.path());
    assert_eq!(code, 0, "{err}");
    let mut drawn = 0;
    for seed in 0..2 {
        let room = dir.path().join(format!("bench/seed_{seed}"));
        let record: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(room.join("status.json")).expect("status.json"),
        )
        .expect("JSON");
        assert_eq!(record["input"]["unseen"], true, "{record}");
        drawn += std::fs::read_to_string(room.join("spec.json"))
            .expect("spec")
            .matches("\"mjcf_")
            .count();
        let graph =
            std::fs::read_to_string(room.join("reconstruction/contact_graph.json")).expect("graph");
        assert!(
            !graph.contains("mjcf_"),
            "seed {seed} searched the database"
        );
    }
    assert!(drawn > 0, "no LIBERO model in two kitchens");
}

#[test]
fn the_benchmark_scores_every_room_resumes_and_keeps_its_bounds() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("bench");
    let out_s = out.to_str().expect("utf-8");
    let panda = crate::common::panda_urdf();
    let args = [
        "benchmark",
        "--seeds",
        "0:3",
        "--frames",
        "60",
        "--robot",
        panda.to_str().expect("utf-8"),
        "--out",
        out_s,
    ];
    let (code, stdout, err) = iscene(&args, dir.path());
    assert_eq!(code, 0, "{err}");
    assert!(stdout.contains("| pq |"), "{stdout}");
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("summary.json")).expect("summary.json"),
    )
    .expect("json");
    assert_eq!(summary["rooms"], 3, "{summary}");
    let metrics = &summary["metrics"];
    for key in [
        "pq",
        "instance_map50",
        "ged",
        "ged_positional",
        "stable_fraction",
        "cad_yaw_accuracy",
        "cad_class_accuracy",
        "cad_chamfer_m",
        "fit_residual_m",
        "mean_alignment_error",
        "articulation_precision",
        "articulation_recall",
        "articulation_f1",
        "pick_place_success",
        "pick_place_seconds",
    ] {
        for stat in ["mean", "median", "worst"] {
            assert!(
                metrics[key][stat].as_f64().is_some_and(f64::is_finite),
                "{key}.{stat} in {metrics}"
            );
        }
    }
    let mean = |key: &str| metrics[key]["mean"].as_f64().expect(key);
    let worst = |key: &str| metrics[key]["worst"].as_f64().expect(key);
    // Bounds of a short (60-frame) run over three rooms: what the pipeline reaches today with a
    // margin, so that a regression fails; the 300-frame goals of the issue stand in the README.
    // (At 40 frames, small objects in shelves are seen by fewer than the 30 points replacement
    // needs.) Since models are built to their fitted size (2026-11-27) these rooms reach class
    // accuracy 0.88 (0.80 before) and stable fraction 1.0 in each (0.93 before).
    assert!(mean("pq") >= 0.75 && worst("pq") >= 0.65, "pq {metrics}");
    assert!(mean("instance_map50") >= 0.8, "mAP {metrics}");
    assert!(mean("cad_class_accuracy") >= 0.8, "{metrics}");
    assert!(mean("cad_chamfer_m") <= 0.03, "{metrics}");
    assert!(
        mean("stable_fraction") >= 0.95 && worst("stable_fraction") >= 0.9,
        "{metrics}"
    );
    assert!(
        mean("ged") <= 20.0 && mean("ged_positional") <= 25.0,
        "{metrics}"
    );
    // Articulation: with the fronts and handles the camera saw choosing among cabinet models,
    // these rooms reproduce 0.6 of their moving parts at 60 frames (one in six before; the
    // metric is checked against known answers in src/eval/articulation.rs).
    assert!(mean("articulation_f1") >= 0.5, "{metrics}");
    // Seed 0's chest of drawers shows its three horizontal bars, and every door and drawer the
    // reconstructions list has a handle.
    let report = |seed: u64| -> serde_json::Value {
        let path = out.join(format!("seed_{seed}/reconstruction/report.json"));
        serde_json::from_str(&std::fs::read_to_string(&path).expect("report.json")).expect("json")
    };
    let horizontal_bars = |front: &serde_json::Value| {
        front["handles"]
            .as_array()
            .expect("handles")
            .iter()
            .filter(|h| h["kind"] == "bar" && h["axis"][2].as_f64().is_some_and(|z| z.abs() < 0.3))
            .count()
    };
    let fronts = report(0)["cad"]["fronts"].clone();
    assert!(
        fronts
            .as_array()
            .expect("fronts")
            .iter()
            .any(|f| horizontal_bars(f) == 3),
        "{fronts:#}"
    );
    for seed in 0..3 {
        let path = out.join(format!("seed_{seed}/reconstruction/contact_graph.json"));
        let graph: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&path).expect("graph")).expect("json");
        for node in graph["nodes"].as_array().expect("nodes") {
            for part in node["parts"].as_array().into_iter().flatten() {
                assert!(
                    part["handle"].is_object(),
                    "seed {seed}: {}/{} has no handle",
                    node["id"],
                    part["name"]
                );
            }
        }
    }
    // The rapier verdicts of each reconstruction agree with MuJoCo loading its MJCF.
    let disagreements: Vec<String> = (0..3)
        .flat_map(|seed| mujoco_disagreements(&out.join(format!("seed_{seed}/reconstruction"))))
        .collect();
    assert!(disagreements.is_empty(), "{disagreements:#?}");
    // What the reconstructions found, as it was (tests/golden, common/golden.rs).
    for seed in 0..3 {
        let dir = out.join(format!("seed_{seed}/reconstruction"));
        crate::common::golden::assert_json_matches(
            &dir.join("contact_graph.json"),
            &format!("seed_{seed}_60/contact_graph.json"),
            &[],
        );
        crate::common::golden::assert_report_matches(
            &dir.join("report.json"),
            &format!("seed_{seed}_60/report.json"),
        );
    }
    let worst_rooms = summary["worst_rooms"].as_array().expect("worst rooms");
    assert!(
        worst_rooms
            .iter()
            .any(|w| w["metric"] == "pq" && (0..3).contains(&w["seed"].as_u64().expect("seed"))),
        "{summary}"
    );
    for name in ["summary.csv", "summary.md"] {
        assert!(out.join(name).is_file(), "{name}");
    }
    // Resumed: a finished room is not redone.
    let eval = out.join("seed_1/eval.json");
    let before = std::fs::metadata(&eval)
        .and_then(|m| m.modified())
        .expect("mtime");
    let (code, _, err) = iscene(&args, dir.path());
    assert_eq!(code, 0, "{err}");
    let after = std::fs::metadata(&eval)
        .and_then(|m| m.modified())
        .expect("mtime");
    assert_eq!(before, after, "seed 1 was redone");
    // A folder it did not write is refused.
    let mine = dir.path().join("mine");
    std::fs::create_dir(&mine).expect("mkdir");
    std::fs::write(mine.join("thesis.tex"), "x").expect("write");
    let (code, _, err) = iscene(
        &[
            "benchmark",
            "--seeds",
            "0:1",
            "--frames",
            "2",
            "--out",
            "mine",
        ],
        dir.path(),
    );
    assert_eq!(code, 2, "{err}");
    assert_eq!(listing(&mine).len(), 1);
}

/// Where the rest test of the reconstruction in `dir` (report.json) and MuJoCo resting its
/// `scene.xml` disagree: an object rapier judges stable that MuJoCo moves more than the rest
/// test's 1 cm, or one it judges unstable that MuJoCo keeps within 1 mm (between the two, the
/// solvers may differ on a slow creep).
fn mujoco_disagreements(dir: &Path) -> Vec<String> {
    let python = crate::common::validator(".venv-validators/bin/python");
    let mujoco_rest = crate::common::validator("tests/external/mujoco_rest.py");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("report.json")).expect("report.json"),
    )
    .expect("report JSON");
    let verdicts = report["physics"]["objects"].as_array().expect("physics");
    let (code, stdout, stderr) =
        crate::common::run_tool(&python, &[&mujoco_rest, &dir.join("scene.xml")]);
    if code != 0 {
        return vec![format!("{}: MuJoCo: {stderr}", dir.display())];
    }
    let result = crate::common::json_line(&stdout);
    let mut found = Vec::new();
    for (joint, moved) in result["free_moved"].as_object().expect("free_moved") {
        let object = joint.trim_end_matches("_joint");
        let moved = moved.as_f64().expect("metres");
        let Some(verdict) = verdicts.iter().find(|v| v["object"] == object) else {
            found.push(format!(
                "{}: {object} is free in MuJoCo, not judged",
                dir.display()
            ));
            continue;
        };
        let stable = verdict["verdict"] == "stable";
        let penetrating = verdict["verdict"] == "penetrating";
        if (stable && moved > 0.01) || (!stable && !penetrating && moved < 0.001) {
            found.push(format!(
                "{}: {object}: rapier {} ({}), MuJoCo moved {:.1} mm",
                dir.display(),
                verdict["verdict"],
                verdict["reason"],
                moved * 1000.0
            ));
        }
    }
    found
}

/// Seeds of the physics agreement test: rooms the other tests do not look at.
const REST_SEEDS: std::ops::Range<u64> = 20..26;

/// The ground truth of generated rooms, where every object stands exactly on its support, is at
/// rest in both physics checks: `simulate`'s rapier rest test judges every object stable, and
/// MuJoCo, loading the URDF and MJCF that `simulate` exports of the same room, keeps every free
/// body within 1 mm and starts with nothing inside anything.
#[test]
fn ground_truth_of_generated_rooms_rests_in_rapier_and_in_mujoco() {
    let python = crate::common::validator(".venv-validators/bin/python");
    let mujoco_rest = crate::common::validator("tests/external/mujoco_rest.py");
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(
        dir.path().join("rest.json"),
        r#"{"steps": [{"action": "navigate", "to": "floor"}]}"#,
    )
    .expect("task");
    let mut failures = Vec::new();
    for seed in REST_SEEDS {
        let (spec, seq, sim) = (
            format!("room_{seed}.json"),
            format!("seq_{seed}"),
            format!("sim_{seed}"),
        );
        let s = seed.to_string();
        for args in [
            vec!["generate", "--seed", &s, "--out", &spec],
            vec!["render", &spec, "--out", &seq, "--frames", "2"],
            vec![
                "simulate",
                &format!("{seq}/gt"),
                "--task",
                "rest.json",
                "--out",
                &sim,
            ],
        ] {
            let (code, _, err) = iscene(&args, dir.path());
            assert_eq!(code, 0, "seed {seed}: {args:?}: {err}");
        }
        let trace: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(&sim).join("trace.json")).expect("trace"),
        )
        .expect("trace JSON");
        let rapier = &trace["physics_before"];
        if rapier["stable_fraction"].as_f64() != Some(1.0) {
            failures.push(format!("seed {seed}: rapier: {}", rapier["not_stable"]));
        }
        for file in ["scene.urdf", "scene.xml"] {
            let path = dir.path().join(&sim).join(file);
            let (code, stdout, stderr) = crate::common::run_tool(&python, &[&mujoco_rest, &path]);
            if code != 0 {
                failures.push(format!(
                    "seed {seed}: MuJoCo could not load {file}: {stderr}"
                ));
                continue;
            }
            let result = crate::common::json_line(&stdout);
            for (joint, moved) in result["free_moved"].as_object().expect("free_moved") {
                let moved = moved.as_f64().expect("metres");
                if moved > 0.001 {
                    failures.push(format!(
                        "seed {seed}: {file} in MuJoCo: {joint} moved {:.2} mm at rest",
                        moved * 1000.0
                    ));
                }
            }
            let overlaps = result["start_overlaps"].as_array().expect("overlaps");
            if !overlaps.is_empty() {
                failures.push(format!(
                    "seed {seed}: {file} starts with overlaps {overlaps:?}"
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
