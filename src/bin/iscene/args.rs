//! The command line's arguments: every subcommand and flag, with their help texts and parsers.

use std::path::PathBuf;

use clap::{Parser, Subcommand};
use iscene::base::InvalidValue;
use iscene::batch::Shard;
use iscene::cad::import::body_tree::ImportScale;
use iscene::cad::replace::replacement::AlignMethod;
use iscene::panoptic::InstanceFusion;
use iscene::render::noise::NoiseChoice;
use iscene::scene::generate::RoomStyle;
use iscene::segmentation::SegmentationChoice;
use iscene::segmentation::onnx::OnnxDevice;

#[derive(Parser)]
#[command(
    name = "iscene",
    version,
    about = "RGB-D stream of a room to an interactive, simulatable scene"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Option<Command>,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Render a scene specification to an RGB-D sequence folder with ground truth.
    Render(RenderArgs),
    /// Reconstruct a scene from a specification (rendered first), a sequence folder or a TUM folder.
    Reconstruct(ReconstructArgs),
    /// Write the scene specification of a procedural room, the same for the same seed.
    Generate(GenerateArgs),
    /// Generate, render, reconstruct and score a range of procedural rooms; summary in --out.
    Benchmark(BenchmarkArgs),
    /// Reconstruct (and score) the inputs of a manifest into one folder, whole or as a shard,
    /// locally or as a Slurm job array; `iscene batch merge DIR` summarises.
    Batch(BatchArgs),
    /// Score a reconstruction against a rendered sequence's ground truth; one JSON object on stdout.
    Eval(EvalArgs),
    /// Run a task (actions, or goals to plan for) in a reconstructed scene folder (or a rendered
    /// sequence's gt/); writes the trace, the task's PDDL and the exports after the last step.
    Simulate(SimulateArgs),
    /// Look at a scene folder (a reconstruction, or a rendered sequence's gt/) in a window, or
    /// render it off screen into a PNG (built with `--features viewer`).
    View(ViewArgs),
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
pub(crate) struct RenderArgs {
    pub(crate) spec: PathBuf,
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Number of frames (default: the specification's, else 300).
    #[arg(long)]
    pub(crate) frames: Option<usize>,
    /// Turn every noise model off.
    #[arg(long)]
    pub(crate) no_noise: bool,
    /// Replace an earlier output of another iscene command at --out (a folder iscene did
    /// not write is never replaced).
    #[arg(long)]
    pub(crate) force: bool,
}

#[derive(clap::Args)]
pub(crate) struct GenerateArgs {
    #[arg(long)]
    pub(crate) seed: u64,
    /// The specification file to write.
    #[arg(long)]
    pub(crate) out: PathBuf,
    #[arg(long, value_enum, default_value_t = RoomStyle::Any)]
    pub(crate) style: RoomStyle,
    /// CAD databases (`iscene cad import`) whose models the room may use (repeatable).
    #[arg(long, value_name = "DB")]
    pub(crate) cad: Vec<PathBuf>,
    /// Noise of the rendering: Kinect depth, realistic segmentation and tracker poses, or none.
    #[arg(long, value_enum, default_value_t = NoiseChoice::Realistic)]
    pub(crate) noise: NoiseChoice,
    /// Frames of the default camera path.
    #[arg(long, default_value_t = 300)]
    pub(crate) frames: usize,
}

#[derive(clap::Args)]
pub(crate) struct BenchmarkArgs {
    /// Seeds as A:B (B excluded).
    #[arg(long, value_parser = parse_seeds)]
    pub(crate) seeds: (u64, u64),
    #[arg(long, value_enum, default_value_t = RoomStyle::Any)]
    pub(crate) style: RoomStyle,
    #[arg(long, value_enum, default_value_t = NoiseChoice::Realistic)]
    pub(crate) noise: NoiseChoice,
    /// A CAD database the rooms draw models from and the reconstruction searches.
    #[arg(long, value_name = "DB")]
    pub(crate) cad: Option<PathBuf>,
    /// With --cad: the reconstruction searches only its own library, so the database's
    /// models are ones it has never seen.
    #[arg(long, requires = "cad")]
    pub(crate) unseen: bool,
    /// Frames per room.
    #[arg(long, default_value_t = 300)]
    pub(crate) frames: usize,
    /// Rooms run at once (default: what cores and memory allow).
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Run only shard I of N (0-based: rooms I, I+N, ...); `iscene batch merge DIR` then
    /// writes the summary of every shard's rooms.
    #[arg(long, value_parser = Shard::parse)]
    pub(crate) shard: Option<Shard>,
    /// The URDF of an arm on the robot's base: each room also gets a pick and place planned
    /// with it (success and seconds in the summary).
    #[arg(long, value_name = "ARM.urdf")]
    pub(crate) robot: Option<PathBuf>,
}

#[derive(clap::Args)]
pub(crate) struct EvalArgs {
    pub(crate) dir: PathBuf,
    #[arg(long)]
    pub(crate) gt: PathBuf,
}

#[derive(clap::Args)]
pub(crate) struct SimulateArgs {
    /// A folder with contact_graph.json.
    pub(crate) dir: PathBuf,
    #[arg(long)]
    pub(crate) task: PathBuf,
    #[arg(long)]
    pub(crate) out: PathBuf,
    /// Replace an earlier output of another iscene command at --out (a folder iscene did
    /// not write is never replaced).
    #[arg(long)]
    pub(crate) force: bool,
    /// The URDF of an arm on the robot's base (for instance the Franka Panda that
    /// scripts/setup-validators.sh installs with PyBullet); picks and places become its
    /// planned motions, in the trace.
    #[arg(long)]
    pub(crate) robot: Option<PathBuf>,
}

#[derive(clap::Args)]
pub(crate) struct ViewArgs {
    /// A folder with contact_graph.json; with --replay, a reconstruction's output folder.
    pub(crate) dir: PathBuf,
    /// Render off screen into this PNG and exit.
    #[arg(long)]
    pub(crate) screenshot: Option<PathBuf>,
    /// Layers shown: colour, segments, boxes, graph, planes, collision, occupancy, physics,
    /// map (repeat or separate with commas).
    #[arg(long, value_delimiter = ',')]
    pub(crate) layer: Vec<String>,
    /// Frames rendered before the screenshot.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..))]
    pub(crate) frames: u32,
    /// Screenshot size in pixels, WIDTHxHEIGHT.
    #[arg(long, default_value = "960x720", value_parser = parse_size)]
    pub(crate) size: (u32, u32),
    /// Open this object's main door or drawer first (repeatable).
    #[arg(long)]
    pub(crate) open: Vec<String>,
    /// Play back the reconstruction in DIR (written by `iscene reconstruct`) frame by frame.
    #[arg(long)]
    pub(crate) replay: bool,
    /// A task script (scenes/tasks/*.json) to run in the window: N does the next action, P
    /// plays them; with --screenshot, the picture is taken after the last action.
    #[arg(long)]
    pub(crate) task: Option<PathBuf>,
    /// The URDF of an arm on the robot's base, as `iscene simulate --robot`: the task's picks,
    /// places, opens and closes are the arm's motions, shown moving.
    #[arg(long, conflicts_with_all = ["replay", "live"])]
    pub(crate) robot: Option<PathBuf>,
    /// With --replay and --screenshot: this many pictures from the first frame to the last
    /// (FILE.gif: one animated GIF; otherwise numbered PNGs FILE_00.png ...).
    #[arg(long, default_value_t = 6, value_parser = clap::value_parser!(u32).range(1..=200))]
    pub(crate) shots: u32,
    /// Follow a running `iscene reconstruct ... --live --out DIR`: the world is rebuilt each
    /// time the session refreshes it (every second), then shows the finished output.
    #[arg(long, conflicts_with_all = ["replay", "task"])]
    pub(crate) live: bool,
}

#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub(crate) struct BatchArgs {
    #[command(subcommand)]
    pub(crate) command: Option<BatchCommand>,
    /// The manifest (JSON: inputs of seeds, specifications and sequence folders, with options);
    /// default: the one DIR/batch.json holds.
    pub(crate) manifest: Option<PathBuf>,
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Run only shard I of N (0-based: inputs I, I+N, ...), as a Slurm array task or a
    /// Kubernetes Indexed Job pod does.
    #[arg(long, value_parser = Shard::parse)]
    pub(crate) shard: Option<Shard>,
    /// Inputs run at once (default: what cores and memory allow).
    #[arg(long)]
    pub(crate) jobs: Option<usize>,
    /// DIR must hold this batch already: run (or with --slurm, submit) only what is not done.
    #[arg(long)]
    pub(crate) resume: bool,
    /// Write a Slurm job array (one task per shard) and a merge job into DIR/slurm and submit them.
    #[arg(long, conflicts_with = "shard")]
    pub(crate) slurm: bool,
    /// With --slurm: the partition.
    #[arg(long, requires = "slurm")]
    pub(crate) partition: Option<String>,
    /// With --slurm: minutes per task (default: from measured time per input, with margin).
    #[arg(long, requires = "slurm")]
    pub(crate) time: Option<u64>,
    /// With --slurm: memory per task in MB (default: from measured peak memory per input).
    #[arg(long, requires = "slurm")]
    pub(crate) mem: Option<u64>,
    /// With --slurm: cores per task (default 2; a task runs one input per 2 cores).
    #[arg(long, requires = "slurm")]
    pub(crate) cpus: Option<usize>,
    /// With --slurm: array tasks (default: one per input).
    #[arg(long, requires = "slurm")]
    pub(crate) shards: Option<usize>,
    /// Internal: run one input of a prepared batch folder (what each shard starts per input).
    #[arg(long, hide = true, requires = "out")]
    pub(crate) run_input: Option<String>,
}

