//! An arm motion as the physics check sees it: its phases (the reach, the hand on a door's or
//! drawer's handle, the retreat), each the world poses of the arm's links and of the scene's
//! links that move with the hand, at times `step_s` apart and at the arm's speed
//! ([`ARM_SPEED`], as the trajectory times them).
//!
//! What moves with the hand changes between phases, so each phase starts from the scene as the
//! phase before left it: an object picked rides in the hand from the retreat on; an object
//! placed stays where the reach put it (held there, not yet free: the rest test after the
//! action judges whether it stands); a part followed by the hand stays where the hand let go.

use glam::Affine3A;

use crate::arm::rig::ArmRig;
use crate::arm::rrt::distance;
use crate::kinematics::tree::KinematicTree;
use crate::sim::actions::{Change, PartFollow};
use crate::sim::robot::{GRIPPER_LINK, ROBOT_LINK};
use crate::sim::trajectory::ARM_SPEED;

/// One phase of an arm motion.
#[derive(Clone, Debug)]
pub struct ArmPhase {
    /// The phase in words ("reach", "handle", "retreat").
    pub what: &'static str,
    /// The scene as the phase starts.
    pub tree: KinematicTree,
    /// Links of `tree` driven along their world poses, each with what hangs from it.
    pub links: Vec<(usize, Vec<Affine3A>)>,
    /// Links of `tree` whose own collision pieces take no part: the gripper link, which stands
    /// for the stowed hand where the arm's own hand is a body.
    pub hidden: Vec<usize>,
    /// Links of `tree` whose insides the hand goes into (the object it takes or sets down, and
    /// what it sets it on or in): their bodies are simulated with their hollows.
    pub hollow: Vec<usize>,
    /// Links of `tree` that hold still, the arm's contacts with them measured: the object the
    /// hand comes to take, which it must not go into (nor push: simulating its hollow free
    /// cost ten times the rest of the check).
    pub still: Vec<usize>,
    /// Links of `tree` the object in the hand is set down on or lifted from (a place's new
    /// support, a pick's old one): touching them is the set-down or the lift, not a knock.
    pub set_on: Vec<usize>,
    /// The arm's links' world poses at each instant: `arm[k][l]` is link `l`'s at instant `k`.
    pub arm: Vec<Vec<Affine3A>>,
}

