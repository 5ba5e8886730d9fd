//! `iscene reconstruct --live`: frames taken as they arrive, from a recording replayed at a rate
//! or from a folder another program is writing, give the batch run's output.

use std::path::Path;
use std::time::Duration;

use crate::common;

/// Every output file but the live previews and the report (which holds timings), hashed.
fn outputs(dir: &Path) -> Vec<(String, String)> {
    common::hash_tree(dir)
        .into_iter()
        .filter(|(name, _)| !name.starts_with("live") && name != "report.json")
        .collect()
}

fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("report.json")).expect("report.json"))
        .expect("json")
}

fn reconstruct(seq: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "reconstruct",
        seq.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--segmentation",
        "none",
    ];
    args.extend_from_slice(extra);
    let (code, stdout, stderr) = common::iscene(&args, &common::root());
    assert_eq!(code, 0, "{args:?}: {stdout}{stderr}");
    stdout
}

/// A recording replayed at 10 frames per second: every frame arrives on time, is integrated,
/// the world is refreshed while they arrive, and the final output is the batch run's, file for
/// file.
#[test]
fn a_replayed_recording_gives_the_batch_output() {
    let dir = tempfile::tempdir().expect("tempdir");
    let seq = dir.path().join("seq");
    common::render_scene("kitchen", &seq, 30, false);
    let batch = dir.path().join("batch");
    reconstruct(&seq, &batch, &[]);
    let live = dir.path().join("live");
    let started = std::time::Instant::now();
    let stdout = reconstruct(&seq, &live, &["--live", "--rate", "10"]);
    // 30 frames at 10 per second cannot take less than the 2.9 s over which they arrive.
    assert!(started.elapsed() > Duration::from_millis(2900), "{stdout}");
    assert_eq!(outputs(&live), outputs(&batch));
    let r = report(&live);
    assert_eq!(r["live"]["frames_arrived"], 30, "{r}");
    assert_eq!(r["live"]["frames_integrated"], 30, "{r}");
    assert_eq!(r["live"]["labels_dropped"], 0, "{r}");
    assert!(
        r["live"]["refreshes"].as_u64().expect("refreshes") >= 1,
        "{r}"
    );
    assert_eq!(r["ingest"], report(&batch)["ingest"]);
    let status: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(live.join("live/status.json")).expect("live/status.json"),
    )
    .expect("json");
    assert_eq!(status["finished"], true);
    assert_eq!(status["frames_integrated"], 30);
    assert!(live.join("live/contact_graph.json").is_file());
}

/// A folder written while the session runs: the session waits for the first frame, takes each
/// frame once its depth image is in place, ends after --idle seconds without a new one, and
/// gives what a batch run over the finished folder gives.
#[test]
fn a_followed_folder_is_mapped_as_it_is_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let recording = dir.path().join("recording");
    common::render_scene("kitchen", &recording, 12, false);
    let growing = dir.path().join("growing");
    std::fs::create_dir(&growing).expect("mkdir");
    let live = dir.path().join("live");
    let session = std::process::Command::new(env!("CARGO_BIN_EXE_iscene"))
        .args([
            "reconstruct",
            growing.to_str().expect("utf8"),
            "--out",
            live.to_str().expect("utf8"),
            "--segmentation",
            "none",
            "--live",
            "--idle",
            "4",
        ])
        .current_dir(common::root())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start iscene");
    // The writer: the sequence's files first, then each frame with its depth image renamed into
    // place last, 150 ms apart.
    let mut names: Vec<String> = std::fs::read_dir(&recording)
        .expect("read recording")
        .filter_map(Result::ok)
        .filter(|e| e.path().is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    std::thread::sleep(Duration::from_millis(500));
    for name in names.iter().filter(|n| !n.starts_with("frame-")) {
        std::fs::copy(recording.join(name), growing.join(name)).expect("copy");
    }
    for k in 0..12 {
        let prefix = format!("frame-{k:06}.");
        for name in names.iter().filter(|n| n.starts_with(&prefix)) {
            if !name.ends_with(".depth.png") {
                std::fs::copy(recording.join(name), growing.join(name)).expect("copy");
            }
        }
        let depth = format!("{prefix}depth.png");
        let partial = growing.join(format!(".{depth}.partial"));
        std::fs::copy(recording.join(&depth), &partial).expect("copy depth");
        std::fs::rename(&partial, growing.join(&depth)).expect("rename depth");
        std::thread::sleep(Duration::from_millis(150));
    }
    let output = session.wait_with_output().expect("wait for iscene");
    assert!(
        output.status.success(),
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let r = report(&live);
    assert_eq!(r["live"]["frames_integrated"], 12, "{r}");
    assert_eq!(r["ingest"]["frames"], 12, "{r}");
    let batch = dir.path().join("batch");
    reconstruct(&growing, &batch, &[]);
    assert_eq!(outputs(&live), outputs(&batch));
}

/// A followed folder in which no frame ever arrives ends with a clear error and no output.
#[test]
fn a_folder_that_stays_empty_is_refused_after_the_idle_time() {
    let dir = tempfile::tempdir().expect("tempdir");
    let empty = dir.path().join("empty");
    std::fs::create_dir(&empty).expect("mkdir");
    std::fs::write(
        empty.join("camera-intrinsics.txt"),
        "525 0 319.5\n0 525 239.5\n0 0 1\n",
    )
    .expect("write");
    let out = dir.path().join("out");
    let (code, stdout, stderr) = common::iscene(
        &[
            "reconstruct",
            empty.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
            "--segmentation",
            "none",
            "--live",
            "--idle",
            "1",
        ],
        dir.path(),
    );
    assert_eq!(code, 2, "{stdout}{stderr}");
    assert!(stderr.contains("no frame arrived"), "{stderr}");
    assert!(!out.exists());
}
