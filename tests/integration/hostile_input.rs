//! Hostile input (issue 39): one case per finding. Every case gets exit code 2 with a message
//! naming the file or flag and the problem, leaves no output behind, touches nothing outside
//! `--out` (the listing of the folder around it is the same before and after), and ends within
//! a time bound.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common;

/// Runs iscene in `cwd`, killed after `limit`; (exit code, stderr). A run past the limit fails
/// the test: nothing may hang.
fn run_within(args: &[&str], cwd: &Path, limit: Duration) -> (i32, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_iscene"))
        .args(args)
        .current_dir(cwd)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run iscene");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().expect("wait") {
            let mut stderr = String::new();
            std::io::Read::read_to_string(child.stderr.as_mut().expect("stderr"), &mut stderr)
                .expect("stderr");
            return (status.code().unwrap_or(-1), stderr);
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("iscene {args:?} ran past {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// Runs a case in `dir`: exit code 2 within `seconds`, stderr naming each of `words`, and `dir`
/// exactly as before.
fn refused(dir: &Path, args: &[&str], words: &[&str], seconds: u64) {
    let before = common::listing(dir);
    let (code, stderr) = run_within(args, dir, Duration::from_secs(seconds));
    assert_eq!(code, 2, "{args:?}: exit code {code}: {stderr}");
    for word in words {
        assert!(
            stderr.to_lowercase().contains(&word.to_lowercase()),
            "{args:?}: the message does not say {word:?}: {stderr}"
        );
    }
    assert_eq!(
        before,
        common::listing(dir),
        "{args:?}: files changed around the output"
    );
}

fn ok(dir: &Path, args: &[&str]) {
    let (code, stderr) = run_within(args, dir, Duration::from_secs(600));
    assert_eq!(code, 0, "{args:?}: {stderr}");
}

/// `reconstruct INPUT --segmentation none` is refused, saying each of `words`.
fn refused_without_labels(dir: &Path, input: &str, words: &[&str]) {
    let args = [
        "reconstruct",
        input,
        "--out",
        "out",
        "--segmentation",
        "none",
    ];
    refused(dir, &args, words, 60);
}

/// A 3-frame noise-free kitchen sequence at `dir/data/seq`.
fn small_sequence(dir: &Path) -> PathBuf {
    let seq = dir.join("data").join("seq");
    common::render_scene("kitchen", &seq, 3, true);
    seq
}

#[test]
fn out_never_deletes_or_replaces_what_iscene_did_not_write() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    small_sequence(dir);
    std::fs::create_dir_all(dir.join("mine")).expect("mkdir");
    std::fs::write(dir.join("mine/thesis.tex"), "years of work").expect("write");
    std::fs::write(dir.join("notes.txt"), "mine").expect("write");
    std::os::unix::fs::symlink(dir.join("mine"), dir.join("link")).expect("symlink");
    let reconstruct = |out: &str| ["reconstruct", "data/seq", "--out", out].map(str::to_owned);
    for (out, words) in [
        ("data/seq", vec!["--out", "is the input"]),
        ("data", vec!["--out", "holds the input"]),
        (".", vec!["holds the input"]),
        ("data/seq/out", vec!["lies inside the input"]),
        ("mine", vec!["mine", "did not write"]),
        ("notes.txt", vec!["notes.txt", "existing file"]),
        ("link", vec!["symbolic link"]),
    ] {
        let args = reconstruct(out);
        refused(dir, &args.each_ref().map(String::as_str), &words, 60);
    }

    // An earlier output of the same command is replaced; one with a file added, or changed, is not.
    ok(dir, &["reconstruct", "data/seq", "--out", "out"]);
    ok(dir, &["reconstruct", "data/seq", "--out", "out"]);
    std::fs::write(dir.join("out/my-notes.md"), "mine").expect("write");
    refused(
        dir,
        &["reconstruct", "data/seq", "--out", "out"],
        &["my-notes.md", "did not write"],
        60,
    );
    std::fs::remove_file(dir.join("out/my-notes.md")).expect("rm");
    let report = dir.join("out/report.json");
    let text = std::fs::read_to_string(&report).expect("report");
    std::fs::write(&report, text.replace("\"input\"", "\"input_edited\"")).expect("write");
    refused(
        dir,
        &["reconstruct", "data/seq", "--out", "out"],
        &["report.json", "changed"],
        60,
    );

    // Another command's output is replaced only with --force.
    let spec = common::root().join("scenes/kitchen.json");
    let spec = spec.to_str().expect("utf8");
    ok(dir, &["render", spec, "--out", "rendered", "--frames", "2"]);
    refused(
        dir,
        &["reconstruct", "data/seq", "--out", "rendered"],
        &["iscene render", "--force"],
        60,
    );
    ok(
        dir,
        &["reconstruct", "data/seq", "--out", "rendered", "--force"],
    );
    assert!(dir.join("rendered/report.json").is_file());
}

#[test]
fn render_and_simulate_outputs_never_swallow_their_inputs() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    std::fs::create_dir_all(dir.join("specs")).expect("mkdir");
    std::fs::copy(
        common::root().join("scenes/kitchen.json"),
        dir.join("specs/kitchen.json"),
    )
    .expect("copy");
    refused(
        dir,
        &[
            "render",
            "specs/kitchen.json",
            "--out",
            "specs",
            "--frames",
            "2",
        ],
        &["holds the input"],
        60,
    );
    // The folder a specification is rendered into for `reconstruct` is a user's folder here.
    std::fs::create_dir_all(dir.join("room.sequence")).expect("mkdir");
    std::fs::write(dir.join("room.sequence/frames.txt"), "mine").expect("write");
    refused(
        dir,
        &["reconstruct", "specs/kitchen.json", "--out", "room"],
        &["room.sequence", "did not write"],
        60,
    );

    ok(
        dir,
        &[
            "render",
            "specs/kitchen.json",
            "--out",
            "seq",
            "--frames",
            "2",
            "--no-noise",
        ],
    );
    let task = common::root().join("scenes/tasks/kitchen_fridge_to_microwave.json");
    let task = task.to_str().expect("utf8");
    refused(
        dir,
        &["simulate", "seq/gt", "--task", task, "--out", "seq/gt"],
        &["is the input"],
        60,
    );
    refused(
        dir,
        &["simulate", "seq/gt", "--task", task, "--out", "seq"],
        &["holds the input"],
        60,
    );
}

