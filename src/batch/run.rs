//! Running a shard of a batch: each input of the shard's share in a process of its own (so that a
//! crash or an out-of-memory kill of one input is recorded as its failure, and its peak memory is
//! its own), skipping the inputs a status record already marks done.

use std::io::{BufRead, BufReader, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::manifest::{BatchInput, InputSource, Manifest, Shard};
use super::status::{InputStatus, State, peak_memory_mb, read_status, status_path, write_status};
use crate::error::{InputError, IsceneError};
use crate::pipeline::{ReconstructOptions, reconstruct};
use crate::render::noise::NoiseChoice;
use crate::scene::SceneSpec;
use crate::scene::generate::{GenerateOptions, RoomStyle, generate, write_generated};
use crate::scene::{RenderOptions, render_sequence};

/// The file that marks a folder as a batch's and holds its resolved manifest.
pub const BATCH_FILE: &str = "batch.json";
/// The marker of a benchmark folder written before benchmarks ran on batches.
const OLD_BENCHMARK_MARKER: &str = "benchmark.json";
/// An input's log (its process's standard output and error), in its folder.
pub const LOG_FILE: &str = "log.txt";
/// Lines of a killed input's log that its status record quotes.
const LOG_LINES_QUOTED: usize = 5;

/// `batch.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BatchFile {
    pub written_by: String,
    pub manifest: Manifest,
}

/// How to run a shard.
#[derive(Clone, Debug)]
pub struct ShardOptions {
    pub out: PathBuf,
    pub shard: Shard,
    /// Inputs at once; `None`: what the cores and the memory allow.
    pub jobs: Option<usize>,
    /// The `iscene` executable that runs each input (`iscene batch --run-input`).
    pub executable: PathBuf,
    /// A line on standard error per finished input.
    pub report: bool,
}

/// What a shard did.
#[derive(Clone, Debug, Default)]
pub struct ShardReport {
    pub shard: String,
    /// Inputs of the share finished by an earlier run.
    pub skipped: usize,
    pub done: usize,
    /// Names and errors.
    pub failed: Vec<(String, String)>,
}

/// Claims `out` for a batch of `manifest` and records the manifest in it. `out` must be new,
/// empty, or an earlier batch or benchmark folder: nothing else is written into. Shards that
/// start together all write the same `batch.json`, each whole (a rename).
pub fn claim_folder(out: &Path, manifest: &Manifest) -> Result<(), IsceneError> {
    let inputs: Vec<&Path> = manifest.inputs.iter().flat_map(BatchInput::paths).collect();
    if let Some(why) = crate::io::output_folder::input_clash(out, &inputs) {
        return Err(InputError::invalid(out, format!("--out {why}; nothing was written")).into());
    }
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(InputError::invalid(out, "--out is a symbolic link; name a folder").into());
    }
    if out.exists() {
        if !out.is_dir() {
            return Err(InputError::invalid(out, "--out is a file; name a folder").into());
        }
        // Shards started together (pods of an Indexed Job) claim the folder at once: another
        // shard's batch.json on its way in counts as the batch's own.
        let partial = format!(".{BATCH_FILE}.");
        let foreign = std::fs::read_dir(out)
            .map_err(|e| InputError::io(out, &e))?
            .flatten()
            .any(|e| !e.file_name().to_string_lossy().starts_with(&partial));
        if foreign && !out.join(BATCH_FILE).is_file() && !out.join(OLD_BENCHMARK_MARKER).is_file() {
            return Err(InputError::invalid(
                out,
                "--out is a folder iscene batch or benchmark did not write; it is left alone (choose a new or empty folder)",
            )
            .into());
        }
    }
    std::fs::create_dir_all(out)
        .map_err(|e| IsceneError::io(format!("creating {}", out.display()), e))?;
    let file = BatchFile {
        written_by: "iscene batch".into(),
        manifest: manifest.clone(),
    };
    let text = serde_json::to_string_pretty(&file)
        .map_err(|e| IsceneError::Internal(format!("batch JSON: {e}")))?;
    let path = out.join(BATCH_FILE);
    // Unique among shards on other machines and in containers, where process ids repeat.
    let unique = format!(
        "{}.{}.{}",
        super::status::host_name(),
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos())
    );
    let temporary = out.join(format!(".{BATCH_FILE}.{unique}.partial"));
    std::fs::write(&temporary, text + "\n")
        .and_then(|()| std::fs::rename(&temporary, &path))
        .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
}

