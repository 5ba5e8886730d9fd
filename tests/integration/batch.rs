//! `iscene batch`: a manifest run whole or in shards merges to the same summary; a killed input
//! is redone and nothing finished is; and the same batch as a Slurm job array on a one-node
//! cluster (scripts/slurm-local.sh) merges to the summary of a single process.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{iscene, root};

/// Frames per room: enough for every stage to run, few enough for CI.
const FRAMES: usize = 20;

fn summary(dir: &Path) -> serde_json::Value {
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("summary JSON")
}

/// What two runs of the same inputs must agree on: everything but the clock, the cost and the
/// benchmark's description.
fn results(mut summary: serde_json::Value) -> serde_json::Value {
    let object = summary.as_object_mut().expect("object");
    for key in [
        "seconds",
        "room_seconds",
        "cost",
        "seeds",
        "style",
        "noise",
        "frames",
    ] {
        object.remove(key);
    }
    summary
}

fn modified(path: &Path) -> std::time::SystemTime {
    std::fs::metadata(path)
        .and_then(|m| m.modified())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Marks input `name` as a task killed while it ran leaves it.
fn kill_input(dir: &Path, name: &str) {
    let path = dir.join(name).join("status.json");
    let mut status: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("status")).expect("JSON");
    status["state"] = "running".into();
    status["finished_at"] = serde_json::Value::Null;
    std::fs::write(&path, status.to_string()).expect("write status");
}

#[test]
fn shards_merge_to_the_whole_runs_summary_and_a_killed_input_alone_is_redone() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir(dir.path().join("empty")).expect("mkdir");
    let kitchen = root().join("scenes/kitchen.json");
    let manifest = serde_json::json!({
        "defaults": {"frames": FRAMES},
        "inputs": [
            {"seeds": "0:2"},
            {"spec": kitchen},
            {"sequence": "empty"},
        ]
    });
    std::fs::write(dir.path().join("m.json"), manifest.to_string()).expect("manifest");
    // Whole, in one process: the empty sequence fails, is listed, and fails the run (exit 1).
    let (code, stdout, err) = iscene(&["batch", "m.json", "--out", "whole"], dir.path());
    assert_eq!(code, 1, "{stdout}\n{err}");
    let whole = summary(&dir.path().join("whole"));
    assert_eq!(whole["rooms"], 3, "{whole}");
    assert_eq!(whole["failed"][0]["input"], "empty", "{whole}");
    assert!(
        whole["failed"][0]["error"]
            .as_str()
            .is_some_and(|e| e.contains("empty")),
        "the error names the folder: {whole}"
    );
    for worst in whole["worst_rooms"].as_array().expect("worst rooms") {
        let seeded = worst["input"]
            .as_str()
            .is_some_and(|i| i.starts_with("seed_"));
        assert_eq!(worst["seed"].is_u64(), seeded, "{worst}");
    }
    let status: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("whole/seed_0/status.json")).expect("status"),
    )
    .expect("JSON");
    assert_eq!(status["state"], "done");
    assert!(
        status["peak_memory_mb"]
            .as_f64()
            .is_some_and(|mb| mb > 10.0),
        "{status}"
    );
    assert!(
        status["seconds"].as_f64().is_some_and(|s| s > 0.0),
        "{status}"
    );
    // In two shards, the second from the folder's own batch.json, then merged.
    for shard in ["0/2", "1/2"] {
        let manifest: &[&str] = if shard == "0/2" { &["m.json"] } else { &[] };
        let args: Vec<&str> = ["batch"]
            .into_iter()
            .chain(manifest.iter().copied())
            .chain(["--out", "sharded", "--shard", shard])
            .collect();
        let (code, stdout, err) = iscene(&args, dir.path());
        // Shard 1 holds the empty sequence (input 3).
        assert_eq!(code, if shard == "1/2" { 1 } else { 0 }, "{stdout}\n{err}");
        assert!(stdout.contains(&format!("shard {shard}")), "{stdout}");
    }
    let (code, _, err) = iscene(&["batch", "merge", "sharded"], dir.path());
    assert_eq!(code, 0, "{err}");
    let sharded = summary(&dir.path().join("sharded"));
    assert_eq!(results(sharded.clone()), results(whole.clone()));
    // A killed input is redone on --resume; the finished ones are not.
    let sharded_dir = dir.path().join("sharded");
    kill_input(&sharded_dir, "seed_1");
    let (seed_0, seed_1) = (
        modified(&sharded_dir.join("seed_0/eval.json")),
        modified(&sharded_dir.join("seed_1/eval.json")),
    );
    let (_, stdout, err) = iscene(
        &["batch", "m.json", "--out", "sharded", "--resume"],
        dir.path(),
    );
    assert!(stdout.contains("# Batch"), "{stdout}\n{err}");
    assert!(
        err.contains("seed_1 done") && !err.contains("seed_0 done"),
        "{err}"
    );
    assert_eq!(modified(&sharded_dir.join("seed_0/eval.json")), seed_0);
    assert_ne!(modified(&sharded_dir.join("seed_1/eval.json")), seed_1);
    assert_eq!(results(summary(&sharded_dir)), results(whole));
    // Bad manifests and folders: exit 2, the file named, nothing written.
    std::fs::write(
        dir.path().join("bad.json"),
        "{\"inputs\": [{\"seed\": \"x\"}]}",
    )
    .expect("bad");
    let (code, _, err) = iscene(&["batch", "bad.json", "--out", "b"], dir.path());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("bad.json") && err.contains("seed"), "{err}");
    assert!(!dir.path().join("b").exists());
    let (code, _, err) = iscene(&["batch", "m.json", "--out", "empty"], dir.path());
    assert_eq!(code, 2, "{err}");
    let (code, _, err) = iscene(&["batch", "m.json", "--out", "new", "--resume"], dir.path());
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("resume"), "{err}");
}

