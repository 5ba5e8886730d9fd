//! `iscene batch` and the output of `iscene benchmark`, which runs on the same machinery.

use std::path::PathBuf;

use iscene::batch::slurm::SlurmOptions;
use iscene::batch::{BatchOptions, BatchOutcome};
use iscene::error::{InputError, IsceneError};

use crate::args::{BatchArgs, BatchCommand, BenchmarkArgs};

/// This program, which runs each input of a batch in a process of its own.
pub(crate) fn executable() -> Result<PathBuf, IsceneError> {
    std::env::current_exe()
        .map_err(|e| IsceneError::io("finding the iscene executable".to_string(), e))
}

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn print_batch_outcome(outcome: &BatchOutcome) {
    match outcome {
        BatchOutcome::Summary(summary) => println!("{summary}"),
        BatchOutcome::Shard(report) => {
            println!(
                "shard {}: {} done, {} done before, {} failed; `iscene batch merge DIR` summarises every shard",
                report.shard,
                report.done,
                report.skipped,
                report.failed.len()
            );
            for (name, error) in &report.failed {
                println!("{name} failed: {error}");
            }
        }
    }
}

pub(crate) fn benchmark(args: BenchmarkArgs) -> Result<(), IsceneError> {
    let outcome = iscene::benchmark::run(&iscene::benchmark::BenchmarkOptions {
        seeds: args.seeds.0..args.seeds.1,
        style: args.style,
        noise: args.noise,
        cad: args.cad,
        unseen: args.unseen,
        frames: args.frames,
        jobs: args.jobs,
        out: args.out,
        shard: args.shard,
        executable: executable()?,
        robot: args.robot,
    })?;
    print_batch_outcome(&outcome);
    Ok(())
}

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn batch(args: BatchArgs) -> Result<(), IsceneError> {
    if let Some(BatchCommand::Merge { dir }) = args.command {
        let summary = iscene::batch::merge(&dir)?;
        println!("{summary}");
        return Ok(());
    }
    let out = args.out.ok_or_else(|| {
        InputError::invalid("--out", "iscene batch needs --out DIR (the batch folder)")
    })?;
    if let Some(name) = args.run_input {
        return iscene::batch::run_one(&out, &name);
    }
    if args.manifest.is_none() && !out.join(iscene::batch::run::BATCH_FILE).is_file() {
        return Err(InputError::invalid(
            &out,
            "no MANIFEST given and the folder holds no batch.json to run",
        )
        .into());
    }
    if args.slurm {
        let manifest = iscene::batch::prepare(args.manifest.as_deref(), &out, args.resume)?;
        let options = SlurmOptions {
            partition: args.partition,
            minutes: args.time,
            memory_mb: args.mem,
            cpus: args.cpus,
            shards: args.shards,
            resume: args.resume,
        };
        match iscene::batch::slurm::submit(&out, &manifest, &executable()?, &options)? {
            Some(s) => println!(
                "submitted job array {} (tasks {} of {} shards, {} inputs to run; {} cores, {} MB, {} min per task from {}) and merge job {}; scripts in {}",
                s.array_job,
                s.array,
                s.shards,
                s.inputs_to_run,
                s.request.cpus,
                s.request.memory_mb,
                s.request.minutes,
                s.request.figures,
                s.merge_job,
                out.join("slurm").display()
            ),
            None => {
                println!("every input is done; nothing submitted");
                println!("{}", iscene::batch::merge(&out)?);
            }
        }
        return Ok(());
    }
    let outcome = iscene::batch::run(&BatchOptions {
        manifest: args.manifest,
        out,
        shard: args.shard,
        jobs: args.jobs,
        resume: args.resume,
        executable: executable()?,
    })?;
    let failed = match &outcome {
        BatchOutcome::Shard(r) => !r.failed.is_empty(),
        BatchOutcome::Summary(s) => !s.failed.is_empty(),
    };
    print_batch_outcome(&outcome);
    if failed {
        // The folder holds every result; the exit status tells a scheduler the task failed.
        return Err(IsceneError::Internal(
            "some inputs failed (listed above)".into(),
        ));
    }
    Ok(())
}
