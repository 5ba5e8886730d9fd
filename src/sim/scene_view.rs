//! Geometric questions the actions ask of the kinematic tree as it stands: where a node's links
//! are, what supports it, whether a container is open, which shelf levels a container has inside
//! and where on a surface or in a container an object fits without touching anything.

use glam::{Affine3A, Vec2, Vec3};

use crate::classes::{ClassTable, EntityKind};
use crate::geometry::TriMesh;
use crate::kinematics::JointKind;
use crate::kinematics::joint_sweep::{LinkSolids, link_penetration};
use crate::kinematics::tree::KinematicTree;

/// Overlap (metres) up to which a placed object only touches its neighbours.
pub const TOUCH_M: f32 = 0.002;
/// A door or drawer counts as open beyond this fraction of its range.
pub const OPEN_FRACTION: f32 = 0.5;
/// Free height an object needs above itself on a shelf, metres.
const HEADROOM_M: f32 = 0.01;
/// Gap kept between a placed object and anything beside it, metres.
const SIDE_GAP_M: f32 = 0.02;
/// Spacing of the spots tried on a surface, metres.
const SPOT_STEP_M: f32 = 0.05;

/// The tree at its current joint values, with every link's world pose.
pub struct SceneView<'a> {
    pub tree: &'a KinematicTree,
    pub poses: Vec<Affine3A>,
}

impl<'a> SceneView<'a> {
    pub fn new(tree: &'a KinematicTree) -> Self {
        Self {
            tree,
            poses: tree.world_from_links(),
        }
    }

    pub fn link(&self, name: &str) -> Option<usize> {
        self.tree.links.iter().position(|l| l.name == name)
    }

    /// The node's own link (named by the node).
    pub fn node_link(&self, id: &str) -> Option<usize> {
        self.tree
            .links
            .iter()
            .position(|l| l.name == id && l.node.as_deref() == Some(id))
    }

    pub fn class_of(&self, id: &str) -> Option<&str> {
        self.node_link(id)
            .and_then(|l| self.tree.links[l].class.as_deref())
    }

    /// Every contact-graph node in the tree, in tree order.
    pub fn nodes(&self) -> Vec<&str> {
        self.tree
            .links
            .iter()
            .filter(|l| l.node.as_deref() == Some(l.name.as_str()))
            .map(|l| l.name.as_str())
            .collect()
    }

    /// The node that carries `id` (its parent link's node), `None` when it hangs from the root
    /// or from something that is no node (the robot's gripper).
    pub fn support_of(&self, id: &str) -> Option<&str> {
        let link = self.node_link(id)?;
        let parent = self.tree.links[link].parent?;
        self.tree.links[parent].node.as_deref()
    }

    /// Whether `link` hangs below `ancestor` (or is it).
    pub fn descends_from(&self, link: usize, ancestor: usize) -> bool {
        self.tree.descends_from(link, ancestor)
    }

    /// The links of node `id` that move with its own link (its body and fixed parts).
    pub fn body_links(&self, id: &str) -> Vec<usize> {
        let Some(own) = self.node_link(id) else {
            return Vec::new();
        };
        (0..self.tree.links.len())
            .filter(|&i| {
                self.tree.links[i].node.as_deref() == Some(id) && {
                    let mut at = i;
                    loop {
                        if at == own {
                            break true;
                        }
                        if self.tree.links[at].joint.kind != JointKind::Fixed {
                            break false;
                        }
                        match self.tree.links[at].parent {
                            Some(p) => at = p,
                            None => break false,
                        }
                    }
                }
            })
            .collect()
    }

    /// The revolute and prismatic joints of node `id` (their links), door first.
    pub fn moving_parts(&self, id: &str) -> Vec<usize> {
        let mut parts: Vec<usize> = (0..self.tree.links.len())
            .filter(|&i| {
                let l = &self.tree.links[i];
                l.node.as_deref() == Some(id)
                    && matches!(l.joint.kind, JointKind::Revolute | JointKind::Prismatic)
                    && l.joint.limits.is_some()
            })
            .collect();
        parts.sort_by_key(|&i| !self.tree.links[i].name.ends_with("_door"));
        parts
    }

    /// The joint that opens container `id`: its door, else its first moving part.
    pub fn main_part(&self, id: &str) -> Option<usize> {
        self.moving_parts(id).first().copied()
    }

