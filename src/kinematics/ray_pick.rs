//! Which link a ray hits first (a click in the viewer), and which joint a click on it works:
//! the nearest moving part at or above the hit link (a click on a handle works its door), else
//! the object's main door or drawer.

use glam::Vec3;
use parry3d::math::Pose;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::TriMesh as ParryTriMesh;

use crate::kinematics::JointKind;
use crate::kinematics::tree::KinematicTree;

/// The first link `origin + t * direction` hits (t > 0) and the distance along the ray, passing
/// through links of the classes in `see_through` (what the viewer does not draw).
pub fn pick_link(
    tree: &KinematicTree,
    origin: Vec3,
    direction: Vec3,
    see_through: &[&str],
) -> Option<(usize, f32)> {
    pick_link_where(tree, origin, direction, |link| {
        !see_through.contains(&tree.links[link].class.as_deref().unwrap_or(""))
    })
}

/// The first link the ray hits among those `solid` accepts (by index), and the distance.
pub fn pick_link_where(
    tree: &KinematicTree,
    origin: Vec3,
    direction: Vec3,
    solid: impl Fn(usize) -> bool,
) -> Option<(usize, f32)> {
    let direction = direction.normalize_or_zero();
    if direction == Vec3::ZERO {
        return None;
    }
    let poses = tree.world_from_links();
    let mut best: Option<(usize, f32)> = None;
    for (i, link) in tree.links.iter().enumerate() {
        let Some(g) = &link.geometry else {
            continue;
        };
        if g.visual.triangles.is_empty() || !solid(i) {
            continue;
        }
        // The ray in the link's frame: the mesh stays as it is.
        let link_from_world = poses[i].inverse();
        let ray = Ray::new(
            link_from_world.transform_point3(origin),
            link_from_world.transform_vector3(direction),
        );
        let Ok(mesh) = ParryTriMesh::new(g.visual.positions.clone(), g.visual.triangles.clone())
        else {
            continue;
        };
        let Some(t) = mesh.cast_ray(&Pose::IDENTITY, &ray, f32::MAX, false) else {
            continue;
        };
        // The local ray's direction is scaled like the link's frame: measure in the world.
        let distance = t * ray.dir.length() / direction.length();
        if best.is_none_or(|(_, d)| distance < d) {
            best = Some((i, distance));
        }
    }
    best
}

/// The joint a click on `link` works: the link itself or its nearest ancestor with a revolute
/// or prismatic joint within the same object.
pub fn joint_of_click(tree: &KinematicTree, link: usize) -> Option<usize> {
    let node = tree.links[link].node.as_deref()?;
    let mut at = Some(link);
    while let Some(l) = at {
        let here = &tree.links[l];
        if here.node.as_deref() != Some(node) {
            return None;
        }
        if matches!(here.joint.kind, JointKind::Revolute | JointKind::Prismatic) {
            return Some(l);
        }
        at = here.parent;
    }
    None
}

#[cfg(test)]
mod tests {
    use glam::Affine3A;

    use super::*;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;

    /// A cabinet at x in [0, 1] with a door on its front (y = -0.5) hinged at x = 0, and a
    /// handle on the door.
    fn cabinet() -> KinematicTree {
        let mut door = TreeLink::body(
            "cabinet_1_door",
            "cabinet",
            1,
            JointSpec::revolute(Vec3::Z, 0.0, 1.5),
            Affine3A::from_translation(Vec3::new(0.0, -0.5, 0.0)),
            TriMesh::cuboid(Vec3::new(0.0, -0.02, 0.0), Vec3::new(1.0, 0.0, 1.0)),
        );
        door.node = Some("cabinet_1".into());
        let mut handle = TreeLink::body(
            "cabinet_1_door_handle",
            "cabinet",
            2,
            JointSpec::FIXED,
            Affine3A::IDENTITY,
            TriMesh::cuboid(Vec3::new(0.8, -0.06, 0.4), Vec3::new(0.9, -0.02, 0.6)),
        );
        handle.node = Some("cabinet_1".into());
        KinematicTree {
            links: vec![
                TreeLink::root(),
                TreeLink::body(
                    "cabinet_1",
                    "cabinet",
                    0,
                    JointSpec::FIXED,
                    Affine3A::IDENTITY,
                    TriMesh::cuboid(Vec3::new(0.0, -0.5, 0.0), Vec3::new(1.0, 0.5, 1.0)),
                ),
                door,
                handle,
            ],
        }
    }

    #[test]
    fn a_ray_at_the_handle_hits_it_first_and_works_the_door() {
        let tree = cabinet();
        let (link, distance) =
            pick_link(&tree, Vec3::new(0.85, -3.0, 0.5), Vec3::Y, &[]).expect("a hit");
        assert_eq!(tree.links[link].name, "cabinet_1_door_handle");
        assert!((distance - (3.0 - 0.56)).abs() < 1e-4, "{distance}");
        assert_eq!(joint_of_click(&tree, link), Some(2));
        // Beside the handle the door itself is hit; the body has no joint of its own.
        let (door, _) = pick_link(&tree, Vec3::new(0.3, -3.0, 0.5), Vec3::Y, &[]).expect("a hit");
        assert_eq!(tree.links[door].name, "cabinet_1_door");
        assert_eq!(joint_of_click(&tree, 1), None);
        assert!(pick_link(&tree, Vec3::new(3.0, -3.0, 0.5), Vec3::Y, &[]).is_none());
        // Through what is not drawn.
        let (behind, _) =
            pick_link(&tree, Vec3::new(0.3, -3.0, 0.5), Vec3::Y, &["cabinet"]).unwrap_or((0, 0.0));
        assert_eq!(behind, 0, "nothing but cabinet parts on that line");
    }
}
