//! The three real layouts read as they are: 7-Scenes (native), Open3D's trajectory.log, TUM.

use crate::common;

use std::path::Path;

use glam::Vec3;
use iscene::io::Sequence;
use iscene::io::sequence::SequenceFormat;

fn median_valid(depth: &[f32]) -> f32 {
    let mut v: Vec<f32> = depth.iter().copied().filter(|&d| d > 0.0).collect();
    v.sort_by(f32::total_cmp);
    v[v.len() / 2]
}

#[test]
fn seven_scenes_redkitchen_reads_as_is_with_its_gravity() {
    let root = common::shared_data("rgbd/7scenes-redkitchen");
    let seq = Sequence::open(&root).expect("7-Scenes opens");
    assert_eq!(seq.format, SequenceFormat::Native);
    assert_eq!(seq.frames.len(), 1000);
    assert_eq!(
        (
            seq.camera.width,
            seq.camera.height,
            seq.camera.fx,
            seq.camera.cx
        ),
        (640, 480, 585.0, 320.0)
    );
    let g = seq.gravity.expect("gravity-direction.txt");
    assert!(
        (g - Vec3::new(-0.0089, 0.9044, 0.4265).normalize()).length() < 1e-3,
        "gravity {g}"
    );
    let frame = seq.load_frame(500).expect("frame 500");
    let m = median_valid(&frame.depth);
    assert!((0.5..4.0).contains(&m), "median depth {m} m");
    assert_eq!(frame.color.len(), 640 * 480 * 3);
    // Consecutive 30 Hz poses of a handheld camera are a few centimetres apart.
    let step = Vec3::from(seq.frames[501].world_from_camera.translation)
        .distance(seq.frames[500].world_from_camera.translation.into());
    assert!(step < 0.1, "camera moved {step} m between frames");
}

#[test]
fn open3d_trajectory_log_layout_reads_with_its_camera_json() {
    let root = common::shared_data("rgbd/formats/RGBD");
    let seq = Sequence::open(&root).expect("trajectory.log layout opens");
    assert_eq!(seq.format, SequenceFormat::Open3dLog);
    assert_eq!(seq.frames.len(), 5);
    assert_eq!(
        (seq.camera.fx, seq.camera.cx, seq.camera.cy),
        (525.0, 319.5, 239.5)
    );
    let t = seq.frames[0].world_from_camera.translation;
    assert!(
        (Vec3::from(t) - Vec3::new(-0.3106, 0.5730, 2.1265)).length() < 1e-3,
        "first pose {t}"
    );
    for i in 0..5 {
        let f = seq.load_frame(i).expect("frame loads");
        let m = median_valid(&f.depth);
        assert!((0.3..6.0).contains(&m), "frame {i}: median depth {m}");
    }
}

/// Builds a TUM folder around the one TUM frame in the shared data.
fn tum_folder(dir: &Path) {
    let other = common::shared_data("rgbd/formats/RGBD/other_formats");
    std::fs::create_dir_all(dir.join("rgb")).expect("mkdir");
    std::fs::create_dir_all(dir.join("depth")).expect("mkdir");
    std::fs::copy(
        other.join("TUM_color.png"),
        dir.join("rgb/1305031102.175304.png"),
    )
    .expect("copy");
    std::fs::copy(
        other.join("TUM_depth.png"),
        dir.join("depth/1305031102.160407.png"),
    )
    .expect("copy");
    std::fs::write(
        dir.join("rgb.txt"),
        "# color images\n# timestamp filename\n1305031102.175304 rgb/1305031102.175304.png\n",
    )
    .expect("write");
    std::fs::write(
        dir.join("depth.txt"),
        "# depth maps\n1305031102.160407 depth/1305031102.160407.png\n",
    )
    .expect("write");
    std::fs::write(dir.join("groundtruth.txt"), "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n1305031102.1600 1.3405 0.6266 1.6575 0.6574 0.6126 -0.2949 -0.3248\n").expect("write");
}

#[test]
fn tum_folders_associate_by_timestamp_and_scale_depth_by_5000() {
    let dir = tempfile::tempdir().expect("tempdir");
    let root = dir.path().join("rgbd_dataset_freiburg1_xyz");
    tum_folder(&root);
    let seq = Sequence::open(&root).expect("TUM opens");
    assert_eq!(seq.format, SequenceFormat::Tum);
    assert_eq!(seq.depth_scale, 5000.0);
    assert_eq!(seq.frames.len(), 1);
    assert_eq!(
        seq.camera.fx, 517.3,
        "freiburg1 calibration from the folder name"
    );
    let f = seq.load_frame(0).expect("frame loads");
    let m = median_valid(&f.depth);
    assert!((0.3..5.0).contains(&m), "median depth {m} m");
}

#[test]
fn the_native_reader_refuses_bit_shifted_sun_rgbd_depth() {
    // SUN RGB-D's depth PNG rotates its bits: read as millimetres it is not a room.
    let dir = tempfile::tempdir().expect("tempdir");
    let other = common::shared_data("rgbd/formats/RGBD/other_formats");
    std::fs::copy(
        other.join("SUN_depth.png"),
        dir.path().join("frame-000000.depth.png"),
    )
    .expect("copy");
    std::fs::copy(
        other.join("SUN_color.jpg"),
        dir.path().join("frame-000000.color.jpg"),
    )
    .expect("copy");
    std::fs::write(
        dir.path().join("frame-000000.pose.txt"),
        "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n",
    )
    .expect("write");
    std::fs::write(
        dir.path().join("camera-intrinsics.txt"),
        "518 0 320\n0 518 240\n0 0 1\n",
    )
    .expect("write");
    let seq = Sequence::open(dir.path()).expect("folder opens");
    let err = seq
        .load_frame(0)
        .expect_err("implausible depth")
        .to_string();
    assert!(
        err.contains("frame-000000.depth.png") && err.contains("depth scale"),
        "{err}"
    );
}
