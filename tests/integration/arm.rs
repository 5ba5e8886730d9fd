//! The Franka Emika Panda of the PyBullet package as the arm (issue 37): its forward kinematics
//! against PyBullet's, inverse kinematics to poses it can reach, and collision-free motions
//! planned around a table, picks and places, and doors opened and closed by their handles.

use glam::{Affine3A, Quat, Vec3};
use iscene::arm::collision::{ArmCollider, Obstacles};
use iscene::arm::ik::{IkSettings, pose_error, solve};
use iscene::arm::rrt::{PlanSettings, densify, plan, segment_free};
use iscene::arm::{Arm, LinkMotion};
use iscene::geometry::TriMesh;
use rand::SeedableRng;

use crate::common;
use crate::common::panda_urdf;

fn random_configuration(arm: &Arm, rng: &mut rand_chacha::ChaCha8Rng) -> Vec<f32> {
    iscene::arm::random_configuration(&arm.limits(), rng)
}

/// Every link frame of the Panda in 20 random configurations, fingers half open, matches
/// PyBullet's within 0.1 mm and 0.001 rad.
#[test]
fn panda_forward_kinematics_match_pybullet() {
    let urdf = panda_urdf();
    let arm = Arm::read_urdf(&urdf, None).expect("the Panda reads");
    assert_eq!(arm.dof(), 7, "the Panda's seven joints");
    assert_eq!(arm.links[arm.tool].name, "panda_grasptarget");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let configurations: Vec<Vec<f32>> = (0..20)
        .map(|_| random_configuration(&arm, &mut rng))
        .collect();
    let opening = 0.5;
    let named: Vec<serde_json::Value> = configurations
        .iter()
        .map(|q| {
            let mut values = serde_json::Map::new();
            for (l, link) in arm.links.iter().enumerate() {
                let Some(joint) = &link.joint else { continue };
                let value = match arm.motion[l] {
                    LinkMotion::Chain(i) => q[i],
                    _ => joint.limits.0 + opening * (joint.limits.1 - joint.limits.0),
                };
                values.insert(joint.name.clone(), serde_json::json!(value));
            }
            serde_json::Value::Object(values)
        })
        .collect();
    let tmp = tempfile::tempdir().expect("tempdir");
    let file = tmp.path().join("configurations.json");
    std::fs::write(
        &file,
        serde_json::json!({ "configurations": named }).to_string(),
    )
    .expect("write");
    let python = common::validator(".venv-validators/bin/python");
    let script = common::root().join("tests/external/pybullet_fk.py");
    let (code, stdout, stderr) = common::run_tool(&python, &[&script, &urdf, &file]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    let truth = common::json_line(&stdout);
    let (mut compared, mut worst_m, mut worst_rad) = (0, 0.0f32, 0.0f32);
    for (q, poses) in configurations
        .iter()
        .zip(truth["poses"].as_array().expect("poses"))
    {
        let ours = arm.link_poses(&Affine3A::IDENTITY, q, opening);
        for (l, link) in arm.links.iter().enumerate().skip(1) {
            let v: Vec<f32> = poses[&link.name]
                .as_array()
                .unwrap_or_else(|| panic!("PyBullet has no link {}", link.name))
                .iter()
                .map(|x| x.as_f64().expect("number") as f32)
                .collect();
            let theirs = Affine3A::from_rotation_translation(
                Quat::from_xyzw(v[3], v[4], v[5], v[6]).normalize(),
                Vec3::new(v[0], v[1], v[2]),
            );
            let (dp, dr) = pose_error(&ours[l], &theirs);
            worst_m = worst_m.max(dp.length());
            worst_rad = worst_rad.max(dr.length());
            compared += 1;
        }
    }
    eprintln!("{compared} link poses: worst {worst_m:.2e} m, {worst_rad:.2e} rad");
    assert!(compared >= 20 * 10, "{compared} link poses compared");
    assert!(worst_m < 1e-4, "positions differ by {worst_m} m");
    assert!(worst_rad < 1e-3, "rotations differ by {worst_rad} rad");
}

/// Tool poses of random configurations are reached again from the middle of the joint ranges,
/// within 1 mm and 0.01 rad and the limits; a pose 2 m away is not.
#[test]
fn panda_inverse_kinematics_reach_what_it_can_reach() {
    let arm = Arm::read_urdf(&panda_urdf(), None).expect("the Panda reads");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let settings = IkSettings::default();
    let base = Affine3A::IDENTITY;
    let mut solved = 0;
    let trials = 30;
    for t in 0..trials {
        let target = arm.tool_pose(&base, &random_configuration(&arm, &mut rng));
        let Some(q) = solve(
            &arm,
            &base,
            &target,
            &arm.middle(),
            &IkSettings {
                seed: t,
                ..settings
            },
            &|_| true,
        ) else {
            continue;
        };
        assert!(arm.within_limits(&q), "{q:?} outside the limits");
        let (dp, dr) = pose_error(&arm.tool_pose(&base, &q), &target);
        assert!(dp.length() <= 1e-3 && dr.length() <= 1e-2, "{dp} {dr}");
        solved += 1;
    }
    eprintln!("{solved} of {trials} reachable poses solved");
    assert!(solved * 10 >= trials * 9, "{solved} of {trials}");
    let far = Affine3A::from_translation(Vec3::new(2.0, 0.0, 0.5));
    assert!(solve(&arm, &base, &far, &arm.middle(), &settings, &|_| true).is_none());
}

/// The Panda on a table's edge moves its hand from one side of a post to the other: the
/// straight joint-space motion hits the post; the motion planned with a 2 cm margin, checked
/// every 0.01 rad, keeps 5 mm from everything at every 0.0025 rad step, its own links included.
#[test]
fn panda_plans_around_a_post() {
    let arm = Arm::read_urdf(&panda_urdf(), None).expect("the Panda reads");
    let collider = ArmCollider::new(&arm);
    assert!(
        collider.self_pairs.len() >= 10,
        "{} self pairs",
        collider.self_pairs.len()
    );
    let base = Affine3A::IDENTITY;
    let mut obstacles = Obstacles::default();
    // The table the arm stands beside (its top 2 cm under the arm's base) and a post on it.
    obstacles.add(
        "table",
        &TriMesh::cuboid(Vec3::new(0.25, -0.6, -0.75), Vec3::new(1.0, 0.6, -0.02)),
        &Affine3A::IDENTITY,
    );
    obstacles.add(
        "post",
        &TriMesh::cuboid(Vec3::new(0.45, -0.05, -0.02), Vec3::new(0.55, 0.05, 0.9)),
        &Affine3A::IDENTITY,
    );
    let free_by = |q: &[f32], margin: f32| {
        arm.within_limits(q)
            && collider
                .touching(&arm.link_poses(&base, q, 1.0), &obstacles, margin)
                .is_none()
    };
    let free = |q: &[f32]| free_by(q, 0.02);
    // Hand down, 30 cm above the table, left and right of the post.
    let down = Quat::from_rotation_x(std::f32::consts::PI);
    let pose = |y: f32| Affine3A::from_rotation_translation(down, Vec3::new(0.5, y, 0.3));
    let ik = |target: &Affine3A| {
        solve(
            &arm,
            &base,
            target,
            &arm.middle(),
            &IkSettings::default(),
            &free,
        )
        .expect("a free configuration")
    };
    let (start, goal) = (ik(&pose(-0.3)), ik(&pose(0.3)));
    assert!(
        !segment_free(&start, &goal, &free, 0.01),
        "the straight motion should hit the post"
    );
    let settings = PlanSettings {
        resolution: 0.01,
        ..PlanSettings::default()
    };
    let started = std::time::Instant::now();
    let path = plan(&start, &goal, &arm.limits(), &free, &settings).expect("a path");
    let seconds = started.elapsed().as_secs_f32();
    let steps = densify(&path, 0.0025);
    for q in &steps {
        assert!(free_by(q, 0.005), "{q:?} comes within 5 mm of something");
    }
    let again = plan(&start, &goal, &arm.limits(), &free, &settings).expect("a path");
    assert_eq!(path, again, "the same seed plans the same path");
    eprintln!(
        "{} waypoints, {:.2} rad, {} checked steps, planned in {seconds:.2} s",
        path.len(),
        iscene::arm::rrt::path_length(&path),
        steps.len()
    );
}

/// On the rendered kitchen's ground truth the Panda on its base picks a cup, a bowl and a
/// bottle and sets each down elsewhere (`iscene simulate --robot`): every step succeeds, the
/// trace holds each motion's joint values within the limits, and the first pick's reach, replayed
/// against the scene as it stood, never touches anything but the cup between its fingers. The
/// whole task replayed in MuJoCo (`replay.xml` with `trajectory.csv`) keeps the arm and what it
/// holds within 5 mm of the scene at every sample, and a held object stays where the fingers
/// took it. A robot file that is no URDF is refused, naming it, before anything is written.
/// The step's arm motion ran in rapier phase by phase (`phases`, in order) before it was made,
/// after the drive there (if any) with the stowed arm on the base: the arm's links kinematic
/// bodies, nothing knocked, and no link of the arm more than 5 mm into the scene.
fn assert_arm_ran_in_rapier(step: &serde_json::Value, phases: &[&str]) {
    let checks: Vec<&serde_json::Value> = step["motion"]
        .as_array()
        .expect("motion checks")
        .iter()
        .collect();
    let mut names: Vec<String> = phases.iter().map(|p| format!("robot ({p})")).collect();
    if checks.len() > names.len() {
        names.insert(0, "robot".into());
    }
    assert_eq!(
        checks
            .iter()
            .map(|m| m["link"].as_str().unwrap_or(""))
            .collect::<Vec<_>>(),
        names,
        "{step}"
    );
    for check in checks {
        assert!(check.get("arm_depth").is_some(), "{check}");
        assert!(
            check["simulated_s"].as_f64().is_some_and(|s| s > 0.5),
            "{check}"
        );
        assert_eq!(check["knocked"], serde_json::json!([]), "{check}");
        let depth = check["arm_depth"]["depth_m"].as_f64().expect("depth");
        assert!(depth <= 0.005, "{check}");
    }
}

#[test]
fn panda_picks_and_places_in_the_kitchen() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (gt, task, out, trace) = panda_task_in_the_kitchen(
        tmp.path(),
        serde_json::json!([
            {"action": "pick", "object": "cup_2"},
            {"action": "place_on", "object": "cup_2", "surface": "cabinet_2"},
            {"action": "pick", "object": "bowl_1"},
            {"action": "place_on", "object": "bowl_1", "surface": "table_1"},
            {"action": "pick", "object": "bottle_1"},
            {"action": "place_on", "object": "bottle_1", "surface": "table_1"},
        ]),
    );
    let rig = panda_rig();
    let mut motions = 0;
    for step in trace["steps"].as_array().expect("steps") {
        let changes = step["changes"].as_array().expect("changes");
        let motion = changes
            .iter()
            .find(|c| c["change"] == "arm_motion")
            .unwrap_or_else(|| panic!("no arm motion in {step}"));
        for part in ["reach", "retreat"] {
            let path = motion[part].as_array().expect("configurations");
            assert!(path.len() > 2, "{part} of {step}");
            for q in path {
                let q: Vec<f32> = serde_json::from_value(q.clone()).expect("joint values");
                assert!(rig.arm.within_limits(&q), "{q:?} outside the limits");
            }
        }
        assert_arm_ran_in_rapier(step, &["reach", "retreat"]);
        motions += 1;
    }
    assert_eq!(motions, 6);
    // The first pick's reach against the scene before it, the cup left out.
    let first = &trace["steps"][0]["changes"];
    let base: iscene::sim::robot::BasePose = first
        .as_array()
        .expect("changes")
        .iter()
        .find(|c| c["change"] == "move_base")
        .map_or_else(
            || panic!("the base drives to the cup first: {first}"),
            |c| serde_json::from_value(c["to"].clone()).expect("base pose"),
        );
    let reach: Vec<Vec<f32>> = first
        .as_array()
        .expect("changes")
        .iter()
        .find(|c| c["change"] == "arm_motion")
        .map(|c| serde_json::from_value(c["reach"].clone()).expect("reach"))
        .expect("arm motion");
    let (_, mut app) = iscene::simulation::task_world(&gt, &task, None).expect("the task's world");
    let tree = iscene::systems::kinematic_tree::read_kinematic_tree(app.world_mut()).expect("tree");
    let view = iscene::sim::scene_view::SceneView::new(&tree);
    let cup = view.node_link("cup_2").expect("cup_2");
    let obstacles = iscene::sim::actions::scene_obstacles(&view, &[cup]);
    let root = base.world_from_base() * rig.base_from_root;
    assert!(
        iscene::arm::reach::path_clear(
            &rig,
            &root,
            &reach,
            &obstacles,
            &iscene::arm::reach::Held::default(),
            0.0
        ),
        "the reach touches the scene"
    );
    // Every step moves the arm, and a held object stays where the fingers took it.
    let replay = replay_in_mujoco(&out, &rig);
    assert_eq!(
        replay["steps"],
        serde_json::json!([0, 1, 2, 3, 4, 5]),
        "{replay}"
    );
    assert!(
        replay["arm_travel_rad"].as_f64().expect("travel") > 6.0,
        "{replay}"
    );
    assert!(
        replay["held_samples"].as_u64().expect("held") > 100,
        "{replay}"
    );
    let drift = replay["held_drift_m"].as_f64().expect("drift");
    assert!(
        drift < 1e-3,
        "a held object slipped {drift} m in the hand: {replay}"
    );
    // A robot file that is no arm.
    let bad = tmp.path().join("robot.urdf");
    std::fs::write(&bad, "<robot name='x'><link name='a'/></robot>").expect("write");
    let out2 = tmp.path().join("sim2");
    let (code, _, stderr) = common::simulate(&gt, &task, &out2, Some(&bad));
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("robot.urdf"), "{stderr}");
    assert!(!out2.exists(), "nothing written");
}