/// A one-node Slurm cluster in a folder, stopped when dropped.
struct LocalCluster {
    dir: PathBuf,
    conf: PathBuf,
}

impl LocalCluster {
    fn start(dir: &Path) -> Self {
        let script = root().join("scripts/slurm-local.sh");
        let out = Command::new(&script)
            .arg("start")
            .arg(dir)
            .output()
            .expect("run scripts/slurm-local.sh");
        assert!(
            out.status.success(),
            "Slurm cannot be started on this machine (scripts/setup-slurm.sh installs it; \
             scripts/test.sh runs that): {}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        Self {
            dir: dir.to_path_buf(),
            conf: dir.join("slurm.conf"),
        }
    }

    fn log_tails(&self) -> String {
        ["slurmctld.log", "slurmd.log"]
            .iter()
            .map(|name| {
                let text = std::fs::read_to_string(self.dir.join(name)).unwrap_or_default();
                let lines: Vec<&str> = text.lines().collect();
                format!(
                    "{name}: {}",
                    lines[lines.len().saturating_sub(8)..].join("\n")
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl Drop for LocalCluster {
    fn drop(&mut self) {
        let _ = Command::new(root().join("scripts/slurm-local.sh"))
            .arg("stop")
            .arg(&self.dir)
            .output();
    }
}

/// Runs iscene with the cluster's configuration.
fn iscene_on(cluster: &LocalCluster, args: &[&str], cwd: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_iscene"))
        .args(args)
        .current_dir(cwd)
        .env("SLURM_CONF", &cluster.conf)
        .output()
        .expect("run iscene");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Waits until the merge job has written `summary.json` newer than `after`.
fn wait_for_summary(cluster: &LocalCluster, dir: &Path, after: Option<std::time::SystemTime>) {
    let start = Instant::now();
    let path = dir.join("summary.json");
    while start.elapsed() < Duration::from_secs(600) {
        if path.is_file() && after.is_none_or(|t| modified(&path) > t) {
            // The merge job writes it last; give its rename a moment.
            std::thread::sleep(Duration::from_millis(200));
            return;
        }
        std::thread::sleep(Duration::from_secs(1));
    }
    let outputs: Vec<String> = std::fs::read_dir(dir.join("slurm"))
        .into_iter()
        .flatten()
        .flatten()
        .filter(|e| e.path().extension().is_some_and(|x| x == "out"))
        .map(|e| {
            format!(
                "{}: {}",
                e.path().display(),
                std::fs::read_to_string(e.path()).unwrap_or_default()
            )
        })
        .collect();
    panic!(
        "no summary from the merge job in 10 minutes\n{}\n{}",
        outputs.join("\n"),
        cluster.log_tails()
    );
}

#[test]
fn a_slurm_job_array_merges_to_the_summary_of_one_process() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cluster = LocalCluster::start(&dir.path().join("cluster"));
    let manifest =
        serde_json::json!({"defaults": {"frames": FRAMES}, "inputs": [{"seeds": "0:4"}]});
    std::fs::write(dir.path().join("m.json"), manifest.to_string()).expect("manifest");
    // Four rooms as a two-task array (one core each, both running at once here) plus the merge
    // job.
    let submit = |extra: &[&str]| {
        let mut args = vec![
            "batch",
            "m.json",
            "--out",
            "cluster_out",
            "--slurm",
            "--shards",
            "2",
            "--cpus",
            "1",
        ];
        args.extend_from_slice(extra);
        iscene_on(&cluster, &args, dir.path())
    };
    let (code, stdout, err) = submit(&[]);
    assert_eq!(code, 0, "{stdout}\n{err}");
    assert!(stdout.contains("tasks 0-1 of 2 shards"), "{stdout}");
    let out = dir.path().join("cluster_out");
    let script = std::fs::read_to_string(out.join("slurm/shards.sbatch")).expect("script");
    assert!(
        script.contains("--shard \"${SLURM_ARRAY_TASK_ID}/2\""),
        "{script}"
    );
    wait_for_summary(&cluster, &out, None);
    let on_slurm = summary(&out);
    assert_eq!(on_slurm["rooms"], 4, "{on_slurm}\n{}", cluster.log_tails());
    for task in 0..2 {
        let log = std::fs::read_to_string(out.join(format!("slurm/shard-{task}.out")))
            .expect("task output");
        assert!(log.contains(&format!("shard {task}/2: 2 done")), "{log}");
    }
    // The same seeds in one process, as `iscene benchmark` runs them.
    let frames = FRAMES.to_string();
    let (code, _, err) = iscene(
        &[
            "benchmark",
            "--seeds",
            "0:4",
            "--frames",
            &frames,
            "--jobs",
            "1",
            "--out",
            "single",
        ],
        dir.path(),
    );
    assert_eq!(code, 0, "{err}");
    let single = summary(&dir.path().join("single"));
    assert_eq!(results(on_slurm.clone()), results(single));
    // A killed task's input is resubmitted alone (its shard only) and nothing else is redone.
    kill_input(&out, "seed_3");
    let seed_0 = modified(&out.join("seed_0/eval.json"));
    let before = modified(&out.join("summary.json"));
    let (code, stdout, err) = submit(&["--resume"]);
    assert_eq!(code, 0, "{stdout}\n{err}");
    assert!(
        stdout.contains("tasks 1 of 2 shards, 1 inputs to run"),
        "{stdout}"
    );
    assert!(
        stdout.contains("this batch's 3 finished inputs"),
        "{stdout}"
    );
    wait_for_summary(&cluster, &out, Some(before));
    assert_eq!(modified(&out.join("seed_0/eval.json")), seed_0);
    assert_eq!(results(summary(&out)), results(on_slurm));
}
