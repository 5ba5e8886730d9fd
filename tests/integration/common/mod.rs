//! Helpers shared by the integration tests.
#![allow(
    dead_code,
    reason = "some helpers serve only the viewer tests, built with the viewer feature"
)]

use std::path::{Path, PathBuf};
use std::process::Command;

pub mod golden;

/// The project's root folder.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// `../shared/data/<relative>`, or a panic that says the test needs the shared data.
pub fn shared_data(relative: &str) -> PathBuf {
    let path = root().join("../shared/data").join(relative);
    assert!(
        path.exists(),
        "this test needs the shared data set at {} (see ../shared/data/README.md); it is always present in CI",
        path.display()
    );
    path
}

/// Runs the `iscene` binary; returns (exit code, stdout, stderr).
pub fn iscene(args: &[&str], cwd: &Path) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_iscene"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("run iscene");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `iscene simulate GT --task TASK --out OUT [--robot ROBOT]` from the project's root: exit
/// code, stdout, stderr.
pub fn simulate(gt: &Path, task: &Path, out: &Path, robot: Option<&Path>) -> (i32, String, String) {
    let mut args = vec![gt, Path::new("--task"), task, Path::new("--out"), out];
    if let Some(robot) = robot {
        args.extend([Path::new("--robot"), robot]);
    }
    let args: Vec<&str> = std::iter::once("simulate")
        .chain(args.iter().map(|a| a.to_str().expect("utf8")))
        .collect();
    iscene(&args, &root())
}

/// The scene specifications shipped in scenes/.
pub fn scene_specs() -> Vec<PathBuf> {
    let mut specs: Vec<PathBuf> = std::fs::read_dir(root().join("scenes"))
        .expect("scenes/")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    specs.sort();
    specs
}

/// SHA-256 of every file under `dir`, by relative path; an output folder's marker is left out,
/// since it records when each file was written.
pub fn hash_tree(dir: &Path) -> Vec<(String, String)> {
    listing(dir)
        .into_iter()
        .filter(|(name, hash)| hash != DIR && !name.ends_with(iscene::io::output_folder::MARKER))
        .collect()
}

/// What [`listing`] gives a folder instead of a hash.
const DIR: &str = "dir";

/// Every path under `dir` (symbolic links not followed) with the SHA-256 of its content, `dir`
/// for a folder or `link` for a link, sorted: what "nothing touched" compares.
pub fn listing(dir: &Path) -> Vec<(String, String)> {
    use sha2::Digest;
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d)
            .expect("read dir")
            .filter_map(Result::ok)
        {
            let p = entry.path();
            let name = p.strip_prefix(dir).expect("prefix").display().to_string();
            let meta = p.symlink_metadata().expect("metadata");
            let hash = if meta.is_dir() {
                stack.push(p);
                DIR.to_string()
            } else if meta.file_type().is_symlink() {
                "link".to_string()
            } else {
                let digest = sha2::Sha256::digest(std::fs::read(&p).expect("read file"));
                digest.iter().map(|b| format!("{b:02x}")).collect()
            };
            out.push((name, hash));
        }
    }
    out.sort();
    out
}

/// Renders `scenes/<scene>.json` through the CLI into `out`, as a user would.
pub fn render_scene(scene: &str, out: &Path, frames: usize, no_noise: bool) {
    let spec = root().join("scenes").join(format!("{scene}.json"));
    let frames = frames.to_string();
    let mut args = vec![
        "render",
        spec.to_str().expect("utf8"),
        "--out",
        out.to_str().expect("utf8"),
        "--frames",
        &frames,
    ];
    if no_noise {
        args.push("--no-noise");
    }
    let (code, stdout, stderr) = iscene(&args, &root());
    assert_eq!(code, 0, "rendering {scene} failed: {stdout}{stderr}");
}

/// Renders `scene` (300 frames) into `dir` and reconstructs every second frame with the oracle
/// segmentation in `voxel` metres voxels; returns the sequence and output folders.
pub fn render_and_map_every_second_frame(
    scene: &str,
    dir: &Path,
    no_noise: bool,
    voxel: f32,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let seq = dir.join("seq");
    render_scene(scene, &seq, 300, no_noise);
    let out = dir.join("out");
    reconstruct_every_second_frame(&seq, &out, None, iscene::pipeline::AlignMethod::Lm, voxel);
    (seq, out)
}

/// Reconstructs every second frame of the rendered sequence `seq` into `out` with the oracle
/// segmentation at 2 cm, replacing objects from the CAD database folder `cad` when given.
pub fn map_every_second_frame(seq: &Path, out: &Path, cad: Option<PathBuf>) {
    map_every_second_frame_aligning(seq, out, cad, iscene::pipeline::AlignMethod::Lm);
}