/// The kitchen rendered into `dir` (2 frames, no noise) and the task of `steps` simulated on its
/// ground truth with the Panda (`iscene simulate --robot`), which must succeed: the truth's
/// folder, the task file, the output folder and its trace.
fn panda_task_in_the_kitchen(
    dir: &std::path::Path,
    steps: serde_json::Value,
) -> (
    std::path::PathBuf,
    std::path::PathBuf,
    std::path::PathBuf,
    serde_json::Value,
) {
    let seq = dir.join("seq");
    common::render_scene("kitchen", &seq, 2, true);
    let gt = seq.join("gt");
    let (task, out, trace) = panda_task(&gt, serde_json::json!({ "steps": steps }), dir);
    (gt, task, out, trace)
}

/// The `task` (a task file's JSON) written into `dir` and simulated on the scene folder `scene`
/// with the Panda (`iscene simulate --robot`), which must exit 0: the task file, the output
/// folder and its trace.
fn panda_task(
    scene: &std::path::Path,
    task: serde_json::Value,
    dir: &std::path::Path,
) -> (std::path::PathBuf, std::path::PathBuf, serde_json::Value) {
    let file = dir.join("task.json");
    std::fs::write(&file, task.to_string()).expect("task");
    let out = dir.join("sim");
    let (code, stdout, stderr) = common::simulate(scene, &file, &out, Some(&panda_urdf()));
    assert_eq!(code, 0, "{stdout}{stderr}");
    let trace: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("trace.json")).expect("trace"))
            .expect("JSON");
    (file, out, trace)
}

