//! `iscene benchmark`: generate, render, reconstruct and score a range of procedural rooms, and
//! summarise every numeric key of `iscene eval` over them (mean, median, worst, and the worst
//! rooms with their seeds, so that one command reproduces a failure).
//!
//! The folder is resumable: each room lives in `DIR/seed_N/` and is finished when its
//! `eval.json` exists and `room.json` records the same options; a finished room is not redone.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use serde::Serialize;
use serde_json::Value;

use crate::error::{InputError, IsceneError};
use crate::pipeline::{AlignMethod, ReconstructOptions, SegmentationChoice, reconstruct};
use crate::render::noise::NoiseChoice;
use crate::render::{RenderOptions, render_sequence};
use crate::scene::SceneSpec;
use crate::scene::generate::{GenerateOptions, RoomStyle, generate, write_generated};

/// The file that marks a folder as a benchmark's (and records its options).
const MARKER: &str = "benchmark.json";
/// How many worst rooms the summary lists per metric.
const WORST_ROOMS: usize = 5;
/// Memory one room may take while it is reconstructed, GB (a 2 cm map of a generated room,
/// the rendering and the CAD stage, with margin).
const ROOM_MEMORY_GB: f64 = 3.0;

#[derive(Clone, Debug)]
pub struct BenchmarkOptions {
    pub seeds: Range<u64>,
    pub style: RoomStyle,
    pub noise: NoiseChoice,
    pub cad: Option<PathBuf>,
    /// The rooms draw models from `cad`, but the reconstruction searches only its own library.
    pub unseen: bool,
    pub frames: usize,
    /// Rooms at once; `None`: what the cores and the memory allow.
    pub jobs: Option<usize>,
    pub out: PathBuf,
    pub progress: bool,
}

/// The options a room was made with, in `room.json`: a room made otherwise is redone.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
struct RoomRecord {
    seed: u64,
    style: String,
    noise: String,
    cad: Option<String>,
    /// The reconstruction did not search `cad`.
    #[serde(default)]
    unseen: bool,
    frames: usize,
    version: String,
    seconds: f64,
}

impl RoomRecord {
    fn same_room(&self, other: &RoomRecord) -> bool {
        (
            self.seed,
            &self.style,
            &self.noise,
            &self.cad,
            self.unseen,
            self.frames,
            &self.version,
        ) == (
            other.seed,
            &other.style,
            &other.noise,
            &other.cad,
            other.unseen,
            other.frames,
            &other.version,
        )
    }
}

/// Mean, median and worst of one metric over the rooms that report it.
#[derive(Clone, Debug, Serialize)]
pub struct MetricSummary {
    pub mean: f64,
    pub median: f64,
    pub worst: f64,
    /// Rooms that report the metric (others have it null).
    pub rooms: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct WorstRoom {
    pub seed: u64,
    pub metric: String,
    pub value: f64,
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct BenchmarkSummary {
    pub rooms: usize,
    pub metrics: BTreeMap<String, MetricSummary>,
    pub worst_rooms: Vec<WorstRoom>,
    /// Rooms that failed, with the error (a failure is a finding, not a reason to stop).
    pub failed: Vec<(u64, String)>,
    pub seeds: [u64; 2],
    pub style: String,
    pub noise: String,
    pub frames: usize,
    /// Wall-clock seconds of this run, and summed over every room's own run.
    pub seconds: f64,
    pub room_seconds: f64,
    #[serde(skip)]
    pub dir: PathBuf,
}

/// Per seed: the room's `iscene eval` object and its seconds, or why it failed.
type RoomResults = BTreeMap<u64, Result<(Value, f64), String>>;

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
    ];
    !lower.iter().any(|w| metric.contains(w))
}

pub fn run(options: &BenchmarkOptions) -> Result<BenchmarkSummary, IsceneError> {
    let start = Instant::now();
    crate::scene::spec::check_frame_count(options.frames)
        .map_err(|e| InputError::invalid("--frames", e))?;
    if let Some(db) = &options.cad
        && !db.join("index.json").is_file()
    {
        return Err(InputError::missing(
            db.join("index.json"),
            "--cad: not a CAD database (`iscene cad import` writes one)",
        )
        .into());
    }
    claim_folder(&options.out)?;
    let seeds: Vec<u64> = options.seeds.clone().collect();
    let jobs = options
        .jobs
        .unwrap_or_else(default_jobs)
        .clamp(1, seeds.len().max(1));
    let next = AtomicUsize::new(0);
    let results: Mutex<RoomResults> = Mutex::new(BTreeMap::new());
    let progress = crate::progress::bar(seeds.len() as u64, "rooms", options.progress);
    std::thread::scope(|scope| {
        for _ in 0..jobs {
            scope.spawn(|| {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(&seed) = seeds.get(k) else {
                        break;
                    };
                    let result = run_room(options, seed).map_err(|e| e.to_string());
                    if let Ok(mut r) = results.lock() {
                        r.insert(seed, result);
                    }
                    progress.inc(1);
                }
            });
        }
    });
    progress.finish_and_clear();
    let results = results
        .into_inner()
        .map_err(|_| IsceneError::Internal("a room's thread panicked".into()))?;
    let summary = summarise(options, &results, start.elapsed().as_secs_f64());
    write_summary(&options.out, &summary)?;
    Ok(summary)
}

