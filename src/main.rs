//! The `iscene` command line: parse, run, print. Exit codes: 0 success, 2 bad input, 1 internal failure.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use iscene::cad::body_tree::ImportScale;
use iscene::cad::import::{ModelFormat, import_model_files};
use iscene::error::IsceneError;
use iscene::panoptic::InstanceFusion;
use iscene::pipeline::{AlignMethod, ReconstructOptions, SegmentationChoice, reconstruct};
use iscene::render::{RenderOptions, render_sequence};
use iscene::scene::SceneSpec;

#[derive(Parser)]
#[command(
    name = "iscene",
    version,
    about = "RGB-D stream of a room to an interactive, simulatable scene"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene specification to an RGB-D sequence folder with ground truth.
    Render {
        spec: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Number of frames (default: the specification's, else 300).
        #[arg(long)]
        frames: Option<usize>,
        /// Turn every noise model off.
        #[arg(long)]
        no_noise: bool,
        /// Replace an earlier output of another iscene command at --out (a folder iscene did
        /// not write is never replaced).
        #[arg(long)]
        force: bool,
    },
    /// Reconstruct a scene from a specification (rendered first), a sequence folder or a TUM folder.
    Reconstruct(ReconstructArgs),
    /// Score a reconstruction against a rendered sequence's ground truth; one JSON object on stdout.
    Eval {
        dir: PathBuf,
        #[arg(long)]
        gt: PathBuf,
    },
    /// Run a task (actions, or goals to plan for) in a reconstructed scene folder (or a rendered
    /// sequence's gt/); writes the trace, the task's PDDL and the exports after the last step.
    Simulate {
        /// A folder with contact_graph.json.
        dir: PathBuf,
        #[arg(long)]
        task: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// Replace an earlier output of another iscene command at --out (a folder iscene did
        /// not write is never replaced).
        #[arg(long)]
        force: bool,
    },
    /// Look at a scene folder (a reconstruction, or a rendered sequence's gt/) in a window, or
    /// render it off screen into a PNG (built with `--features viewer`).
    View {
        /// A folder with contact_graph.json; with --replay, a reconstruction's output folder.
        dir: PathBuf,
        /// Render off screen into this PNG and exit.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        /// Layers shown: colour, segments, boxes, graph, planes, collision, occupancy, physics,
        /// map (repeat or separate with commas).
        #[arg(long, value_delimiter = ',')]
        layer: Vec<String>,
        /// Frames rendered before the screenshot.
        #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
        frames: u32,
        /// Screenshot size in pixels, WIDTHxHEIGHT.
        #[arg(long, default_value = "960x720", value_parser = parse_size)]
        size: (u32, u32),
        /// Open this object's main door or drawer first (repeatable).
        #[arg(long)]
        open: Vec<String>,
        /// Play back the reconstruction in DIR (written by `iscene reconstruct`) frame by frame.
        #[arg(long)]
        replay: bool,
        /// A task script (scenes/tasks/*.json) to run in the window: N does the next action, P
        /// plays them; with --screenshot, the picture is taken after the last action.
        #[arg(long)]
        task: Option<PathBuf>,
        /// With --replay and --screenshot: this many pictures from the first frame to the last
        /// (FILE.gif: one animated GIF; otherwise numbered PNGs FILE_00.png ...).
        #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=200))]
        shots: u32,
    },
    /// Benchmarks that print their figures as one JSON object on stdout.
    Bench {
        #[command(subcommand)]
        command: BenchCommand,
    },
    /// The CAD database.
    Cad {
        #[command(subcommand)]
        command: CadCommand,
    },
}