/// The task in `out` (a `simulate --robot` output) replayed in MuJoCo: every joint of the CSV
/// is in the model and nothing of the robot or in its hand goes 5 mm into the scene at any
/// sample; the replay's figures (tests/external/mujoco_replay.py) for the caller's checks.
pub(crate) fn replay_in_mujoco(
    out: &std::path::Path,
    rig: &iscene::arm::rig::ArmRig,
) -> serde_json::Value {
    let python = common::validator(".venv-validators/bin/python");
    let script = common::root().join("tests/external/mujoco_replay.py");
    let tool = format!("robot_{}", rig.arm.links[rig.arm.tool].name);
    let (code, stdout, stderr) = common::run_tool(
        &python,
        &[
            &script,
            &out.join("replay.xml"),
            &out.join("trajectory.csv"),
            std::path::Path::new(&tool),
        ],
    );
    assert_eq!(code, 0, "{stdout}{stderr}");
    let replay = common::json_line(&stdout);
    eprintln!("MuJoCo replay: {replay}");
    assert_eq!(replay["missing_joints"], serde_json::json!([]), "{replay}");
    if let Some(depth) = replay["deepest"]["depth_m"].as_f64() {
        assert!(
            depth <= 0.005,
            "the robot goes {depth} m into the scene: {replay}"
        );
    }
    replay
}

