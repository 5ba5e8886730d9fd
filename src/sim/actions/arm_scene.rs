//! The scene as the arm's planner sees it: every link's collision pieces as obstacles, the
//! object the hand takes or sets down apart from the rest, and the object in the hand as
//! pieces in the tool's frame, with the neighbours it may touch while it is lifted off them.

use glam::{Affine3A, Vec3};
use parry3d::shape::ConvexPolyhedron;

use crate::arm::collision::Obstacles;
use crate::arm::reach::{Held, LIFT_M, STRETCH_MARGIN_M, TRANSIT_MARGIN_M};
use crate::arm::rig::ArmRig;
use crate::geometry::TriMesh;
use crate::sim::robot::{GRIPPER_LINK, ROBOT_LINK};
use crate::sim::scene_view::SceneView;

/// Every link's collision pieces at its pose, except the robot's own and `skip`.
pub fn scene_obstacles(view: &SceneView, skip: &[usize]) -> Obstacles {
    let own = [view.link(ROBOT_LINK), view.link(GRIPPER_LINK)];
    let links: Vec<usize> = (0..view.tree.links.len())
        .filter(|l| !skip.contains(l) && !own.contains(&Some(*l)))
        .collect();
    let mut obstacles = Obstacles::default();
    add_links(&mut obstacles, view, &links, &Affine3A::IDENTITY);
    obstacles
}

/// The collision pieces of `links`, each with its link's name and world pose.
pub(super) fn collision_pieces<'a>(
    view: &'a SceneView,
    links: &'a [usize],
) -> impl Iterator<Item = (&'a str, &'a TriMesh, Affine3A)> + 'a {
    links.iter().flat_map(move |&l| {
        let link = &view.tree.links[l];
        link.geometry
            .iter()
            .flat_map(|g| g.collision.iter())
            .map(move |piece| (link.name.as_str(), piece, view.poses[l]))
    })
}

/// Adds the collision pieces of `links`, each at its pose moved by `moved` (world).
pub(super) fn add_links(
    obstacles: &mut Obstacles,
    view: &SceneView,
    links: &[usize],
    moved: &Affine3A,
) {
    for (name, piece, pose) in collision_pieces(view, links) {
        obstacles.add(name, piece, &(*moved * pose));
    }
}

/// The scene's obstacles around an object the arm takes or sets down, built once per action
/// (every base pose and spot tried shares them).
pub(super) struct AroundObject {
    /// The object's link and what it carries.
    pub(super) links: Vec<usize>,
    /// Everything but the robot.
    pub(super) with_object: Obstacles,
    /// Everything but the robot and the object.
    pub(super) without_object: Obstacles,
    /// Everything but the robot, the object as what the fingers grasp: the palm and the rest
    /// of the arm keep clear of it on a pick's last stretch.
    pub(super) grasped: Obstacles,
}

impl AroundObject {
    pub(super) fn new(view: &SceneView, link: usize) -> Self {
        let links = subtree(view, link);
        let without_object = scene_obstacles(view, &links);
        let mut object = Obstacles::default();
        add_links(&mut object, view, &links, &Affine3A::IDENTITY);
        let mut with_object = without_object.clone();
        with_object.items.extend(object.items.iter().cloned());
        let mut grasped = without_object.clone();
        grasped.items.extend(object.grasped().items);
        Self {
            links,
            with_object,
            without_object,
            grasped,
        }
    }
}

/// The links of `link`'s subtree (an object and what it carries).
pub(super) fn subtree(view: &SceneView, link: usize) -> Vec<usize> {
    (0..view.tree.links.len())
        .filter(|&l| view.descends_from(l, link))
        .collect()
}

/// `held` (in the hand at `world_from_tool`, where it was taken) with the obstacles of `scene`
/// beside it, which it may touch while it is lifted off them, and how far it is lifted:
/// `LIFT_M`, or over their tops by the clearance kept on the way after the lift and 1 cm. The
/// map's models of neighbours can overlap by a centimetre (a bottle and the cup beside it),
/// which a lift straight up does not change. What it stands on (`support`: its links' names)
/// is left by the lift anyway.
pub(super) fn standing_against(
    rig: &ArmRig,
    mut held: Held,
    world_from_tool: &Affine3A,
    scene: &Obstacles,
    support: &[String],
) -> (Held, f32) {
    let beside: Vec<usize> = rig
        .collider
        .held_touching(world_from_tool, &held.pieces, scene, STRETCH_MARGIN_M)
        .into_iter()
        .filter(|&o| !support.contains(&scene.items[o].name))
        .collect();
    let bottom = held
        .pieces
        .iter()
        .flat_map(|p| p.points().iter())
        .map(|p| world_from_tool.transform_point3(Vec3::new(p.x, p.y, p.z)).z)
        .fold(f32::INFINITY, f32::min);
    let lift = beside
        .iter()
        .map(|&o| scene.items[o].top() - bottom + TRANSIT_MARGIN_M + LIFT_CLEAR_M)
        .fold(LIFT_M, f32::max);
    held.beside = beside
        .iter()
        .map(|&o| scene.items[o].name.clone())
        .collect();
    held.beside.sort();
    held.beside.dedup();
    (held, lift)
}

/// A lift off what the held object stands against clears its top by this much, metres.
const LIFT_CLEAR_M: f32 = 0.01;

/// The object's convex pieces in the tool's frame when the tool is at `world_from_tool`.
pub(super) fn held_pieces(view: &SceneView, links: &[usize], world_from_tool: &Affine3A) -> Held {
    let tool_from_world = world_from_tool.inverse();
    let pieces = collision_pieces(view, links)
        .filter_map(|(_, piece, pose)| {
            let tool_from_piece = tool_from_world * pose;
            let points: Vec<Vec3> = piece
                .positions
                .iter()
                .map(|p| tool_from_piece.transform_point3(*p))
                .collect();
            ConvexPolyhedron::from_convex_hull(&points)
        })
        .collect();
    Held {
        pieces,
        beside: Vec::new(),
    }
}
