//! The onnx segmentation backend on the real 7-Scenes kitchen: the networks' detections against
//! the reference output in ../shared/ORT.md, the layout survey against the dataset's gravity file,
//! the reconstruction's contact graph, and the errors for a missing library or model. Needs the
//! shared data (models and 7-Scenes) and ONNX Runtime in .ort/ (scripts/setup-ort.sh, run by
//! scripts/test.sh).

use crate::common;

use std::path::Path;

use iscene::io::Sequence;
use iscene::segmentation::SegmentationService;
use iscene::segmentation::geometric::{GeometricParams, segment_depth};
use iscene::segmentation::onnx::layout::{LayoutLabel, LayoutParams, RoomLayout};
use iscene::segmentation::onnx::{OnnxModels, OnnxParams, OnnxSegmentation};

fn kitchen() -> Sequence {
    Sequence::open(&common::shared_data("rgbd/7scenes-redkitchen")).expect("7-Scenes redkitchen")
}

fn backend(sequence: &Sequence) -> OnnxSegmentation {
    OnnxSegmentation::for_sequence(
        sequence,
        &OnnxModels::in_dir(&common::shared_data("models")),
        OnnxParams::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"))
}

/// `iscene reconstruct` of 7-Scenes redkitchen with the onnx backend and the flags `extra`, into
/// `out`, from the checkout's root: exit code, stdout, stderr.
fn reconstruct_with_onnx(extra: &[&str], out: &Path) -> (i32, String, String) {
    let input = common::shared_data("rgbd/7scenes-redkitchen");
    let mut args = vec![
        "reconstruct",
        input.to_str().expect("utf-8"),
        "--segmentation",
        "onnx",
    ];
    args.extend_from_slice(extra);
    args.extend(["--out", out.to_str().expect("utf-8")]);
    common::iscene(&args, &common::root())
}

#[test]
fn frame_500_detections_match_the_reference_run() {
    let sequence = kitchen();
    let onnx = backend(&sequence);
    let frame = sequence.load_frame(500).expect("frame 500");
    let image = image::RgbImage::from_raw(640, 480, frame.color.clone()).expect("rgb");
    let detections = onnx.detect(&image).expect("detect");
    let scores = |class: &str| -> Vec<f32> {
        detections
            .iter()
            .filter(|d| d.class == class)
            .map(|d| d.score)
            .collect()
    };
    // ORT.md, measured with Python's onnxruntime: diningtable 0.86, chairs 0.84/0.80/0.66, cups
    // 0.65/0.65, book 0.45. Scores agree to 0.03 (our resampling of the letterbox differs).
    let close = |got: Vec<f32>, want: &[f32]| {
        assert!(got.len() >= want.len(), "{got:?} vs {want:?}");
        for (g, w) in got.iter().zip(want) {
            assert!((g - w).abs() <= 0.03, "{got:?} vs {want:?}");
        }
    };
    close(scores("table"), &[0.86]);
    close(scores("chair"), &[0.84, 0.80, 0.66]);
    close(scores("cup"), &[0.65, 0.65]);
    close(scores("book"), &[0.45]);
}

#[test]
fn frame_500_masks_are_deterministic_and_separate_the_two_cups_from_the_table() {
    let sequence = kitchen();
    let onnx = backend(&sequence);
    let frame = sequence.load_frame(500).expect("frame 500");
    let geometry = segment_depth(&frame.depth, &frame.camera, &GeometricParams::default());
    let a = onnx.segment(&frame, &geometry).expect("segment");
    let b = onnx.segment(&frame, &geometry).expect("segment");
    assert_eq!(a, b);
    let pixels = |class: &str| -> Vec<usize> {
        a.segments
            .iter()
            .filter(|s| s.class == class)
            .map(|s| a.segment_of_pixel.iter().filter(|&&p| p == s.id).count())
            .collect()
    };
    let cups = pixels("cup");
    assert_eq!(cups.len(), 2, "{:?}", a.segments);
    // A cup 2 m away is a few hundred to a few thousand pixels, not the table top around it.
    assert!(cups.iter().all(|&n| (200..5000).contains(&n)), "{cups:?}");
    assert!(pixels("table")[0] > 20_000);
}

/// A frame the networks skip (`--segment-every`) still gets the surveyed floor and walls: the
/// pixels a segmented frame gives them, and those the objects' masks were painted over.
#[test]
fn frame_500_without_networks_has_the_floor_and_walls_of_the_segmented_frame() {
    let sequence = kitchen();
    let onnx = backend(&sequence);
    let frame = sequence.load_frame(500).expect("frame 500");
    let geometry = segment_depth(&frame.depth, &frame.camera, &GeometricParams::default());
    let segmented = onnx.segment(&frame, &geometry).expect("segment");
    let layout_only = onnx
        .segment_without_networks(&frame, &geometry)
        .expect("the onnx backend knows the layout without its networks");
    let class_of = |f: &iscene::segmentation::PanopticFrame, pixel: usize| {
        let id = f.segment_of_pixel[pixel];
        f.segments
            .iter()
            .find(|s| s.id == id)
            .map(|s| s.class.clone())
    };
    assert!(
        layout_only
            .segments
            .iter()
            .all(|s| s.class == "floor" || s.class == "wall"),
        "{:?}",
        layout_only.segments
    );
    let mut layout_pixels = 0;
    for pixel in 0..segmented.segment_of_pixel.len() {
        let class = class_of(&segmented, pixel);
        if matches!(class.as_deref(), Some("floor" | "wall")) {
            assert_eq!(class_of(&layout_only, pixel), class, "pixel {pixel}");
            layout_pixels += 1;
        }
    }
    let layout_only_pixels = layout_only
        .segment_of_pixel
        .iter()
        .filter(|&&id| id != 0)
        .count();
    assert!(
        layout_pixels > 10_000,
        "{layout_pixels} floor and wall pixels"
    );
    assert!(layout_only_pixels >= layout_pixels);
}

#[test]
fn the_survey_estimates_gravity_within_2_degrees_and_finds_the_floor() {
    let mut sequence = kitchen();
    let given = sequence.gravity.expect("the kitchen has a gravity file");
    sequence.gravity = None;
    let layout = RoomLayout::survey(&sequence, LayoutParams::default()).expect("survey");
    let angle = layout.up.angle_between(-given).to_degrees();
    assert!(
        angle < 2.0,
        "estimated up is {angle} degrees off the gravity file"
    );
    assert!(layout.floor_height.is_some(), "the floor is seen");
    // With the given gravity, frame 0's lower half is mostly floor (it looks down past the table).
    let with_given = RoomLayout::survey(&kitchen(), LayoutParams::default()).expect("survey");
    for w in &with_given.walls {
        eprintln!(
            "wall: normal {:.3} offset {:.2} span {:.2?} heights {:.2?}",
            w.plane.normal, w.plane.offset, w.span, w.heights
        );
    }
    // The tiled wall behind the counter: 4.5 m long, seen from the floor (under the counter's
    // knee space) to above the monitors.
    assert!(
        with_given
            .walls
            .iter()
            .any(|w| w.span[1] - w.span[0] > 3.0 && w.heights[1] > 1.5),
        "{:?}",
        with_given.walls
    );
    let frame = sequence.load_frame(0).expect("frame 0");
    let on_floor = (320 * 640..480 * 640)
        .filter(|&i| frame.depth[i] > 0.0)
        .filter(|&i| {
            let (u, v) = ((i % 640) as f32, (i / 640) as f32);
            let p = frame
                .world_from_camera
                .transform_point3(frame.camera.unproject(u, v, frame.depth[i]));
            with_given.label(p) == Some(LayoutLabel::Floor)
        })
        .count();
    assert!(
        on_floor > 30_000,
        "{on_floor} floor pixels in frame 0's lower third"
    );
}

#[test]
fn the_kitchen_reconstructs_with_table_chairs_cups_and_a_counter_holding_the_monitors_and_its_exports_rest()
 {
    let out = tempfile::tempdir().expect("tempdir");
    let (code, _, stderr) = reconstruct_with_onnx(&["--frames", "0::2"], out.path());
    assert_eq!(code, 0, "{stderr}");
    let graph: serde_json::Value = serde_json::from_slice(
        &std::fs::read(out.path().join("contact_graph.json")).expect("contact_graph.json"),
    )
    .expect("json");
    let parent = |child: &str| -> Option<String> {
        graph["edges"].as_array()?.iter().find_map(|e| {
            (e["type"] == "support" && e["child"] == child)
                .then(|| e["parent"].as_str().map(str::to_string))?
        })
    };
    let nodes: Vec<&serde_json::Value> = graph["nodes"].as_array().expect("nodes").iter().collect();
    let of_class = |class: &str| -> Vec<&serde_json::Value> {
        nodes
            .iter()
            .copied()
            .filter(|n| n["class"] == class)
            .collect()
    };
    let height = |n: &serde_json::Value| n["box"]["size"][2].as_f64().unwrap_or(0.0);
    let floor = of_class("floor");
    assert_eq!(floor.len(), 1);
    assert!(height(floor[0]) < 0.2, "the floor is flat: {}", floor[0]);
    let walls = of_class("wall");
    assert!(
        !walls.is_empty() && walls.iter().all(|w| w["kind"] == "layout"),
        "walls are layout nodes: {walls:?}"
    );
    let tables = of_class("table");
    assert_eq!(tables.len(), 1, "one dining table");
    let table = tables[0]["id"].as_str().expect("id");
    assert_eq!(parent(table).as_deref(), Some("floor"));
    let standing_chairs = of_class("chair")
        .into_iter()
        .filter(|c| parent(c["id"].as_str().unwrap_or("")).as_deref() == Some("floor"))
        .filter(|c| (0.6..1.2).contains(&height(c)))
        .count();
    assert!(
        standing_chairs >= 3,
        "{standing_chairs} full-height chairs on the floor"
    );
    let cups_on_table = of_class("cup")
        .into_iter()
        .filter(|c| parent(c["id"].as_str().unwrap_or("")).as_deref() == Some(table))
        .count();
    // The table has two mugs; the second is seen by the detector in under half the frames and
    // only stays apart from the table because cut-out segments vote twice (MapperParams).
    assert!(cups_on_table >= 2, "{cups_on_table} cups on the table");
    // The counter, found from geometry (no segmenter here has the class): on the floor, its top
    // at counter height, at least 1.5 m long, and the monitors whose stands were never seen on it.
    let counters: Vec<&str> = of_class("counter")
        .into_iter()
        .filter(|c| parent(c["id"].as_str().unwrap_or("")).as_deref() == Some("floor"))
        .filter(|c| {
            let b = &c["box"];
            let top = b["center"][2].as_f64().unwrap_or(0.0) + height(c) / 2.0;
            let long = b["size"][0]
                .as_f64()
                .unwrap_or(0.0)
                .max(b["size"][1].as_f64().unwrap_or(0.0));
            (0.8..1.0).contains(&top) && long >= 1.5
        })
        .filter_map(|c| c["id"].as_str())
        .collect();
    assert!(!counters.is_empty(), "{:?}", of_class("counter"));
    let monitors_on_counter = of_class("monitor")
        .into_iter()
        .filter(|m| {
            parent(m["id"].as_str().unwrap_or("")).is_some_and(|p| counters.contains(&p.as_str()))
        })
        .count();
    assert!(
        monitors_on_counter >= 2,
        "{monitors_on_counter} monitors on the counter"
    );
    for export in ["scene.urdf", "scene.xml", "scene.glb", "occupancy.pgm"] {
        assert!(out.path().join(export).is_file(), "{export} written");
    }
    // rapier's rest test: the report names every object that does not stand, with its reason.
    let report: serde_json::Value = serde_json::from_slice(
        &std::fs::read(out.path().join("report.json")).expect("report.json"),
    )
    .expect("json");
    let objects = report["physics"]["objects"].as_array().expect("verdicts");
    let stable = objects.iter().filter(|o| o["verdict"] == "stable").count();
    assert!(
        objects.len() >= 10 && stable as f64 >= 0.9 * objects.len() as f64,
        "{stable} of {} stable in rapier: {:?}",
        objects.len(),
        report["physics"]["objects"]
    );
    assert!(
        objects
            .iter()
            .all(|o| (o["verdict"] == "stable") == o["reason"].is_null())
    );
    let urdf_path = out.path().join("scene.urdf");
    let urdf = std::fs::read_to_string(&urdf_path).expect("urdf");
    assert!(urdf.contains(&format!("<link name=\"{table}\"")));
    exports_load_and_rest_in_the_validators(out.path(), urdf.matches("<link ").count());
    // What the real kitchen reconstructs to, as it was (tests/golden, common/golden.rs).
    common::golden::assert_json_matches(
        &out.path().join("contact_graph.json"),
        "redkitchen_onnx_frames_0__2/contact_graph.json",
        &[],
    );
    common::golden::assert_report_matches(
        &out.path().join("report.json"),
        "redkitchen_onnx_frames_0__2/report.json",
    );
    let counter = the_counter_s_doors_are_seen_and_open_into_the_room(out.path(), &graph);
    panda_takes_a_cup_from_the_table_onto_the_counter(out.path(), &graph, table);
    panda_opens_the_counter(out.path(), &counter);
}

/// Issue 37's last item on the real kitchen, now that the counter has doors (issue 36): from
/// the start north of the table the Panda opens the counter, planned from the goal; every arm
/// motion runs in rapier before it is made, and in MuJoCo's replay the hand stays on the handle.
fn panda_opens_the_counter(rec: &Path, counter: &str) {
    let (_dir, out, _) = panda_succeeds_from_north_of_the_table(rec, &format!("{counter} open"));
    let replay = crate::arm::replay_in_mujoco(&out, &crate::arm::panda_rig());
    assert!(
        replay["part_samples"].as_u64().is_some_and(|n| n >= 20),
        "{replay}"
    );
    let drift = replay["part_drift_m"].as_f64().expect("part drift");
    assert!(
        drift < 0.002,
        "the hand slipped {drift} m on the handle: {replay}"
    );
}

/// Issue 36 on the real kitchen: the red counter along the north wall shows four doors about
/// 40 cm wide in the frames, each with a steel bar along its top and a groove between it and the
/// next; the depth cannot resolve the bars (they stand out less than its noise), the front's
/// image baked from the frames does. The fourth door's bar, in the shade of the corner, is
/// lost in its image: three doors are found, each with its bar, hinged on a vertical axis,
/// opening into the room through their whole range, and MuJoCo opens them to their limits
/// without them meeting anything. Returns the counter's id.
fn the_counter_s_doors_are_seen_and_open_into_the_room(
    out: &Path,
    graph: &serde_json::Value,
) -> String {
    let nodes = graph["nodes"].as_array().expect("nodes");
    let floor = nodes
        .iter()
        .find(|n| n["class"] == "floor")
        .expect("a floor");
    let xy = |v: &serde_json::Value| {
        glam::Vec2::new(
            v[0].as_f64().unwrap_or(0.0) as f32,
            v[1].as_f64().unwrap_or(0.0) as f32,
        )
    };
    let room = xy(&floor["box"]["center"]);
    let counter = nodes
        .iter()
        .filter(|n| n["class"] == "counter")
        .max_by_key(|n| n["parts"].as_array().map_or(0, Vec::len))
        .expect("a counter");
    let id = counter["id"].as_str().expect("id");
    assert_eq!(counter["kind"], "articulated", "{counter}");
    let parts = counter["parts"].as_array().expect("parts");
    let with_bars = parts
        .iter()
        .filter(|p| p["handle"]["kind"] == "bar")
        .count();
    assert!(
        (3..=4).contains(&with_bars) && with_bars == parts.len(),
        "{id}: {with_bars} of {} parts with bar handles: {parts:?}",
        parts.len()
    );
    let centre = xy(&counter["box"]["center"]);
    for part in parts {
        assert_eq!(part["source"], "perceived", "{part}");
        let joint = &part["joint"];
        assert_eq!(joint["type"], "revolute", "a door: {part}");
        assert!(
            joint["axis"][2].as_f64().is_some_and(|z| z.abs() > 0.99),
            "a vertical hinge: {part}"
        );
        assert!(
            joint["upper"].as_f64().is_some_and(|u| u >= 1.5),
            "opens through its whole range: {part}"
        );
        let width = part["front"]["size"][0].as_f64().unwrap_or(0.0);
        assert!((0.3..0.55).contains(&width), "a 40 cm door: {part}");
        // The handle is on the side the room is.
        let handle = xy(&part["handle"]["center"]);
        assert!(
            (handle - centre).dot(room - centre) > 0.0,
            "{id}'s door faces away from the room: {part}"
        );
    }
    crate::perceived_parts::mujoco_opens_every_part_of(out, id);
    id.to_string()
}

/// Issue 37 on the real kitchen: the Panda (`--robot`) takes a cup from the table onto the
/// counter nearest where it starts, north of the table (the table's ends leave 40-45 cm
/// between it and the chairs, too narrow for the base's 50 cm), planned from goals. Every arm
/// motion runs in rapier before it is made, the cup ends on the counter in the output graph,
/// and MuJoCo's replay keeps the robot within 5 mm of the scene and the cup in the fingers.
fn panda_takes_a_cup_from_the_table_onto_the_counter(
    rec: &Path,
    graph: &serde_json::Value,
    table: &str,
) {
    let start = NORTH_OF_THE_TABLE;
    let nodes = graph["nodes"].as_array().expect("nodes");
    let centre = |n: &serde_json::Value| {
        glam::Vec2::new(
            n["box"]["center"][0].as_f64().expect("x") as f32,
            n["box"]["center"][1].as_f64().expect("y") as f32,
        )
    };
    let nearest = |class: &str, on: Option<&str>| -> String {
        nodes
            .iter()
            .filter(|n| n["class"] == class)
            .filter(|n| {
                on.is_none_or(|parent| {
                    graph["edges"].as_array().expect("edges").iter().any(|e| {
                        e["type"] == "support" && e["parent"] == parent && e["child"] == n["id"]
                    })
                })
            })
            .min_by(|a, b| {
                centre(a)
                    .distance(start)
                    .total_cmp(&centre(b).distance(start))
            })
            .and_then(|n| n["id"].as_str())
            .unwrap_or_else(|| panic!("no {class}"))
            .to_string()
    };
    let (cup, counter) = (nearest("cup", Some(table)), nearest("counter", None));
    let (_dir, out, trace) =
        panda_succeeds_from_north_of_the_table(rec, &format!("{cup} on {counter}"));
    for step in trace["steps"].as_array().expect("steps") {
        for check in step["motion"].as_array().expect("motion checks") {
            assert!(
                check["knocked"].as_array().is_some_and(Vec::is_empty),
                "{check}"
            );
        }
    }
    crate::arm::assert_supports(&out, &counter, &cup);
    crate::arm::replay_holding(&out, "cup");
}

/// Where the Panda starts on the real kitchen's reconstruction: north of the table, facing south.
const NORTH_OF_THE_TABLE: glam::Vec2 = glam::Vec2::new(-1.0, 2.45);

/// Runs the Panda on `rec` for `goal` from [`NORTH_OF_THE_TABLE`], asserting that it succeeds:
/// the folder holding the output, the output (`simulate`'s) and its trace.
fn panda_succeeds_from_north_of_the_table(
    rec: &Path,
    goal: &str,
) -> (tempfile::TempDir, std::path::PathBuf, serde_json::Value) {
    let dir = tempfile::tempdir().expect("tempdir");
    let task = dir.path().join("task.json");
    let start = NORTH_OF_THE_TABLE;
    std::fs::write(
        &task,
        serde_json::json!({
            "start": {"position": [start.x, start.y], "yaw_deg": -90},
            "goals": [goal],
        })
        .to_string(),
    )
    .expect("task");
    let out = dir.path().join("sim");
    let (code, stdout, stderr) = common::simulate(rec, &task, &out, Some(&common::panda_urdf()));
    assert_eq!(code, 0, "{stdout}{stderr}");
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("trace.json")).expect("trace"))
            .expect("JSON");
    assert_eq!(trace["success"], true, "{}", trace["steps"]);
    (dir, out, trace)
}

