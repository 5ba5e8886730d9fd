//! `iscene batch merge DIR`: one summary of a batch folder from its inputs' status records and
//! `eval.json` files, whichever shards and machines wrote them: every numeric key of `iscene eval`
//! over the scored inputs (mean, median, worst, the worst inputs), the failures, the inputs not
//! run yet, and the time and memory per input (what `--slurm` sizes its requests from).

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;
use serde_json::Value;

use super::manifest::{BenchmarkInfo, Manifest};
use super::run::read_batch;
use super::status::{State, read_status};
use crate::error::IsceneError;

/// How many worst inputs the summary lists per metric.
const WORST_INPUTS: usize = 5;

/// Mean, median and worst of one metric over the inputs that report it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MetricSummary {
    pub mean: f64,
    pub median: f64,
    pub worst: f64,
    /// Inputs that report the metric (others have it null).
    pub rooms: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorstInput {
    pub input: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    pub metric: String,
    pub value: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FailedInput {
    pub input: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    pub error: String,
}

/// Time and peak memory per finished input, from the status records.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct InputCost {
    pub inputs: usize,
    pub seconds_mean: f64,
    pub seconds_max: f64,
    pub peak_memory_mb_mean: f64,
    pub peak_memory_mb_max: f64,
}

/// `summary.json` of a batch or benchmark folder.
#[derive(Clone, Debug, Serialize)]
pub struct BatchSummary {
    /// Scored inputs.
    pub rooms: usize,
    pub metrics: BTreeMap<String, MetricSummary>,
    pub worst_rooms: Vec<WorstInput>,
    /// Inputs that failed, with the error (a failure is a finding, not a reason to stop).
    pub failed: Vec<FailedInput>,
    /// Inputs of the manifest with no finished record: not run yet, still running, or killed.
    pub missing: Vec<String>,
    /// Finished inputs that were not scored (no truth, or `"evaluate": false`).
    pub unscored: Vec<String>,
    pub cost: Option<InputCost>,
    /// Wall-clock seconds from the first input's start to the last one's end, and summed over
    /// every input's own run.
    pub seconds: f64,
    pub room_seconds: f64,
    #[serde(flatten)]
    pub benchmark: Option<BenchmarkInfo>,
    #[serde(skip)]
    pub dir: PathBuf,
}

/// Whether a larger value of `metric` is better (accuracies, qualities, fractions) or a smaller
/// one (distances, errors, edit costs, penetrations).
pub fn higher_is_better(metric: &str) -> bool {
    let lower = [
        "ged",
        "error",
        "chamfer",
        "penetration",
        "residual",
        "void_voxels",
        "distance",
        "seconds",
    ];
    !lower.iter().any(|w| metric.contains(w))
}

/// Reads the batch folder `dir` and writes `summary.json`, `summary.csv` and `summary.md` in it.
pub fn merge(dir: &Path) -> Result<BatchSummary, IsceneError> {
    let manifest = read_batch(dir)?;
    let summary = summarise(dir, &manifest);
    write_summary(dir, &summary)?;
    Ok(summary)
}