/// The phases of `change` (an arm motion) from the scene `tree`, the robot carrying `rig`;
/// `handover` is the attachment that follows it in the action (a pick's take, a place's
/// release). Empty for any other change, or a tree without the robot.
pub fn arm_phases(
    tree: &KinematicTree,
    rig: &ArmRig,
    change: &Change,
    handover: Option<&Change>,
    step_s: f32,
) -> Vec<ArmPhase> {
    let Change::ArmMotion {
        reach,
        retreat,
        part,
        ..
    } = change
    else {
        return Vec::new();
    };
    let link_named = |name: &str| tree.links.iter().position(|l| l.name == name);
    let (Some(robot), Some(gripper)) = (link_named(ROBOT_LINK), link_named(GRIPPER_LINK)) else {
        return Vec::new();
    };
    let root = tree.world_from_links()[robot] * rig.base_from_root;
    let hidden = vec![gripper];
    let holds = tree.links.iter().any(|l| l.parent == Some(gripper));
    let hollow: Vec<usize> = match handover {
        Some(Change::Attach { link, to, .. }) => [link_named(link), link_named(to)]
            .into_iter()
            .flatten()
            .filter(|&l| l != gripper)
            .collect(),
        _ => Vec::new(),
    };
    let tool = |q: &[f32]| rig.arm.tool_pose(&root, q);
    let arm_poses = |instants: &[(Vec<f32>, f32)]| -> Vec<Vec<Affine3A>> {
        instants
            .iter()
            .map(|(q, _)| rig.arm.link_poses(&root, q, 1.0))
            .collect()
    };
    let mut phases = Vec::new();
    let mut tree = tree.clone();
    let mut last = rig.stow.clone();

    // The reach: what the hand holds (a place's object) rides with it.
    let instants = timed(&last, reach, None, step_s);
    let links = if holds {
        vec![(gripper, instants.iter().map(|(q, _)| tool(q)).collect())]
    } else {
        Vec::new()
    };
    // A place's object touches its new support from the set-down on; a picked one its old
    // support until the lift has taken it off.
    let set_on: Vec<usize> = match handover {
        Some(Change::Attach { to, .. }) if holds => link_named(to).into_iter().collect(),
        Some(Change::Attach { from, to, .. }) if to == GRIPPER_LINK => {
            link_named(from).into_iter().collect()
        }
        _ => Vec::new(),
    };
    let taken: Vec<usize> = match handover {
        Some(Change::Attach { link, to, .. }) if to == GRIPPER_LINK => {
            link_named(link).into_iter().collect()
        }
        _ => Vec::new(),
    };
    // The object whose door or drawer the hand works holds still throughout, as an object to
    // be taken does, its contacts with the arm measured: the fingers end round the handle.
    // Free, a cabinet was thrown back by the fingers arriving 7 mm from its drawer's front
    // (and the bottle on it launched) where MuJoCo's replay finds no contact. While the part
    // moves it does not collide with its object anyway, and holding the object still took the
    // microwave door's check from 200 to 156 ms.
    let worked: Vec<usize> = part
        .iter()
        .filter_map(|p| link_named(&p.link))
        .filter_map(|l| tree.links[l].node.as_deref())
        .filter_map(link_named)
        .collect();
    phases.push(ArmPhase {
        what: "reach",
        tree: tree.clone(),
        links,
        hidden: hidden.clone(),
        hollow: hollow.clone(),
        still: [taken, worked.clone()].concat(),
        set_on: set_on.clone(),
        arm: arm_poses(&instants),
    });
    if let Some(q) = reach.last() {
        last.clone_from(q);
    }

    // The hand on a part's handle: the part follows it.
    if let Some(PartFollow {
        link,
        values,
        along,
    }) = part
        && let Some(l) = link_named(link)
        && !along.is_empty()
    {
        let start = tree.links[l].value;
        let instants = timed(&last, along, Some((start, values)), step_s);
        let parent = tree.links[l]
            .parent
            .map_or(Affine3A::IDENTITY, |p| tree.world_from_links()[p]);
        let link = &tree.links[l];
        let part_poses = instants
            .iter()
            .map(|(_, v)| parent * link.parent_from_link * link.joint.motion(*v))
            .collect();
        phases.push(ArmPhase {
            what: "handle",
            tree: tree.clone(),
            links: vec![(l, part_poses)],
            hidden: hidden.clone(),
            hollow: hollow.clone(),
            still: worked.clone(),
            set_on: Vec::new(),
            arm: arm_poses(&instants),
        });
        if let (Some(q), Some(&v)) = (along.last(), values.last()) {
            last.clone_from(q);
            tree.links[l].value = v;
        }
    }

    // The retreat: a picked object rides in the hand; a placed one stays where it was set.
    let instants = timed(&last, retreat, None, step_s);
    let links = match handover {
        Some(Change::Attach {
            link,
            to,
            parent_from_link,
            ..
        }) if to == GRIPPER_LINK => link_named(link)
            .map(|l| {
                let poses = instants
                    .iter()
                    .map(|(q, _)| tool(q) * *parent_from_link)
                    .collect();
                vec![(l, poses)]
            })
            .unwrap_or_default(),
        Some(Change::Attach { .. }) if holds => {
            let set_down = tool(&last);
            vec![(gripper, vec![set_down; instants.len()])]
        }
        _ => Vec::new(),
    };
    phases.push(ArmPhase {
        what: "retreat",
        tree,
        links,
        hidden,
        hollow,
        still: worked,
        set_on,
        arm: arm_poses(&instants),
    });
    phases.retain(|p| p.arm.len() > 1);
    phases
}

