//! Rendered sequences know their truth: depth back-projects onto the ground-truth meshes, the
//! default camera path sees every object, noise follows its model, and a seed fixes every byte.

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;

use glam::{Affine3A, Vec3};
use iscene::geometry::point_triangle::closest_point_on_triangle;
use iscene::geometry::{Pinhole, TriMesh};
use iscene::io::Sequence;
use iscene::io::ply::read_mesh_ply;
use iscene::render::render_scene::RenderScene;
use iscene::render::trajectory::room_loop;
use iscene::render::{DepthNoise, rasterize};
use iscene::scene::render_sequence::{
    DEFAULT_CAMERA_HEIGHT, DEFAULT_FRAMES, render_frame, visible_instances,
};
use iscene::scene::{SceneSpec, SceneWorld, Support};

fn world_of(spec_path: &Path) -> (SceneSpec, SceneWorld) {
    let spec = SceneSpec::load(spec_path).expect("spec parses");
    let world = SceneWorld::from_spec(&spec, spec_path).expect("world builds");
    (spec, world)
}

#[test]
fn every_spec_has_enough_objects_stacked_and_articulated_ones() {
    let specs = common::scene_specs();
    for name in ["kitchen", "office", "living_room", "bedroom"] {
        assert!(
            specs
                .iter()
                .any(|p| p.file_stem().is_some_and(|s| s == name)),
            "scenes/{name}.json missing"
        );
    }
    for path in specs {
        let (_, world) = world_of(&path);
        assert!(
            world.objects.len() >= 8,
            "{}: {} objects",
            path.display(),
            world.objects.len()
        );
        assert!(
            world
                .objects
                .iter()
                .any(|o| matches!(o.support, Support::OnObject(_))),
            "{}: nothing stands on anything",
            path.display()
        );
        assert!(
            world.objects.iter().any(|o| o.model.is_articulated()),
            "{}: nothing articulated",
            path.display()
        );
    }
}

#[test]
fn the_default_trajectory_sees_every_object_and_occludes_some() {
    for path in common::scene_specs() {
        let (spec, world) = world_of(&path);
        let scene = world.render_scene();
        let poses = room_loop(
            world.room_size,
            spec.camera.frames.unwrap_or(DEFAULT_FRAMES),
            spec.camera.height.unwrap_or(DEFAULT_CAMERA_HEIGHT),
        );
        let camera = Pinhole::KINECT;
        // Frames in which each instance covers at least 50 pixels.
        let mut frames_seen: BTreeMap<u16, usize> = BTreeMap::new();
        for pose in poses.iter().step_by(3) {
            let raster = rasterize(&scene, &camera, &pose.inverse());
            let labels: Vec<u16> = raster
                .triangle
                .iter()
                .map(|&t| {
                    if t == u32::MAX {
                        0
                    } else {
                        scene.instances[t as usize]
                    }
                })
                .collect();
            for (id, n) in visible_instances(&labels) {
                if n >= 50 {
                    *frames_seen.entry(id).or_default() += 1;
                }
            }
        }
        for o in &world.objects {
            if matches!(o.support, Support::InObject(_)) {
                // Inside a closed container: hidden by design (the robot opens it in simulation).
                continue;
            }
            let seen = frames_seen.get(&o.instance).copied().unwrap_or(0);
            assert!(
                seen >= 3,
                "{}: {} is seen in only {seen} of {} sampled frames",
                path.display(),
                o.id,
                poses.len() / 3
            );
        }
        // Partly occluded objects: in at least three quarters of the views that would show them,
        // other objects hide a tenth of them or more.
        let partly_occluded: Vec<&str> = world
            .objects
            .iter()
            .filter(|o| !matches!(o.support, Support::InObject(_)))
            .filter(|o| {
                let alone = only_instance(&scene, o.instance);
                let (mut views, mut occluded) = (0, 0);
                for pose in poses.iter().step_by(10) {
                    let full = rasterize(&scene, &camera, &pose.inverse());
                    let solo = rasterize(&alone, &camera, &pose.inverse());
                    let visible = full
                        .triangle
                        .iter()
                        .filter(|&&t| t != u32::MAX && scene.instances[t as usize] == o.instance)
                        .count();
                    let silhouette = solo.triangle.iter().filter(|&&t| t != u32::MAX).count();
                    if silhouette > 0 {
                        views += 1;
                        occluded += usize::from((visible as f32) < 0.9 * silhouette as f32);
                    }
                }
                views > 0 && 4 * occluded >= 3 * views
            })
            .map(|o| o.id.as_str())
            .collect();
        assert!(
            !partly_occluded.is_empty(),
            "{}: no object is partly occluded in every view",
            path.display()
        );
    }
}