/// Writes `text` as the task file `dir/task.json` and expects `simulate` to refuse it.
fn refused_task(dir: &Path, text: &str, words: &[&str]) {
    std::fs::write(dir.join("task.json"), text).expect("task");
    let mut words = words.to_vec();
    words.push("task.json");
    refused(
        dir,
        &["simulate", "seq/gt", "--task", "task.json", "--out", "sim"],
        &words,
        60,
    );
    std::fs::remove_file(dir.join("task.json")).expect("rm");
}

#[test]
fn scene_folders_and_tasks_cannot_name_paths_hang_or_panic() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    common::render_scene("kitchen", &dir.join("seq"), 2, true);

    // Refused steps are bad input: nothing runs and nothing is written.
    refused_task(
        dir,
        r#"{"steps": [{"action": "pick", "object": "unicorn_1"}]}"#,
        &["unicorn_1"],
    );
    refused_task(
        dir,
        r#"{"steps": [{"action": "pick", "object": "wall_0"}]}"#,
        &["wall_0", "layout"],
    );
    refused_task(
        dir,
        r#"{"steps": [{"action": "push", "object": "box_1", "direction": [1, 0], "distance": 1e30}]}"#,
        &["distance"],
    );
    refused_task(
        dir,
        r#"{"robot": {"radius": 1e20, "height": 1.1, "reach": 1.0, "max_reach_height": 1.8},
            "steps": [{"action": "navigate", "to": "fridge_1"}]}"#,
        &["robot.radius"],
    );
    refused_task(
        dir,
        r#"{"robot": {"height": 0.75, "lift": [0.8, 1.1]},
            "steps": [{"action": "navigate", "to": "fridge_1"}]}"#,
        &["robot.lift", "robot.height"],
    );
    refused_task(
        dir,
        r#"{"steps": [{"action": "pick", "object": "../../../x"}]}"#,
        &["not a plain name"],
    );

    // A node id that is a path, or holds a quote, never reaches a file name.
    let graph_path = dir.join("seq/gt/contact_graph.json");
    let graph = std::fs::read_to_string(&graph_path).expect("graph");
    for evil in ["../../../escaped", "box\\\"1"] {
        std::fs::write(
            &graph_path,
            graph.replace("\"box_1\"", &format!("\"{evil}\"")),
        )
        .expect("write");
        std::fs::write(
            dir.join("task.json"),
            r#"{"steps": [{"action": "navigate", "to": "fridge_1"}]}"#,
        )
        .expect("task");
        refused(
            dir,
            &["simulate", "seq/gt", "--task", "task.json", "--out", "sim"],
            &["contact_graph.json", "not a plain name"],
            60,
        );
    }
    assert!(!dir.join("escaped.obj").exists());
}

