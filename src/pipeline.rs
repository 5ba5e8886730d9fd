//! `iscene reconstruct`: resolve the input (render a specification first), run the stages in an
//! ECS app, and write the output folder.

use std::path::{Path, PathBuf};
use std::time::Instant;

use bevy::prelude::*;
use serde::Serialize;

use crate::cad::db::database::CadDatabase;
use crate::error::{InputError, IsceneError};
use crate::graph::gravity::GravityReport;
use crate::io::Sequence;
use crate::io::atomic::{StagedDir, write_file_atomically};
use crate::io::output_folder::{MARKER, OutputCommand, OutputTarget};
use crate::io::sequence::SequenceFormat;
use crate::io::write_sequence::write_text;
use crate::map::memory_budget::{check_map_fits, check_memory_budget, check_voxel_size};
use crate::panoptic::live::{LiveReport, LiveSettings, map_live, wait_for_sequence};
use crate::panoptic::{InstanceFusion, MapperParams, PanopticMapper};
use crate::scene::SceneSpec;
use crate::scene::{RenderOptions, render_sequence};
use crate::systems::Reconstruct;
use crate::systems::cad_replacement::{CadAlignMethod, CadAlignmentCache, CadLibrary, CadReport};
use crate::systems::contact_graph::{GravityConfig, SceneGravity};
use crate::systems::export::{ExportTarget, ExportedFiles};
use crate::systems::ingest::{IngestReport, InputSequence};
use crate::systems::panoptic_mapping::{
    LivePreview, MappingConfig, PanopticMap, PanopticSurface, Segmenter, segmentation_service,
};
use crate::systems::physics_validation::PhysicsReport;
use crate::systems::scene_nodes::read_contact_graph;
use crate::systems::stages::{StageError, StageMarks};

pub use crate::cad::replace::replacement::AlignMethod;
pub use crate::segmentation::SegmentationChoice;
pub use crate::segmentation::onnx::OnnxDevice;

#[derive(Clone, Debug)]
pub struct ReconstructOptions {
    /// A scene specification, a sequence folder, or `None` for the built-in kitchen.
    pub input: Option<PathBuf>,
    pub out: PathBuf,
    /// `(start, end, step)` over the sequence's frames.
    pub frames: Option<(usize, Option<usize>, usize)>,
    pub voxel: f32,
    pub segmentation: SegmentationChoice,
    /// Segment every this many frames; the others are fused with geometric segments only.
    pub segment_every: usize,
    /// The onnx backend's model folder; `None` for ../shared/data/models.
    pub models: Option<PathBuf>,
    /// Where the onnx backend's networks run (`--onnx-device`).
    pub onnx_device: OnnxDevice,
    /// Joint fusion, or the Voxblox++ baseline.
    pub fusion: InstanceFusion,
    /// Ignore the sequence's gravity file and estimate gravity from the map.
    pub estimate_gravity: bool,
    /// A CAD database folder (`iscene cad generate` / `iscene cad import`) that replacement
    /// matches against, instead of the built-in parametric library.
    pub cad: Option<PathBuf>,
    /// How CAD candidates are chosen and aligned.
    pub align: AlignMethod,
    pub progress: bool,
    /// Replace an earlier output of another iscene command at `out` (`--force`).
    pub force: bool,
    /// The map's memory budget, GB (`--max-memory`): a voxel size expected to outgrow it is
    /// refused before mapping.
    pub max_memory_gb: f64,
    /// Map frames as they arrive (`--live`), refreshing a preview of the world meanwhile.
    pub live: Option<LiveSettings>,
}

impl ReconstructOptions {
    /// `iscene reconstruct INPUT --out OUT` with every flag at its default: all frames, 2 cm, the
    /// oracle segmentation on every frame, the joint fusion, the built-in library aligned by
    /// Levenberg-Marquardt, no progress bar, no `--force`, the default memory budget.
    pub fn new(input: impl Into<PathBuf>, out: impl Into<PathBuf>) -> Self {
        Self {
            input: Some(input.into()),
            out: out.into(),
            frames: None,
            voxel: 0.02,
            segmentation: SegmentationChoice::Oracle,
            segment_every: 1,
            models: None,
            onnx_device: OnnxDevice::Cpu,
            fusion: InstanceFusion::Joint,
            estimate_gravity: false,
            cad: None,
            align: AlignMethod::default(),
            progress: false,
            force: false,
            max_memory_gb: crate::map::memory_budget::DEFAULT_MAX_MEMORY_GB,
            live: None,
        }
    }
}