/// On the rendered kitchen's ground truth the Panda opens the microwave's door and a cabinet's
/// drawer by their handles and closes them again (`iscene simulate --robot`): the hand takes
/// the part's bar handle and follows its arc or line, the part moving with it, until it is open
/// at least as far as the simulation asks of a part opened as far as it goes (0.6 of its range),
/// lets go, and later pushes it shut the same way. Replayed in MuJoCo, the hand keeps its place
/// on the part (within 2 mm from one sample to the next) while the part moves, and nothing of
/// the robot goes 5 mm into the scene.
#[test]
fn panda_opens_and_closes_a_door_and_a_drawer_by_their_handles() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, _, out, trace) = panda_task_in_the_kitchen(
        tmp.path(),
        serde_json::json!([
            {"action": "open", "object": "microwave_1"},
            {"action": "close", "object": "microwave_1"},
            {"action": "open", "object": "cabinet_2", "part": "drawer_1"},
            {"action": "close", "object": "cabinet_2", "part": "drawer_1"},
        ]),
    );
    let robot = urdf_rs::read_file(out.join("scene.urdf")).expect("the scene's URDF");
    let upper = |link: &str| {
        robot
            .joints
            .iter()
            .find(|j| j.child.link == link)
            .map(|j| j.limit.upper)
            .unwrap_or_else(|| panic!("no joint moves {link}"))
    };
    let parts = [
        "microwave_1_door",
        "microwave_1_door",
        "cabinet_2_drawer_1",
        "cabinet_2_drawer_1",
    ];
    let steps = trace["steps"].as_array().expect("steps");
    assert_eq!(steps.len(), parts.len());
    for (k, (step, link)) in steps.iter().zip(parts).enumerate() {
        assert_eq!(step["success"], true, "{step}");
        assert_arm_ran_in_rapier(step, &["reach", "handle", "retreat"]);
        let changes = step["changes"].as_array().expect("changes");
        let motion = changes
            .iter()
            .find(|c| c["change"] == "arm_motion")
            .unwrap_or_else(|| panic!("the arm works {link}: {step}"));
        assert!(
            motion["what"]
                .as_str()
                .is_some_and(|w| w.contains(&format!("handle of {link}"))),
            "{motion}"
        );
        let part = &motion["part"];
        assert_eq!(part["link"], link, "{motion}");
        let values: Vec<f64> = serde_json::from_value(part["values"].clone()).expect("values");
        let along = part["along"].as_array().expect("along");
        assert_eq!(values.len(), along.len(), "one configuration per value");
        // A centimetre of handle travel per pose: many poses, each a small move.
        assert!(values.len() >= 15, "{values:?}");
        assert!(
            values.windows(2).all(|w| (w[1] - w[0]).abs() < 0.05),
            "{values:?}"
        );
        let set = changes
            .iter()
            .find(|c| c["change"] == "set_joint")
            .expect("the part's new value");
        let last = *values.last().expect("values");
        assert!(
            (set["to"].as_f64().expect("to") - last).abs() < 1e-4,
            "{set}"
        );
        if k % 2 == 0 {
            let range = upper(link);
            assert!(last >= 0.6 * range, "{link} opened to {last} of {range}");
        } else {
            assert!(last.abs() < 1e-4, "{link} closed to {last}");
        }
    }
    let rig = panda_rig();
    let replay = replay_in_mujoco(&out, &rig);
    assert_eq!(replay["steps"], serde_json::json!([0, 1, 2, 3]), "{replay}");
    assert!(
        replay["part_samples"].as_u64().expect("part samples") >= 60,
        "{replay}"
    );
    let drift = replay["part_drift_m"].as_f64().expect("part drift");
    assert!(
        drift < 0.002,
        "the hand slipped {drift} m on a handle: {replay}"
    );
}

