//! `iscene render`: a scene specification to an RGB-D sequence folder with ground truth.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Affine3A;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::base::stable_hash;
use crate::error::{InputError, IsceneError};
use crate::geometry::Pinhole;
use crate::io::atomic::StagedDir;
use crate::io::output_folder::{OutputCommand, OutputTarget};
use crate::io::ply::mesh_ply_bytes;
use crate::io::write_sequence::{
    pose_text, write_camera, write_color, write_depth, write_labels, write_text,
};
use crate::render::noise::{DepthNoise, NoiseSettings};
use crate::render::pose_noise::PoseNoise;
use crate::render::raster::{NO_TRIANGLE, rasterize};
use crate::render::render_scene::RenderScene;
use crate::render::shading::shade;
use crate::render::trajectory::room_loop;
use crate::scene::{SceneSpec, SceneWorld};
use crate::segmentation::noise::SegmentationNoise;

/// Frames of the default trajectory.
pub const DEFAULT_FRAMES: usize = 300;
pub const DEFAULT_CAMERA_HEIGHT: f32 = 1.45;

#[derive(Clone, Debug, Default)]
pub struct RenderOptions {
    /// Overrides the specification's frame count.
    pub frames: Option<usize>,
    /// Turns every noise model off (`--no-noise`).
    pub no_noise: bool,
    pub progress: bool,
    /// Replace an earlier output of another iscene command at `out` (`--force`).
    pub force: bool,
    /// Written to `gt/spec.fingerprint`: lets `reconstruct` reuse the rendering of an unchanged
    /// specification.
    pub fingerprint: Option<String>,
}

#[derive(Clone, Debug)]
pub struct RenderSummary {
    pub dir: PathBuf,
    pub frames: usize,
    pub objects: usize,
    pub triangles: usize,
    pub seconds: f64,
}

/// One rendered frame in memory.
pub struct RenderedFrame {
    pub color: Vec<u8>,
    pub depth: Vec<f32>,
    pub labels: Vec<u16>,
}

/// The noise models in force, written to `gt/render.json` so the oracle segmenter applies the
/// same segmentation noise the specification asked for.
#[derive(Serialize)]
struct RenderRecord<'a> {
    scene: &'a str,
    seed: u64,
    frames: usize,
    camera: Pinhole,
    depth_noise: Option<DepthNoise>,
    segmentation_noise: Option<SegmentationNoise>,
    /// The pose noise of the written `pose.txt` files (the frames are rendered from true poses).
    pose_noise: Option<PoseNoise>,
}

/// Renders frame `k` of a sequence: rasterise, shade, and pass depth through `noise`.
pub fn render_frame(
    scene: &RenderScene,
    camera: &Pinhole,
    world_from_camera: &Affine3A,
    noise: Option<&DepthNoise>,
    seed: u64,
    k: usize,
) -> RenderedFrame {
    let camera_from_world = world_from_camera.inverse();
    let raster = rasterize(scene, camera, &camera_from_world);
    let color = shade(scene, &raster, world_from_camera);
    let labels: Vec<u16> = raster
        .triangle
        .iter()
        .map(|&t| {
            if t == NO_TRIANGLE {
                0
            } else {
                scene.instances[t as usize]
            }
        })
        .collect();
    let mut depth = raster.depth.clone();
    if let Some(model) = noise {
        let w = camera.width as usize;
        let cos_incidence: Vec<f32> = raster
            .triangle
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                if t == NO_TRIANGLE {
                    return 0.0;
                }
                let ray = camera
                    .unproject((i % w) as f32, (i / w) as f32, 1.0)
                    .normalize();
                let normal = camera_from_world.transform_vector3(scene.normals[t as usize]);
                normal.dot(ray).abs()
            })
            .collect();
        let mut rng = ChaCha8Rng::seed_from_u64(stable_hash(seed, &format!("depth-{k}")));
        model.apply(&mut depth, &cos_incidence, w, camera.fx, &mut rng);
    }
    RenderedFrame {
        color,
        depth,
        labels,
    }
}

fn frame_path(dir: &Path, k: usize, suffix: &str) -> PathBuf {
    dir.join(format!("frame-{k:06}.{suffix}"))
}

