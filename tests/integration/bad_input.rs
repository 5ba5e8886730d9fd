//! Every kind of bad input gets exit code 2, a message naming the file and the problem, and no
//! output folder.

use crate::common;

use std::path::{Path, PathBuf};

/// A valid 3-frame sequence rendered without noise, copied fresh for each case.
fn good_sequence(dir: &Path) -> PathBuf {
    let seq = dir.join("seq");
    common::render_scene("kitchen", &seq, 3, true);
    seq
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("mkdir");
    for entry in std::fs::read_dir(from)
        .expect("read")
        .filter_map(Result::ok)
    {
        let p = entry.path();
        if p.is_dir() {
            copy_dir(&p, &to.join(entry.file_name()));
        } else {
            std::fs::copy(&p, to.join(entry.file_name())).expect("copy");
        }
    }
}

/// Runs `reconstruct` on a broken copy and checks the answer.
fn expect_rejected(
    dir: &Path,
    good: &Path,
    case: &str,
    break_it: impl FnOnce(&Path),
    file: &str,
    problem: &str,
) {
    let seq = dir.join(case);
    copy_dir(good, &seq);
    break_it(&seq);
    let out = dir.join(format!("{case}-out"));
    let (code, stdout, stderr) = common::iscene(
        &[
            "reconstruct",
            seq.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        dir,
    );
    assert_eq!(
        code, 2,
        "{case}: exit code {code}, stdout {stdout}, stderr {stderr}"
    );
    assert!(
        stderr.contains(file),
        "{case}: message does not name {file}: {stderr}"
    );
    assert!(
        stderr.to_lowercase().contains(&problem.to_lowercase()),
        "{case}: message does not say {problem:?}: {stderr}"
    );
    assert!(!out.exists(), "{case}: an output folder was left behind");
}

#[test]
fn broken_sequences_are_rejected_with_the_file_and_the_problem() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let good = good_sequence(dir);
    let write = |p: PathBuf, text: &str| std::fs::write(p, text).expect("write");
    expect_rejected(
        dir,
        &good,
        "depth-8bit",
        |s| {
            std::fs::copy(
                s.join("frame-000001.color.png"),
                s.join("frame-000001.depth.png"),
            )
            .expect("copy");
        },
        "frame-000001.depth.png",
        "16-bit",
    );
    expect_rejected(
        dir,
        &good,
        "pose-not-rigid",
        |s| {
            write(
                s.join("frame-000002.pose.txt"),
                "2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",
            )
        },
        "frame-000002.pose.txt",
        "orthonormal",
    );
    expect_rejected(
        dir,
        &good,
        "pose-nan",
        |s| {
            write(
                s.join("frame-000000.pose.txt"),
                "1 0 0 nan\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",
            )
        },
        "frame-000000.pose.txt",
        "NaN",
    );
    expect_rejected(
        dir,
        &good,
        "pose-short",
        |s| write(s.join("frame-000000.pose.txt"), "1 0 0 0\n0 1 0 0\n"),
        "frame-000000.pose.txt",
        "16 numbers",
    );
    expect_rejected(
        dir,
        &good,
        "pose-missing",
        |s| std::fs::remove_file(s.join("frame-000001.pose.txt")).expect("rm"),
        "frame-000001.pose.txt",
        "missing",
    );
    expect_rejected(
        dir,
        &good,
        "frame-missing",
        |s| std::fs::remove_file(s.join("frame-000001.depth.png")).expect("rm"),
        "frame-000001.depth.png",
        "missing",
    );
    expect_rejected(
        dir,
        &good,
        "color-missing",
        |s| std::fs::remove_file(s.join("frame-000002.color.png")).expect("rm"),
        "frame-000002.color",
        "missing",
    );
    expect_rejected(
        dir,
        &good,
        "size-mismatch",
        |s| {
            write(
                s.join("camera.json"),
                r#"{"width": 320, "height": 240, "depth_scale": 1000}"#,
            )
        },
        "frame-000000.depth.png",
        "320x240",
    );
    expect_rejected(
        dir,
        &good,
        "depth-scale",
        |s| {
            write(
                s.join("camera.json"),
                r#"{"width": 640, "height": 480, "depth_scale": 50}"#,
            )
        },
        "frame-000000.depth.png",
        "depth scale",
    );
    expect_rejected(
        dir,
        &good,
        "intrinsics",
        |s| write(s.join("camera-intrinsics.txt"), "525 0 319.5\n0 525\n"),
        "camera-intrinsics.txt",
        "9 numbers",
    );
    expect_rejected(
        dir,
        &good,
        "intrinsics-negative",
        |s| {
            write(
                s.join("camera-intrinsics.txt"),
                "-525 0 319.5\n0 525 239.5\n0 0 1\n",
            )
        },
        "camera-intrinsics.txt",
        "positive",
    );
    expect_rejected(
        dir,
        &good,
        "gravity",
        |s| write(s.join("gravity-direction.txt"), "0 0\n"),
        "gravity-direction.txt",
        "3 numbers",
    );
    expect_rejected(
        dir,
        &good,
        "labels",
        |s| write(s.join("labels.json"), "{\"instances\": [}"),
        "labels.json",
        "invalid labels.json",
    );
    expect_rejected(
        dir,
        &good,
        "camera-json",
        |s| write(s.join("camera.json"), "{\"width\": 640}"),
        "camera.json",
        "invalid camera.json",
    );
    expect_rejected(
        dir,
        &good,
        "empty",
        |s| {
            for e in std::fs::read_dir(s).expect("read").filter_map(Result::ok) {
                if e.file_name().to_string_lossy().starts_with("frame-") {
                    std::fs::remove_file(e.path()).expect("rm");
                }
            }
        },
        "empty",
        "no frame-NNNNNN.depth.png",
    );
}

