//! The viewer (issue 9), built with `--features viewer` and run off screen on Mesa's software
//! Vulkan driver (lavapipe; scripts/setup-viewer.sh installs it): a screenshot of the rendered
//! kitchen is a picture of the kitchen (not blank, many colours), an opened fridge door and each
//! layer change the picture, and a click on the fridge door through Bevy's input opens it.
#![cfg(feature = "viewer")]

use std::path::{Path, PathBuf};

use crate::common;

use bevy::input::ButtonState;
use bevy::input::keyboard::{Key, KeyboardInput};
use bevy::input::mouse::MouseButtonInput;
use bevy::prelude::*;
use bevy::window::CursorMoved;
use iscene::components::Joint;
use iscene::viewer::{
    ActiveLayers, DragPreview, Layer, Motion, NodeLabel, ReplayClock, ReplayLabel, TaskPlayer,
    ViewOptions, ViewerStatus, render_offscreen, replay_app, viewer_app,
};

fn kitchen_truth(dir: &Path) -> PathBuf {
    let seq = dir.join("seq");
    common::render_scene("kitchen", &seq, 2, true);
    seq.join("gt")
}

/// `iscene view GT --screenshot OUT ...extra`, asserting success; the picture as RGB.
fn screenshot(gt: &Path, out: &Path, extra: &[&str]) -> image::RgbImage {
    let mut args = vec![
        "view",
        gt.to_str().expect("utf8"),
        "--screenshot",
        out.to_str().expect("utf8"),
        "--size",
        "480x360",
    ];
    args.extend_from_slice(extra);
    let (code, stdout, stderr) = common::iscene(&args, &common::root());
    assert_eq!(code, 0, "{stdout}{stderr}");
    image::open(out).expect("a PNG").to_rgb8()
}

/// Share of pixels that are not the clear colour.
fn coverage(picture: &image::RgbImage) -> f64 {
    let background = image::Rgb([237u8, 240, 245]);
    let scene = picture
        .pixels()
        .filter(|p| {
            p.0.iter()
                .zip(background.0)
                .any(|(x, y)| x.abs_diff(y) > 12)
        })
        .count();
    scene as f64 / (picture.width() * picture.height()) as f64
}

/// Share of pixels that differ between two pictures by more than a rounding step.
fn changed_fraction(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let changed = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 8))
        .count();
    changed as f64 / (a.width() * a.height()) as f64
}

#[test]
fn a_screenshot_of_the_kitchen_shows_the_kitchen_and_changes_with_doors_and_layers() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let plain = screenshot(&gt, &dir.path().join("colour.png"), &[]);
    assert_eq!(plain.dimensions(), (480, 360));

    // Not blank: most pixels are scene, not the clear colour, in many distinct colours.
    let covered = coverage(&plain);
    assert!(covered > 0.5, "scene covers {covered:.2} of the picture");
    let mut colours: Vec<[u8; 3]> = plain.pixels().map(|p| p.0.map(|c| c / 16)).collect();
    colours.sort_unstable();
    colours.dedup();
    assert!(colours.len() > 40, "{} colours", colours.len());
    let luma: Vec<f64> = plain
        .pixels()
        .map(|p| 0.299 * p.0[0] as f64 + 0.587 * p.0[1] as f64 + 0.114 * p.0[2] as f64)
        .collect();
    let mean = luma.iter().sum::<f64>() / luma.len() as f64;
    let sd = (luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luma.len() as f64).sqrt();
    assert!(sd > 15.0, "luma standard deviation {sd:.1}");

    // The same picture twice: rendering is deterministic.
    let again = screenshot(&gt, &dir.path().join("again.png"), &[]);
    assert!(changed_fraction(&plain, &again) < 0.001);

    let opened = screenshot(&gt, &dir.path().join("open.png"), &["--open", "fridge_1"]);
    let by_door = changed_fraction(&plain, &opened);
    assert!(by_door > 0.01, "opening the fridge changed {by_door:.4}");

    for layer in [
        "segments",
        "boxes",
        "graph",
        "planes",
        "collision",
        "occupancy",
        "physics",
    ] {
        let shown = screenshot(
            &gt,
            &dir.path().join(format!("{layer}.png")),
            &["--layer", layer],
        );
        let changed = changed_fraction(&plain, &shown);
        assert!(changed > 0.005, "layer {layer} changed {changed:.4}");
    }
}