/// The resolved manifest a batch folder holds.
pub fn read_batch(dir: &Path) -> Result<Manifest, IsceneError> {
    let path = dir.join(BATCH_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        InputError::missing(
            &path,
            format!("not a batch folder (iscene batch writes {BATCH_FILE}): {e}"),
        )
    })?;
    let file: BatchFile = serde_json::from_str(&text)
        .map_err(|e| InputError::invalid(&path, format!("not a batch file: {e}")))?;
    Ok(file.manifest)
}

/// The names of the inputs a status record does not mark done.
pub fn unfinished(dir: &Path, manifest: &Manifest) -> Vec<usize> {
    (0..manifest.inputs.len())
        .filter(|&k| {
            let input = &manifest.inputs[k];
            !read_status(dir, &input.name).is_some_and(|s| s.finishes(input))
        })
        .collect()
}

/// Runs the share of `options.shard` of the batch whose folder `claim_folder` prepared.
pub fn run_shard(manifest: &Manifest, options: &ShardOptions) -> Result<ShardReport, IsceneError> {
    let share = manifest.share(options.shard);
    let jobs = options
        .jobs
        .unwrap_or_else(default_jobs)
        .clamp(1, share.len().max(1));
    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let report = Mutex::new(ShardReport {
        shard: options.shard.to_string(),
        ..ShardReport::default()
    });
    let first_error: Mutex<Option<IsceneError>> = Mutex::new(None);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                while let Some(&k) = share.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let input = &manifest.inputs[k];
                    if read_status(&options.out, &input.name).is_some_and(|s| s.finishes(input)) {
                        if let Ok(mut r) = report.lock() {
                            r.skipped += 1;
                        }
                        finished.fetch_add(1, Ordering::Relaxed);
                        continue;
                    }
                    match run_in_process_of_its_own(input, options) {
                        Ok(status) => {
                            let n = finished.fetch_add(1, Ordering::Relaxed) + 1;
                            if options.report {
                                eprintln!(
                                    "[{n}/{}] shard {}: {}",
                                    share.len(),
                                    options.shard,
                                    describe(&status)
                                );
                            }
                            if let Ok(mut r) = report.lock() {
                                match status.error {
                                    None => r.done += 1,
                                    Some(e) => r.failed.push((status.name, e)),
                                }
                            }
                        }
                        Err(e) => {
                            // The batch folder itself cannot be written: stop this worker.
                            if let Ok(mut slot) = first_error.lock() {
                                slot.get_or_insert(e);
                            }
                            break;
                        }
                    }
                }
            });
        }
    });
    if let Some(e) = first_error.into_inner().ok().flatten() {
        return Err(e);
    }
    let mut report = report
        .into_inner()
        .map_err(|_| IsceneError::Internal("a shard's worker panicked".into()))?;
    report.failed.sort();
    Ok(report)
}

fn describe(status: &InputStatus) -> String {
    let figures = format!(
        "{:.1} s, {:.0} MB",
        status.seconds.unwrap_or(0.0),
        status.peak_memory_mb.unwrap_or(0.0)
    );
    match &status.error {
        None => format!("{} done in {figures}", status.name),
        Some(e) => format!("{} FAILED after {figures}: {e}", status.name),
    }
}