/// One instant of an arm motion as the viewer shows it.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmInstant {
    pub q: Vec<f32>,
    /// The followed part's value, when the motion follows one.
    pub part: Option<f32>,
    /// Whether the reach is over (a pick's object is in the hand, a place's is set down).
    pub reached: bool,
    /// The fingers' opening (0 closed .. 1 open).
    pub opening: f32,
}

/// The whole of `change` (an arm motion) from the stowed arm at instants `step_s` apart: the
/// reach, the hand on the part's handle (from the part's value `part_from`), the retreat. The
/// fingers close on what the hand holds: from the start of the reach when it comes `holding`
/// something (a place) to its end, from the end of the reach on for a pick, on the handle
/// while the part follows.
pub fn arm_timeline(
    rig: &ArmRig,
    change: &Change,
    part_from: f32,
    holding: bool,
    step_s: f32,
) -> Vec<ArmInstant> {
    let Change::ArmMotion {
        reach,
        retreat,
        part,
        grip_m,
        ..
    } = change
    else {
        return Vec::new();
    };
    let [on_reach, on_handle, on_retreat] = rig.finger_openings(*grip_m, holding, part.is_some());
    let followed = part.as_ref().filter(|p| !p.along.is_empty());
    let mut part_value = followed.map(|_| part_from);
    let mut instants: Vec<ArmInstant> = timed(&rig.stow, reach, None, step_s)
        .into_iter()
        .map(|(q, _)| ArmInstant {
            q,
            part: part_value,
            reached: false,
            opening: on_reach,
        })
        .collect();
    let mut last = reach.last().unwrap_or(&rig.stow).clone();
    if let Some(p) = followed {
        let along = timed(&last, &p.along, Some((part_from, &p.values)), step_s);
        instants.extend(along.into_iter().skip(1).map(|(q, v)| ArmInstant {
            q,
            part: Some(v),
            reached: true,
            opening: on_handle,
        }));
        if let Some(q) = p.along.last() {
            last.clone_from(q);
        }
        part_value = p.values.last().copied();
    }
    instants.extend(
        timed(&last, retreat, None, step_s)
            .into_iter()
            .skip(1)
            .map(|(q, _)| ArmInstant {
                q,
                part: part_value,
                reached: true,
                opening: on_retreat,
            }),
    );
    instants
}