/// The viewer's app on `gt` rendering off screen into a `size` image, ready to update, with
/// `task` loaded when given.
fn offscreen_viewer(gt: PathBuf, size: (u32, u32), task: Option<PathBuf>) -> App {
    offscreen_app(&ViewOptions {
        task,
        ..view_options(gt, size)
    })
}

/// The viewer's options for `dir` off screen in a `size` image, everything else at its default.
fn view_options(dir: PathBuf, size: (u32, u32)) -> ViewOptions {
    ViewOptions {
        dir,
        screenshot: None,
        layers: Vec::new(),
        frames: 1,
        size,
        open: Vec::new(),
        replay: false,
        shots: 1,
        task: None,
        robot: None,
        live: false,
    }
}

/// The viewer's app for `options`, rendering off screen, ready to update.
fn offscreen_app(options: &ViewOptions) -> App {
    let size = options.size;
    let mut app = viewer_app(options, true).expect("viewer app");
    render_offscreen(&mut app, size);
    app.finish();
    app.cleanup();
    app
}

#[test]
fn a_click_on_the_fridge_door_through_bevy_input_opens_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let mut app = offscreen_viewer(gt, (480, 360), None);
    // A twentieth of a second per frame, however slow software rendering is.
    app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        std::time::Duration::from_millis(50),
    ));
    for _ in 0..3 {
        app.update();
    }
    let door = |app: &mut App| {
        app.world_mut()
            .query::<(&Name, &Joint, &Transform)>()
            .iter(app.world())
            .find(|(n, _, _)| n.as_str() == "fridge_1_door")
            .map(|(_, j, t)| (j.value, *t))
            .expect("the fridge door")
    };
    let (closed, closed_at) = door(&mut app);
    assert_eq!(closed, 0.0);
    // Where the door's middle shows on the picture.
    let centre = {
        let world = app.world_mut();
        world
            .query::<(&Name, &GlobalTransform, &iscene::components::LinkBody)>()
            .iter(world)
            .find(|(n, _, _)| n.as_str() == "fridge_1_door")
            .map(|(_, t, body)| {
                // Low on the door: its top is out of the picture.
                let (lo, hi) = body.0.visual.bounds().expect("door mesh");
                let low = (lo + hi) / 2.0;
                t.transform_point(low.with_z(lo.z + 0.15 * (hi.z - lo.z)))
            })
            .expect("door")
    };
    let middle = pixel_of(&mut app, centre);
    assert!(
        (0.0..480.0).contains(&middle.x) && (0.0..360.0).contains(&middle.y),
        "the door shows at {middle}"
    );
    let window = Entity::PLACEHOLDER;
    app.world_mut().write_message(CursorMoved {
        window,
        position: middle,
        delta: None,
    });
    let click = |app: &mut App| {
        for state in [ButtonState::Pressed, ButtonState::Released] {
            app.world_mut().write_message(MouseButtonInput {
                button: MouseButton::Left,
                state,
                window,
            });
            app.update();
        }
    };
    click(&mut app);
    let (opened, _) = door(&mut app);
    let status = app
        .world()
        .resource::<iscene::viewer::ViewerStatus>()
        .0
        .clone();
    assert!(
        opened > 0.5,
        "the door opened to {opened}: {status:?} (clicked at {middle})"
    );
    assert!(status[0].starts_with("opened fridge_1_door"), "{status:?}");
    // The rest test ran on the changed scene (the physics layer and the panel show it).
    let verdicts = app.world().resource::<iscene::viewer::RestVerdicts>();
    assert_eq!(verdicts.revision, Some(1));
    let report = verdicts.report.as_ref().expect("a rest test");
    assert!(
        report.objects.iter().any(|o| o.object == "fridge_1"),
        "{:?}",
        report.objects
    );

    // The door is shown swinging open; a second click while it swings closes it. The swing
    // ends first, so once the closing motion is over the door stands exactly where it started.
    let running = |app: &App| {
        app.world()
            .resource::<iscene::viewer::Motion>()
            .is_running()
    };
    assert!(running(&app), "the door is shown swinging");
    click(&mut app);
    for _ in 0..100 {
        if !running(&app) {
            break;
        }
        app.update();
    }
    let (value, at) = door(&mut app);
    assert_eq!(value, closed);
    assert!(
        at.translation.distance(closed_at.translation) < 1e-4
            && at.rotation.angle_between(closed_at.rotation) < 1e-4,
        "closed again at {at:?}, started at {closed_at:?}"
    );
}