/// Issue 6's bar on the real kitchen's exports: check_urdf silent with every link; MuJoCo loads
/// the URDF and the MJCF, every free body moves under 1 mm in 2 s of rest and nothing starts
/// overlapping by more than 1 mm; PyBullet loads every link; the Khronos validator finds no
/// error.
fn exports_load_and_rest_in_the_validators(out: &Path, links: usize) {
    let python = common::validator(".venv-validators/bin/python");
    let urdf = out.join("scene.urdf");
    let (code, stdout, stderr) = common::run_tool(Path::new("check_urdf"), &[&urdf]);
    let printed = 1 + stdout.matches("child(").count() - stdout.matches("child(ren)").count();
    assert!(
        code == 0 && stderr.trim().is_empty(),
        "check_urdf: {stderr}"
    );
    assert_eq!(printed, links, "check_urdf's tree");
    let mujoco_rest = common::validator("tests/external/mujoco_rest.py");
    for file in [urdf.clone(), out.join("scene.xml")] {
        let (code, stdout, stderr) = common::run_tool(&python, &[&mujoco_rest, &file]);
        assert_eq!(code, 0, "MuJoCo on {}: {stderr}", file.display());
        let result = common::json_line(&stdout);
        let free = result["free_moved"].as_object().expect("free_moved");
        assert!(free.len() >= 10, "{} free bodies: {stdout}", free.len());
        for (joint, moved) in free {
            let moved = moved.as_f64().expect("metres");
            assert!(
                moved < 0.001,
                "{}: {joint} moved {:.2} mm in 2 s of rest",
                file.display(),
                moved * 1000.0
            );
        }
        assert_eq!(
            result["start_overlaps"].as_array().map(Vec::len),
            Some(0),
            "{}: overlaps over 1 mm at the start: {stdout}",
            file.display()
        );
    }
    let pybullet_load = common::validator("tests/external/pybullet_load.py");
    let (code, stdout, stderr) = common::run_tool(&python, &[&pybullet_load, &urdf]);
    assert_eq!(code, 0, "PyBullet: {stderr}");
    assert_eq!(
        common::json_line(&stdout)["links"].as_u64(),
        Some(links as u64)
    );
    let gltf_validate = common::validator("tests/external/gltf_validate.js");
    let (code, stdout, stderr) =
        common::run_tool(Path::new("node"), &[&gltf_validate, &out.join("scene.glb")]);
    assert_eq!(code, 0, "glTF validator: {stderr}");
    assert_eq!(
        common::json_line(&stdout)["errors"].as_u64(),
        Some(0),
        "{stdout}"
    );
}