/// What a reconstruction did, for the summary the CLI prints.
#[derive(Clone, Debug, Serialize)]
pub struct ReconstructReport {
    pub input: PathBuf,
    pub format: String,
    pub rendered: bool,
    /// `--frames` as `[start, end or null, step]` over the input's frames, when given.
    pub frame_selection: Option<(usize, Option<usize>, usize)>,
    pub ingest: IngestReport,
    pub entities: usize,
    /// Support and proximal edges of the contact graph.
    pub relations: usize,
    pub gravity: Option<GravityReport>,
    pub panoptic: Option<PanopticReport>,
    /// The CAD models that replaced objects, with their alignment errors.
    pub cad: Option<CadReport>,
    /// The rest test's verdict per object and the sweep of every door and drawer.
    pub physics: Option<PhysicsReport>,
    /// Stages that ran, with wall-clock seconds; rendering (or live mapping) comes first.
    pub timings: Vec<(String, f64)>,
    pub outputs: Vec<String>,
    /// What a live session measured (`--live`).
    pub live: Option<LiveReport>,
}

/// What the panoptic map holds.
#[derive(Clone, Debug, Serialize)]
pub struct PanopticReport {
    /// The segmentation service, and for onnx where its networks ran: "oracle", "none",
    /// "onnx on cpu", "onnx on cuda".
    pub segmentation: String,
    pub fusion: String,
    pub voxel_size_m: f32,
    pub blocks: usize,
    pub map_memory_mb: f64,
    /// The frames' label images kept for the checks after mapping: megabytes, and how many
    /// frames' (all of them within the mapper's budget, an even spread past it).
    pub frame_labels_mb: f64,
    pub frame_labels_kept: usize,
    pub label_merges: usize,
    pub instance_merges: usize,
    pub instance_splits: usize,
    pub surface_voxels: usize,
    /// Entity id, class and surface voxels.
    pub entities: Vec<(String, String, usize)>,
}

fn spec_fingerprint(text: &str) -> String {
    use sha2::Digest;
    let digest = sha2::Sha256::digest(format!("{text}\n{}", env!("CARGO_PKG_VERSION")).as_bytes());
    digest.iter().take(8).map(|b| format!("{b:02x}")).collect()
}

/// Where a specification given to `reconstruct --out OUT` is rendered: `OUT.sequence`.
pub fn rendered_input_dir(out: &Path) -> PathBuf {
    PathBuf::from(format!("{}.sequence", out.display()))
}

/// Renders a specification next to the output folder (`OUT.sequence`), reusing an earlier
/// rendering of the same specification.
fn render_input(
    spec_text: &str,
    spec_path: &Path,
    out: &Path,
    progress: bool,
    timings: &mut Vec<(String, f64)>,
) -> Result<PathBuf, IsceneError> {
    let spec = SceneSpec::parse(spec_text, spec_path)?;
    let sequence_dir = rendered_input_dir(out);
    let stamp = sequence_dir.join("gt").join("spec.fingerprint");
    // The databases of "cad" are part of what is rendered.
    let indices: Vec<String> = spec
        .databases
        .iter()
        .map(|db| std::fs::read_to_string(db.dir.join("index.json")).unwrap_or_default())
        .collect();
    let fingerprint = spec_fingerprint(&format!("{spec_text}\n{}", indices.join("\n")));
    let ours = OutputTarget::claim(
        "--out",
        &sequence_dir,
        OutputCommand::Render,
        &[spec_path],
        false,
    )
    .is_ok_and(|_| sequence_dir.join(MARKER).is_file());
    if ours && std::fs::read_to_string(&stamp).is_ok_and(|s| s.trim() == fingerprint) {
        return Ok(sequence_dir);
    }
    let start = Instant::now();
    let summary = render_sequence(
        &spec,
        spec_path,
        &sequence_dir,
        &RenderOptions {
            frames: None,
            no_noise: false,
            progress,
            force: false,
            fingerprint: Some(fingerprint),
        },
    )
    .map_err(|e| match e {
        IsceneError::Input(InputError::Invalid { path, problem }) if path == sequence_dir => {
            InputError::invalid(
                path,
                format!(
                    "(where the specification is rendered for --out {}): {problem}",
                    out.display()
                ),
            )
            .into()
        }
        e => e,
    })?;
    timings.push(("render".into(), start.elapsed().as_secs_f64()));
    Ok(summary.dir)
}