/// The kitchen rendered with `frames` frames and reconstructed into `dir/out`.
fn reconstructed_kitchen(dir: &Path, frames: usize) -> PathBuf {
    let seq = dir.join("seq");
    common::render_scene("kitchen", &seq, frames, true);
    let out = dir.join("out");
    let (code, stdout, stderr) = common::iscene(
        &[
            "reconstruct",
            seq.to_str().expect("utf8"),
            "--out",
            out.to_str().expect("utf8"),
        ],
        &common::root(),
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    out
}

#[test]
fn a_replay_grows_the_map_along_the_camera_path() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = reconstructed_kitchen(dir.path(), 24);

    // The timeline: the sensor saw the room bit by bit, not all at the first or last frame.
    let replay = iscene::replay::load_replay(&out).expect("replay");
    assert_eq!(replay.frames(), 24);
    let triangles: Vec<u32> = replay
        .segments
        .iter()
        .flat_map(|s| s.revealed_at.iter().copied())
        .collect();
    let share = |pred: &dyn Fn(u32) -> bool| {
        triangles.iter().filter(|&&t| pred(t)).count() as f64 / triangles.len() as f64
    };
    let at_start = share(&|t| t == 0);
    let before_end = share(&|t| t < 23);
    assert!(
        at_start > 0.02 && at_start < 0.5,
        "{at_start:.2} of the map seen in the first frame"
    );
    assert!(
        before_end > 0.9,
        "{before_end:.2} of the map seen before the last frame"
    );
    assert!(replay.nodes.iter().all(|n| n.appears_at < 24));
    assert!(replay.support_edges_at(0).len() < replay.support_edges_at(23).len());

    // Four pictures from the first frame to the last: the map grows and every picture differs.
    let (code, stdout, stderr) = common::iscene(
        &[
            "view",
            out.to_str().expect("utf8"),
            "--replay",
            "--screenshot",
            dir.path().join("replay.png").to_str().expect("utf8"),
            "--shots",
            "4",
            "--size",
            "320x240",
        ],
        &common::root(),
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    let shots: Vec<image::RgbImage> = (0..4)
        .map(|k| {
            image::open(dir.path().join(format!("replay_{k:02}.png")))
                .expect("a PNG per shot")
                .to_rgb8()
        })
        .collect();
    let covered: Vec<f64> = shots.iter().map(coverage).collect();
    assert!(
        covered.windows(2).all(|w| w[1] >= w[0] - 0.01) && covered[3] > covered[0] + 0.1,
        "coverage along the replay {covered:?}"
    );
    assert!(covered[3] > 0.3, "coverage along the replay {covered:?}");
    for pair in shots.windows(2) {
        let changed = changed_fraction(&pair[0], &pair[1]);
        assert!(changed > 0.005, "consecutive shots changed {changed:.4}");
    }

    // The same as one animated GIF.
    let gif = dir.path().join("replay.gif");
    let (code, stdout, stderr) = common::iscene(
        &[
            "view",
            out.to_str().expect("utf8"),
            "--replay",
            "--screenshot",
            gif.to_str().expect("utf8"),
            "--shots",
            "3",
            "--size",
            "160x120",
        ],
        &common::root(),
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    use image::AnimationDecoder;
    let decoder = image::codecs::gif::GifDecoder::new(std::io::BufReader::new(
        std::fs::File::open(&gif).expect("the GIF"),
    ))
    .expect("a GIF");
    assert_eq!(decoder.into_frames().count(), 3);

    // The graph layer's tags: each node's from the frame it appears in.
    let mut app = replay_app(replay.clone(), true);
    render_offscreen(&mut app, (320, 240));
    app.finish();
    app.cleanup();
    let mut tagged_at = |frame: u32| {
        app.world_mut()
            .resource_mut::<ReplayClock>()
            .seek(frame as f32);
        app.update();
        app.update();
        let world = app.world_mut();
        let mut tagged = world
            .query::<(&ReplayLabel, &InheritedVisibility)>()
            .iter(world)
            .filter(|(_, v)| v.get())
            .map(|(l, _)| l.0)
            .collect::<Vec<_>>();
        tagged.sort();
        tagged
    };
    let appeared_by = |frame: u32| {
        (0..replay.nodes.len())
            .filter(|&i| replay.nodes[i].appears_at <= frame && replay.nodes[i].class != "ceiling")
            .collect::<Vec<_>>()
    };
    let (first, last) = (tagged_at(0), tagged_at(23));
    assert_eq!(first, appeared_by(0));
    assert_eq!(last, appeared_by(23));
    assert!(first.len() < last.len(), "{first:?} then {last:?}");
}

/// A key pressed and released through Bevy's input, one update each.
fn press(app: &mut App, key: KeyCode, character: &str) {
    for state in [ButtonState::Pressed, ButtonState::Released] {
        app.world_mut().write_message(KeyboardInput {
            key_code: key,
            logical_key: Key::Character(character.into()),
            state,
            text: None,
            repeat: false,
            window: Entity::PLACEHOLDER,
        });
        app.update();
    }
}

#[test]
fn a_task_runs_step_by_step_and_plays_from_the_keyboard() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let task = common::root().join("scenes/tasks/kitchen_fridge_to_microwave.json");
    let mut app = offscreen_viewer(gt, (320, 240), Some(task));
    // A tenth of a second per frame, however slow software rendering is.
    app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        std::time::Duration::from_millis(100),
    ));
    app.update();
    let actions = app.world().resource::<TaskPlayer>().actions.len();
    assert!(actions >= 7, "{actions} actions");
    let trace = |app: &App| {
        app.world()
            .resource::<iscene::systems::simulation::SimulationTrace>()
            .0
            .clone()
    };
    assert!(trace(&app).is_empty());

    // N: one action, reported in the panel's status.
    press(&mut app, KeyCode::KeyN, "n");
    app.update();
    let done = trace(&app);
    assert_eq!(done.len(), 1);
    assert!(done[0].success, "{:?}", done[0].failed_precondition);
    let status = app
        .world()
        .resource::<iscene::viewer::ViewerStatus>()
        .0
        .clone();
    assert!(
        status[0].starts_with(&format!("task step 1 of {actions}: ")),
        "{status:?}"
    );

    // The drive is shown happening: the robot passes between where it was and where it went,
    // and stops where the tree has it; the next action waits for the motion.
    let (from, to) = done[0]
        .changes
        .iter()
        .find_map(|c| match c {
            iscene::sim::actions::Change::MoveBase { from, to, .. } => Some((*from, *to)),
            _ => None,
        })
        .expect("the first action drives");
    let robot_at = |app: &mut App| {
        let world = app.world_mut();
        world
            .query::<(&Name, &Transform)>()
            .iter(world)
            .find(|(n, _)| n.as_str() == iscene::sim::robot::ROBOT_LINK)
            .map(|(_, t)| t.translation.truncate())
            .expect("the robot")
    };
    let running = |app: &App| {
        app.world()
            .resource::<iscene::viewer::Motion>()
            .is_running()
    };
    assert!(running(&app), "the drive is shown");
    press(&mut app, KeyCode::KeyN, "n");
    assert!(running(&app), "the drive and turn take 0.9 s");
    assert_eq!(trace(&app).len(), 1, "N waits for the motion");
    let mut passed_between = false;
    for _ in 0..100 {
        if !running(&app) {
            break;
        }
        let at = robot_at(&mut app);
        passed_between |= at.distance(from.position) > 0.05 && at.distance(to.position) > 0.05;
        app.update();
    }
    assert!(!running(&app), "the drive ends");
    assert!(passed_between, "the robot drove from {from:?} to {to:?}");
    assert!(robot_at(&mut app).distance(to.position) < 1e-4);

    // P: the rest, one a second, until the last.
    press(&mut app, KeyCode::KeyP, "p");
    for _ in 0..1000 {
        if trace(&app).len() == actions {
            break;
        }
        app.update();
    }
    let done = trace(&app);
    assert_eq!(done.len(), actions);
    assert!(done.iter().all(|r| r.success));
    // The demo ends with both doors closed.
    let fridge_door = app
        .world_mut()
        .query::<(&Name, &Joint)>()
        .iter(app.world())
        .find(|(n, _)| n.as_str() == "fridge_1_door")
        .map(|(_, j)| j.value)
        .expect("the fridge door");
    assert!(fridge_door.abs() < 1e-3, "fridge door at {fridge_door}");
    assert!(!app.world().resource::<TaskPlayer>().playing);
}