#[derive(Subcommand)]
pub(crate) enum BatchCommand {
    /// Write DIR/summary.json (and .csv, .md) from every shard's results; lists failures and
    /// inputs not finished.
    Merge { dir: PathBuf },
}

#[derive(clap::Args)]
pub(crate) struct ReconstructArgs {
    /// Scene specification (.json), sequence folder, or TUM folder; default: the built-in kitchen.
    pub(crate) input: Option<PathBuf>,
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
    /// Frames to use as A:B[:STEP] (B may be empty for "to the end").
    #[arg(long, value_parser = parse_frames)]
    pub(crate) frames: Option<(usize, Option<usize>, usize)>,
    /// TSDF voxel size in metres.
    #[arg(long, default_value_t = 0.02)]
    pub(crate) voxel: f32,
    #[arg(long, value_enum, default_value_t = SegmentationChoice::Oracle)]
    pub(crate) segmentation: SegmentationChoice,
    /// Segment every K-th frame (the others are fused with geometric segments only).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..))]
    pub(crate) segment_every: u64,
    /// Folder of the onnx backend's models (yolox_nano.onnx, deeplab_v3_1_default_1.opset13.onnx,
    /// coco.names); default ../shared/data/models.
    #[arg(long)]
    pub(crate) models: Option<PathBuf>,
    /// Where the onnx backend's networks run: ONNX Runtime's CPU provider, or its CUDA
    /// provider (needs the onnxruntime-gpu library through ORT_DYLIB_PATH; docs/live.md).
    #[arg(long, value_enum, default_value_t = OnnxDevice::Cpu)]
    pub(crate) onnx_device: OnnxDevice,
    /// Map like this baseline instead of the joint fusion (for the ablation).
    #[arg(long, value_enum)]
    pub(crate) baseline: Option<InstanceFusion>,
    /// Estimate gravity from the map even when the sequence has a gravity file (which is then
    /// only compared with, in report.json).
    #[arg(long)]
    pub(crate) estimate_gravity: bool,
    /// CAD database folder to replace objects from, instead of the built-in parametric library
    /// (`iscene cad import` writes one; `iscene cad generate --into DB` adds the parametric
    /// models to it). The models used are copied into OUT/cad.
    #[arg(long, value_name = "DB")]
    pub(crate) cad: Option<PathBuf>,
    /// How CAD candidates are chosen and aligned: `lm` ranks every model of the class in 24
    /// orientations and aligns the 10 best by Levenberg-Marquardt over per-axis scale, yaw and
    /// translation (Han et al.); `icp` aligns every upright model of the class by a yaw sweep
    /// and ICP over yaw, floor position and width and depth scales (Sivananda et al.).
    #[arg(long, value_enum, default_value_t = AlignMethod::Lm)]
    pub(crate) align: AlignMethod,
    /// Replace an earlier output of another iscene command at --out (a folder iscene did not
    /// write is never replaced).
    #[arg(long)]
    pub(crate) force: bool,
    /// The map's memory budget in GB: a --voxel expected to outgrow it (estimated from the
    /// surface a sample of the frames sees) is refused before mapping.
    #[arg(long, default_value_t = iscene::map::memory_budget::DEFAULT_MAX_MEMORY_GB)]
    pub(crate) max_memory: f64,
    /// Map frames as they arrive: with --rate, the recording replayed at that many frames per
    /// second; without, the folder followed as another program writes it (each frame's depth
    /// image put in place last), ending after --idle seconds with no new frame. The world so far
    /// is refreshed once a second in OUT's staging folder, live/contact_graph.json.
    #[arg(long)]
    pub(crate) live: bool,
    /// With --live: replay the recording at this many frames per second.
    #[arg(long, requires = "live", value_parser = positive_rate)]
    pub(crate) rate: Option<f64>,
    /// With --live and no --rate: seconds without a new frame that end the session.
    #[arg(long, requires = "live", default_value_t = 3.0, value_parser = positive_rate)]
    pub(crate) idle: f64,
}