#[test]
fn bad_specifications_and_missing_inputs_are_rejected() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let dir = tmp.path();
    let cases = [
        (
            "malformed.json",
            "{\"name\": \"x\", \"room\": {\"size\": [4, 3, 2.5]}, \"objects\": [",
            "EOF",
        ),
        (
            "unknown-key.json",
            r#"{"name": "x", "room": {"size": [4, 3, 2.5]}, "objects": [{"id": "t", "class": "table", "position": [1, 1], "colour": "red"}]}"#,
            "colour",
        ),
        (
            "unknown-class.json",
            r#"{"name": "x", "room": {"size": [4, 3, 2.5]}, "objects": [{"id": "t", "class": "piano", "position": [1, 1]}]}"#,
            "objects[0].class",
        ),
        (
            "dangling.json",
            r#"{"name": "x", "room": {"size": [4, 3, 2.5]}, "objects": [{"id": "c", "class": "cup", "on": "table_9"}]}"#,
            "objects[0].on",
        ),
        (
            "outside.json",
            r#"{"name": "x", "room": {"size": [4, 3, 2.5]}, "objects": [{"id": "t", "class": "table", "position": [3.9, 1]}]}"#,
            "objects[0].position",
        ),
    ];
    for (name, text, needle) in cases {
        let spec = dir.join(name);
        std::fs::write(&spec, text).expect("write");
        for command in ["render", "reconstruct"] {
            let out = dir.join(format!("{name}-{command}-out"));
            let (code, _, stderr) = common::iscene(
                &[
                    command,
                    spec.to_str().expect("utf8"),
                    "--out",
                    out.to_str().expect("utf8"),
                ],
                dir,
            );
            assert_eq!(code, 2, "{command} {name}: {stderr}");
            assert!(
                stderr.contains(name) && stderr.contains(needle),
                "{command} {name}: {stderr}"
            );
            assert!(!out.exists(), "{command} {name}: output left behind");
        }
    }
    let (code, _, stderr) = common::iscene(&["reconstruct", "no/such/folder", "--out", "x"], dir);
    assert_eq!(code, 2);
    assert!(
        stderr.contains("no/such/folder") && stderr.contains("not found"),
        "{stderr}"
    );
    let broken_db = dir.join("broken_db");
    std::fs::create_dir_all(&broken_db).expect("mkdir");
    std::fs::write(broken_db.join("index.json"), "{\"models\": [").expect("write");
    let (code, _, stderr) = common::iscene(
        &[
            "reconstruct",
            "--cad",
            broken_db.to_str().expect("utf8"),
            "--out",
            "cad-out",
        ],
        dir,
    );
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("broken_db/index.json"), "{stderr}");
    assert!(!dir.join("cad-out").exists());
    let (code, _, stderr) = common::iscene(&["render", "missing.json", "--out", "x"], dir);
    assert_eq!(code, 2);
    assert!(stderr.contains("missing.json"), "{stderr}");
    let (code, _, stderr) = common::iscene(&["reconstruct", "--frames", "5:2", "--out", "x"], dir);
    assert_eq!(code, 2, "{stderr}");
}