#[test]
fn the_arm_is_shown_taking_a_cup_from_the_table_and_stowing_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let task = dir.path().join("pick.json");
    std::fs::write(
        &task,
        r#"{"steps": [{"action": "pick", "object": "cup_2"}]}"#,
    )
    .expect("task");
    let mut app = offscreen_app(&ViewOptions {
        task: Some(task),
        robot: Some(common::panda_urdf()),
        ..view_options(gt, (320, 240))
    });
    app.insert_resource(bevy::time::TimeUpdateStrategy::ManualDuration(
        std::time::Duration::from_millis(100),
    ));
    app.update();
    // The arm is in the world, drawn: one entity per link of the Panda with collision pieces.
    let world = app.world_mut();
    let drawn = world
        .query_filtered::<(), (With<iscene::components::RobotArmLink>, With<Mesh3d>)>()
        .iter(world)
        .count();
    assert!(drawn >= 8, "{drawn} arm links drawn");
    let pose_of = |app: &mut App, name: &str| {
        let world = app.world_mut();
        world
            .query::<(&Name, &GlobalTransform)>()
            .iter(world)
            .find(|(n, _)| n.as_str() == name)
            .map(|(_, t)| t.translation())
            .unwrap_or_else(|| panic!("no {name}"))
    };
    let cup_before = pose_of(&mut app, "cup_2");

    press(&mut app, KeyCode::KeyN, "n");
    let trace = app
        .world()
        .resource::<iscene::systems::simulation::SimulationTrace>()
        .0
        .clone();
    assert!(trace[0].success, "{:?}", trace[0].failed_precondition);
    let running = |app: &App| {
        app.world()
            .resource::<iscene::viewer::Motion>()
            .is_running()
    };
    // Frame by frame: the hand comes to the cup, which stands where it stood until the hand
    // has it, then rides in the hand.
    let (mut nearest, mut cup_left_at, mut frames) = (f32::MAX, None, 0);
    while running(&app) && frames < 2000 {
        let hand = pose_of(&mut app, iscene::sim::robot::GRIPPER_LINK);
        let cup = pose_of(&mut app, "cup_2");
        nearest = nearest.min(hand.distance(cup_before));
        if cup_left_at.is_none() && cup.distance(cup_before) > 1e-3 {
            cup_left_at = Some(hand.distance(cup_before));
        }
        app.update();
        frames += 1;
    }
    assert!(!running(&app), "the motion ends");
    assert!(frames > 20, "the pick is shown over {frames} frames");
    assert!(nearest < 0.15, "the hand came {nearest} m from the cup");
    let left_at = cup_left_at.expect("the cup was taken");
    assert!(
        left_at < 0.15,
        "the cup left the table with the hand {left_at} m away"
    );
    // At the end the world is the tree's: the cup in the stowed hand.
    let stowed = pose_of(&mut app, iscene::sim::robot::GRIPPER_LINK);
    assert!(pose_of(&mut app, "cup_2").distance(stowed) < 0.2);
}