/// Prepares the input's folder, runs `iscene batch --run-input` on it and returns its final
/// status record, which the parent writes itself when the process died before writing it.
fn run_in_process_of_its_own(
    input: &BatchInput,
    options: &ShardOptions,
) -> Result<InputStatus, IsceneError> {
    let folder = options.out.join(&input.name);
    if std::fs::symlink_metadata(&folder).is_ok() {
        // Unfinished, failed or made with other options; only this batch's inputs are here.
        std::fs::remove_dir_all(&folder)
            .or_else(|_| std::fs::remove_file(&folder))
            .map_err(|e| IsceneError::io(format!("clearing {}", folder.display()), e))?;
    }
    std::fs::create_dir_all(&folder)
        .map_err(|e| IsceneError::io(format!("creating {}", folder.display()), e))?;
    let started = InputStatus::started(input, &options.shard.to_string());
    write_status(&options.out, &started)?;
    let log_path = folder.join(LOG_FILE);
    let log = std::fs::File::create(&log_path)
        .map_err(|e| IsceneError::io(format!("creating {}", log_path.display()), e))?;
    let log_err = log
        .try_clone()
        .map_err(|e| IsceneError::io(format!("opening {}", log_path.display()), e))?;
    let exit = Command::new(&options.executable)
        .arg("batch")
        .arg("--run-input")
        .arg(&input.name)
        .arg("--out")
        .arg(&options.out)
        .stdin(Stdio::null())
        .stdout(log)
        .stderr(log_err)
        .status()
        .map_err(|e| {
            IsceneError::io(
                format!(
                    "starting {} for {}",
                    options.executable.display(),
                    input.name
                ),
                e,
            )
        })?;
    match read_status(&options.out, &input.name) {
        Some(status) if status.state != State::Running => Ok(status),
        _ => {
            let status = started.finished(
                Some(format!(
                    "its process ended ({exit}) before it finished (killed, out of memory?); the end of {}: {}",
                    log_path.display(),
                    log_tail(&log_path)
                )),
                false,
            );
            write_status(&options.out, &status)?;
            Ok(status)
        }
    }
}

fn log_tail(path: &Path) -> String {
    let Ok(mut file) = std::fs::File::open(path) else {
        return String::new();
    };
    let length = file.metadata().map_or(0, |m| m.len());
    let _ = file.seek(SeekFrom::Start(length.saturating_sub(4096)));
    let lines: Vec<String> = BufReader::new(file).lines().map_while(Result::ok).collect();
    lines[lines.len().saturating_sub(LOG_LINES_QUOTED)..].join(" | ")
}

/// `iscene batch --run-input NAME --out DIR`: runs one input of a prepared batch folder in this
/// process and writes its final status record (done or failed, with this process's peak memory).
pub fn run_one(dir: &Path, name: &str) -> Result<(), IsceneError> {
    let manifest = read_batch(dir)?;
    let input = manifest
        .inputs
        .iter()
        .find(|i| i.name == name)
        .ok_or_else(|| InputError::invalid(dir.join(BATCH_FILE), format!("no input {name:?}")))?;
    let started = read_status(dir, name)
        .filter(|s| s.state == State::Running && &s.input == input)
        .ok_or_else(|| {
            InputError::invalid(
                status_path(dir, name),
                "the input was not started by a shard (run `iscene batch MANIFEST --out DIR`)",
            )
        })?;
    let result = run_input(input, &dir.join(name));
    let (error, evaluated) = match &result {
        Ok(evaluated) => (None, *evaluated),
        Err(e) => (Some(e.to_string()), false),
    };
    let mut status = started.finished(error, evaluated);
    status.peak_memory_mb = peak_memory_mb();
    write_status(dir, &status)?;
    result.map(|_| ())
}

/// Renders (when needed), reconstructs and scores one input into `folder`; whether it was scored.
pub fn run_input(input: &BatchInput, folder: &Path) -> Result<bool, IsceneError> {
    let rendered = folder.join("sequence");
    let render = |spec_path: &Path, frames: Option<usize>| -> Result<(), IsceneError> {
        let spec = SceneSpec::load(spec_path)?;
        render_sequence(
            &spec,
            spec_path,
            &rendered,
            &RenderOptions {
                frames,
                no_noise: false,
                progress: false,
                force: false,
                fingerprint: None,
            },
        )?;
        Ok(())
    };
    let (sequence, frames) = match &input.source {
        InputSource::Seed { seed, style, noise } => {
            let spec_path = folder.join("spec.json");
            let parse_style = |s: &str| clap::ValueEnum::from_str(s, false).ok();
            let style: RoomStyle = parse_style(style).unwrap_or(RoomStyle::Any);
            let noise: NoiseChoice =
                clap::ValueEnum::from_str(noise, false).unwrap_or(NoiseChoice::Realistic);
            let generated = generate(
                &GenerateOptions {
                    seed: *seed,
                    style,
                    cad: input.cad.iter().cloned().collect(),
                    noise,
                    frames: input.frames.unwrap_or(300),
                },
                &spec_path,
            )?;
            write_generated(&spec_path, &generated.json)?;
            render(&spec_path, None)?;
            (rendered.clone(), None)
        }
        InputSource::Spec { spec } => {
            render(spec, input.frames)?;
            (rendered.clone(), None)
        }
        InputSource::Sequence { sequence } => {
            (sequence.clone(), input.frames.map(|n| (0, Some(n), 1)))
        }
    };
    let reconstruction = folder.join("reconstruction");
    reconstruct(&ReconstructOptions {
        frames,
        voxel: input.voxel,
        segmentation: input.segmentation_choice(),
        cad: input.searched_cad(),
        ..ReconstructOptions::new(&sequence, &reconstruction)
    })?;
    if !input.evaluate || !sequence.join("labels.json").is_file() {
        return Ok(false);
    }
    let report = crate::eval::evaluate_reconstruction(&reconstruction, &sequence)?;
    let mut eval: Value = serde_json::to_value(&report)
        .map_err(|e| IsceneError::Internal(format!("eval JSON: {e}")))?;
    if let Some(robot) = &input.robot
        && let Some(trial) = crate::simulation::pick_and_place_trial(
            &reconstruction,
            robot,
            &folder.join("pick_place"),
        )?
    {
        eval["pick_place_success"] = serde_json::json!(if trial.success { 1.0 } else { 0.0 });
        eval["pick_place_seconds"] = serde_json::json!(trial.seconds);
    }
    let path = folder.join("eval.json");
    std::fs::write(
        &path,
        serde_json::to_string_pretty(&eval).unwrap_or_default() + "\n",
    )
    .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))?;
    Ok(true)
}

