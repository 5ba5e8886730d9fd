//! `iscene batch MANIFEST --out DIR --slurm`: writes a Slurm job array (one task per shard,
//! `SLURM_ARRAY_TASK_ID` picks the shard) and a merge job that waits for it, into `DIR/slurm/`,
//! and submits both with `sbatch`. The scripts stay there for a user to read, edit and resubmit.
//! The tasks run from `DIR/batch.json`, the manifest as resolved when the batch was submitted.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde::Serialize;

use super::manifest::{Manifest, Shard};
use super::resources::{Cost, TaskRequest, input_cost, task_request};
use super::run::unfinished;
use super::summary::summarise;
use crate::error::{InputError, IsceneError};

/// The most tasks of one array (Slurm's default `MaxArraySize` is 1001).
pub const MAX_SHARDS: usize = 1000;

/// What the user asks of the cluster; anything left out is derived from measured figures.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    pub partition: Option<String>,
    pub minutes: Option<u64>,
    pub memory_mb: Option<u64>,
    pub cpus: Option<usize>,
    /// Array tasks; default one per input.
    pub shards: Option<usize>,
    /// Submit only the shards that hold inputs not done yet.
    pub resume: bool,
}

/// What was submitted, also written to `DIR/slurm/jobs.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Submission {
    pub array_job: String,
    pub merge_job: String,
    /// The array's task ids (`0-5`, or the resumed shards `1,4`).
    pub array: String,
    pub shards: usize,
    pub inputs_to_run: usize,
    pub request: SubmittedRequest,
    pub scripts: [PathBuf; 2],
}

#[derive(Clone, Debug, Serialize)]
pub struct SubmittedRequest {
    pub cpus: usize,
    pub jobs: usize,
    pub memory_mb: u64,
    pub minutes: u64,
    /// Where the figures came from: this batch's finished inputs, or the reference machine.
    pub figures: String,
}

/// Writes the scripts for the batch in `dir` (claimed, with `batch.json`) and submits them.
/// Returns `None` when every input is done already (nothing is submitted; the summary is merged).
pub fn submit(
    dir: &Path,
    manifest: &Manifest,
    executable: &Path,
    options: &SlurmOptions,
) -> Result<Option<Submission>, IsceneError> {
    let shards = options
        .shards
        .unwrap_or(manifest.inputs.len())
        .clamp(1, MAX_SHARDS.min(manifest.inputs.len()));
    let pending = unfinished(dir, manifest);
    if pending.is_empty() {
        return Ok(None);
    }
    // Resuming submits only the shards that hold an unfinished input; their finished inputs
    // are skipped by the tasks themselves.
    let shard = |index| Shard {
        index,
        count: shards,
    };
    let tasks: Vec<usize> = (0..shards)
        .filter(|&i| !options.resume || pending.iter().any(|&k| shard(i).holds(k)))
        .collect();
    // Sized for the task with the most work left: its unfinished inputs (the others it skips).
    let measured = summarise(dir, manifest).cost;
    let cpus = options.cpus.unwrap_or(2).max(1);
    let jobs = (cpus / 2).max(1);
    let total = |costs: &Vec<Cost>| costs.iter().map(|c| c.seconds).sum::<f64>();
    let largest_share = tasks
        .iter()
        .map(|&i| {
            pending
                .iter()
                .filter(|&&k| shard(i).holds(k))
                .map(|&k| input_cost(&manifest.inputs[k], measured.as_ref()))
                .collect::<Vec<_>>()
        })
        .max_by(|a, b| total(a).total_cmp(&total(b)))
        .unwrap_or_default();
    let derived = task_request(&largest_share, cpus, jobs);
    let request = TaskRequest {
        memory_mb: options.memory_mb.unwrap_or(derived.memory_mb),
        minutes: options.minutes.unwrap_or(derived.minutes),
        ..derived
    };
    let slurm_dir = dir.join("slurm");
    std::fs::create_dir_all(&slurm_dir)
        .map_err(|e| IsceneError::io(format!("creating {}", slurm_dir.display()), e))?;
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (dir_abs, exe_abs) = (absolute(dir), absolute(executable));
    let array = array_ids(&tasks);
    let shard_script = slurm_dir.join("shards.sbatch");
    let merge_script = slurm_dir.join("merge.sbatch");
    write_script(
        &shard_script,
        &shards_script(
            &exe_abs,
            &dir_abs,
            shards,
            &array,
            &request,
            options.partition.as_deref(),
        ),
    )?;
    write_script(
        &merge_script,
        &merge_script_text(&exe_abs, &dir_abs, options.partition.as_deref()),
    )?;
    let array_job = sbatch(&[format!("--array={array}")], &shard_script)?;
    let merge_job = sbatch(
        &[format!("--dependency=afterany:{array_job}")],
        &merge_script,
    )?;
    let submission = Submission {
        array_job,
        merge_job,
        array,
        shards,
        inputs_to_run: pending.len(),
        request: SubmittedRequest {
            cpus: request.cpus,
            jobs: request.jobs,
            memory_mb: request.memory_mb,
            minutes: request.minutes,
            figures: match &measured {
                Some(m) => format!("this batch's {} finished inputs", m.inputs),
                None => "the reference machine (README, Batches and clusters)".into(),
            },
        },
        scripts: [shard_script, merge_script],
    };
    let record = slurm_dir.join("jobs.json");
    std::fs::write(
        &record,
        serde_json::to_string_pretty(&submission).unwrap_or_default() + "\n",
    )
    .map_err(|e| IsceneError::io(format!("writing {}", record.display()), e))?;
    Ok(Some(submission))
}