/// The summary of `manifest`'s inputs as their records in `dir` stand.
pub fn summarise(dir: &Path, manifest: &Manifest) -> BatchSummary {
    let mut values: BTreeMap<String, Vec<(usize, f64)>> = BTreeMap::new();
    let mut failed = Vec::new();
    let mut missing = Vec::new();
    let mut unscored = Vec::new();
    let mut seconds = Vec::new();
    let mut memory = Vec::new();
    let (mut first_start, mut last_end) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut rooms = 0;
    for (k, input) in manifest.inputs.iter().enumerate() {
        let status = read_status(dir, &input.name).filter(|s| s.input == *input);
        let Some(status) = status.filter(|s| s.state != State::Running) else {
            missing.push(input.name.clone());
            continue;
        };
        first_start = first_start.min(status.started_at);
        last_end = last_end.max(status.finished_at.unwrap_or(status.started_at));
        if status.state == State::Failed {
            failed.push(FailedInput {
                input: input.name.clone(),
                seed: input.seed(),
                error: status.error.unwrap_or_default(),
            });
            continue;
        }
        seconds.push(status.seconds.unwrap_or(0.0));
        memory.extend(status.peak_memory_mb);
        let eval = std::fs::read_to_string(dir.join(&input.name).join("eval.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<Value>(&t).ok());
        let Some(eval) = eval.filter(|_| status.evaluated) else {
            unscored.push(input.name.clone());
            continue;
        };
        rooms += 1;
        for (key, value) in eval.as_object().into_iter().flatten() {
            if let Some(v) = value.as_f64() {
                values.entry(key.clone()).or_default().push((k, v));
            }
        }
    }
    let mut metrics = BTreeMap::new();
    let mut worst_rooms = Vec::new();
    for (key, mut list) in values {
        let higher = higher_is_better(&key);
        // Worst first; ties in manifest order.
        list.sort_by(|a, b| {
            let order = a.1.total_cmp(&b.1);
            if higher { order } else { order.reverse() }
        });
        let mut sorted: Vec<f64> = list.iter().map(|(_, v)| *v).collect();
        sorted.sort_by(f64::total_cmp);
        metrics.insert(
            key.clone(),
            MetricSummary {
                mean: mean(&sorted),
                median: median(&sorted),
                worst: list[0].1,
                rooms: sorted.len(),
            },
        );
        worst_rooms.extend(
            list.iter()
                .take(WORST_INPUTS)
                .map(|&(k, value)| WorstInput {
                    input: manifest.inputs[k].name.clone(),
                    seed: manifest.inputs[k].seed(),
                    metric: key.clone(),
                    value,
                }),
        );
    }
    let cost = (!seconds.is_empty()).then(|| InputCost {
        inputs: seconds.len(),
        seconds_mean: mean(&seconds),
        seconds_max: seconds.iter().copied().fold(0.0, f64::max),
        peak_memory_mb_mean: mean(&memory),
        peak_memory_mb_max: memory.iter().copied().fold(0.0, f64::max),
    });
    BatchSummary {
        rooms,
        metrics,
        worst_rooms,
        failed,
        missing,
        unscored,
        room_seconds: seconds.iter().sum(),
        cost,
        seconds: if last_end >= first_start {
            last_end - first_start
        } else {
            0.0
        },
        benchmark: manifest.benchmark.clone(),
        dir: dir.to_path_buf(),
    }
}

fn mean(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.iter().sum::<f64>() / values.len() as f64
}

/// The median of sorted `values`.
fn median(sorted: &[f64]) -> f64 {
    let n = sorted.len();
    match n {
        0 => 0.0,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
    }
}

fn write_summary(out: &Path, summary: &BatchSummary) -> Result<(), IsceneError> {
    let write = |name: &str, text: String| {
        let path = out.join(name);
        let temporary = out.join(format!(".{name}.{}.partial", std::process::id()));
        std::fs::write(&temporary, text)
            .and_then(|()| std::fs::rename(&temporary, &path))
            .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
    };
    write(
        "summary.json",
        serde_json::to_string_pretty(summary).unwrap_or_default() + "\n",
    )?;
    let mut csv = String::from("metric,mean,median,worst,rooms\n");
    for (key, m) in &summary.metrics {
        csv += &format!("{key},{},{},{},{}\n", m.mean, m.median, m.worst, m.rooms);
    }
    write("summary.csv", csv)?;
    write("summary.md", summary.to_string() + "\n")
}

impl fmt::Display for BatchSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.benchmark {
            Some(b) => {
                writeln!(
                    f,
                    "# Benchmark: seeds {}:{}, {} rooms, style {}, noise {}, {} frames",
                    b.seeds[0], b.seeds[1], self.rooms, b.style, b.noise, b.frames
                )?;
                writeln!(
                    f,
                    "\nReproduce: `iscene benchmark --seeds {}:{} --style {} --noise {} --frames {} --out {}`.",
                    b.seeds[0],
                    b.seeds[1],
                    b.style,
                    b.noise,
                    b.frames,
                    self.dir.display(),
                )?;
            }
            None => writeln!(
                f,
                "# Batch {}: {} inputs scored",
                self.dir.display(),
                self.rooms
            )?,
        }
        writeln!(
            f,
            "\n{:.0} s wall clock, {:.0} s summed over inputs.",
            self.seconds, self.room_seconds
        )?;
        if let Some(c) = &self.cost {
            writeln!(
                f,
                "Per input ({} finished): {:.1} s mean, {:.1} s max; peak memory {:.0} MB mean, {:.0} MB max.",
                c.inputs,
                c.seconds_mean,
                c.seconds_max,
                c.peak_memory_mb_mean,
                c.peak_memory_mb_max
            )?;
        }
        writeln!(
            f,
            "\n| metric | mean | median | worst | rooms | worst inputs |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for (key, m) in &self.metrics {
            let worst: Vec<String> = self
                .worst_rooms
                .iter()
                .filter(|w| &w.metric == key)
                .map(|w| w.seed.map_or_else(|| w.input.clone(), |s| s.to_string()))
                .collect();
            writeln!(
                f,
                "| {key} | {:.4} | {:.4} | {:.4} | {} | {} |",
                m.mean,
                m.median,
                m.worst,
                m.rooms,
                worst.join(", ")
            )?;
        }
        for failure in &self.failed {
            writeln!(f, "\n{} failed: {}", failure.input, failure.error)?;
        }
        if !self.missing.is_empty() {
            writeln!(
                f,
                "\nNot finished ({}): {}; `iscene batch MANIFEST --out DIR --resume` runs them.",
                self.missing.len(),
                self.missing.join(", ")
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::manifest::Manifest;
    use crate::batch::run::claim_folder;
    use crate::batch::status::{InputStatus, write_status};

    #[test]
    fn the_worst_is_the_lowest_quality_and_the_highest_error() {
        assert!(higher_is_better("pq"));
        assert!(higher_is_better("stable_fraction"));
        assert!(higher_is_better("articulation_f1"));
        assert!(!higher_is_better("ged_positional"));
        assert!(!higher_is_better("cad_chamfer_m"));
        assert!(!higher_is_better("fit_residual_m"));
        assert!(!higher_is_better("max_penetration_m"));
    }

    /// A batch folder of four seeds: two scored, one failed, one never run.
    fn folder() -> (tempfile::TempDir, Manifest) {
        let dir = tempfile::tempdir().expect("tempdir");
        let manifest = Manifest::from_value(
            &serde_json::json!({"inputs": [{"seeds": "0:4", "frames": 10}]}),
            Path::new("."),
        )
        .expect("manifest");
        claim_folder(dir.path(), &manifest).expect("claim");
        for (k, outcome) in [(0, Some(0.9)), (1, Some(0.6)), (2, None)] {
            let input = &manifest.inputs[k];
            std::fs::create_dir(dir.path().join(&input.name)).expect("mkdir");
            let error = outcome.is_none().then(|| "broken".to_string());
            let mut status = InputStatus::started(input, "0/1").finished(error, outcome.is_some());
            status.peak_memory_mb = Some(100.0 * (k + 1) as f64);
            write_status(dir.path(), &status).expect("status");
            if let Some(pq) = outcome {
                let eval = serde_json::json!({"pq": pq, "ged": 10.0 * pq, "stable_fraction": null});
                std::fs::write(
                    dir.path().join(&input.name).join("eval.json"),
                    eval.to_string(),
                )
                .expect("eval");
            }
        }
        (dir, manifest)
    }

    #[test]
    fn a_merge_scores_the_finished_inputs_and_lists_the_rest() {
        let (dir, _) = folder();
        let summary = merge(dir.path()).expect("merge");
        assert_eq!(summary.rooms, 2);
        let pq = &summary.metrics["pq"];
        assert!((pq.mean - 0.75).abs() < 1e-12 && pq.worst == 0.6, "{pq:?}");
        assert_eq!(summary.metrics["ged"].worst, 9.0);
        assert!(!summary.metrics.contains_key("stable_fraction"));
        let first = &summary.worst_rooms[0];
        assert_eq!((first.metric.as_str(), first.seed), ("ged", Some(0)));
        assert_eq!(summary.failed[0].input, "seed_2");
        assert_eq!(summary.missing, ["seed_3"]);
        let cost = summary.cost.as_ref().expect("cost");
        assert_eq!((cost.inputs, cost.peak_memory_mb_max), (2, 200.0));
        for name in ["summary.json", "summary.csv", "summary.md"] {
            assert!(dir.path().join(name).is_file(), "{name}");
        }
        let text = summary.to_string();
        assert!(
            text.contains("seed_2 failed: broken") && text.contains("--resume"),
            "{text}"
        );
    }

    #[test]
    fn a_record_of_other_options_does_not_count() {
        let (dir, manifest) = folder();
        let mut other = manifest.clone();
        for input in &mut other.inputs {
            input.voxel = 0.05;
        }
        let summary = summarise(dir.path(), &other);
        assert_eq!(summary.rooms, 0);
        assert_eq!(summary.missing.len(), 4);
    }
}
