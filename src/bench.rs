//! Benchmarks that print figures (`iscene bench ...`): runs too long for criterion's repeated
//! sampling, and figures a criterion run cannot give (peak memory, surface accuracy).

use std::path::PathBuf;
use std::time::Instant;

use rayon::prelude::*;

use crate::error::IsceneError;
use crate::io::Sequence;
use crate::io::atomic::write_file_atomically;
use crate::map::agreement::{DepthAgreement, depth_residuals, summarise};
use crate::map::memory_budget::{check_map_fits, check_memory_budget, check_voxel_size};
use crate::map::{SegmentLabel, TsdfFrame, TsdfMap, extract_mesh};
use crate::segmentation::geometric::{GeometricParams, segment_depth};

pub struct TsdfBenchOptions {
    pub sequence: PathBuf,
    pub frames: (usize, Option<usize>, usize),
    pub voxel: f32,
    /// Every `holdout_every`-th selected frame is left out of the fusion and used to measure
    /// depth agreement; 0 fuses every frame and measures nothing.
    pub holdout_every: usize,
    /// Fuse a per-pixel segment label with every frame (geometric segments of its depth, computed
    /// before the clock starts), as the panoptic mapper does.
    pub labels: bool,
    /// Write the map's mesh (PLY) here, for side-by-side accuracy checks with other systems.
    pub mesh: Option<PathBuf>,
    /// Integrations of the whole selection into fresh maps; the fastest is reported.
    pub runs: usize,
    /// The map's memory budget, GB.
    pub max_memory_gb: f64,
    /// [`TsdfMap::pack_after_frames`].
    pub pack_after_frames: u32,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct TsdfBenchReport {
    pub sequence: PathBuf,
    pub voxel_m: f32,
    pub labels: bool,
    pub threads: usize,
    pub frames_fused: usize,
    pub frames_held_out: usize,
    /// Reading and decoding the fused frames (in parallel, with their labels when asked for),
    /// not part of integration.
    pub load_s: f64,
    /// Integration only (frames already in memory), the figure comparable with other mappers:
    /// the fastest of `integrate_runs_s`.
    pub integrate_s: f64,
    pub integrate_runs_s: Vec<f64>,
    pub integrate_frames_per_s: f64,
    pub mesh_s: f64,
    pub mesh_vertices: usize,
    pub mesh_triangles: usize,
    pub blocks: usize,
    /// Blocks packed at the end (no frame touched them in the last `pack_after_frames`).
    pub packed_blocks: usize,
    pub map_bytes: usize,
    /// Peak resident memory of the whole process (the map plus a batch of 64 decoded frames).
    pub peak_resident_bytes: Option<u64>,
    pub held_out: Option<DepthAgreement>,
}

/// Integrates the selected frames into a fresh map `runs` times, timing integration alone, then
/// extracts the last map's mesh (every run builds the same map) and raycasts the held-out frames.
pub fn bench_tsdf(options: &TsdfBenchOptions) -> Result<TsdfBenchReport, IsceneError> {
    check_voxel_size(options.voxel)?;
    check_memory_budget(options.max_memory_gb)?;
    let mut sequence = Sequence::open(&options.sequence)?;
    let (start, end, step) = options.frames;
    sequence.select(start, end, step);
    check_map_fits(&sequence, options.voxel, options.max_memory_gb)?;
    let n = sequence.frames.len();
    let held_out = |i: usize| {
        options.holdout_every > 0 && i % options.holdout_every == options.holdout_every - 1
    };
    let fused_frames: Vec<usize> = (0..n).filter(|&i| !held_out(i)).collect();
    let mut runs = Vec::new();
    let mut load_s = 0.0;
    let mut map = None;
    for _ in 0..options.runs.max(1) {
        // The previous run's map goes first, so peak memory is one map's.
        drop(map.take());
        let run = integrate_frames(&sequence, &fused_frames, options)?;
        load_s += run.load_s;
        runs.push(run.integrate_s);
        map = Some(run.map);
    }
    let map = map.expect("at least one run");
    let fused = fused_frames.len();
    let integrate_s = runs.iter().copied().fold(f64::INFINITY, f64::min);

    let clock = Instant::now();
    let mesh = extract_mesh(&map, 0.0).mesh;
    let mesh_s = clock.elapsed().as_secs_f64();
    if let Some(path) = &options.mesh {
        let bytes = crate::io::ply::mesh_ply_bytes(&mesh, [0.7, 0.7, 0.7])
            .map_err(|e| IsceneError::Internal(format!("PLY of the map: {e}")))?;
        write_file_atomically(path, &bytes)?;
    }

    let mut residuals = Vec::new();
    let (mut misses, mut evaluated) = (0, 0);
    for i in (0..n).filter(|&i| held_out(i)) {
        let f = sequence.load_frame(i)?;
        let (r, m) = depth_residuals(&map, &f.depth, &f.camera, &f.world_from_camera, 2);
        residuals.extend(r);
        misses += m;
        evaluated += 1;
    }
    Ok(TsdfBenchReport {
        sequence: options.sequence.clone(),
        voxel_m: options.voxel,
        labels: options.labels,
        threads: rayon::current_num_threads(),
        frames_fused: fused,
        frames_held_out: evaluated,
        load_s,
        integrate_s,
        integrate_runs_s: runs,
        integrate_frames_per_s: fused as f64 / integrate_s.max(1e-9),
        mesh_s,
        mesh_vertices: mesh.positions.len(),
        mesh_triangles: mesh.triangles.len(),
        blocks: map.blocks.len(),
        packed_blocks: map.packed_blocks(),
        map_bytes: map.memory_bytes(),
        peak_resident_bytes: crate::base::process::peak_resident_bytes(),
        held_out: (evaluated > 0).then(|| summarise(residuals, misses, evaluated)),
    })
}

struct IntegrationRun {
    map: TsdfMap,
    load_s: f64,
    integrate_s: f64,
}

/// Integrates `frames` of `sequence` into a fresh map, timing integration alone. Frames are read
/// (and segmented) a batch at a time in parallel, off the clock, so memory stays bounded by the
/// batch and the map.
fn integrate_frames(
    sequence: &Sequence,
    frames: &[usize],
    options: &TsdfBenchOptions,
) -> Result<IntegrationRun, IsceneError> {
    let mut run = IntegrationRun {
        map: TsdfMap::new(options.voxel),
        load_s: 0.0,
        integrate_s: 0.0,
    };
    run.map.pack_after_frames = options.pack_after_frames;
    for batch in frames.chunks(64) {
        let clock = Instant::now();
        let loaded = batch
            .par_iter()
            .map(|&i| sequence.load_frame(i))
            .collect::<Result<Vec<_>, _>>()?;
        let labels: Vec<Option<Vec<SegmentLabel>>> = loaded
            .par_iter()
            .map(|f| {
                options.labels.then(|| {
                    segment_depth(&f.depth, &f.camera, &GeometricParams::default()).segment_of_pixel
                })
            })
            .collect();
        run.load_s += clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        for (f, l) in loaded.iter().zip(&labels) {
            run.map.integrate(&TsdfFrame {
                depth: &f.depth,
                color: &f.color,
                labels: l.as_deref(),
                label_gains: None,
                camera: &f.camera,
                world_from_camera: &f.world_from_camera,
            });
        }
        run.integrate_s += clock.elapsed().as_secs_f64();
    }
    Ok(run)
}