    /// Whether container `id`'s main part is open (beyond half its range).
    pub fn is_open(&self, id: &str) -> bool {
        self.main_part(id).is_some_and(|j| self.is_part_open(j))
    }

    /// Whether moving part `link` is open (beyond half its range).
    pub fn is_part_open(&self, link: usize) -> bool {
        open_fraction(self.tree, link) > OPEN_FRACTION
    }

    /// Whether `id`'s class is a container (articulated: it has doors or drawers).
    pub fn is_container(&self, id: &str) -> bool {
        self.class_of(id)
            .and_then(|c| ClassTable::builtin().get(c))
            .is_some_and(|c| c.kind == EntityKind::Articulated)
            && self.main_part(id).is_some()
    }

    /// Whether `id`'s class moves (a floating joint to its support).
    pub fn is_movable(&self, id: &str) -> bool {
        self.class_of(id)
            .and_then(|c| ClassTable::builtin().get(c))
            .is_some_and(|c| c.movable)
    }

    pub fn is_layout(&self, id: &str) -> bool {
        ClassTable::builtin().is_layout(self.class_of(id))
    }

    /// A link's surface mesh in the world.
    pub fn world_mesh(&self, link: usize) -> TriMesh {
        self.tree.links[link]
            .geometry
            .as_ref()
            .map(|g| g.surface.transformed(&self.poses[link]))
            .unwrap_or_default()
    }

    /// The node's body meshes in the node's own link frame.
    pub fn body_mesh_in_node(&self, id: &str) -> TriMesh {
        let Some(own) = self.node_link(id) else {
            return TriMesh::default();
        };
        let node_from_world = self.poses[own].inverse();
        let mut mesh = TriMesh::default();
        for l in self.body_links(id) {
            if let Some(g) = &self.tree.links[l].geometry {
                mesh.append(&g.surface.transformed(&(node_from_world * self.poses[l])));
            }
        }
        mesh
    }

    /// World bounds of all of node `id`'s links.
    pub fn node_bounds(&self, id: &str) -> Option<(Vec3, Vec3)> {
        let mut mesh = TriMesh::default();
        for (i, l) in self.tree.links.iter().enumerate() {
            if l.node.as_deref() == Some(id) {
                mesh.append(&self.world_mesh(i));
            }
        }
        mesh.bounds()
    }

    /// Whether `object` is inside container `container`: carried by it and its centre below
    /// the container's top, within its footprint.
    pub fn is_inside(&self, object: &str, container: &str) -> bool {
        if self.support_of(object) != Some(container) || !self.is_container(container) {
            return false;
        }
        let (Some(o), Some(c)) = (self.node_link(object), self.node_link(container)) else {
            return false;
        };
        let Some((lo, hi)) = self.body_mesh_in_node(container).bounds() else {
            return false;
        };
        let Some((olo, ohi)) = self.local_bounds(o) else {
            return false;
        };
        let centre = self.poses[c]
            .inverse()
            .transform_point3(self.poses[o].transform_point3((olo + ohi) / 2.0));
        centre.cmpgt(lo).all() && centre.cmplt(hi).all()
    }

    /// A link's visual bounds in its own frame.
    pub fn local_bounds(&self, link: usize) -> Option<(Vec3, Vec3)> {
        self.tree.links[link].geometry.as_ref()?.visual.bounds()
    }

    /// The deepest overlap of `link`, posed at `world_from_link`, with every other link but
    /// what it carries and the links in `ignore`.
    pub fn overlap_at(&self, link: usize, world_from_link: Affine3A, ignore: &[usize]) -> f32 {
        let moving = LinkSolids::of(self.tree, link);
        let mut deepest = 0.0f32;
        for other in 0..self.tree.links.len() {
            if self.descends_from(other, link) || ignore.contains(&other) {
                continue;
            }
            let solids = LinkSolids::of(self.tree, other);
            if solids.is_empty() {
                continue;
            }
            deepest = deepest.max(link_penetration(
                &moving,
                &world_from_link,
                &solids,
                &self.poses[other],
            ));
        }
        deepest
    }

