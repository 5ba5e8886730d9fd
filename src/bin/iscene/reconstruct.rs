//! `iscene reconstruct` (and `iscene` alone: the built-in kitchen): run the pipeline and print
//! what it found.

use std::path::PathBuf;

use iscene::error::IsceneError;
use iscene::panoptic::InstanceFusion;
use iscene::panoptic::live::{Arrivals, LiveSettings};
use iscene::pipeline::{ReconstructOptions, reconstruct as run};
use std::time::Duration;

use clap::{Args, FromArgMatches};

use crate::args::ReconstructArgs;

/// `iscene` alone is `iscene reconstruct` with every default of its flags (the built-in kitchen):
/// the defaults are clap's, so they stand in one place.
pub(crate) fn default_args() -> Result<ReconstructArgs, IsceneError> {
    let matches = ReconstructArgs::augment_args(clap::Command::new("reconstruct"))
        .try_get_matches_from(["reconstruct"])
        .map_err(|e| IsceneError::Internal(format!("default arguments: {e}")))?;
    ReconstructArgs::from_arg_matches(&matches)
        .map_err(|e| IsceneError::Internal(format!("default arguments: {e}")))
}

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
pub(crate) fn reconstruct(args: ReconstructArgs, interactive: bool) -> Result<(), IsceneError> {
    let out = args.out.unwrap_or_else(|| {
        let stem = args
            .input
            .as_ref()
            .and_then(|p| p.file_stem())
            .map_or("kitchen".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from("out").join(stem)
    });
    let options = ReconstructOptions {
        input: args.input,
        out: out.clone(),
        frames: args.frames,
        voxel: args.voxel,
        segmentation: args.segmentation,
        segment_every: args.segment_every as usize,
        models: args.models,
        onnx_device: args.onnx_device,
        fusion: args.baseline.unwrap_or(InstanceFusion::Joint),
        estimate_gravity: args.estimate_gravity,
        cad: args.cad,
        align: args.align,
        progress: interactive,
        force: args.force,
        max_memory_gb: args.max_memory,
        live: args.live.then(|| LiveSettings {
            arrivals: match args.rate {
                Some(hz) => Arrivals::Replay { hz },
                None => Arrivals::Follow {
                    idle: Duration::from_secs_f64(args.idle),
                },
            },
            refresh_every: Duration::from_secs(1),
            max_backlog: 30,
            selection: args.frames,
        }),
    };
    let r = run(&options)?;
    println!(
        "input      {} ({}{} frames, {}x{})",
        r.input.display(),
        if r.rendered { "rendered, " } else { "" },
        r.ingest.frames,
        r.ingest.width,
        r.ingest.height
    );
    println!(
        "depth      {:.1}% valid, {:.2}..{:.2} m; trajectory {:.2} m; gravity {}",
        100.0 * r.ingest.valid_depth_fraction,
        r.ingest.min_depth_m,
        r.ingest.max_depth_m,
        r.ingest.trajectory_length_m,
        if r.ingest.has_gravity {
            "given"
        } else {
            "to be estimated"
        }
    );
    println!("entities   {}   relations {}", r.entities, r.relations);
    if let Some(cad) = &r.cad {
        println!(
            "cad        {} of {} objects replaced from {} models, mean AE {}; {}",
            cad.replaced.len(),
            cad.objects,
            cad.database_models,
            cad.mean_alignment_error_m
                .map_or("-".to_string(), |e| format!("{:.1} mm", 1000.0 * e)),
            if cad.conflicted.is_empty() {
                "no physical conflicts".to_string()
            } else {
                format!(
                    "in conflict, kept as segments: {}",
                    cad.conflicted.join(", ")
                )
            }
        );
        // Moved by more than a voxel or two (pulled apart from neighbours, out of a wall, back
        // onto what holds it): the map's segmentation or the fit at fault.
        let parted: Vec<String> = cad
            .replaced
            .iter()
            .filter(|o| o.check.separated_m > 0.03)
            .map(|o| format!("{} {:.0} cm", o.id, 100.0 * o.check.separated_m))
            .collect();
        if !parted.is_empty() {
            println!(
                "           moved to fit (apart, off a wall, onto a holder): {}",
                parted.join(", ")
            );
        }
    }
    for (stage, seconds) in &r.timings {
        println!("  {stage:<20} {seconds:>8.3} s");
    }
    if let Some(live) = &r.live {
        println!(
            "live       {}: {} of {} frames integrated, labels dropped on {}; lag mean {:.3} s, max {:.3} s; {} refreshes ({:.3} s each), the world at most {:.2} s behind the newest frame",
            live.mode,
            live.frames_integrated,
            live.frames_arrived,
            live.labels_dropped,
            live.integration_lag_mean_s,
            live.integration_lag_max_s,
            live.refreshes,
            live.refresh_seconds_mean,
            live.refresh_lag_max_s
        );
    }
    println!("wrote {}: {}", out.display(), r.outputs.join(", "));
    Ok(())
}