/// One room per 2 cores (each reconstruction is parallel itself), as memory allows.
fn default_jobs() -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let memory_gb = sysinfo_memory_gb().unwrap_or(8.0);
    (cores / 2)
        .min((memory_gb / ROOM_MEMORY_GB) as usize)
        .max(1)
}

/// Available memory from /proc/meminfo, GB.
fn sysinfo_memory_gb() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb / 1e6)
}

/// `--out` must be new, empty, or a benchmark folder: nothing else is written into.
fn claim_folder(out: &Path) -> Result<(), IsceneError> {
    if std::fs::symlink_metadata(out).is_ok_and(|m| m.file_type().is_symlink()) {
        return Err(InputError::invalid(out, "--out is a symbolic link; name a folder").into());
    }
    if out.exists() {
        if !out.is_dir() {
            return Err(InputError::invalid(out, "--out is a file; name a folder").into());
        }
        let empty = std::fs::read_dir(out)
            .map_err(|e| InputError::io(out, &e))?
            .next()
            .is_none();
        if !empty && !out.join(MARKER).is_file() {
            return Err(InputError::invalid(
                out,
                "--out is a folder iscene benchmark did not write; it is left alone (choose a new or empty folder)",
            )
            .into());
        }
    }
    std::fs::create_dir_all(out)
        .map_err(|e| IsceneError::io(format!("creating {}", out.display()), e))?;
    std::fs::write(out.join(MARKER), "{\"written_by\": \"iscene benchmark\"}\n")
        .map_err(|e| IsceneError::io(format!("writing {}", out.join(MARKER).display()), e))
}

fn room_record(options: &BenchmarkOptions, seed: u64, seconds: f64) -> RoomRecord {
    RoomRecord {
        seed,
        style: options.style.name().into(),
        noise: options.noise.name().into(),
        cad: options.cad.as_ref().map(|p| p.display().to_string()),
        unseen: options.unseen,
        frames: options.frames,
        version: env!("CARGO_PKG_VERSION").into(),
        seconds,
    }
}

/// Generates, renders, reconstructs and scores room `seed`, or reads its earlier scores.
fn run_room(options: &BenchmarkOptions, seed: u64) -> Result<(Value, f64), IsceneError> {
    let dir = options.out.join(format!("seed_{seed}"));
    let eval_path = dir.join("eval.json");
    let record_path = dir.join("room.json");
    let wanted = room_record(options, seed, 0.0);
    if let (Ok(eval), Ok(record)) = (
        std::fs::read_to_string(&eval_path),
        std::fs::read_to_string(&record_path),
    ) && let (Ok(eval), Ok(record)) = (
        serde_json::from_str::<Value>(&eval),
        serde_json::from_str::<RoomRecord>(&record),
    ) && record.same_room(&wanted)
    {
        return Ok((eval, record.seconds));
    }
    let start = Instant::now();
    if dir.exists() {
        // A room left unfinished or made with other options; only benchmark rooms are here.
        std::fs::remove_dir_all(&dir)
            .map_err(|e| IsceneError::io(format!("clearing {}", dir.display()), e))?;
    }
    std::fs::create_dir_all(&dir)
        .map_err(|e| IsceneError::io(format!("creating {}", dir.display()), e))?;
    let spec_path = dir.join("spec.json");
    let generated = generate(
        &GenerateOptions {
            seed,
            style: options.style,
            cad: options.cad.iter().cloned().collect(),
            noise: options.noise,
            frames: options.frames,
        },
        &spec_path,
    )?;
    write_generated(&spec_path, &generated.json)?;
    let spec = SceneSpec::load(&spec_path)?;
    let sequence = dir.join("sequence");
    render_sequence(
        &spec,
        &spec_path,
        &sequence,
        &RenderOptions {
            frames: None,
            no_noise: false,
            progress: false,
            force: false,
            fingerprint: None,
        },
    )?;
    let reconstruction = dir.join("reconstruction");
    reconstruct(&ReconstructOptions {
        input: Some(sequence.clone()),
        out: reconstruction.clone(),
        frames: None,
        voxel: 0.02,
        segmentation: SegmentationChoice::Oracle,
        segment_every: 1,
        models: None,
        fusion: crate::panoptic::InstanceFusion::Joint,
        estimate_gravity: false,
        cad: options.cad.clone().filter(|_| !options.unseen),
        align: AlignMethod::default(),
        progress: false,
        force: false,
        max_memory_gb: crate::map::memory_budget::DEFAULT_MAX_MEMORY_GB,
    })?;
    let report = crate::eval::evaluate_reconstruction(&reconstruction, &sequence)?;
    let eval = serde_json::to_value(&report)
        .map_err(|e| IsceneError::Internal(format!("eval JSON: {e}")))?;
    let seconds = start.elapsed().as_secs_f64();
    let write = |path: &Path, value: String| {
        std::fs::write(path, value)
            .map_err(|e| IsceneError::io(format!("writing {}", path.display()), e))
    };
    write(
        &record_path,
        serde_json::to_string_pretty(&room_record(options, seed, seconds)).unwrap_or_default(),
    )?;
    // Last: its presence marks the room finished.
    write(
        &eval_path,
        serde_json::to_string_pretty(&eval).unwrap_or_default(),
    )?;
    Ok((eval, seconds))
}