    /// Where `object` can stand on top of `surface`: its pose in the world, upright with its
    /// current yaw, at the free spot nearest `near` (the robot) on the surface's top, or `None`.
    pub fn spot_on(
        &self,
        object: usize,
        surface: &str,
        near: Vec2,
        ignore: &[usize],
    ) -> Option<Affine3A> {
        let own = self.node_link(surface)?;
        let body = self.body_mesh_in_node(surface);
        let (lo, hi) = body.bounds()?;
        let (olo, ohi) = self.local_bounds(object)?;
        let half = (ohi - olo).truncate() / 2.0;
        let margin = half.max_element() + SIDE_GAP_M;
        let world_from_surface = self.poses[own];
        let mut spots: Vec<Vec2> = Vec::new();
        let (nx, ny) = (
            ((hi.x - lo.x - 2.0 * margin) / SPOT_STEP_M).floor() as i32,
            ((hi.y - lo.y - 2.0 * margin) / SPOT_STEP_M).floor() as i32,
        );
        for i in 0..=nx.max(-1) {
            for j in 0..=ny.max(-1) {
                spots.push(Vec2::new(
                    lo.x + margin + i as f32 * SPOT_STEP_M,
                    lo.y + margin + j as f32 * SPOT_STEP_M,
                ));
            }
        }
        let distance = |s: &Vec2| {
            world_from_surface
                .transform_point3(s.extend(hi.z))
                .truncate()
                .distance(near)
        };
        spots.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
        let yaw = yaw_of(&self.poses[object]);
        spots.into_iter().find_map(|s| {
            // The top must be there (a table's top, not the gap beside an L-shaped desk).
            let top = vertical_hits(&body, s).into_iter().fold(f32::MIN, f32::max);
            if top < hi.z - 0.01 {
                return None;
            }
            let bottom_in_world = world_from_surface.transform_point3(s.extend(top));
            let pose = upright_on(bottom_in_world, yaw, olo, ohi);
            (self.overlap_at(object, pose, ignore) <= TOUCH_M).then_some(pose)
        })
    }

    /// Where `object` fits inside `container` (whose door is open): the first of
    /// [`Self::spots_in`] without `near`; `None` when it fits nowhere.
    pub fn spot_in(&self, object: usize, container: &str, ignore: &[usize]) -> Option<Affine3A> {
        self.spots_in(object, container, ignore, None).next()
    }

    /// Where `object` fits inside `container` (whose door is open), best first: behind an open
    /// door, on the lowest of its inner levels with room for it, centred, else shifted towards
    /// the front, or nearest `near` first (the base of an arm that puts it there: a spot near
    /// the front is in reach). The object keeps the container's orientation. Each spot's room
    /// is measured as it is asked for.
    pub fn spots_in<'s>(
        &'s self,
        object: usize,
        container: &str,
        ignore: &'s [usize],
        near: Option<Vec2>,
    ) -> impl Iterator<Item = Affine3A> + 's {
        let candidates = self.local_bounds(object).map_or_else(Vec::new, |bounds| {
            self.candidate_spots_in(container, bounds, near)
        });
        candidates
            .into_iter()
            .filter(move |pose| self.overlap_at(object, *pose, ignore) <= TOUCH_M)
    }

    /// The poses [`Self::spots_in`] tries, in its order: on the levels of `container` with room
    /// for an object of local bounds `olo..ohi`.
    fn candidate_spots_in(
        &self,
        container: &str,
        (olo, ohi): (Vec3, Vec3),
        near: Option<Vec2>,
    ) -> Vec<Affine3A> {
        let mut spots = Vec::new();
        let body = self.body_mesh_in_node(container);
        let (Some(own), Some((lo, hi))) = (self.node_link(container), body.bounds()) else {
            return spots;
        };
        let height = ohi.z - olo.z;
        let centre = (lo + hi).truncate() / 2.0;
        let world_from_container = self.poses[own];
        let yaw = yaw_of(&world_from_container);
        // Behind an open door, else in the middle: one door of two open leaves the middle
        // half behind the closed one.
        let mut across = self.open_doors_across(container);
        across.push(centre.x);
        for x in across {
            let at = Vec2::new(x, centre.y);
            for (floor, ceiling) in inner_levels(&body, at, lo.z, hi.z) {
                if ceiling - floor < height + HEADROOM_M {
                    continue;
                }
                // Centred first, then towards the open front (-y in the model frame); or
                // nearest `near` first.
                let mut depths = [0.0, -0.05, -0.1, 0.05];
                if let Some(near) = near {
                    let from = world_from_container
                        .inverse()
                        .transform_point3(near.extend(0.0));
                    let off = |dy: &f32| Vec2::new(x, centre.y + dy).distance(from.truncate());
                    depths.sort_by(|a, b| off(a).total_cmp(&off(b)));
                }
                for dy in depths {
                    let bottom = Vec3::new(x, centre.y + dy, floor + 0.001);
                    spots.push(upright_on(
                        world_from_container.transform_point3(bottom),
                        yaw,
                        olo,
                        ohi,
                    ));
                }
            }
        }
        spots
    }

    /// The middle (x in the frame of node `container`) of the front each of its open doors
    /// closes.
    fn open_doors_across(&self, container: &str) -> Vec<f32> {
        let Some(own) = self.node_link(container) else {
            return Vec::new();
        };
        let node_from_world = self.poses[own].inverse();
        self.moving_parts(container)
            .into_iter()
            .filter(|&j| {
                self.tree.links[j].joint.kind == JointKind::Revolute
                    && open_fraction(self.tree, j) > OPEN_FRACTION
            })
            .filter_map(|j| {
                let link = &self.tree.links[j];
                let parent = link.parent.map_or(Affine3A::IDENTITY, |p| self.poses[p]);
                let closed =
                    parent * link.parent_from_link * link.joint.motion(closed_value(self.tree, j));
                let door = link
                    .geometry
                    .as_ref()?
                    .visual
                    .transformed(&(node_from_world * closed));
                let (lo, hi) = door.bounds()?;
                Some(0.5 * (lo.x + hi.x))
            })
            .collect()
    }
}