fn positive_rate(text: &str) -> Result<f64, InvalidValue> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(InvalidValue::whole(format!(
            "{text} is not a positive number"
        ))),
    }
}

#[derive(Subcommand)]
pub(crate) enum BenchCommand {
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
        /// Where the networks run (`reconstruct --onnx-device`).
        #[arg(long, value_enum, default_value_t = OnnxDevice::Cpu)]
        onnx_device: OnnxDevice,
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
        /// Pack a block no frame touched for this many frames (0: never) once the map holds over
        /// 4096 blocks, as the mapper does.
        #[arg(long, default_value_t = iscene::map::tsdf::PACK_AFTER_FRAMES)]
        pack_after: u32,
    },
    /// Time per action of a task (with its physics check), over fresh runs of the task on a
    /// scene folder (as `iscene simulate` takes).
    Simulation {
        dir: PathBuf,
        #[arg(long)]
        task: PathBuf,
        /// The URDF of an arm on the base, as `iscene simulate --robot`.
        #[arg(long)]
        robot: Option<PathBuf>,
        #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
        runs: u32,
    },
}

#[derive(Subcommand)]
pub(crate) enum CadCommand {
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
pub(crate) enum ImportFormat {
    Sh3d,
    Mjcf,
    Urdf,
}

pub(crate) fn parse_import_scale(s: &str) -> Result<ImportScale, InvalidValue> {
    if s == "class" {
        return Ok(ImportScale::Class);
    }
    s.parse::<f32>()
        .ok()
        .filter(|f| f.is_finite() && *f > 0.0)
        .map(ImportScale::Factor)
        .ok_or_else(|| {
            InvalidValue::whole(format!("{s:?} is neither `class` nor a positive number"))
        })
}

pub(crate) fn parse_size(s: &str) -> Result<(u32, u32), InvalidValue> {
    let (w, h) = s
        .split_once('x')
        .ok_or_else(|| InvalidValue::whole(format!("{s:?} is not WIDTHxHEIGHT")))?;
    let number = |p: &str| {
        p.parse::<u32>()
            .ok()
            .filter(|n| (16..=8192).contains(n))
            .ok_or_else(|| {
                InvalidValue::whole(format!(
                    "{p:?} in {s:?} is not a size from 16 to 8192 pixels"
                ))
            })
    };
    Ok((number(w)?, number(h)?))
}

pub(crate) fn parse_frames(s: &str) -> Result<(usize, Option<usize>, usize), InvalidValue> {
    let parts: Vec<&str> = s.split(':').collect();
    let number = |p: &str| {
        p.parse::<usize>().map_err(|_| {
            InvalidValue::whole(format!("{p:?} is not a frame number (expected A:B[:STEP])"))
        })
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
                return Err(InvalidValue::whole(format!("{s:?} selects no frames")));
            }
            Ok((start, end, step))
        }
        _ => Err(InvalidValue::whole(format!("{s:?}: expected A:B[:STEP]"))),
    }
}

/// `A:B` seeds, B excluded and greater than A.
fn parse_seeds(text: &str) -> Result<(u64, u64), InvalidValue> {
    iscene::batch::manifest::parse_seed_range(text).map(|r| (r.start, r.end))
}