/// Renders `spec` into the sequence folder `out` (replaced as a whole when complete).
pub fn render_sequence(
    spec: &SceneSpec,
    spec_path: &Path,
    out: &Path,
    options: &RenderOptions,
) -> Result<RenderSummary, IsceneError> {
    let start = Instant::now();
    let mut inputs: Vec<&Path> = vec![spec_path];
    inputs.extend(spec.databases.iter().map(|db| db.dir.as_path()));
    let target = OutputTarget::claim("--out", out, OutputCommand::Render, &inputs, options.force)?;
    let world = SceneWorld::from_spec(spec, spec_path)?;
    let scene = world.render_scene();
    let camera = Pinhole::KINECT;
    let frames = options
        .frames
        .or(spec.camera.frames)
        .unwrap_or(DEFAULT_FRAMES);
    crate::scene::spec::check_frame_count(frames)
        .map_err(|e| InputError::invalid("--frames", e))?;
    let poses = room_loop(
        world.room_size,
        frames,
        spec.camera.height.unwrap_or(DEFAULT_CAMERA_HEIGHT),
    );
    let noise = if options.no_noise {
        NoiseSettings::off()
    } else {
        spec.noise.clone()
    };
    let depth_noise = noise.depth_model();
    let pose_noise = noise.pose_model();
    let reported_poses = match &pose_noise {
        Some(model) => model.apply(&poses, spec.seed),
        None => poses.clone(),
    };

    let staged = StagedDir::new(&target)?;
    let dir = staged.path().to_path_buf();
    write_camera(&dir, &camera, 1000.0)?;
    write_text(&dir.join("gravity-direction.txt"), "0 0 -1\n")?;
    write_text(&dir.join("labels.json"), &pretty_json(&world.labels()))?;
    let gt = dir.join("gt");
    let meshes = gt.join("meshes");
    std::fs::create_dir_all(&meshes)
        .map_err(|e| IsceneError::io(format!("creating {}", meshes.display()), e))?;
    write_text(
        &gt.join("contact_graph.json"),
        &world.contact_graph().to_json(),
    )?;
    world.write_own_models(&gt)?;
    for (id, mesh, color) in world.entity_meshes() {
        let bytes = mesh_ply_bytes(&mesh, color)
            .map_err(|e| IsceneError::Internal(format!("PLY of {id}: {e}")))?;
        std::fs::write(meshes.join(format!("{id}.ply")), bytes)
            .map_err(|e| IsceneError::io(format!("writing mesh of {id}"), e))?;
    }
    let record = RenderRecord {
        scene: &spec.name,
        seed: spec.seed,
        frames,
        camera,
        depth_noise,
        segmentation_noise: noise.segmentation_model(),
        pose_noise,
    };
    write_text(&gt.join("render.json"), &pretty_json(&record))?;
    if let Some(fingerprint) = &options.fingerprint {
        write_text(&gt.join("spec.fingerprint"), fingerprint)?;
    }

    let progress = crate::progress::bar(frames as u64, "rendering", options.progress);
    poses.par_iter().enumerate().try_for_each(
        |(k, world_from_camera)| -> Result<(), IsceneError> {
            let f = render_frame(
                &scene,
                &camera,
                world_from_camera,
                depth_noise.as_ref(),
                spec.seed,
                k,
            );
            write_color(&frame_path(&dir, k, "color.png"), &f.color, &camera)?;
            write_depth(&frame_path(&dir, k, "depth.png"), &f.depth, &camera)?;
            write_labels(&frame_path(&dir, k, "label.png"), &f.labels, &camera)?;
            write_text(
                &frame_path(&dir, k, "pose.txt"),
                &pose_text(&reported_poses[k]),
            )?;
            progress.inc(1);
            Ok(())
        },
    )?;
    progress.finish_and_clear();
    let dir = staged.commit()?;
    Ok(RenderSummary {
        dir,
        frames,
        objects: world.objects.len(),
        triangles: scene.len(),
        seconds: start.elapsed().as_secs_f64(),
    })
}

fn pretty_json(value: &impl Serialize) -> String {
    // Plain records of strings and finite numbers: serialisation cannot fail.
    serde_json::to_string_pretty(value).unwrap_or_default()
}

/// Which instances a frame sees, with their pixel counts.
pub fn visible_instances(labels: &[u16]) -> std::collections::BTreeMap<u16, usize> {
    let mut counts = std::collections::BTreeMap::new();
    for &l in labels {
        if l != 0 {
            *counts.entry(l).or_default() += 1;
        }
    }
    counts
}