/// The reconstruction world with its stages' settings; the caller adds the input sequence (and,
/// for a live session, the map).
fn reconstruction_app(
    options: &ReconstructOptions,
    mapping: &MappingConfig,
    cad_library: &Option<std::sync::Arc<CadDatabase>>,
) -> App {
    let mut app = App::new();
    app.add_plugins(crate::ReconstructionPlugins);
    app.insert_resource(mapping.clone());
    app.insert_resource(GravityConfig {
        estimate: options.estimate_gravity,
    });
    if let Some(db) = cad_library {
        app.insert_resource(CadLibrary(db.clone()));
    }
    app.insert_resource(CadAlignMethod(options.align));
    app
}

type LiveMap = (
    PanopticMapper,
    Option<Box<dyn crate::segmentation::SegmentationService>>,
);

/// Maps the frames as they arrive (`--live`). At every refresh the stages after integration run
/// on a copy of the map so far (extraction without carving, contact graph, CAD, kinematic tree,
/// physics) and `live/contact_graph.json` and `live/status.json` are rewritten whole in the
/// output being staged.
fn map_live_with_previews(
    sequence_dir: &Path,
    first: Sequence,
    options: &ReconstructOptions,
    mapping: &MappingConfig,
    live: &LiveSettings,
    cad_library: &Option<std::sync::Arc<CadDatabase>>,
    staged: &Path,
) -> Result<(LiveMap, Sequence, IngestReport, LiveReport), IsceneError> {
    let service = segmentation_service(mapping, &first)?;
    let preview_dir = staged.join("live");
    std::fs::create_dir_all(&preview_dir)
        .map_err(|e| IsceneError::io(format!("creating {}", preview_dir.display()), e))?;
    // Said whether or not a person watches: a program following the session needs the place.
    eprintln!(
        "live: the world so far is refreshed every second in {}",
        preview_dir.display()
    );
    // Objects whose boxes have not moved keep the last refresh's CAD alignments.
    let mut cad_cache = CadAlignmentCache::default();
    let mut refresh = |map: &PanopticMapper, seen: &Sequence, report: &LiveReport| {
        let mut app = reconstruction_app(options, mapping, cad_library);
        app.insert_resource(LivePreview);
        app.insert_resource(std::mem::take(&mut cad_cache));
        app.insert_resource(InputSequence(seen.clone()));
        app.insert_resource(PanopticMap(map.clone()));
        app.insert_resource(IngestReport::default());
        run_stages(&mut app)?;
        cad_cache = app
            .world_mut()
            .remove_resource::<CadAlignmentCache>()
            .unwrap_or_default();
        if app.world().contains_resource::<SceneGravity>() {
            write_file_atomically(
                &preview_dir.join("contact_graph.json"),
                read_contact_graph(app.world_mut()).to_json().as_bytes(),
            )?;
        }
        if options.progress {
            eprintln!(
                "live: {} frames integrated (newest {}), a frame {:.2} s after its arrival at worst, labels dropped on {}",
                seen.frames.len(),
                seen.frames.last().map_or(0, |f| f.index),
                report.integration_lag_max_s,
                report.labels_dropped
            );
        }
        write_live_status(&preview_dir, seen, report, false)
    };
    let (map, seen, report) = map_live(
        sequence_dir,
        first,
        service.as_deref(),
        &mapping.params,
        live,
        &mut refresh,
    )?;
    let ingest = IngestReport::new(&seen, &report.depth);
    write_live_status(&preview_dir, &seen, &report, true)?;
    Ok(((map, service), seen, ingest, report))
}

/// `live/status.json`: the frames integrated so far, the newest, and the session's figures.
fn write_live_status(
    dir: &Path,
    seen: &Sequence,
    report: &LiveReport,
    finished: bool,
) -> Result<(), IsceneError> {
    let status = serde_json::json!({
        "frames_integrated": seen.frames.len(),
        "newest_frame": seen.frames.last().map(|f| f.index),
        "finished": finished,
        "live": report,
    });
    write_file_atomically(
        &dir.join("status.json"),
        serde_json::to_string_pretty(&status)
            .unwrap_or_default()
            .as_bytes(),
    )
}