#[test]
fn cad_files_cannot_escape_their_folder_nest_without_end_or_set_endless_ranges() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let import = |file: &str, format: &str| {
        ["cad", "import", format, file, "--into", "db/out"].map(str::to_owned)
    };
    let refused_import = |file: &str, format: &str, text: &str, words: &[&str]| {
        std::fs::create_dir_all(dir.join("models")).expect("mkdir");
        std::fs::write(dir.join("models").join(file), text).expect("write");
        let path = format!("models/{file}");
        let args = import(&path, format);
        refused(dir, &args.each_ref().map(String::as_str), words, 60);
        std::fs::remove_file(dir.join("models").join(file)).expect("rm");
    };
    let box_link = |name: &str| {
        format!(
            r#"<link name="{name}"><collision><geometry><box size="0.5 0.5 0.5"/></geometry></collision></link>"#
        )
    };
    // A prismatic joint of plus or minus 1e30 m.
    refused_import(
        "cabinet.urdf",
        "urdf",
        &format!(
            r#"<robot name="cabinet">{}{}<joint name="slide" type="prismatic"><parent link="carcass"/>
            <child link="drawer"/><axis xyz="0 1 0"/><limit lower="-1e30" upper="1e30" effort="1" velocity="1"/></joint></robot>"#,
            box_link("carcass"),
            box_link("drawer")
        ),
        &["cabinet.urdf", "limits"],
    );
    // A chain of 10,000 links.
    let mut chain = String::from(r#"<robot name="cabinet">"#);
    for i in 0..10_000 {
        chain.push_str(&box_link(&format!("l{i}")));
        if i > 0 {
            chain.push_str(&format!(
                r#"<joint name="j{i}" type="fixed"><parent link="l{}"/><child link="l{i}"/></joint>"#,
                i - 1
            ));
        }
    }
    chain.push_str("</robot>");
    refused_import(
        "cabinet.urdf",
        "urdf",
        &chain,
        &["cabinet.urdf", "10000 links"],
    );
    // 100,000 nested elements.
    let nested = format!(
        r#"<robot name="cabinet">{}{}</robot>"#,
        "<a>".repeat(100_000),
        "</a>".repeat(100_000)
    );
    refused_import("cabinet.urdf", "urdf", &nested, &["cabinet.urdf", "nested"]);
    // 20,000 nested MJCF bodies.
    let bodies = format!(
        r#"<mujoco model="cabinet"><worldbody>{}</worldbody></mujoco>"#,
        r#"<body><geom type="box" size="0.1 0.1 0.1"/>"#.repeat(20_000) + &"</body>".repeat(20_000)
    );
    refused_import("cabinet.xml", "mjcf", &bodies, &["cabinet.xml", "nested"]);
    // A mesh outside the model's folder.
    std::fs::write(dir.join("secret.stl"), "solid x\nendsolid x\n").expect("write");
    refused_import(
        "cabinet.xml",
        "mjcf",
        r#"<mujoco model="cabinet"><asset><mesh name="m" file="../secret.stl"/></asset>
           <worldbody><body><geom type="mesh" mesh="m"/></body></worldbody></mujoco>"#,
        &["cabinet.xml", "outside"],
    );
    // A negative mass.
    refused_import(
        "cabinet.urdf",
        "urdf",
        r#"<robot name="cabinet"><link name="carcass"><inertial><mass value="-5"/>
            <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
            <collision><geometry><box size="0.5 0.5 0.5"/></geometry></collision></link></robot>"#,
        &["cabinet.urdf", "mass"],
    );
    // --into a user's folder.
    std::fs::create_dir_all(dir.join("mine")).expect("mkdir");
    std::fs::write(dir.join("mine/thesis.tex"), "mine").expect("write");
    let libero = common::shared_data("cad/libero/articulated_objects");
    refused(
        dir,
        &[
            "cad",
            "import",
            "mjcf",
            libero.to_str().expect("utf8"),
            "--into",
            "mine",
        ],
        &["mine", "not a CAD database"],
        60,
    );
    refused(dir, &["cad", "generate", "--into", "mine"], &["mine"], 60);
}