/// Slurm's array syntax for `tasks`: ranges where they are consecutive (`0-3,7,9-10`).
fn array_ids(tasks: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut k = 0;
    while k < tasks.len() {
        let start = tasks[k];
        let mut end = start;
        while k + 1 < tasks.len() && tasks[k + 1] == end + 1 {
            k += 1;
            end = tasks[k];
        }
        parts.push(if end > start {
            format!("{start}-{end}")
        } else {
            start.to_string()
        });
        k += 1;
    }
    parts.join(",")
}

/// Single-quoted for the shell.
fn quoted(path: &Path) -> String {
    format!("'{}'", path.display().to_string().replace('\'', "'\\''"))
}

fn shards_script(
    executable: &Path,
    dir: &Path,
    shards: usize,
    array: &str,
    request: &TaskRequest,
    partition: Option<&str>,
) -> String {
    let mut text = format!(
        "#!/bin/bash\n\
         # Written by `iscene batch --slurm`: one array task per shard of {shards}; task I runs\n\
         # inputs I, I+{shards}, I+2*{shards}, ... of {dir}/batch.json and skips the ones done.\n\
         # Resubmit after editing with: sbatch --array={array} {script}\n\
         #SBATCH --job-name=iscene-batch\n\
         #SBATCH --array={array}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         #SBATCH --mem={mem}M\n\
         #SBATCH --time={hours:02}:{minutes:02}:00\n\
         #SBATCH --output={dir}/slurm/shard-%a.out\n",
        dir = dir.display(),
        script = dir.join("slurm/shards.sbatch").display(),
        cpus = request.cpus,
        mem = request.memory_mb,
        hours = request.minutes / 60,
        minutes = request.minutes % 60,
    );
    if let Some(p) = partition {
        text += &format!("#SBATCH --partition={p}\n");
    }
    text += &format!(
        "set -euo pipefail\n\
         exec {exe} batch --out {dir} --shard \"${{SLURM_ARRAY_TASK_ID}}/{shards}\" --jobs {jobs}\n",
        exe = quoted(executable),
        dir = quoted(dir),
        jobs = request.jobs,
    );
    text
}

fn merge_script_text(executable: &Path, dir: &Path, partition: Option<&str>) -> String {
    let mut text = format!(
        "#!/bin/bash\n\
         # Written by `iscene batch --slurm`: merges the shards' results into {dir}/summary.json\n\
         # once every array task has ended (done or not; failures are listed).\n\
         #SBATCH --job-name=iscene-merge\n\
         #SBATCH --cpus-per-task=1\n\
         #SBATCH --mem=500M\n\
         #SBATCH --time=00:10:00\n\
         #SBATCH --output={dir}/slurm/merge.out\n",
        dir = dir.display()
    );
    if let Some(p) = partition {
        text += &format!("#SBATCH --partition={p}\n");
    }
    text += &format!(
        "set -euo pipefail\nexec {} batch merge {}\n",
        quoted(executable),
        quoted(dir)
    );
    text
}

fn write_script(path: &Path, text: &str) -> Result<(), IsceneError> {
    std::fs::write(path, text)
        .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
}

/// Submits `script` with `sbatch --parsable`, returning the job id.
fn sbatch(arguments: &[String], script: &Path) -> Result<String, IsceneError> {
    let output = Command::new("sbatch")
        .arg("--parsable")
        .args(arguments)
        .arg(script)
        .output()
        .map_err(|e| {
            InputError::missing(
                "sbatch",
                format!(
                    "cannot run sbatch ({e}): --slurm needs a Slurm login node; the scripts are in {} to submit by hand",
                    script.parent().map_or_else(String::new, |p| p.display().to_string())
                ),
            )
        })?;
    if !output.status.success() {
        return Err(InputError::invalid(
            script,
            format!(
                "sbatch refused it: {}",
                String::from_utf8_lossy(&output.stderr).trim()
            ),
        )
        .into());
    }
    let text = String::from_utf8_lossy(&output.stdout);
    // `--parsable` prints "id" or "id;cluster".
    let id = text
        .trim()
        .split(';')
        .next()
        .unwrap_or_default()
        .to_string();
    if id.is_empty() || !id.chars().all(|c| c.is_ascii_digit()) {
        return Err(IsceneError::Internal(format!(
            "sbatch printed no job id: {text:?}"
        )));
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn consecutive_tasks_become_ranges() {
        assert_eq!(array_ids(&[0, 1, 2, 3]), "0-3");
        assert_eq!(array_ids(&[1, 4, 5, 9]), "1,4-5,9");
        assert_eq!(array_ids(&[7]), "7");
    }

    #[test]
    fn the_array_script_runs_its_shard_with_the_request() {
        let request = TaskRequest {
            cpus: 4,
            jobs: 2,
            memory_mb: 2700,
            minutes: 75,
        };
        let text = shards_script(
            Path::new("/opt/iscene"),
            Path::new("/scratch/it's"),
            6,
            "0-5",
            &request,
            Some("gpu"),
        );
        for line in [
            "#SBATCH --array=0-5",
            "#SBATCH --cpus-per-task=4",
            "#SBATCH --mem=2700M",
            "#SBATCH --time=01:15:00",
            "#SBATCH --partition=gpu",
            "exec '/opt/iscene' batch --out '/scratch/it'\\''s' --shard \"${SLURM_ARRAY_TASK_ID}/6\" --jobs 2",
        ] {
            assert!(text.contains(line), "{line} in\n{text}");
        }
        assert!(text.starts_with("#!/bin/bash\n"));
        let merge = merge_script_text(Path::new("/opt/iscene"), Path::new("/d"), None);
        assert!(
            merge.contains("exec '/opt/iscene' batch merge '/d'"),
            "{merge}"
        );
        assert!(!merge.contains("partition"));
    }
}