/// The triangles of one instance only.
fn only_instance(scene: &RenderScene, instance: u16) -> RenderScene {
    let mut out = RenderScene::default();
    for t in (0..scene.len()).filter(|&t| scene.instances[t] == instance) {
        out.corners.push(scene.corners[t]);
        out.normals.push(scene.normals[t]);
        out.instances.push(instance);
        out.colors.push(scene.colors[t]);
        out.surfaces.push(scene.surfaces[t]);
    }
    out
}

#[test]
fn back_projected_depth_lands_on_the_ground_truth_meshes() {
    let dir = tempfile::tempdir().expect("tempdir");
    let seq_dir = dir.path().join("kitchen");
    common::render_scene("kitchen", &seq_dir, 12, true);
    let sequence = Sequence::open(&seq_dir).expect("the rendered sequence reads back");
    assert_eq!(sequence.frames.len(), 12);
    assert_eq!(sequence.gravity, Some(Vec3::new(0.0, 0.0, -1.0)));
    let labels = sequence.labels.clone().expect("labels.json");
    let meshes: BTreeMap<u16, TriMesh> = labels
        .by_instance()
        .into_iter()
        .map(|(id, e)| {
            (
                id,
                read_mesh_ply(&seq_dir.join("gt/meshes").join(format!("{}.ply", e.entity)))
                    .expect("gt mesh"),
            )
        })
        .collect();
    let mut errors = Vec::new();
    for i in 0..sequence.frames.len() {
        let frame = sequence.load_frame(i).expect("frame loads");
        let frame_labels = frame.labels.as_ref().expect("label image");
        let w = frame.camera.width as usize;
        for p in (0..frame.depth.len()).step_by(97) {
            let (d, l) = (frame.depth[p], frame_labels[p]);
            if d == 0.0 || l == 0 {
                continue;
            }
            let point = frame
                .world_from_camera
                .transform_point3(frame.camera.unproject((p % w) as f32, (p / w) as f32, d));
            let mesh = &meshes[&l];
            let dist = (0..mesh.triangles.len())
                .map(|t| point.distance(closest_point_on_triangle(point, mesh.triangle(t))))
                .fold(f32::INFINITY, f32::min);
            errors.push(dist);
        }
    }
    assert!(errors.len() > 500, "only {} samples", errors.len());
    errors.sort_by(f32::total_cmp);
    let median = errors[errors.len() / 2];
    let p95 = errors[errors.len() * 95 / 100];
    eprintln!(
        "back-projection error over {} samples: median {median:.6} m, 95th percentile {p95:.6} m",
        errors.len()
    );
    assert!(median < 0.002, "median back-projection error {median} m");
    assert!(p95 < 0.005, "95th percentile {p95} m");
}