#[test]
fn a_cad_database_id_cannot_name_a_path_outside_the_output() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    small_sequence(dir);
    ok(dir, &["cad", "generate", "--into", "db"]);
    let index = dir.join("db/index.json");
    let text = std::fs::read_to_string(&index).expect("index");
    let first_id =
        serde_json::from_str::<serde_json::Value>(&text).expect("json")["models"][0]["id"]
            .as_str()
            .expect("id")
            .to_owned();
    std::fs::write(
        &index,
        text.replacen(&format!("\"{first_id}\""), "\"../../../escaped\"", 1),
    )
    .expect("write");
    refused(
        dir,
        &["reconstruct", "data/seq", "--out", "out", "--cad", "db"],
        &["index.json", "not a plain name"],
        60,
    );
}

/// A zip whose one entry, `name`, is `bytes` zeros: a few hundred kilobytes on disk.
fn zip_bomb(path: &Path, name: &str, bytes: usize) {
    use std::io::Write;
    let file = std::fs::File::create(path).expect("create");
    let mut zip = zip::ZipWriter::new(file);
    zip.start_file(
        name,
        zip::write::SimpleFileOptions::default()
            .compression_method(zip::CompressionMethod::Deflated),
    )
    .expect("entry");
    let chunk = vec![b'#'; 1 << 20];
    for _ in 0..bytes >> 20 {
        zip.write_all(&chunk).expect("write");
    }
    zip.finish().expect("finish");
}

#[test]
fn sizes_set_by_files_and_flags_are_bounded() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    small_sequence(dir);
    for voxel in ["NaN", "1e-5"] {
        refused(
            dir,
            &[
                "bench", "tsdf", "data/seq", "--frames", "0:3", "--voxel", voxel,
            ],
            &["--voxel"],
            30,
        );
    }
    // 2 mm voxels over what three frames see take about 4 GB (the whole kitchen's 300 frames,
    // over the default 8 GB budget).
    refused(
        dir,
        &[
            "reconstruct",
            "data/seq",
            "--out",
            "out",
            "--voxel",
            "0.002",
            "--max-memory",
            "1",
        ],
        &["--voxel", "--max-memory"],
        60,
    );
    // A focal length of 1 px.
    let broken = dir.join("data/wide");
    std::fs::create_dir_all(&broken).expect("mkdir");
    for entry in std::fs::read_dir(dir.join("data/seq"))
        .expect("ls")
        .filter_map(Result::ok)
    {
        if entry.path().is_file() {
            std::fs::copy(entry.path(), broken.join(entry.file_name())).expect("copy");
        }
    }
    std::fs::write(
        broken.join("camera-intrinsics.txt"),
        "1 0 320\n0 1 240\n0 0 1\n",
    )
    .expect("write");
    refused_without_labels(dir, "data/wide", &["camera-intrinsics.txt", "focal"]);
    // A pose 1e30 m away.
    std::fs::copy(
        dir.join("data/seq/camera-intrinsics.txt"),
        broken.join("camera-intrinsics.txt"),
    )
    .expect("copy");
    std::fs::write(
        broken.join("frame-000001.pose.txt"),
        "1 0 0 1e30\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",
    )
    .expect("write");
    refused_without_labels(dir, "data/wide", &["frame-000001.pose.txt", "translation"]);

    // Specifications: a trillion frames, four thousand objects.
    let spec: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(common::root().join("scenes/kitchen.json")).expect("spec"),
    )
    .expect("json");
    let mut frames = spec.clone();
    frames["camera"]["frames"] = serde_json::json!(1_000_000_000_000u64);
    std::fs::write(dir.join("frames.json"), frames.to_string()).expect("write");
    refused(
        dir,
        &["render", "frames.json", "--out", "seq2"],
        &["frames.json", "camera.frames"],
        30,
    );
    refused(
        dir,
        &[
            "render",
            common::root()
                .join("scenes/kitchen.json")
                .to_str()
                .expect("utf8"),
            "--out",
            "seq2",
            "--frames",
            "100000000",
        ],
        &["--frames"],
        30,
    );
    let mut crowd = spec.clone();
    let object = spec["objects"][0].clone();
    crowd["objects"] = serde_json::Value::Array(
        (0..4000)
            .map(|i| {
                let mut o = object.clone();
                o["id"] = serde_json::json!(format!("thing_{i}"));
                o
            })
            .collect(),
    );
    std::fs::write(dir.join("crowd.json"), crowd.to_string()).expect("write");
    refused(
        dir,
        &["render", "crowd.json", "--out", "seq2"],
        &["crowd.json", "4000 objects"],
        30,
    );

    // A 5 MB catalogue that expands to 200 MB, and furniture 1e30 cm tall.
    zip_bomb(
        &dir.join("bomb.sh3f"),
        "PluginFurnitureCatalog.properties",
        200 << 20,
    );
    refused(
        dir,
        &["cad", "import", "sh3d", "bomb.sh3f", "--into", "db"],
        &["bomb.sh3f", "expands past"],
        60,
    );
}