pub fn reconstruct(options: &ReconstructOptions) -> Result<ReconstructReport, IsceneError> {
    check_voxel_size(options.voxel)?;
    check_memory_budget(options.max_memory_gb)?;
    let target = claim_output(options)?;
    // Read before rendering or mapping, so a broken database fails at once.
    let cad_library = options
        .cad
        .as_deref()
        .map(|dir| CadDatabase::from_folder(dir).map(std::sync::Arc::new))
        .transpose()?;
    let mut timings = Vec::new();
    let (sequence_dir, rendered) = resolve_input(options, &mut timings)?;
    let sequence = open_sequence(&sequence_dir, options)?;
    let format = sequence.format;
    let mapping = mapping_config(options);
    // Staged before the work, so that a live session's previews land in the output's own folder.
    let staged = StagedDir::new(&target)?;
    let mut app = reconstruction_app(options, &mapping, &cad_library);
    app.insert_resource(ExportTarget(staged.path().to_path_buf()));
    let live_report = match &options.live {
        Some(live) => {
            let start = Instant::now();
            let live_map = map_live_with_previews(
                &sequence_dir,
                sequence,
                options,
                &mapping,
                live,
                &cad_library,
                staged.path(),
            )?;
            timings.push(("live mapping".into(), start.elapsed().as_secs_f64()));
            Some(insert_live_map(&mut app, live_map))
        }
        None => {
            app.insert_resource(InputSequence(sequence));
            None
        }
    };
    run_stages(&mut app)?;
    let mut report = collect_report(app.world_mut(), options, sequence_dir, format, rendered);
    report.timings.splice(0..0, timings);
    report.live = live_report;
    write_text(
        &staged.path().join("report.json"),
        &serde_json::to_string_pretty(&report).unwrap_or_default(),
    )?;
    staged.commit()?;
    Ok(report)
}

/// The mapping settings `options` ask for.
fn mapping_config(options: &ReconstructOptions) -> MappingConfig {
    MappingConfig {
        params: MapperParams {
            segment_every: options.segment_every.max(1),
            ..MapperParams::new(options.voxel, options.fusion)
        },
        segmentation: options.segmentation,
        models: options.models.clone(),
        onnx_device: options.onnx_device,
        progress: options.progress,
    }
}

/// Gives the reconstruction the map a live session made, with what it saw, so that the
/// schedule maps nothing again; returns the session's report.
fn insert_live_map(
    app: &mut App,
    ((map, segmenter), seen, ingest, report): (LiveMap, Sequence, IngestReport, LiveReport),
) -> LiveReport {
    app.insert_resource(PanopticMap(map));
    app.insert_resource(Segmenter(segmenter));
    app.insert_resource(ingest);
    app.insert_resource(InputSequence(seen));
    report
}

