//! Rendering speed: one 640x480 frame of the kitchen in memory, and the 300-frame kitchen
//! sequence written to disk as `iscene render` does (goal: under 10 s on 2 cores).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use iscene::geometry::Pinhole;
use iscene::render::shading::shade;
use iscene::render::trajectory::room_loop;
use iscene::render::{DepthNoise, rasterize};
use iscene::scene::render_sequence::{DEFAULT_CAMERA_HEIGHT, render_frame};
use iscene::scene::{RenderOptions, render_sequence};
use iscene::scene::{SceneSpec, SceneWorld};
use rand::SeedableRng;

fn kitchen() -> SceneSpec {
    SceneSpec::parse(iscene::BUILTIN_KITCHEN, Path::new("scenes/kitchen.json"))
        .expect("kitchen spec")
}

fn one_frame(c: &mut Criterion) {
    let spec = kitchen();
    let world = SceneWorld::from_spec(&spec, Path::new("kitchen.json")).expect("world");
    let scene = world.render_scene();
    let poses = room_loop(world.room_size, 300, DEFAULT_CAMERA_HEIGHT);
    let camera = Pinhole::KINECT;
    let pose = poses[40];
    c.bench_function("rasterize_640x480", |b| {
        b.iter(|| rasterize(&scene, &camera, &pose.inverse()))
    });
    let raster = rasterize(&scene, &camera, &pose.inverse());
    c.bench_function("shade_640x480", |b| {
        b.iter(|| shade(&scene, &raster, &pose))
    });
    let cos_incidence = vec![0.9f32; camera.pixel_count()];
    c.bench_function("kinect_depth_noise_640x480", |b| {
        b.iter(|| {
            let mut depth = raster.depth.clone();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
            DepthNoise::KINECT.apply(&mut depth, &cos_incidence, 640, camera.fx, &mut rng);
            depth
        })
    });
    let mut k = 0;
    c.bench_function("render_frame_640x480_with_kinect_noise", |b| {
        b.iter(|| {
            k = (k + 1) % poses.len();
            render_frame(
                &scene,
                &Pinhole::KINECT,
                &poses[k],
                Some(&DepthNoise::KINECT),
                7,
                k,
            )
        })
    });
}

fn whole_sequence(c: &mut Criterion) {
    let spec = kitchen();
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("kitchen");
    let mut group = c.benchmark_group("render_sequence");
    group.sample_size(10);
    group.bench_function("kitchen_300_frames_to_disk", |b| {
        b.iter(|| {
            render_sequence(
                &spec,
                Path::new("kitchen.json"),
                &out,
                &RenderOptions {
                    frames: Some(300),
                    no_noise: false,
                    progress: false,
                    ..Default::default()
                },
            )
            .expect("render")
        })
    });
    group.finish();
}

criterion_group!(benches, one_frame, whole_sequence);
criterion_main!(benches);