/// A catalogue's table 1e30 cm tall is listed as not imported, not made a model of that size.
#[test]
fn a_sweet_home_3d_size_of_1e30_cm_is_not_imported() {
    use std::io::Write;
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let file = std::fs::File::create(dir.join("huge.sh3f")).expect("create");
    let mut zip = zip::ZipWriter::new(file);
    let options = zip::write::SimpleFileOptions::default();
    zip.start_file("PluginFurnitureCatalog.properties", options)
        .expect("entry");
    zip.write_all(
        b"id#1=huge\nname#1=Table\ncategory#1=Kitchen\nmodel#1=/table.obj\nwidth#1=100\n\
          depth#1=80\nheight#1=1e30\n",
    )
    .expect("write");
    zip.start_file("table.obj", options).expect("entry");
    zip.write_all(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n")
        .expect("write");
    zip.finish().expect("finish");
    let (code, stdout, stderr) =
        common::iscene(&["cad", "import", "sh3d", "huge.sh3f", "--into", "db"], dir);
    assert_eq!(code, 0, "{stderr}");
    assert!(
        stdout.contains("imported 0 models") && stdout.contains("not imported: huge"),
        "{stdout}"
    );
    assert!(stdout.contains("is not furniture's"), "{stdout}");
}

/// A reconstruction interrupted at random moments (SIGINT, SIGTERM, SIGKILL) leaves the earlier
/// output whole, and the next run clears what the killed one left.
#[test]
fn a_killed_reconstruction_leaves_the_earlier_output_whole() {
    use rand::{Rng, SeedableRng};
    use rustix::process::{Pid, Signal, kill_process};
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    common::render_scene("kitchen", &dir.join("seq"), 20, true);
    let args = ["reconstruct", "seq", "--out", "out"];
    let start = Instant::now();
    ok(dir, &args);
    let full_run = start.elapsed();
    // report.json holds the run's timings; every other file is the same from run to run.
    let whole = |out: &Path| -> Vec<(String, String)> {
        let report = std::fs::read_to_string(out.join("report.json")).expect("report.json");
        serde_json::from_str::<serde_json::Value>(&report).expect("a whole report.json");
        common::hash_tree(out)
            .into_iter()
            .filter(|(name, _)| name != "report.json")
            .collect()
    };
    let earlier = whole(&dir.join("out"));
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(39);
    for (round, signal) in [Signal::INT, Signal::TERM, Signal::KILL]
        .into_iter()
        .cycle()
        .take(6)
        .enumerate()
    {
        let mut child = Command::new(env!("CARGO_BIN_EXE_iscene"))
            .args(args)
            .current_dir(dir)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("run iscene");
        std::thread::sleep(full_run.mul_f64(rng.random_range(0.05..1.1)));
        let pid = Pid::from_raw(child.id() as i32).expect("pid");
        let _ = kill_process(pid, signal);
        child.wait().expect("wait");
        // Whatever the moment, the folder holds one whole output (the same input gives the
        // same files) with the marker that lets a later run replace it.
        assert!(
            whole(&dir.join("out")) == earlier,
            "round {round}: the output is not whole"
        );
        assert!(
            iscene::io::output_folder::OutputMarker::read(&dir.join("out")).is_some(),
            "round {round}: the output lost its marker"
        );
    }
    ok(dir, &args);
    let leftovers: Vec<String> = std::fs::read_dir(dir)
        .expect("ls")
        .filter_map(Result::ok)
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(leftovers.is_empty(), "left behind: {leftovers:?}");
}