/// How far a joint is open: its value as a fraction of the way to the limit farther from 0.
pub fn open_fraction(tree: &KinematicTree, link: usize) -> f32 {
    let l = &tree.links[link];
    let open = open_value(tree, link);
    if open.abs() < 1e-6 {
        return 0.0;
    }
    (l.value / open).clamp(0.0, 1.0)
}

pub use crate::kinematics::joint_sweep::open_value;

/// The closed end of a joint's range: the limit nearer zero.
pub fn closed_value(tree: &KinematicTree, link: usize) -> f32 {
    let (lo, hi) = tree.links[link].joint.limits.unwrap_or((0.0, 0.0));
    if hi.abs() >= lo.abs() { lo } else { hi }
}

/// The yaw of a pose's x axis about +z.
pub fn yaw_of(pose: &Affine3A) -> f32 {
    let x = pose.matrix3.x_axis;
    x.y.atan2(x.x)
}

/// The pose that sets an object of local bounds `lo..hi` upright with `yaw`, the centre of its
/// bottom face at `bottom_in_world`.
fn upright_on(bottom_in_world: Vec3, yaw: f32, lo: Vec3, hi: Vec3) -> Affine3A {
    let rotation = glam::Quat::from_rotation_z(yaw);
    let bottom_in_link = Vec3::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, lo.z);
    Affine3A::from_rotation_translation(rotation, bottom_in_world - rotation * bottom_in_link)
}

/// Heights where a vertical line through `p` crosses `mesh`, ascending.
pub fn vertical_hits(mesh: &TriMesh, p: Vec2) -> Vec<f32> {
    let mut hits: Vec<f32> = vertical_crossings(mesh, p)
        .into_iter()
        .map(|(z, _)| z)
        .collect();
    hits.dedup_by(|a, b| (*a - *b).abs() < 1e-4);
    hits
}

/// Where a vertical line through `p` crosses `mesh`, ascending, each with whether the line,
/// going up, enters the solid there (the face looks down; meaningful for a closed,
/// outward-wound mesh). The triangles of one face meeting on the line count once; a board's top
/// touching the bottom of the one above counts as both, the entry first.
fn vertical_crossings(mesh: &TriMesh, p: Vec2) -> Vec<(f32, bool)> {
    let mut hits = Vec::new();
    for t in 0..mesh.triangles.len() {
        let [a, b, c] = mesh.triangle(t);
        let (a2, b2, c2) = (a.truncate(), b.truncate(), c.truncate());
        let area = (b2 - a2).perp_dot(c2 - a2);
        if area.abs() < 1e-12 {
            continue;
        }
        let u = (b2 - p).perp_dot(c2 - p) / area;
        let v = (c2 - p).perp_dot(a2 - p) / area;
        let w = 1.0 - u - v;
        if u >= 0.0 && v >= 0.0 && w >= 0.0 {
            // Counter-clockwise seen from above: the face looks up, the line leaves there.
            hits.push((u * a.z + v * b.z + w * c.z, area < 0.0));
        }
    }
    hits.sort_by(|a, b| a.0.total_cmp(&b.0).then(b.1.cmp(&a.1)));
    hits.dedup_by(|a, b| a.1 == b.1 && (a.0 - b.0).abs() < 1e-4);
    hits
}