#[test]
fn a_missing_runtime_library_is_a_clear_error_with_exit_code_2() {
    let out = tempfile::tempdir().expect("tempdir");
    let target = out.path().join("result");
    let input = common::shared_data("rgbd/7scenes-redkitchen");
    let missing = Path::new("/nonexistent/libonnxruntime.so.1.31.1");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_iscene"))
        .args(["reconstruct", input.to_str().expect("utf-8")])
        .args(["--segmentation", "onnx", "--frames", "0:10", "--out"])
        .arg(&target)
        .env("ORT_DYLIB_PATH", missing)
        .current_dir(common::root())
        .output()
        .expect("run iscene");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(missing.to_str().expect("utf-8")),
        "{stderr}"
    );
    assert!(stderr.contains("scripts/setup-ort.sh"), "{stderr}");
    assert!(!target.exists(), "no output left behind");
}

#[test]
fn a_missing_model_is_a_clear_error_with_exit_code_2() {
    let out = tempfile::tempdir().expect("tempdir");
    let models = out.path().join("models");
    std::fs::create_dir(&models).expect("mkdir");
    std::fs::copy(
        common::shared_data("models/coco.names"),
        models.join("coco.names"),
    )
    .expect("copy names");
    let (code, _, stderr) = reconstruct_with_onnx(
        &[
            "--frames",
            "0:10",
            "--models",
            models.to_str().expect("utf-8"),
        ],
        &out.path().join("result"),
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("yolox_nano.onnx"), "{stderr}");
    assert!(!out.path().join("result").exists());
}

/// CI's library (the CPU wheel's) has no CUDA provider: asking for it stops the run with a clear
/// error instead of mapping on the CPU behind the user's back. (On the H200 with the
/// onnxruntime-gpu library the same command maps: docs/live.md.)
#[test]
fn cuda_without_its_provider_is_a_clear_error_with_exit_code_2() {
    let out = tempfile::tempdir().expect("tempdir");
    let target = out.path().join("result");
    let (code, _, stderr) =
        reconstruct_with_onnx(&["--onnx-device", "cuda", "--frames", "0:10"], &target);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("yolox_nano.onnx"), "{stderr}");
    assert!(
        stderr.contains("--onnx-device cuda: ONNX Runtime's CUDA provider did not start"),
        "{stderr}"
    );
    assert!(!target.exists(), "no output left behind");
}
