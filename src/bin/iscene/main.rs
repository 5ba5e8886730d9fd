//! The `iscene` command line: parse, run, print. Exit codes: 0 success, 2 bad input, 1 internal failure.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::Parser;
use iscene::cad::body_tree::ImportScale;
use iscene::cad::import::{ModelFormat, import_model_files};
use iscene::error::IsceneError;
use iscene::panoptic::InstanceFusion;
use iscene::pipeline::{AlignMethod, ReconstructOptions, SegmentationChoice, reconstruct};
use iscene::scene::SceneSpec;
use iscene::scene::generate::GenerateOptions;
use iscene::scene::{RenderOptions, render_sequence};

mod args;
mod batch;

use batch::{batch, executable, print_batch_outcome};

use args::{
    Align, Baseline, BenchCommand, CadCommand, Cli, Command, ImportFormat, ReconstructArgs,
    Segmentation,
};

#[cfg(feature = "viewer")]
#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
fn view(options: iscene::viewer::ViewOptions, layers: &[String]) -> Result<(), IsceneError> {
    use clap::ValueEnum;
    let layers = layers
        .iter()
        .map(|l| {
            iscene::viewer::Layer::from_str(l, true).map_err(|_| {
                IsceneError::Input(iscene::error::InputError::invalid(
                    &options.dir,
                    format!(
                        "--layer {l:?}: the layers are {}",
                        iscene::viewer::Layer::ALL.map(|l| l.name()).join(", ")
                    ),
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let screenshot = options.screenshot.clone();
    let timing = iscene::viewer::view(&iscene::viewer::ViewOptions { layers, ..options })?;
    if let (Some(path), Some(t)) = (screenshot, timing) {
        println!(
            "{} ({} frames after the first in {:.2} s: {:.1} frames/s)",
            path.display(),
            t.frames,
            t.seconds,
            t.frames_per_s()
        );
    }
    Ok(())
}

/// `view --replay` on a specification or sequence: reconstruct it first, into out/<name> as
/// `iscene reconstruct` does by default (the oracle segmentation where ground-truth labels
/// exist, geometry only otherwise).
#[cfg(feature = "viewer")]
fn reconstruct_for_replay(input: &std::path::Path, progress: bool) -> Result<PathBuf, IsceneError> {
    let stem = input
        .file_stem()
        .map_or("replay".into(), |s| s.to_string_lossy().into_owned());
    let out = PathBuf::from("out").join(stem);
    let labelled =
        input.extension().is_some_and(|e| e == "json") || input.join("labels.json").is_file();
    reconstruct(&ReconstructOptions {
        input: Some(input.to_path_buf()),
        out: out.clone(),
        frames: None,
        voxel: 0.02,
        segmentation: if labelled {
            SegmentationChoice::Oracle
        } else {
            SegmentationChoice::None
        },
        segment_every: 1,
        models: None,
        fusion: InstanceFusion::Joint,
        estimate_gravity: false,
        cad: None,
        align: Default::default(),
        progress,
        force: false,
        max_memory_gb: iscene::map::memory_budget::DEFAULT_MAX_MEMORY_GB,
    })?;
    eprintln!(
        "reconstructed {} into {}; replaying it",
        input.display(),
        out.display()
    );
    Ok(out)
}

#[expect(clippy::print_stdout, reason = "the CLI's job is to print the summary")]
fn run(cli: Cli) -> Result<(), IsceneError> {
    let interactive = std::io::IsTerminal::is_terminal(&std::io::stderr());
    match cli.command {
        Some(Command::Render {
            spec,
            out,
            frames,
            no_noise,
            force,
        }) => {
            let parsed = SceneSpec::load(&spec)?;
            let s = render_sequence(
                &parsed,
                &spec,
                &out,
                &RenderOptions {
                    frames,
                    no_noise,
                    progress: interactive,
                    force,
                    fingerprint: None,
                },
            )?;
            println!(
                "rendered {} frames of {} ({} objects, {} triangles) into {} in {:.2} s ({:.1} frames/s)",
                s.frames,
                parsed.name,
                s.objects,
                s.triangles,
                s.dir.display(),
                s.seconds,
                s.frames as f64 / s.seconds.max(1e-9)
            );
        }
        Some(Command::Simulate {
            dir,
            task,
            out,
            force,
        }) => {
            let summary = iscene::simulation::simulate(&iscene::simulation::SimulateOptions {
                dir,
                task,
                out,
                force,
            })?;
            if let Some(plan) = &summary.plan {
                println!("plan ({} steps): {}", plan.len(), plan.join(" "));
            }
            for s in &summary.steps {
                let physics = s.physics.as_ref().map_or(String::new(), |p| {
                    format!(", stable {:.2}", p.stable_fraction)
                });
                match &s.failed_precondition {
                    None => println!(
                        "{:>2} {:<36} ok{physics} ({:.0} ms: motion {:.0} ms, rest {:.0} ms)",
                        s.step,
                        s.action.label(),
                        s.wall_ms,
                        s.motion_ms(),
                        s.physics_ms
                    ),
                    Some(why) => println!("{:>2} {:<36} FAILED: {why}", s.step, s.action.label()),
                }
            }
            println!(
                "{} -> {}",
                if summary.success { "success" } else { "failed" },
                summary.output.display()
            );
            if !summary.success {
                std::process::exit(1);
            }
        }
        Some(Command::Cad {
            command: CadCommand::Generate { into },
        }) => {
            iscene::io::output_folder::check_database_folder(&into, None)?;
            let n = iscene::cad::export::write_library(&into)?;
            println!(
                "wrote {n} parametric models (glb + json) and index.json into {}",
                into.display()
            );
        }
        Some(Command::Cad {
            command:
                CadCommand::Import {
                    format,
                    path,
                    into,
                    scale,
                },
        }) => {
            iscene::io::output_folder::check_database_folder(&into, Some(&path))?;
            let summary = match format {
                ImportFormat::Sh3d if scale.is_some() => {
                    return Err(iscene::error::InputError::invalid(
                        &path,
                        "--scale is for mjcf and urdf models: Sweet Home 3D catalogues give real sizes",
                    )
                    .into());
                }
                ImportFormat::Sh3d => iscene::cad::import::import_sh3d(&path, &into)?,
                ImportFormat::Mjcf => {
                    let scale = scale.unwrap_or(ImportScale::Class);
                    import_model_files(&path, &into, ModelFormat::Mjcf, scale)?
                }
                ImportFormat::Urdf => {
                    let scale = scale.unwrap_or(ImportScale::Factor(1.0));
                    import_model_files(&path, &into, ModelFormat::Urdf, scale)?
                }
            };
            println!("{summary}");
        }
        Some(Command::Bench {
            command:
                BenchCommand::Tsdf {
                    sequence,
                    frames,
                    voxel,
                    holdout,
                    labels,
                    mesh,
                    runs,
                    max_memory,
                },
        }) => {
            let report = iscene::bench::bench_tsdf(&iscene::bench::TsdfBenchOptions {
                sequence,
                frames,
                voxel,
                holdout_every: holdout,
                labels,
                mesh,
                runs: runs as usize,
                max_memory_gb: max_memory,
            })?;
            print_json(&report)?;
        }
        Some(Command::Bench {
            command:
                BenchCommand::Segmentation {
                    sequence,
                    frames,
                    models,
                },
        }) => {
            let report = iscene::segmentation::onnx::bench::bench_segmentation(
                &iscene::segmentation::onnx::bench::SegmentationBenchOptions {
                    sequence,
                    frames,
                    models,
                },
            )?;
            print_json(&report)?;
        }
        Some(Command::Bench {
            command: BenchCommand::Simulation { dir, task, runs },
        }) => {
            let report = iscene::simulation::bench_simulation(&dir, &task, runs as usize)?;
            print_json(&report)?;
        }
        Some(Command::View {
            dir,
            screenshot,
            layer,
            frames,
            size,
            open,
            replay,
            shots,
            task,
        }) => {
            #[cfg(feature = "viewer")]
            let dir = if replay && !dir.join("report.json").is_file() {
                reconstruct_for_replay(&dir, interactive)?
            } else {
                dir
            };
            #[cfg(feature = "viewer")]
            view(
                iscene::viewer::ViewOptions {
                    dir,
                    screenshot,
                    layers: Vec::new(),
                    frames,
                    size,
                    open,
                    replay,
                    shots,
                    task,
                },
                &layer,
            )?;
            #[cfg(not(feature = "viewer"))]
            {
                let _ = (
                    dir, screenshot, layer, frames, size, open, replay, shots, task,
                );
                return Err(IsceneError::Internal(
                    "this iscene was built without the viewer: cargo run --release --features viewer -- view ..."
                        .into(),
                ));
            }
        }
        Some(Command::Generate {
            seed,
            out,
            style,
            cad,
            noise,
            frames,
        }) => {
            iscene::scene::spec::check_frame_count(frames)
                .map_err(|e| iscene::error::InputError::invalid("--frames", e))?;
            let options = GenerateOptions {
                seed,
                style,
                cad,
                noise,
                frames,
            };
            let generated = iscene::scene::generate::generate(&options, &out)?;
            iscene::scene::generate::write_generated(&out, &generated.json)?;
            println!(
                "wrote {}: {} objects, style {} (seed {seed})",
                out.display(),
                generated.objects,
                generated.style.name()
            );
        }
        Some(Command::Benchmark {
            seeds,
            style,
            noise,
            cad,
            unseen,
            frames,
            jobs,
            out,
            shard,
        }) => {
            let outcome = iscene::benchmark::run(&iscene::benchmark::BenchmarkOptions {
                seeds: seeds.0..seeds.1,
                style,
                noise,
                cad,
                unseen,
                frames,
                jobs,
                out,
                shard,
                executable: executable()?,
            })?;
            print_batch_outcome(&outcome);
        }
        Some(Command::Batch(args)) => batch(args)?,
        Some(Command::Eval { dir, gt }) => {
            let report = iscene::eval::evaluate_reconstruction(&dir, &gt)?;
            print_json(&report)?;
        }
        command => {
            let args = match command {
                Some(Command::Reconstruct(args)) => args,
                _ => ReconstructArgs {
                    input: None,
                    out: None,
                    frames: None,
                    voxel: 0.02,
                    segmentation: Segmentation::Oracle,
                    segment_every: 1,
                    models: None,
                    baseline: None,
                    estimate_gravity: false,
                    cad: None,
                    align: Align::Lm,
                    force: false,
                    max_memory: iscene::map::memory_budget::DEFAULT_MAX_MEMORY_GB,
                },
            };
            let out = args.out.unwrap_or_else(|| {
                let stem = args
                    .input
                    .as_ref()
                    .and_then(|p| p.file_stem())
                    .map_or("kitchen".into(), |s| s.to_string_lossy().into_owned());
                PathBuf::from("out").join(stem)
            });
            let segmentation = match args.segmentation {
                Segmentation::Oracle => SegmentationChoice::Oracle,
                Segmentation::Onnx => SegmentationChoice::Onnx,
                Segmentation::None => SegmentationChoice::None,
            };
            let options = ReconstructOptions {
                input: args.input,
                out: out.clone(),
                frames: args.frames,
                voxel: args.voxel,
                segmentation,
                segment_every: args.segment_every as usize,
                models: args.models,
                fusion: match args.baseline {
                    None => InstanceFusion::Joint,
                    Some(Baseline::VoxbloxPlusPlus) => InstanceFusion::Voxblox,
                },
                estimate_gravity: args.estimate_gravity,
                cad: args.cad,
                align: match args.align {
                    Align::Lm => AlignMethod::Lm,
                    Align::Icp => AlignMethod::Icp,
                },
                progress: interactive,
                force: args.force,
                max_memory_gb: args.max_memory,
            };
            let r = reconstruct(&options)?;
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
                // Pulled apart by more than a voxel or two: the map's segmentation at fault.
                let parted: Vec<String> = cad
                    .replaced
                    .iter()
                    .filter(|o| o.check.separated_m > 0.03)
                    .map(|o| format!("{} {:.0} cm", o.id, 100.0 * o.check.separated_m))
                    .collect();
                if !parted.is_empty() {
                    println!(
                        "           pulled apart from overlapping neighbours: {}",
                        parted.join(", ")
                    );
                }
            }
            for (stage, seconds) in &r.timings {
                println!("  {stage:<20} {seconds:>8.3} s");
            }
            println!("not built yet: {}", r.stages_not_built.join(", "));
            println!("wrote {}: {}", out.display(), r.outputs.join(", "));
        }
    }
    Ok(())
}

#[expect(clippy::print_stdout, reason = "machine-readable results go to stdout")]
fn print_json(value: &impl serde::Serialize) -> Result<(), IsceneError> {
    let text =
        serde_json::to_string_pretty(value).map_err(|e| IsceneError::Internal(e.to_string()))?;
    println!("{text}");
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("iscene: error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