/// On the kitchen's reconstruction, the Panda opens and closes the door under the counter with
/// the lowest handle (39 cm up, out of reach from the 0.75 m column before the lift): the lift
/// takes the arm's root down for it, and every phase runs in rapier.
#[test]
fn panda_on_its_lift_opens_and_closes_the_lowest_door_of_the_reconstruction() {
    let (_, rec) = common::shared_noisy_map("kitchen");
    let graph: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(rec.join("contact_graph.json")).expect("graph"),
    )
    .expect("JSON");
    let (object, part, height) = graph["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .flat_map(|n| {
            n["parts"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(move |p| {
                    let z = p["handle"]["center"][2].as_f64()?;
                    (p["joint"]["type"] == "revolute").then(|| {
                        (
                            n["id"].as_str().expect("id").to_string(),
                            p["name"].as_str().expect("name").to_string(),
                            z,
                        )
                    })
                })
        })
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .expect("a door with a handle");
    assert!(height < 0.5, "{object} {part} at {height} m");
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, _, trace) = panda_task(
        &rec,
        serde_json::json!({"steps": [
            {"action": "open", "object": object, "part": part},
            {"action": "close", "object": object, "part": part},
        ]}),
        tmp.path(),
    );
    for step in trace["steps"].as_array().expect("steps") {
        assert_eq!(step["success"], true, "{step}");
        assert_arm_ran_in_rapier(step, &["reach", "handle", "retreat"]);
        let motion = step["changes"]
            .as_array()
            .expect("changes")
            .iter()
            .find(|c| c["change"] == "arm_motion")
            .expect("the arm works the door");
        // The lift is the chain's first joint; stowed it is at 0.
        let lowest = motion["part"]["along"]
            .as_array()
            .expect("the hand on the handle")
            .iter()
            .map(|q| q[0].as_f64().expect("the lift's value"))
            .fold(f64::MAX, f64::min);
        assert!(lowest < -0.1, "the lift goes down for the handle: {lowest}");
    }
}