/// The viewer's camera and where it is.
fn camera(app: &mut App) -> (Camera, GlobalTransform) {
    let world = app.world_mut();
    world
        .query::<(&Camera, &GlobalTransform)>()
        .iter(world)
        .next()
        .map(|(c, t)| (c.clone(), *t))
        .expect("camera")
}

/// The pixel where `point` shows.
fn pixel_of(app: &mut App, point: Vec3) -> Vec2 {
    let (camera, at) = camera(app);
    camera.world_to_viewport(&at, point).expect("in view")
}

#[test]
fn dragging_a_cup_onto_the_floor_moves_it_there_and_makes_the_floor_its_support() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let size = (480, 360);
    let mut app = offscreen_viewer(gt, size, None);
    for _ in 0..3 {
        app.update();
    }
    let cup_at = |app: &mut App| {
        let world = app.world_mut();
        world
            .query::<(&Name, &GlobalTransform)>()
            .iter(world)
            .find(|(n, _)| n.as_str() == "cup_1")
            .map(|(_, t)| t.translation())
            .expect("cup_1")
    };
    let start = cup_at(&mut app);
    let from = pixel_of(&mut app, start);
    // A floor pixel with floor all around it: the first, from the bottom right, whose ray and
    // its neighbours' rays 12 px away all meet the floor first.
    let tree = iscene::systems::kinematic_tree::read_kinematic_tree(app.world_mut()).expect("tree");
    let hits_floor = |app: &mut App, px: Vec2| {
        let (camera, at) = camera(app);
        let ray = camera.viewport_to_world(&at, px).expect("ray");
        iscene::kinematics::ray_pick::pick_link(&tree, ray.origin, *ray.direction, &["ceiling"])
            .is_some_and(|(l, _)| tree.links[l].class.as_deref() == Some("floor"))
    };
    let mut to = None;
    'search: for y in (40..size.1 - 40).rev().step_by(10) {
        for x in (40..size.0 - 40).rev().step_by(10) {
            let px = Vec2::new(x as f32, y as f32);
            let around = [Vec2::ZERO, Vec2::X, -Vec2::X, Vec2::Y, -Vec2::Y].map(|d| px + 12.0 * d);
            if around.iter().all(|p| hits_floor(&mut app, *p)) {
                to = Some(px);
                break 'search;
            }
        }
    }
    let to = to.expect("a floor pixel");
    let window = Entity::PLACEHOLDER;
    let pointer = |app: &mut App, at: Vec2, state: Option<ButtonState>| {
        app.world_mut().write_message(CursorMoved {
            window,
            position: at,
            delta: None,
        });
        if let Some(state) = state {
            app.world_mut().write_message(MouseButtonInput {
                button: MouseButton::Left,
                state,
                window,
            });
        }
        app.update();
    };
    pointer(&mut app, from, Some(ButtonState::Pressed));
    // Held over the floor: a box shows where the cup would land, on the floor, and the panel
    // says so; nothing has moved yet.
    pointer(&mut app, to, None);
    let ghost = app
        .world()
        .resource::<DragPreview>()
        .ghost
        .clone()
        .expect("a landing box while dragging");
    assert_eq!(ghost.object, "cup_1");
    assert!(!ghost.refused);
    let ghost_bottom = ghost.world_from_cube.translation.z - ghost.world_from_cube.scale.z / 2.0;
    assert!(
        ghost_bottom.abs() < 0.005,
        "the box's bottom at {ghost_bottom}"
    );
    let status = app.world().resource::<ViewerStatus>().0.clone();
    assert_eq!(status, ["drop cup_1 onto floor"]);
    assert!(cup_at(&mut app).abs_diff_eq(start, 1e-6));
    pointer(&mut app, to, Some(ButtonState::Released));
    assert!(app.world().resource::<DragPreview>().ghost.is_none());
    // The last few millimetres of the fall are shown, then the cup is where the tree has it.
    let mut frames = 0;
    while app.world().resource::<Motion>().is_running() {
        frames += 1;
        assert!(frames < 100, "the fall never ended");
        app.update();
    }
    let status = app.world().resource::<ViewerStatus>().0.clone();
    assert!(
        status[0].starts_with("moved cup_1 onto floor (it was on table_1)"),
        "{status:?}"
    );
    // It stands on the floor now, well away from the table, and its parent is the floor.
    let end = cup_at(&mut app);
    assert!(end.z < start.z - 0.4, "the cup went from {start} to {end}");
    let parent = {
        let world = app.world_mut();
        let parent = world
            .query::<(&Name, &ChildOf)>()
            .iter(world)
            .find(|(n, _)| n.as_str() == "cup_1")
            .map(|(_, c)| c.parent())
            .expect("cup_1's parent");
        world
            .get::<Name>(parent)
            .expect("named")
            .as_str()
            .to_string()
    };
    assert_eq!(parent, "floor");
    // Rapier let it fall the last few millimetres: it rests on the floor, upright.
    let tree = iscene::systems::kinematic_tree::read_kinematic_tree(app.world_mut()).expect("tree");
    let view = iscene::sim::scene_view::SceneView::new(&tree);
    let (lo, _) = view.node_bounds("cup_1").expect("the cup's bounds");
    assert!(lo.z.abs() < 0.003, "the cup's bottom is at {} m", lo.z);
    let link = view.node_link("cup_1").expect("the cup's link");
    let tilt = view.poses[link]
        .matrix3
        .z_axis
        .angle_between(glam::Vec3A::Z);
    assert!(
        tilt.to_degrees() < 2.0,
        "tipped {} degrees",
        tilt.to_degrees()
    );
    // The rest test ran on the new scene and the cup stands there.
    let verdicts = app.world().resource::<iscene::viewer::RestVerdicts>();
    assert_eq!(verdicts.revision, Some(1));
    let cup = verdicts
        .report
        .as_ref()
        .and_then(|r| r.objects.iter().find(|o| o.object == "cup_1"))
        .expect("the cup's verdict");
    assert_eq!(
        cup.verdict,
        iscene::kinematics::rest_test::Verdict::Stable,
        "{cup:?}"
    );
}