#[test]
fn depth_noise_statistics_follow_the_model() {
    let (_, world) = world_of(&common::root().join("scenes/kitchen.json"));
    let scene = world.render_scene();
    let camera = Pinhole::KINECT;
    let model = DepthNoise::KINECT;
    let poses: Vec<Affine3A> = room_loop(world.room_size, 40, DEFAULT_CAMERA_HEIGHT);
    // Per 0.5 m depth bin: (noisy - clean, clean) over pixels that kept a measurement.
    let mut bins: BTreeMap<usize, Vec<(f32, f32)>> = BTreeMap::new();
    let (mut kept, mut in_range, mut beyond_range_kept) = (0usize, 0usize, 0usize);
    for (k, pose) in poses.iter().enumerate() {
        let clean = render_frame(&scene, &camera, pose, None, 7, k);
        let noisy = render_frame(&scene, &camera, pose, Some(&model), 7, k);
        for (c, n) in clean.depth.iter().zip(&noisy.depth) {
            if *c <= 0.0 {
                continue;
            }
            if *c < model.min_range || *c > model.max_range {
                beyond_range_kept += usize::from(*n > 0.0);
                continue;
            }
            in_range += 1;
            if *n > 0.0 {
                kept += 1;
                bins.entry((*c / 0.5) as usize)
                    .or_default()
                    .push((n - c, *c));
            }
        }
    }
    assert_eq!(
        beyond_range_kept, 0,
        "measurements outside the range limits must drop out"
    );
    let dropout = 1.0 - kept as f32 / in_range as f32;
    eprintln!("dropout fraction within range: {dropout:.4}");
    assert!(
        (0.005..0.2).contains(&dropout),
        "dropout fraction {dropout}"
    );
    let mut checked = 0;
    for (bin, errs) in &bins {
        if errs.len() < 20_000 {
            continue;
        }
        let z = (*bin as f32 + 0.5) * 0.5;
        let n = errs.len() as f64;
        let mean = (errs.iter().map(|(e, _)| f64::from(*e)).sum::<f64>() / n) as f32;
        let std = (errs
            .iter()
            .map(|(e, _)| f64::from(e - mean).powi(2))
            .sum::<f64>()
            / n)
            .sqrt() as f32;
        // The model's variance at each pixel's own depth: axial noise plus uniform quantisation.
        let variance = |z: f32| {
            let q = model.quantisation_step(z, camera.fx);
            f64::from(model.axial_sigma(z).powi(2) + q * q / 12.0)
        };
        let expected = (errs.iter().map(|(_, z)| variance(*z)).sum::<f64>() / n).sqrt() as f32;
        eprintln!(
            "depth {z:.2} m: {} pixels, std {std:.5} m (model {expected:.5}), bias {mean:+.5} m",
            errs.len()
        );
        assert!(
            (std / expected - 1.0).abs() < 0.05,
            "depth {z} m: std {std} vs model {expected}"
        );
        assert!(
            mean.abs() < 0.25 * expected + 0.0005,
            "depth {z} m: bias {mean}"
        );
        checked += 1;
    }
    assert!(checked >= 3, "only {checked} depth bins had enough pixels");
}

#[test]
fn rendering_twice_with_one_seed_gives_identical_files() {
    let dir = tempfile::tempdir().expect("tempdir");
    common::render_scene("kitchen", &dir.path().join("a"), 6, false);
    common::render_scene("kitchen", &dir.path().join("b"), 6, false);
    let a = common::hash_tree(&dir.path().join("a"));
    let b = common::hash_tree(&dir.path().join("b"));
    assert_eq!(
        a.len(),
        // 4 files a frame, 6 of the sequence, 22 true meshes, and gt/cad with the one model
        // the library does not hold as it is (box_1: box_01 made 14 x 10 x 16 cm).
        6 * 4 + 6 + 22 + 3,
        "files written: {:?}",
        a.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    assert_eq!(a, b);
}

#[test]
fn every_spec_renders_through_the_cli() {
    let dir = tempfile::tempdir().expect("tempdir");
    for spec in common::scene_specs() {
        let out = dir.path().join(spec.file_stem().expect("stem"));
        let (code, stdout, stderr) = common::iscene(
            &[
                "render",
                spec.to_str().expect("utf8"),
                "--out",
                out.to_str().expect("utf8"),
                "--frames",
                "3",
            ],
            &common::root(),
        );
        assert_eq!(code, 0, "{}: {stdout}{stderr}", spec.display());
        let graph = iscene::graph::ContactGraph::load(&out.join("gt/contact_graph.json"))
            .expect("gt graph");
        assert!(graph.support_edges().count() >= 8);
        assert!(out.join("frame-000002.depth.png").is_file());
    }
}