/// The Panda on the simulation's arm base, as `simulate --robot` mounts it.
/// The replay of `out` in MuJoCo (`replay_in_mujoco` with the Panda), asserting that `what`
/// the hand holds stays within 1 mm of where the fingers took it; the replay's figures.
pub(crate) fn replay_holding(out: &std::path::Path, what: &str) -> serde_json::Value {
    let replay = replay_in_mujoco(out, &panda_rig());
    let drift = replay["held_drift_m"].as_f64().expect("drift");
    assert!(
        drift < 1e-3,
        "the {what} slipped {drift} m in the hand: {replay}"
    );
    replay
}

/// A task file of scenes/tasks, as JSON.
fn task_file(name: &str) -> serde_json::Value {
    let path = common::root().join("scenes/tasks").join(name);
    serde_json::from_str(&std::fs::read_to_string(&path).expect("task")).expect("JSON")
}

pub(crate) fn panda_rig() -> iscene::arm::rig::ArmRig {
    let arm = Arm::read_urdf(&panda_urdf(), None).expect("the Panda reads");
    let base = iscene::sim::robot::RobotSpec::ARM_BASE;
    base.mount(iscene::arm::rig::ArmRig::new(arm, base.height))
}

/// The output graph of `out` (a `simulate` output) has `parent` supporting `child`.
pub(crate) fn assert_supports(out: &std::path::Path, parent: &str, child: &str) {
    let graph: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("contact_graph.json")).expect("graph"),
    )
    .expect("JSON");
    assert!(
        graph["edges"]
            .as_array()
            .expect("edges")
            .iter()
            .any(|e| { e["type"] == "support" && e["parent"] == parent && e["child"] == child }),
        "{}",
        graph["edges"]
    );
}

/// The Panda's first finger joint at each line of `trajectory.csv`, with what the hand holds.
fn finger_values(csv: &std::path::Path) -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(csv).expect("trajectory");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let finger = header
        .iter()
        .position(|n| *n == "panda_finger_joint1")
        .expect("a finger column");
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            (cells[2].to_string(), cells[finger].parse().expect("value"))
        })
        .collect()
}

/// Every step of a successful task's `trace` succeeded, and each but a drive was an arm motion
/// that ran in rapier before it was made (`assert_arm_ran_in_rapier`): those steps' kinds
/// (`open`, `pick`, ...) and what their hands took, in order.
fn arm_steps_ran_in_rapier(trace: &serde_json::Value) -> (Vec<String>, Vec<String>) {
    let mut kinds = Vec::new();
    let mut grasps = Vec::new();
    for step in trace["steps"].as_array().expect("steps") {
        assert_eq!(step["success"], true, "{step}");
        let kind = step["action"]["action"]
            .as_str()
            .expect("action")
            .to_string();
        let Some(motion) = step["changes"]
            .as_array()
            .expect("changes")
            .iter()
            .find(|c| c["change"] == "arm_motion")
        else {
            assert_eq!(kind, "navigate", "{step}");
            continue;
        };
        let phases: &[&str] = match kind.as_str() {
            "open" | "close" => &["reach", "handle", "retreat"],
            _ => &["reach", "retreat"],
        };
        assert_arm_ran_in_rapier(step, phases);
        grasps.push(motion["what"].as_str().expect("what").to_string());
        kinds.push(kind);
    }
    (kinds, grasps)
}

/// On the kitchen's reconstruction, the Panda takes a box (added by the task: no camera saw
/// inside the fridge) out of the fridge into the microwave and shuts both, planned from goals
/// (the demonstration issue 37 asks for). The fridge stands in the room's corner with its
/// handle 13 cm from the wall: no one place of the base clear of the door's swing has the
/// handle within the arm's reach along its whole arc, so the door opens in two steps from two
/// places (the first part of the way), and shuts the same way. Every arm motion runs in rapier
/// before it is made; the box ends in the microwave in the output graph; MuJoCo's replay keeps
/// the robot within 5 mm of the scene, the box where the fingers took it and the hand on the
/// handles.
#[test]
fn panda_takes_the_box_from_the_fridge_into_the_microwave_of_the_reconstruction() {
    let (_, rec) = common::shared_noisy_map("kitchen");
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, out, trace) = panda_task(
        &rec,
        task_file("kitchen_fridge_to_microwave_panda.json"),
        tmp.path(),
    );
    assert_eq!(trace["success"], true, "{}", trace["steps"]);
    let (kinds, _) = arm_steps_ran_in_rapier(&trace);
    assert_eq!(
        kinds
            .iter()
            .filter(|k| *k == "pick" || *k == "place_in")
            .count(),
        2,
        "{kinds:?}"
    );
    // The fridge's door: part of the way from one place, the rest from another, each way.
    let fridge: Vec<(&str, bool, f64)> = trace["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .filter(|s| s["action"]["object"] == "fridge_1")
        .map(|s| {
            let door = s["changes"]
                .as_array()
                .expect("changes")
                .iter()
                .find(|c| c["change"] == "set_joint")
                .expect("the door moved");
            (
                s["action"]["action"].as_str().expect("action"),
                s.get("part_way").is_some_and(|p| p == true),
                door["to"].as_f64().expect("value"),
            )
        })
        .collect();
    assert_eq!(
        fridge.iter().map(|(a, p, _)| (*a, *p)).collect::<Vec<_>>(),
        [
            ("open", true),
            ("open", false),
            ("close", true),
            ("close", false)
        ],
        "{fridge:?}"
    );
    // Opened at least as far as a door opened as far as it goes (0.6 of its 1.8 rad), shut.
    assert!(fridge[1].2 >= 0.6 * 1.8, "{fridge:?}");
    assert!(fridge[3].2.abs() < 0.02, "{fridge:?}");
    assert_supports(&out, "microwave_1", "box_1");
    let replay = replay_holding(&out, "box");
    let part = replay["part_drift_m"].as_f64().expect("part drift");
    assert!(
        part < 0.002,
        "the hand slipped {part} m on a handle: {replay}"
    );
}