/// [`map_every_second_frame`], its CAD candidates chosen and aligned by `align`.
pub fn map_every_second_frame_aligning(
    seq: &Path,
    out: &Path,
    cad: Option<PathBuf>,
    align: iscene::pipeline::AlignMethod,
) {
    reconstruct_every_second_frame(seq, out, cad, align, 0.02);
}

fn reconstruct_every_second_frame(
    seq: &Path,
    out: &Path,
    cad: Option<PathBuf>,
    align: iscene::pipeline::AlignMethod,
    voxel: f32,
) {
    iscene::pipeline::reconstruct(&iscene::pipeline::ReconstructOptions {
        frames: Some((0, None, 2)),
        voxel,
        cad,
        align,
        ..iscene::pipeline::ReconstructOptions::new(seq, out)
    })
    .expect("reconstruct");
}

/// `scene` rendered with realistic noise and reconstructed from every second frame (as
/// [`render_and_map_every_second_frame`]), once per test run: the contact-graph, CAD and export
/// tests each assert different things of the same reconstruction, and only read it. The folders
/// live under Cargo's temporary folder for integration tests and are redone by every run.
pub fn shared_noisy_map(scene: &str) -> (PathBuf, PathBuf) {
    use std::collections::BTreeMap;
    use std::sync::{Arc, Mutex, OnceLock};
    type Cell = Arc<OnceLock<(PathBuf, PathBuf)>>;
    static MAPS: Mutex<BTreeMap<String, Cell>> = Mutex::new(BTreeMap::new());
    let cell = MAPS
        .lock()
        .expect("shared maps")
        .entry(scene.to_string())
        .or_default()
        .clone();
    // The lock is released before the work: other scenes are mapped meanwhile, and a second test
    // asking for this scene waits in get_or_init.
    cell.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
            .join("noisy_maps")
            .join(scene);
        if dir.exists() {
            std::fs::remove_dir_all(&dir).expect("clear an earlier run's map");
        }
        std::fs::create_dir_all(&dir).expect("map folder");
        render_and_map_every_second_frame(scene, &dir, false, 0.02)
    })
    .clone()
}

/// The length of the plan pyperplan (A* with h_max) finds for `problem` of a `simulate`
/// output folder `out` with its `domain.pddl`, worked on copies in `work` (pyperplan writes
/// its solution beside the problem); a panic naming the problem when it finds none.
pub fn pyperplan_plan_length(out: &Path, problem: &str, work: &Path) -> usize {
    let python = validator(".venv-validators/bin/python");
    std::fs::create_dir_all(work).expect("dir");
    for f in ["domain.pddl", problem] {
        std::fs::copy(out.join(f), work.join(f)).expect("copy");
    }
    let run = std::process::Command::new(&python)
        .args(["-m", "pyperplan", "-s", "astar", "-H", "hmax"])
        .arg(work.join("domain.pddl"))
        .arg(work.join(problem))
        .output()
        .expect("pyperplan");
    let solution =
        std::fs::read_to_string(work.join(format!("{problem}.soln"))).unwrap_or_else(|_| {
            panic!(
                "pyperplan found no plan for {}: {}",
                out.join(problem).display(),
                String::from_utf8_lossy(&run.stderr)
            )
        });
    solution
        .lines()
        .filter(|l| l.trim().starts_with('('))
        .count()
}

/// A validator installed by scripts/setup-validators.sh, or a panic that says to run it.
pub fn validator(relative: &str) -> PathBuf {
    let path = root().join(relative);
    assert!(
        path.exists(),
        "{} is missing: run scripts/setup-validators.sh (the README's test command does)",
        path.display()
    );
    path
}

/// The Panda that scripts/setup-validators.sh installs with PyBullet.
pub fn panda_urdf() -> PathBuf {
    let lib = validator(".venv-validators/lib");
    let urdf = std::fs::read_dir(&lib)
        .expect("the validators' lib folder")
        .filter_map(Result::ok)
        .map(|e| {
            e.path()
                .join("site-packages/pybullet_data/franka_panda/panda.urdf")
        })
        .find(|p| p.is_file());
    urdf.unwrap_or_else(|| {
        panic!(
            "no pybullet_data/franka_panda/panda.urdf under {}: run scripts/setup-validators.sh",
            lib.display()
        )
    })
}

/// Runs a third-party tool in the temporary folder; returns (exit code, stdout, stderr).
pub fn run_tool(program: &Path, args: &[&Path]) -> (i32, String, String) {
    // MuJoCo writes MUJOCO_LOG.TXT into its working folder: keep it out of the checkout.
    let out = Command::new(program)
        .args(args)
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap_or_else(|e| panic!("running {}: {e}", program.display()));
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The last line of `stdout` that is a JSON object (the external scripts print one).
pub fn json_line(stdout: &str) -> serde_json::Value {
    let line = stdout
        .lines()
        .rev()
        .find(|l| l.starts_with('{'))
        .unwrap_or_else(|| panic!("no JSON in {stdout:?}"));
    serde_json::from_str(line).expect("JSON")
}