/// One input per 2 cores (each reconstruction is parallel itself), as memory allows.
fn default_jobs() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let memory_gb = crate::base::process::available_memory_bytes().map_or(8.0, |b| b as f64 / 1e9);
    (cores / 2)
        .min((memory_gb / super::resources::INPUT_MEMORY_BUDGET_GB) as usize)
        .max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn manifest() -> Manifest {
        let value = serde_json::json!({"inputs": [{"seeds": "0:3", "frames": 10}]});
        Manifest::from_value(&value, Path::new(".")).expect("manifest")
    }

    #[test]
    fn an_input_whose_process_dies_is_recorded_failed_and_the_shard_goes_on() {
        let dir = tempfile::tempdir().expect("tempdir");
        let out = dir.path().join("batch");
        let manifest = manifest();
        claim_folder(&out, &manifest).expect("claim");
        // `false` exits 1 without writing a status record, as a process killed mid-way does.
        let report = run_shard(
            &manifest,
            &ShardOptions {
                out: out.clone(),
                shard: Shard { index: 1, count: 2 },
                jobs: Some(1),
                executable: PathBuf::from("false"),
                report: false,
            },
        )
        .expect("shard");
        assert_eq!(report.failed.len(), 1, "{report:?}");
        let status = read_status(&out, "seed_1").expect("status");
        assert_eq!(status.state, State::Failed);
        assert!(
            status
                .error
                .as_deref()
                .is_some_and(|e| e.contains("before it finished")),
            "{status:?}"
        );
        // Shard 1 of 2 holds input 1 only; the others were not touched.
        assert!(read_status(&out, "seed_0").is_none() && read_status(&out, "seed_2").is_none());
        assert_eq!(unfinished(&out, &manifest), [0, 1, 2]);
    }

    #[test]
    fn a_folder_iscene_did_not_write_or_an_input_is_refused() {
        let dir = tempfile::tempdir().expect("tempdir");
        let mine = dir.path().join("mine");
        std::fs::create_dir(&mine).expect("mkdir");
        std::fs::write(mine.join("thesis.tex"), "x").expect("write");
        assert!(claim_folder(&mine, &manifest()).is_err());
        assert_eq!(std::fs::read_dir(&mine).expect("list").count(), 1);
        let sequence = dir.path().join("seq");
        std::fs::create_dir(&sequence).expect("mkdir");
        let value = serde_json::json!({"inputs": [{"sequence": "seq"}]});
        let with_input = Manifest::from_value(&value, dir.path()).expect("manifest");
        for out in [
            sequence.clone(),
            dir.path().to_path_buf(),
            sequence.join("out"),
        ] {
            let err = claim_folder(&out, &with_input).expect_err("refused");
            assert!(err.to_string().contains("input"), "{err}");
        }
        claim_folder(&dir.path().join("new"), &with_input).expect("a new folder");
        assert!(read_batch(&dir.path().join("new")).is_ok_and(|m| m == with_input));
    }
}
