//! `iscene benchmark`: generate, render, reconstruct and score a range of procedural rooms, and
//! summarise every numeric key of `iscene eval` over them (mean, median, worst, and the worst
//! rooms with their seeds, so that one command reproduces a failure).
//!
//! A benchmark is a batch of seeds (`crate::batch`): each room lives in `DIR/seed_N/` with its
//! status record, a finished room is not redone, and `--shard I/N` runs a share of the rooms
//! for `iscene batch merge DIR` to summarise.

use std::ops::Range;
use std::path::PathBuf;

use serde_json::json;

use crate::batch::manifest::Shard;
use crate::batch::{BatchOptions, BatchOutcome, Manifest};
use crate::error::{InputError, IsceneError};
use crate::render::noise::NoiseChoice;
use crate::scene::generate::RoomStyle;

pub use crate::batch::summary::{BatchSummary as BenchmarkSummary, higher_is_better};

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
    /// `None`: every room, then the summary.
    pub shard: Option<Shard>,
    /// The `iscene` executable each room runs in.
    pub executable: PathBuf,
    /// An arm's URDF: each room also gets a pick and place planned with it
    /// ([`crate::simulation::pick_and_place_trial`]).
    pub robot: Option<PathBuf>,
}

impl BenchmarkOptions {
    /// The batch manifest of these rooms.
    pub fn manifest(&self) -> Result<Manifest, IsceneError> {
        crate::scene::spec::check_frame_count(self.frames)
            .map_err(|e| InputError::invalid("--frames", e))?;
        let mut defaults = json!({
            "frames": self.frames,
            "style": self.style.name(),
            "noise": self.noise.name(),
            "unseen": self.unseen,
        });
        if let Some(db) = &self.cad {
            defaults["cad"] = json!(db);
        }
        if let Some(robot) = &self.robot {
            defaults["robot"] = json!(robot);
        }
        let value = json!({
            "benchmark": {
                "seeds": [self.seeds.start, self.seeds.end],
                "style": self.style.name(),
                "noise": self.noise.name(),
                "frames": self.frames,
            },
            "defaults": defaults,
            "inputs": [{"seeds": format!("{}:{}", self.seeds.start, self.seeds.end)}],
        });
        let problem_path = self.cad.clone().unwrap_or_else(|| "--seeds".into());
        Manifest::from_value(&value, std::path::Path::new("."))
            .map_err(|problem| InputError::invalid(problem_path, problem).into())
    }
}

pub fn run(options: &BenchmarkOptions) -> Result<BatchOutcome, IsceneError> {
    let manifest = options.manifest()?;
    crate::batch::run::claim_folder(&options.out, &manifest)?;
    crate::batch::run_manifest(
        &manifest,
        &BatchOptions {
            manifest: None,
            out: options.out.clone(),
            shard: options.shard,
            jobs: options.jobs,
            resume: false,
            executable: options.executable.clone(),
        },
    )
}