/// The empty intervals `(floor, ceiling)` a vertical line through `p` passes inside a body made
/// of closed boards, between `bottom` and `top`: air with a board under it and one over it.
/// Counting the boards the line is in (not taking every second gap between crossings) keeps
/// boards that touch (a plinth under the bottom board) from turning air into board.
pub fn inner_levels(body: &TriMesh, p: Vec2, bottom: f32, top: f32) -> Vec<(f32, f32)> {
    let mut levels = Vec::new();
    let mut inside = 0i32;
    let mut floor = None;
    for (z, enters) in vertical_crossings(body, p) {
        if enters {
            if inside == 0
                && let Some(f) = floor.take()
            {
                levels.push((f, z));
            }
            inside += 1;
        } else {
            inside -= 1;
            if inside == 0 {
                floor = Some(z);
            }
        }
    }
    levels
        .into_iter()
        .filter(|(f, c)| *f > bottom && *c < top + 1e-4 && c > f)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_through_a_shelved_box_finds_the_air_between_the_boards() {
        // Bottom board 0..0.02, shelf 0.5..0.52, top 1.0..1.02.
        let mut body = TriMesh::cuboid(Vec3::new(-0.3, -0.3, 0.0), Vec3::new(0.3, 0.3, 0.02));
        body.append(&TriMesh::cuboid(
            Vec3::new(-0.3, -0.3, 0.5),
            Vec3::new(0.3, 0.3, 0.52),
        ));
        body.append(&TriMesh::cuboid(
            Vec3::new(-0.3, -0.3, 1.0),
            Vec3::new(0.3, 0.3, 1.02),
        ));
        let levels = inner_levels(&body, Vec2::new(0.01, 0.02), 0.0, 1.02);
        assert_eq!(levels.len(), 2, "{levels:?}");
        assert!((levels[0].0 - 0.02).abs() < 1e-5 && (levels[0].1 - 0.5).abs() < 1e-5);
        assert!((levels[1].0 - 0.52).abs() < 1e-5 && (levels[1].1 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn boards_that_touch_leave_the_air_between_them_air() {
        // A plinth 0..0.08 under the bottom board 0.08..0.1 (the cabinet of the kitchen's
        // reconstruction), a shelf 0.48..0.5, the top 0.86..0.88: the crossings at 0.08 are
        // two, and taking every second gap made the boards the levels.
        let mut body = TriMesh::cuboid(Vec3::new(-0.3, -0.3, 0.0), Vec3::new(0.3, 0.3, 0.08));
        for (lo, hi) in [(0.08, 0.1), (0.48, 0.5), (0.86, 0.88)] {
            body.append(&TriMesh::cuboid(
                Vec3::new(-0.3, -0.3, lo),
                Vec3::new(0.3, 0.3, hi),
            ));
        }
        let levels = inner_levels(&body, Vec2::new(0.01, 0.02), 0.0, 0.88);
        assert_eq!(levels.len(), 2, "{levels:?}");
        assert!((levels[0].0 - 0.1).abs() < 1e-5 && (levels[0].1 - 0.48).abs() < 1e-5);
        assert!((levels[1].0 - 0.5).abs() < 1e-5 && (levels[1].1 - 0.86).abs() < 1e-5);
    }

    #[test]
    fn upright_placement_puts_the_bottom_centre_on_the_spot() {
        let pose = upright_on(
            Vec3::new(1.0, 2.0, 0.75),
            0.5,
            Vec3::new(-0.05, -0.05, 0.0),
            Vec3::new(0.05, 0.05, 0.1),
        );
        let p = pose.transform_point3(Vec3::ZERO);
        assert!((p - Vec3::new(1.0, 2.0, 0.75)).length() < 1e-6);
        assert!((yaw_of(&pose) - 0.5).abs() < 1e-6);
    }
}