/// The configurations of `path` (from `start`) at instants `step_s` apart, the arm's fastest
/// joint at [`ARM_SPEED`], evenly spread so the last instant is the path's end; with
/// `values` (a part's value at `start` and at each configuration), the value at each instant.
/// The first instant is `start`.
fn timed(
    start: &[f32],
    path: &[Vec<f32>],
    values: Option<(f32, &[f32])>,
    step_s: f32,
) -> Vec<(Vec<f32>, f32)> {
    let mut points: Vec<(&[f32], f32)> = vec![(start, values.map_or(0.0, |v| v.0))];
    for (k, q) in path.iter().enumerate() {
        let v = values.and_then(|(_, vs)| vs.get(k).copied()).unwrap_or(0.0);
        points.push((q, v));
    }
    let mut at = vec![0.0f32];
    for w in points.windows(2) {
        let last = at[at.len() - 1];
        at.push(last + distance(w[0].0, w[1].0) / ARM_SPEED);
    }
    let total = at[at.len() - 1];
    let steps = (total / step_s).ceil() as usize;
    let mut instants = Vec::with_capacity(steps + 1);
    let mut segment = 0;
    for k in 0..=steps {
        let t = if steps == 0 {
            0.0
        } else {
            total * k as f32 / steps as f32
        };
        while segment + 2 < points.len() && at[segment + 1] < t {
            segment += 1;
        }
        let (a, b) = (
            &points[segment],
            &points[(segment + 1).min(points.len() - 1)],
        );
        let span = at[(segment + 1).min(at.len() - 1)] - at[segment];
        let f = if span > 0.0 {
            ((t - at[segment]) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let q = a.0.iter().zip(b.0).map(|(x, y)| x + (y - x) * f).collect();
        instants.push((q, a.1 + (b.1 - a.1) * f));
    }
    instants
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;
    use glam::Vec3;

    /// The root, a floor, the robot at (1, 0) with its gripper, and a cup on the floor (or in
    /// the gripper when `held`).
    fn tree(held: bool) -> KinematicTree {
        let cube = TriMesh::cuboid(Vec3::splat(-0.05), Vec3::splat(0.05));
        let link = |name: &str, class: &str, parent: usize, joint: JointSpec, at: Vec3| {
            let at = Affine3A::from_translation(at);
            TreeLink::body(name, class, parent, joint, at, cube.clone())
        };
        // The robot's links are no scene nodes.
        let robot_link = |name: &str, parent: usize, at: Vec3| TreeLink {
            node: None,
            ..link(name, "robot", parent, JointSpec::FIXED, at)
        };
        let cup = if held {
            link("cup_1", "cup", 3, JointSpec::FIXED, Vec3::ZERO)
        } else {
            link("cup_1", "cup", 1, JointSpec::FLOATING, Vec3::Y)
        };
        KinematicTree {
            links: vec![
                TreeLink::root(),
                link("floor", "floor", 0, JointSpec::FIXED, Vec3::ZERO),
                robot_link(ROBOT_LINK, 0, Vec3::X),
                robot_link(GRIPPER_LINK, 2, Vec3::Z),
                cup,
            ],
        }
    }

    fn motion() -> Change {
        Change::ArmMotion {
            what: "pick cup_1".into(),
            reach: vec![vec![0.5, 0.0], vec![1.0, 0.0]],
            retreat: vec![vec![0.5, 0.0], vec![0.0, 0.0]],
            part: None,
            grip_m: None,
        }
    }

    #[test]
    fn a_picked_object_rides_in_the_hand_from_the_retreat_on_and_a_placed_one_stays_set_down() {
        let rig = ArmRig::new(crate::arm::tests::two_link_arm(), 0.5);
        let grip = Affine3A::from_translation(Vec3::new(0.0, 0.0, 0.05));
        let take = Change::Attach {
            link: "cup_1".into(),
            from: "floor".into(),
            to: GRIPPER_LINK.into(),
            parent_from_link: grip,
        };
        let phases = arm_phases(&tree(false), &rig, &motion(), Some(&take), 0.1);
        assert_eq!(
            phases.iter().map(|p| p.what).collect::<Vec<_>>(),
            ["reach", "retreat"]
        );
        // The reach moves only the arm; the cup holds still until then, simulated hollow.
        assert!(phases[0].links.is_empty());
        assert_eq!(phases[0].hollow, vec![4]);
        assert_eq!(phases[0].still, vec![4]);
        assert_eq!(phases[0].hidden, vec![3]);
        // The retreat carries the cup at the tool's pose with its grip.
        let (cup, poses) = &phases[1].links[0];
        assert_eq!(*cup, 4);
        let root = Affine3A::from_translation(Vec3::X) * rig.base_from_root;
        let last = phases[1].arm.len() - 1;
        let expected = rig.arm.tool_pose(&root, &[0.0, 0.0]) * grip;
        assert!(
            poses[last]
                .translation
                .abs_diff_eq(expected.translation, 1e-5)
        );
        assert_eq!(poses.len(), phases[1].arm.len());
        // The cup leaving the floor it stood on is the lift, not a knock.
        assert_eq!(phases[1].set_on, vec![1]);

        // A place: the gripper carries the cup on the reach, then holds still where it let go.
        let set = Change::Attach {
            link: "cup_1".into(),
            from: GRIPPER_LINK.into(),
            to: "floor".into(),
            parent_from_link: Affine3A::IDENTITY,
        };
        let phases = arm_phases(&tree(true), &rig, &motion(), Some(&set), 0.1);
        let (gripper, reach) = &phases[0].links[0];
        assert_eq!(*gripper, 3);
        let let_go = rig.arm.tool_pose(&root, &[1.0, 0.0]);
        assert!(reach.last().expect("poses").abs_diff_eq(let_go, 1e-5));
        let (_, retreat) = &phases[1].links[0];
        assert!(retreat.iter().all(|p| p.abs_diff_eq(let_go, 1e-5)));
        assert_eq!(phases[1].hollow, vec![4, 1]);
        // The cup touching the floor it is set on is the set-down, not a knock.
        assert_eq!(phases[0].set_on, vec![1]);
        assert_eq!(phases[1].set_on, vec![1]);
    }

    #[test]
    fn the_object_whose_door_the_hand_works_holds_still_while_the_hand_comes_and_goes() {
        let rig = ArmRig::new(crate::arm::tests::two_link_arm(), 0.5);
        let mut scene = tree(false);
        let cabinet = scene.links[4].clone();
        scene.links[4] = TreeLink {
            name: "cabinet_1".into(),
            node: Some("cabinet_1".into()),
            ..cabinet.clone()
        };
        scene.links.push(TreeLink {
            name: "cabinet_1_door".into(),
            node: Some("cabinet_1".into()),
            parent: Some(4),
            joint: JointSpec::revolute(Vec3::Z, 0.0, 1.5),
            parent_from_link: Affine3A::IDENTITY,
            ..cabinet
        });
        let open = Change::ArmMotion {
            what: "open cabinet_1_door".into(),
            reach: vec![vec![0.5, 0.0], vec![1.0, 0.0]],
            retreat: vec![vec![0.5, 0.0], vec![0.0, 0.0]],
            part: Some(PartFollow {
                link: "cabinet_1_door".into(),
                values: vec![0.5, 1.0],
                along: vec![vec![1.0, 0.5], vec![1.0, 1.0]],
            }),
            grip_m: None,
        };
        let phases = arm_phases(&scene, &rig, &open, None, 0.1);
        assert_eq!(
            phases.iter().map(|p| p.what).collect::<Vec<_>>(),
            ["reach", "handle", "retreat"]
        );
        assert_eq!(phases[0].still, vec![4]);
        // The door turns with the hand, its cabinet still; the hand then lets go.
        assert_eq!(phases[1].links[0].0, 5);
        assert_eq!(phases[1].still, vec![4]);
        assert_eq!(phases[2].still, vec![4]);
    }

    #[test]
    fn a_path_is_timed_at_the_arm_speed_and_ends_where_it_ends() {
        let start = [0.0, 0.0];
        let path = vec![vec![0.5, 0.0], vec![0.5, 1.0]];
        // 1.5 rad at 1 rad/s in steps of 0.1 s: 15 steps, 16 instants.
        let instants = timed(&start, &path, Some((0.0, &[0.1, 0.3])), 0.1);
        assert_eq!(instants.len(), 16);
        assert_eq!(instants[0], (vec![0.0, 0.0], 0.0));
        let (q, v) = &instants[15];
        assert!(
            (q[0] - 0.5).abs() < 1e-6 && (q[1] - 1.0).abs() < 1e-6,
            "{q:?}"
        );
        assert!((v - 0.3).abs() < 1e-6);
        // At 0.5 s, the end of the first segment.
        let (q, v) = &instants[5];
        assert!((q[0] - 0.5).abs() < 1e-5 && q[1].abs() < 1e-5, "{q:?}");
        assert!((v - 0.1).abs() < 1e-5);
        // Nothing to do: the start alone.
        assert_eq!(timed(&start, &[], None, 0.1).len(), 1);
    }
}