#[test]
fn the_graph_layer_labels_each_node_over_its_box() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let size = (480, 360);
    let mut app = offscreen_viewer(gt, size, None);
    let labels = |app: &mut App| {
        let world = app.world_mut();
        world
            .query::<(&NodeLabel, &Text, &Node, &InheritedVisibility)>()
            .iter(world)
            .map(|(l, t, n, v)| (l.0, t.0.clone(), n.left, n.top, v.get()))
            .collect::<Vec<_>>()
    };
    for _ in 0..3 {
        app.update();
    }
    // Off with the graph layer.
    let hidden = labels(&mut app);
    assert!(hidden.len() > 10, "{} labels", hidden.len());
    assert!(hidden.iter().all(|l| !l.4), "{hidden:?}");

    app.world_mut()
        .resource_mut::<ActiveLayers>()
        .set(Layer::Graph, true);
    for _ in 0..3 {
        app.update();
    }
    let shown = labels(&mut app);
    assert!(shown.iter().all(|l| l.4), "{shown:?}");
    // The fridge's tag sits just above the top of its box as the camera sees it.
    let (_, _, left, top, _) = shown
        .iter()
        .find(|l| l.1 == "fridge_1")
        .expect("the fridge's label")
        .clone();
    let fridge_box = app
        .world()
        .get::<iscene::components::OrientedBox>(
            shown.iter().find(|l| l.1 == "fridge_1").expect("label").0,
        )
        .expect("the fridge's box")
        .0;
    let top_point = fridge_box.center.with_z(fridge_box.top_z());
    let at = pixel_of(&mut app, top_point);
    let (Val::Px(x), Val::Px(y)) = (left, top) else {
        panic!("label placed at {left:?}, {top:?}");
    };
    assert!((x - at.x).abs() < 60.0, "label x {x}, box top {at}");
    assert!(y < at.y && at.y - y < 40.0, "label y {y}, box top {at}");
}