/// On the kitchen's reconstruction, the Panda takes `cup_1` from the table into `cabinet_2`
/// and shuts the cabinet, planned from goals (a task issue 37 asks for): the pick looks ahead
/// to the place and takes the cup from the side (from above, the forearm met the cabinet over
/// its low level), every arm motion runs in rapier before it is made, the cup ends inside the
/// cabinet in the output graph, and MuJoCo's replay keeps the robot and the cup within 5 mm of
/// the scene and the cup where the fingers took it.
#[test]
fn panda_puts_the_cup_from_the_table_into_a_cabinet_of_the_reconstruction() {
    let (_, rec) = common::shared_noisy_map("kitchen");
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, out, trace) = panda_task(
        &rec,
        serde_json::json!({"goals": ["cup_1 in cabinet_2", "cabinet_2 closed"]}),
        tmp.path(),
    );
    assert_eq!(trace["success"], true, "{}", trace["steps"]);
    let (kinds, grasps) = arm_steps_ran_in_rapier(&trace);
    assert_eq!(kinds, ["open", "pick", "place_in", "close"]);
    assert!(grasps[1].starts_with("side grasp"), "{}", grasps[1]);
    // The fingers close round the cup once it is held (2 mm off each side), and open again.
    let pick = trace["steps"]
        .as_array()
        .expect("steps")
        .iter()
        .find(|s| s["action"]["action"] == "pick")
        .and_then(|s| {
            s["changes"]
                .as_array()?
                .iter()
                .find(|c| c["change"] == "arm_motion")
        })
        .expect("a pick's arm motion");
    let grip = pick["grip_m"]
        .as_f64()
        .expect("the fingers' gap on the cup");
    assert!(grip > 0.03 && grip < 0.07, "{pick}");
    let fingers = finger_values(&out.join("trajectory.csv"));
    let held: Vec<f64> = fingers
        .iter()
        .filter(|(held, _)| held == "cup_1")
        .map(|(_, v)| *v)
        .collect();
    let closed = held
        .iter()
        .filter(|v| (*v - 0.5 * grip).abs() < 1e-4)
        .count();
    assert!(closed * 10 >= held.len() * 9, "{closed} of {}", held.len());
    assert!((fingers.last().expect("samples").1 - 0.04).abs() < 1e-5);
    assert_supports(&out, "cabinet_2", "cup_1");
    replay_holding(&out, "cup");
}

/// On the kitchen's reconstruction, the Panda puts the bowl from the table into the microwave
/// and shuts it, planned from goals (a task issue 37 asks for). The bowl is too wide for the
/// fingers: the hand takes its rim leaning out over the side, so that the wrist stays outside
/// the microwave's cavity, and leaves it through the front after a rise of a few millimetres
/// (the whole 2 cm rise over the rim put the hand against the cavity's ceiling). Every arm
/// motion runs in rapier before it is made, the bowl ends in the microwave in the output graph,
/// and MuJoCo's replay keeps the robot within 5 mm of the scene and the bowl in the fingers.
#[test]
fn panda_puts_the_bowl_from_the_table_into_the_microwave_of_the_reconstruction() {
    let (_, rec) = common::shared_noisy_map("kitchen");
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, out, trace) = panda_task(
        &rec,
        task_file("kitchen_bowl_to_microwave_panda.json"),
        tmp.path(),
    );
    assert_eq!(trace["success"], true, "{}", trace["steps"]);
    let (kinds, grasps) = arm_steps_ran_in_rapier(&trace);
    assert_eq!(kinds.first().map(String::as_str), Some("open"), "{kinds:?}");
    assert_eq!(&kinds[1..3], ["pick", "place_in"], "{kinds:?}");
    assert!(kinds[3..].iter().all(|k| k == "close"), "{kinds:?}");
    assert!(grasps[1].starts_with("rim grasp"), "{}", grasps[1]);
    assert_supports(&out, "microwave_1", "bowl_1");
    replay_holding(&out, "bowl");
}