/// The output folder `--out`, claimed: a folder that holds what another command wrote, or one
/// of the inputs, is refused (`io::output_folder`).
fn claim_output(options: &ReconstructOptions) -> Result<OutputTarget, IsceneError> {
    let inputs: Vec<&Path> = [
        options.input.as_deref(),
        options.cad.as_deref(),
        options.models.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect();
    OutputTarget::claim(
        "--out",
        &options.out,
        OutputCommand::Reconstruct,
        &inputs,
        options.force,
    )
}

/// Runs the `Reconstruct` schedule; the first stage that failed, if one did.
fn run_stages(app: &mut App) -> Result<(), IsceneError> {
    app.world_mut().run_schedule(Reconstruct);
    match app.world_mut().resource_mut::<StageError>().0.take() {
        Some(err) => Err(err),
        None => Ok(()),
    }
}

/// The sequence folder to map, and whether it was rendered here: a specification (or none, the
/// built-in kitchen) is rendered next to the output first.
fn resolve_input(
    options: &ReconstructOptions,
    timings: &mut Vec<(String, f64)>,
) -> Result<(PathBuf, bool), IsceneError> {
    Ok(match &options.input {
        None => (
            render_input(
                crate::BUILTIN_KITCHEN,
                Path::new("scenes/kitchen.json (built in)"),
                &options.out,
                options.progress,
                timings,
            )?,
            true,
        ),
        Some(p) if p.extension().is_some_and(|e| e == "json") => {
            let text = std::fs::read_to_string(p).map_err(|e| InputError::io(p, &e))?;
            (
                render_input(&text, p, &options.out, options.progress, timings)?,
                true,
            )
        }
        Some(p) => (p.clone(), false),
    })
}

/// The input sequence with `--frames` applied (a live session waits for its first frame and
/// takes every frame), checked against the memory budget and the segmentation's needs.
fn open_sequence(
    sequence_dir: &Path,
    options: &ReconstructOptions,
) -> Result<Sequence, IsceneError> {
    let mut sequence = match &options.live {
        Some(live) => wait_for_sequence(sequence_dir, live)?,
        None => Sequence::open(sequence_dir)?,
    };
    if let Some((start, end, step)) = options.frames.filter(|_| options.live.is_none()) {
        sequence.select(start, end, step);
        if sequence.frames.is_empty() {
            return Err(InputError::invalid(
                sequence_dir,
                format!("--frames {start}:{end:?}:{step} selects no frame"),
            )
            .into());
        }
    }
    check_map_fits(&sequence, options.voxel, options.max_memory_gb)?;
    if options.segmentation == SegmentationChoice::Oracle && sequence.labels.is_none() {
        return Err(InputError::missing(sequence_dir.join("labels.json"), "--segmentation oracle needs ground-truth labels; use --segmentation none (or onnx) for real data").into());
    }
    Ok(sequence)
}

/// report.json's figures, read from the world the stages and the export left.
/// The segmentation service as report.json names it, with the onnx backend's device.
fn segmentation_name(options: &ReconstructOptions) -> String {
    match options.segmentation {
        SegmentationChoice::Oracle => "oracle".into(),
        SegmentationChoice::None => "none".into(),
        SegmentationChoice::Onnx => match options.onnx_device {
            OnnxDevice::Cpu => "onnx on cpu".into(),
            OnnxDevice::Cuda => "onnx on cuda".into(),
        },
    }
}

fn collect_report(
    world: &mut World,
    options: &ReconstructOptions,
    input: PathBuf,
    format: SequenceFormat,
    rendered: bool,
) -> ReconstructReport {
    let panoptic = match (
        world.get_resource::<PanopticMap>(),
        world.get_resource::<PanopticSurface>(),
    ) {
        (Some(map), Some(surface)) => Some(PanopticReport {
            segmentation: segmentation_name(options),
            fusion: options.fusion.name().into(),
            voxel_size_m: options.voxel,
            blocks: map.0.tsdf.blocks.len(),
            map_memory_mb: map.0.tsdf.memory_bytes() as f64 / 1e6,
            frame_labels_mb: map.0.frame_labels_kept().0 as f64 / 1e6,
            frame_labels_kept: map.0.frame_labels_kept().1,
            label_merges: map.0.label_merges,
            instance_merges: map.0.instance_merges,
            instance_splits: map.0.instance_splits,
            surface_voxels: surface.voxels.len(),
            entities: surface
                .entities
                .iter()
                .map(|e| (e.id.clone(), e.class.clone(), e.surface_voxels))
                .collect(),
        }),
        _ => None,
    };
    let gravity = world.get_resource::<SceneGravity>().map(|g| g.0.clone());
    let relations = match gravity {
        Some(_) => read_contact_graph(world).edges.len(),
        None => 0,
    };
    let mut outputs = vec!["report.json".to_string()];
    outputs.extend(world.resource::<ExportedFiles>().0.iter().cloned());
    ReconstructReport {
        input,
        format: match format {
            SequenceFormat::Native => "native",
            SequenceFormat::Tum => "tum",
            SequenceFormat::Open3dLog => "open3d-log",
        }
        .into(),
        rendered,
        frame_selection: options.frames,
        ingest: world
            .get_resource::<IngestReport>()
            .cloned()
            .unwrap_or_default(),
        entities: panoptic.as_ref().map_or(0, |p| p.entities.len()),
        relations,
        gravity,
        panoptic,
        cad: world.get_resource::<CadReport>().cloned(),
        physics: world.get_resource::<PhysicsReport>().cloned(),
        timings: world
            .resource::<StageMarks>()
            .seconds()
            .into_iter()
            .map(|(s, t)| (s.name().to_string(), t))
            .collect(),
        outputs,
        live: None,
    }
}