fn summarise(options: &BenchmarkOptions, results: &RoomResults, seconds: f64) -> BenchmarkSummary {
    let mut values: BTreeMap<String, Vec<(u64, f64)>> = BTreeMap::new();
    let mut failed = Vec::new();
    let mut room_seconds = 0.0;
    let mut rooms = 0;
    for (seed, result) in results {
        match result {
            Ok((eval, s)) => {
                rooms += 1;
                room_seconds += s;
                if let Some(map) = eval.as_object() {
                    for (key, value) in map {
                        if let Some(v) = value.as_f64() {
                            values.entry(key.clone()).or_default().push((*seed, v));
                        } else if value.is_null() {
                            values.entry(key.clone()).or_default();
                        }
                    }
                }
            }
            Err(e) => failed.push((*seed, e.clone())),
        }
    }
    let mut metrics = BTreeMap::new();
    let mut worst_rooms = Vec::new();
    for (key, mut list) in values {
        if list.is_empty() {
            continue;
        }
        let higher = higher_is_better(&key);
        // Worst first.
        list.sort_by(|a, b| {
            let order = a.1.total_cmp(&b.1);
            if higher { order } else { order.reverse() }
        });
        let mut sorted: Vec<f64> = list.iter().map(|(_, v)| *v).collect();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        metrics.insert(
            key.clone(),
            MetricSummary {
                mean: sorted.iter().sum::<f64>() / n as f64,
                median,
                worst: list[0].1,
                rooms: n,
            },
        );
        worst_rooms.extend(
            list.iter()
                .take(WORST_ROOMS)
                .map(|(seed, value)| WorstRoom {
                    seed: *seed,
                    metric: key.clone(),
                    value: *value,
                }),
        );
    }
    BenchmarkSummary {
        rooms,
        metrics,
        worst_rooms,
        failed,
        seeds: [options.seeds.start, options.seeds.end],
        style: options.style.name().into(),
        noise: options.noise.name().into(),
        frames: options.frames,
        seconds,
        room_seconds,
        dir: options.out.clone(),
    }
}

fn write_summary(out: &Path, summary: &BenchmarkSummary) -> Result<(), IsceneError> {
    let write = |name: &str, text: String| {
        let path = out.join(name);
        let temporary = out.join(format!(".{name}.partial"));
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

impl fmt::Display for BenchmarkSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "# Benchmark: seeds {}:{}, {} rooms, style {}, noise {}, {} frames",
            self.seeds[0], self.seeds[1], self.rooms, self.style, self.noise, self.frames
        )?;
        writeln!(
            f,
            "\nReproduce: `iscene benchmark --seeds {}:{} --style {} --noise {} --frames {} --out {}`; {:.0} s wall clock, {:.0} s summed over rooms.\n",
            self.seeds[0],
            self.seeds[1],
            self.style,
            self.noise,
            self.frames,
            self.dir.display(),
            self.seconds,
            self.room_seconds
        )?;
        writeln!(
            f,
            "| metric | mean | median | worst | rooms | worst seeds |"
        )?;
        writeln!(f, "|---|---|---|---|---|---|")?;
        for (key, m) in &self.metrics {
            let seeds: Vec<String> = self
                .worst_rooms
                .iter()
                .filter(|w| &w.metric == key)
                .map(|w| w.seed.to_string())
                .collect();
            writeln!(
                f,
                "| {key} | {:.4} | {:.4} | {:.4} | {} | {} |",
                m.mean,
                m.median,
                m.worst,
                m.rooms,
                seeds.join(", ")
            )?;
        }
        for (seed, e) in &self.failed {
            writeln!(f, "\nroom {seed} failed: {e}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