/// On the kitchen's reconstruction, the Panda opens every drawer of the cabinet that has any
/// and the fridge's freezer drawer, then shuts them all, planned from goals that name the
/// parts (`"goals"`, then `"then"`: a task issue 37 asks for). Each part is opened by its own
/// operator (`open-part`), the second set of goals is planned from where the first leaves the
/// scene, pyperplan finds plans of the same lengths on the exported problems, every part ends
/// shut, and MuJoCo's replay keeps the hand on the handles and the robot out of the scene.
#[test]
fn panda_opens_and_shuts_every_drawer_of_a_cabinet_of_the_reconstruction_from_goals() {
    let (_, rec) = common::shared_noisy_map("kitchen");
    let graph: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(rec.join("contact_graph.json")).expect("graph"),
    )
    .expect("JSON");
    // The drawers: those of the first cabinet that has any, and the fridge's.
    let drawers_of = |node: &serde_json::Value| -> Vec<String> {
        node["parts"].as_array().map_or(Vec::new(), |parts| {
            parts
                .iter()
                .filter(|p| p["joint"]["type"] == "prismatic")
                .map(|p| {
                    format!(
                        "{} {}",
                        node["id"].as_str().expect("id"),
                        p["name"].as_str().expect("name")
                    )
                })
                .collect()
        })
    };
    let nodes = graph["nodes"].as_array().expect("nodes");
    let cabinet = nodes
        .iter()
        .filter(|n| n["class"] == "cabinet")
        .map(drawers_of)
        .find(|d| !d.is_empty())
        .expect("a cabinet with a drawer");
    let fridge = nodes
        .iter()
        .find(|n| n["id"] == "fridge_1")
        .map(drawers_of)
        .expect("the fridge");
    assert_eq!(fridge, ["fridge_1 freezer"]);
    let drawers: Vec<String> = cabinet.into_iter().chain(fridge).collect();
    let tmp = tempfile::tempdir().expect("tempdir");
    let (_, out, trace) = panda_task(
        &rec,
        serde_json::json!({
            "goals": drawers.iter().map(|d| format!("{d} open")).collect::<Vec<_>>(),
            "then": [drawers.iter().map(|d| format!("{d} closed")).collect::<Vec<_>>()],
        }),
        tmp.path(),
    );
    assert_eq!(trace["success"], true, "{}", trace["steps"]);
    let plan: Vec<&str> = trace["plan"]
        .as_array()
        .expect("plan")
        .iter()
        .map(|p| p.as_str().expect("operator"))
        .collect();
    for d in &drawers {
        let link = d.replace(' ', "_");
        for op in ["open-part", "close-part"] {
            assert_eq!(
                plan.iter()
                    .filter(|p| p.starts_with(&format!("({op} {link} ")))
                    .count(),
                1,
                "{op} {link}: {plan:?}"
            );
        }
    }
    // pyperplan on each exported problem: the same number of operators as ours.
    let theirs: usize = ["problem.pddl", "problem_then_0.pddl"]
        .iter()
        .map(|problem| {
            common::pyperplan_plan_length(
                &out,
                problem,
                &tmp.path().join(format!("pddl_{problem}")),
            )
        })
        .sum();
    assert_eq!(plan.len(), theirs, "{plan:?}");
    // Every drawer moved, and ends shut.
    let mut last = std::collections::BTreeMap::new();
    for step in trace["steps"].as_array().expect("steps") {
        for c in step["changes"].as_array().expect("changes") {
            if c["change"] == "set_joint" {
                last.insert(
                    c["link"].as_str().expect("link").to_string(),
                    c["to"].as_f64().expect("value"),
                );
            }
        }
    }
    for d in &drawers {
        let value = last.get(&d.replace(' ', "_")).copied();
        assert!(value.is_some_and(|v| v.abs() < 0.005), "{d}: {last:?}");
    }
    let rig = panda_rig();
    let replay = replay_in_mujoco(&out, &rig);
    let part = replay["part_drift_m"].as_f64().expect("part drift");
    assert!(
        part < 0.002,
        "the hand slipped {part} m on a handle: {replay}"
    );
}