#[derive(clap::Args)]
struct ReconstructArgs {
    /// Scene specification (.json), sequence folder, or TUM folder; default: the built-in kitchen.
    input: Option<PathBuf>,
    #[arg(long)]
    out: Option<PathBuf>,
    /// Frames to use as A:B[:STEP] (B may be empty for "to the end").
    #[arg(long, value_parser = parse_frames)]
    frames: Option<(usize, Option<usize>, usize)>,
    /// TSDF voxel size in metres.
    #[arg(long, default_value_t = 0.02)]
    voxel: f32,
    #[arg(long, value_enum, default_value_t = Segmentation::Oracle)]
    segmentation: Segmentation,
    /// Segment every K-th frame (the others are fused with geometric segments only).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    segment_every: u64,
    /// Folder of the onnx backend's models (yolox_nano.onnx, deeplab_v3_1_default_1.opset13.onnx,
    /// coco.names); default ../shared/data/models.
    #[arg(long)]
    models: Option<PathBuf>,
    /// Map like this baseline instead of the joint fusion (for the ablation).
    #[arg(long, value_enum)]
    baseline: Option<Baseline>,
    /// Estimate gravity from the map even when the sequence has a gravity file (which is then
    /// only compared with, in report.json).
    #[arg(long)]
    estimate_gravity: bool,
    /// CAD database folder to replace objects from, instead of the built-in parametric library
    /// (`iscene cad import` writes one; `iscene cad generate --into DB` adds the parametric
    /// models to it). The models used are copied into OUT/cad.
    #[arg(long, value_name = "DB")]
    cad: Option<PathBuf>,
    /// How CAD candidates are chosen and aligned: `lm` ranks every model of the class in 24
    /// orientations and aligns the 10 best by Levenberg-Marquardt over per-axis scale, yaw and
    /// translation (Han et al.); `icp` aligns every upright model of the class by a yaw sweep
    /// and ICP over yaw, floor position and width and depth scales (Sivananda et al.).
    #[arg(long, value_enum, default_value_t = Align::Lm)]
    align: Align,
    /// Replace an earlier output of another iscene command at --out (a folder iscene did not
    /// write is never replaced).
    #[arg(long)]
    force: bool,
    /// The map's memory budget in GB: a --voxel expected to outgrow it (estimated from the
    /// surface a sample of the frames sees) is refused before mapping.
    #[arg(long, default_value_t = iscene::map::memory_budget::DEFAULT_MAX_MEMORY_GB)]
    max_memory: f64,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Align {
    Lm,
    Icp,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Baseline {
    #[value(name = "voxblox++")]
    VoxbloxPlusPlus,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Segmentation {
    Oracle,
    Onnx,
    None,
}

#[derive(Subcommand)]
enum BenchCommand {
    /// The onnx segmentation backend's time per frame on one core, and on a rendered sequence its
    /// chair and table masks' overlap (IoU) with the ground truth.
    Segmentation {
        sequence: PathBuf,
        /// Frames to use as A:B[:STEP].
        #[arg(long, value_parser = parse_frames, default_value = "0::10")]
        frames: (usize, Option<usize>, usize),
        /// Folder of the models; default ../shared/data/models.
        #[arg(long, default_value = iscene::segmentation::onnx::OnnxModels::DEFAULT_DIR)]
        models: PathBuf,
    },
    /// TSDF integration speed, map memory and depth agreement on held-out frames of a sequence.
    Tsdf {
        sequence: PathBuf,
        /// Frames to use as A:B[:STEP].
        #[arg(long, value_parser = parse_frames, default_value = "0:300")]
        frames: (usize, Option<usize>, usize),
        #[arg(long, default_value_t = 0.02)]
        voxel: f32,
        /// Leave every N-th frame out of the fusion and raycast the map at it (0: fuse all).
        #[arg(long, default_value_t = 0)]
        holdout: usize,
        /// Also fuse a segment label per pixel (geometric segments), as the panoptic mapper does.
        #[arg(long)]
        labels: bool,
        /// Write the map's mesh here (PLY).
        #[arg(long)]
        mesh: Option<PathBuf>,
        /// Integrate the frames this many times into fresh maps and report the fastest run (a
        /// shared machine's noise only ever slows a run down).
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
        /// The map's memory budget in GB (as reconstruct's).
        #[arg(long, default_value_t = iscene::map::memory_budget::DEFAULT_MAX_MEMORY_GB)]
        max_memory: f64,
    },
    /// Time per action of a task (with its physics check), over fresh runs of the task on a
    /// scene folder (as `iscene simulate` takes).
    Simulation {
        dir: PathBuf,
        #[arg(long)]
        task: PathBuf,
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
    },
}

#[derive(Subcommand)]
enum CadCommand {
    /// Write the parametric library (glTF meshes and metadata) into a folder.
    Generate {
        #[arg(long, default_value = "assets/cad")]
        into: PathBuf,
    },
    /// Import third-party models into a database folder (added to what it holds), for
    /// `reconstruct --cad DB`.
    Import {
        /// The format. sh3d: Sweet Home 3D furniture (a *.sh3f catalogue, sweethome3d.jar, or a
        /// folder of them such as /usr/share/sweethome3d/furniture). mjcf: MuJoCo model files
        /// (one *.xml file or a folder of them, such as LIBERO's articulated_objects). urdf: URDF
        /// model files (one *.urdf file or a folder of them).
        format: ImportFormat,
        path: PathBuf,
        #[arg(long)]
        into: PathBuf,
        /// mjcf and urdf: `class` sizes each model uniformly to its class's typical size; a
        /// number scales the file's units by it (1: metres). Default: `class` for mjcf (LIBERO's
        /// objects are made for a tabletop), 1 for urdf (URDF is in metres at real size).
        #[arg(long, value_parser = parse_import_scale)]
        scale: Option<ImportScale>,
    },
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ImportFormat {
    Sh3d,
    Mjcf,
    Urdf,
}

fn parse_import_scale(s: &str) -> Result<ImportScale, String> {
    if s == "class" {
        return Ok(ImportScale::Class);
    }
    s.parse::<f32>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0)
        .map(ImportScale::Factor)
        .ok_or_else(|| format!("{s:?} is neither `class` nor a positive number"))
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| format!("{s:?} is not WIDTHxHEIGHT"))?;
    let number = |p: &str| {
        p.parse::<u32>()
            .ok()
            .filter(|n| (16..=8192).contains(n))
            .ok_or_else(|| format!("{p:?} in {s:?} is not a size from 16 to 8192 pixels"))
    };
    Ok((number(w)?, number(h)?))
}

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

fn parse_frames(s: &str) -> Result<(usize, Option<usize>, usize), String> {
    let parts: Vec<&str> = s.split(':').collect();
    let number = |p: &str| {
        p.parse::<usize>()
            .map_err(|_| format!("{p:?} is not a frame number (expected A:B[:STEP])"))
    };
    match parts[..] {
        [a, b] | [a, b, _] => {
            let start = if a.is_empty() { 0 } else { number(a)? };
            let end = if b.is_empty() { None } else { Some(number(b)?) };
            let step = if parts.len() == 3 {
                number(parts[2])?
            } else {
                1
            };
            if step == 0 || end.is_some_and(|e| e <= start) {
                return Err(format!("{s:?} selects no frames"));
            }
            Ok((start, end, step))
        }
        _ => Err(format!("{s:?}: expected A:B[:STEP]")),
    }
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
