//! `iscene batch`: many inputs (procedural seeds, specifications, sequence folders) reconstructed
//! into one folder, shared out over shards that may run anywhere (processes on one machine, the
//! tasks of a Slurm job array, the pods of a Kubernetes Indexed Job), and merged into one summary.
//!
//! The folder is the only state: `batch.json` holds the resolved manifest, each input has
//! `DIR/<name>/` with its outputs, `log.txt` and `status.json`; a shard skips the inputs marked
//! done, so a rerun or a resubmission redoes only what is missing, and `merge` can run at any
//! time. `iscene benchmark` is a batch of seeds.

pub mod manifest;
pub mod resources;
pub mod run;
pub mod slurm;
pub mod status;
pub mod summary;

use std::path::PathBuf;

pub use manifest::{BatchInput, Manifest, Shard};
pub use run::{ShardReport, run_one};
pub use summary::{BatchSummary, merge};

use crate::error::{InputError, IsceneError};

/// `iscene batch [MANIFEST] --out DIR [--shard I/N] [--resume]`.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// The manifest; `None`: the one `DIR/batch.json` holds (how cluster tasks run).
    pub manifest: Option<PathBuf>,
    pub out: PathBuf,
    /// `None`: every input, then the summary.
    pub shard: Option<Shard>,
    pub jobs: Option<usize>,
    /// The folder must hold this batch already; only what is not done runs.
    pub resume: bool,
    /// The `iscene` executable each input runs in.
    pub executable: PathBuf,
}

/// What a run did: the whole batch's summary, or one shard's report (merged later).
#[derive(Debug)]
pub enum BatchOutcome {
    Summary(Box<BatchSummary>),
    Shard(ShardReport),
}

/// Reads the manifest (or the folder's), claims the folder, and records the manifest in it.
pub fn prepare(
    manifest: Option<&std::path::Path>,
    out: &std::path::Path,
    resume: bool,
) -> Result<Manifest, IsceneError> {
    let batch_file = out.join(run::BATCH_FILE);
    if resume && !batch_file.is_file() {
        return Err(InputError::missing(
            &batch_file,
            "--resume: the folder holds no batch to resume (run it without --resume first)",
        )
        .into());
    }
    match manifest {
        Some(path) => {
            let manifest = Manifest::load(path)?;
            run::claim_folder(out, &manifest)?;
            Ok(manifest)
        }
        None => run::read_batch(out),
    }
}

pub fn run(options: &BatchOptions) -> Result<BatchOutcome, IsceneError> {
    let manifest = prepare(options.manifest.as_deref(), &options.out, options.resume)?;
    run_manifest(&manifest, options)
}

/// Runs `manifest` in its claimed folder: one shard, or all of them and the summary.
pub fn run_manifest(
    manifest: &Manifest,
    options: &BatchOptions,
) -> Result<BatchOutcome, IsceneError> {
    let report = run::run_shard(
        manifest,
        &run::ShardOptions {
            out: options.out.clone(),
            shard: options.shard.unwrap_or(Shard::WHOLE),
            jobs: options.jobs,
            executable: options.executable.clone(),
            report: true,
        },
    )?;
    match options.shard {
        Some(_) => Ok(BatchOutcome::Shard(report)),
        None => Ok(BatchOutcome::Summary(Box::new(merge(&options.out)?))),
    }
}