/// `view OUT --live` follows a live session: it starts from the preview in OUT's staging folder,
/// rebuilds the world when the session rewrites it (nodes, their links and labels: no stale
/// label stays), and shows the finished output once the staging folder has become OUT.
#[test]
fn a_live_view_rebuilds_the_world_as_the_session_refreshes_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let gt = kitchen_truth(dir.path());
    let full = iscene::graph::ContactGraph::load(&gt.join("contact_graph.json")).expect("graph");
    // An early refresh: the room and the furniture, none of the small objects yet.
    let mut early = full.clone();
    let small = ["cup_1", "cup_2", "bowl_1", "bottle_1", "box_1"];
    early.nodes.retain(|n| !small.contains(&n.id.as_str()));
    early.edges.retain(|e| match e {
        iscene::graph::GraphEdge::Support { parent, child } => {
            !small.contains(&parent.as_str()) && !small.contains(&child.as_str())
        }
        iscene::graph::GraphEdge::Proximal { a, b } => {
            !small.contains(&a.as_str()) && !small.contains(&b.as_str())
        }
    });
    assert!(early.nodes.len() < full.nodes.len());
    let out = dir.path().join("out");
    let preview = dir.path().join(".out.partial-4242").join("live");
    std::fs::create_dir_all(&preview).expect("staging");
    std::fs::write(preview.join("contact_graph.json"), early.to_json()).expect("preview");
    let mut app = offscreen_app(&ViewOptions {
        live: true,
        ..view_options(out.clone(), (320, 240))
    });
    let counts = |app: &mut App| {
        let world = app.world_mut();
        let nodes = world
            .query::<&iscene::components::SceneEntity>()
            .iter(world)
            .count();
        let labels: Vec<String> = world
            .query::<&Text>()
            .iter(world)
            .map(|t| t.0.clone())
            .collect();
        (nodes, labels)
    };
    // Polls are half a second apart.
    let settle = |app: &mut App| {
        for _ in 0..3 {
            std::thread::sleep(std::time::Duration::from_millis(300));
            app.update();
        }
    };
    settle(&mut app);
    let (nodes, labels) = counts(&mut app);
    assert_eq!(nodes, early.nodes.len());
    assert!(!labels.iter().any(|l| l == "cup_1"), "{labels:?}");

    // The session refreshes: the small objects appear.
    std::thread::sleep(std::time::Duration::from_millis(20));
    std::fs::write(preview.join("contact_graph.json"), full.to_json()).expect("refresh");
    settle(&mut app);
    let (nodes, labels) = counts(&mut app);
    assert_eq!(nodes, full.nodes.len());
    assert_eq!(
        labels.iter().filter(|l| *l == "fridge_1").count(),
        1,
        "{labels:?}"
    );
    assert!(labels.iter().any(|l| l == "cup_1"), "{labels:?}");

    // The session ends: its output takes OUT's name, and the view follows it there.
    std::fs::remove_dir_all(dir.path().join(".out.partial-4242")).expect("finish");
    std::fs::create_dir_all(&out).expect("out");
    std::fs::write(out.join("contact_graph.json"), early.to_json()).expect("final");
    settle(&mut app);
    assert_eq!(counts(&mut app).0, early.nodes.len());
}

