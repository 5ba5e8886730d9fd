//! Gravity from the map of a real room, without being told: 7-Scenes redkitchen's estimated up
//! direction agrees with the dataset's gravity file.

use crate::common;

use iscene::graph::gravity::{angle_deg, camera_up_hint, estimate_up};
use iscene::io::Sequence;
use iscene::map::{TsdfFrame, TsdfMap, extract_mesh};

#[test]
fn redkitchen_gravity_is_estimated_within_two_degrees() {
    let root = common::shared_data("rgbd/7scenes-redkitchen");
    let mut sequence = Sequence::open(&root).expect("sequence");
    let given = sequence.gravity.expect("the dataset's gravity file");
    sequence.select(0, Some(1000), 10);
    let mut map = TsdfMap::new(0.03);
    for i in 0..sequence.frames.len() {
        let f = sequence.load_frame(i).expect("frame");
        map.integrate(&TsdfFrame {
            depth: &f.depth,
            color: &[],
            labels: None,
            label_gains: None,
            camera: &f.camera,
            world_from_camera: &f.world_from_camera,
        });
    }
    let mesh = extract_mesh(&map, 1.0).mesh;
    let hint = camera_up_hint(sequence.frames.iter().map(|f| f.world_from_camera)).expect("hint");
    let up = estimate_up(&mesh, hint).expect("up");
    let error = angle_deg(up, -given);
    eprintln!(
        "hint {:.1} deg off, estimate {error:.2} deg off",
        angle_deg(hint, -given)
    );
    assert!(
        error < 2.0,
        "estimated up is {error:.2} degrees from the gravity file"
    );
}