/// Mean absolute difference of two pictures, per channel, in 8-bit steps.
fn mean_difference(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let total: u64 = a
        .as_raw()
        .iter()
        .zip(b.as_raw())
        .map(|(x, y)| u64::from(x.abs_diff(*y)))
        .sum();
    total as f64 / a.as_raw().len() as f64
}

#[test]
fn the_map_layer_shows_the_reconstruction_in_place_of_the_models() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = reconstructed_kitchen(dir.path(), 8);
    let map = iscene::viewer::read_map(&out).expect("the map");
    assert!(map.segments.len() > 10, "{} segments", map.segments.len());
    // In the aligned frame: the floor's segment lies at z = 0.
    let floor = map
        .segments
        .iter()
        .find(|s| s.class == "floor")
        .expect("a floor segment");
    let (lo, hi) = floor.mesh.bounds().expect("floor bounds");
    assert!(lo.z > -0.05 && hi.z < 0.05, "floor from {lo} to {hi}");
    // Coloured from the sequence: nearly every vertex was seen by one of its frames.
    assert_eq!(map.uncoloured_because, None);
    let colours: Vec<&Option<[u8; 3]>> = map.segments.iter().flat_map(|s| &s.colours).collect();
    let vertices: usize = map.segments.iter().map(|s| s.mesh.positions.len()).sum();
    assert_eq!(colours.len(), vertices);
    let coloured = colours.iter().filter(|c| c.is_some()).count() as f64 / vertices as f64;
    assert!(coloured > 0.9, "{coloured:.3} of the vertices coloured");

    let models = screenshot(&out, &dir.path().join("models.png"), &[]);
    let mapped = screenshot(&out, &dir.path().join("map.png"), &["--layer", "map"]);
    let by_instance = screenshot(
        &out,
        &dir.path().join("map_segments.png"),
        &["--layer", "map,segments"],
    );
    let changed = changed_fraction(&models, &mapped);
    assert!(
        changed > 0.05,
        "the map changed {changed:.4} of the picture"
    );
    assert!(
        coverage(&mapped) > 0.4,
        "the map covers {:.2}",
        coverage(&mapped)
    );
    // In the sensor's colours the map looks like the scene's own models, more than it does in
    // instance colours.
    let (sensor, instance) = (
        mean_difference(&models, &mapped),
        mean_difference(&models, &by_instance),
    );
    assert!(
        sensor < 0.8 * instance,
        "differs from the models by {sensor:.1} in colour, {instance:.1} by instance"
    );
    // A rendered sequence's truth has no map.
    let gt = dir.path().join("seq").join("gt");
    assert!(
        iscene::viewer::read_map(&gt)
            .expect("no map, no error")
            .segments
            .is_empty()
    );
    // Without its sequence the map still shows, by instance, and says why.
    std::fs::rename(dir.path().join("seq"), dir.path().join("moved")).expect("move");
    let map = iscene::viewer::read_map(&out).expect("the map");
    assert!(map.segments.len() > 10 && map.segments.iter().all(|s| s.colours.is_empty()));
    assert!(map.uncoloured_because.is_some());
    // The panel says why when the map layer comes on.
    let mut app = offscreen_viewer(out, (160, 120), None);
    app.world_mut()
        .resource_mut::<ActiveLayers>()
        .set(Layer::Map, true);
    app.update();
    let status = app.world().resource::<ViewerStatus>().0.clone();
    assert!(
        status[0].contains("instance colours") && status[1] == map.uncoloured_because.expect("why"),
        "{status:?}"
    );
}
