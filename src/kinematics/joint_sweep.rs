//! Sweeps every door and drawer of a kinematic tree across its range and reports what it hits:
//! a door must open without hitting its neighbour, a drawer must slide out of its cabinet.
//!
//! The moving side is the joint's link and everything it carries; the other side is every
//! other link, its own cabinet included. Collisions are contacts between convex collision
//! pieces (parry), deeper than the tolerance, at any of the sampled joint values.

use glam::{Affine3A, Vec3};
use parry3d::shape::ConvexPolyhedron;
use rayon::prelude::*;
use serde::Serialize;

use crate::geometry::convex_depth::convex_penetration;
use crate::kinematics::JointKind;
use crate::kinematics::tree::KinematicTree;

/// Overlaps up to this depth (metres) are contact, not collision (the physical check's bar).
pub const SWEEP_TOLERANCE_M: f32 = 0.01;

/// Joint values tried from the lower to the upper limit.
pub const SWEEP_SAMPLES: usize = 9;

/// A joint's range ends where its part first presses into another object or the room deeper
/// than this (metres) beyond how it touches them at rest: a door left at a limit inside the wall
/// is pushed out by MuJoCo and PyBullet, so the exported limit stops where it touches.
pub const LIMIT_CONTACT_M: f32 = 0.0005;

/// Halvings of the interval between the last sample clear of contact and the first one in it
/// (1.8 rad in 8 samples: to 0.9 mrad, under 1 mm at a 1 m door's edge).
const LIMIT_BISECTIONS: usize = 8;

/// What one joint's sweep found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JointSweep {
    /// The moving link (its joint is `<link>_joint`).
    pub link: String,
    /// The deepest overlap with any other link at any sampled value, metres.
    pub max_penetration_m: f32,
    /// The link hit deepest and the joint value where it happened.
    pub hits: Option<(String, f32)>,
    /// No collision deeper than the tolerance anywhere in the range.
    pub free: bool,
    /// The range the tree should keep when the part meets another object or the room before a
    /// limit (a door stopped by the wall beside it): from its value at rest out to where it
    /// touches, either way.
    pub reachable: Option<(f32, f32)>,
    /// The part cannot move through `MIN_FREE_SHARE` of its model's range: a conflict between
    /// the model or its pose and the scene, kept in the report (the range is not narrowed to
    /// make it fit).
    pub conflict: bool,
    /// Other joints of the same object that had to be open first (a dishwasher's rack slides
    /// out once its door is down); empty when the joint moves from the scene as it stands.
    pub after_opening: Vec<String>,
}

/// A link's collision pieces as parry shapes in the link frame, each with its local bounds.
pub struct LinkSolids {
    pieces: Vec<(ConvexPolyhedron, Vec3, Vec3)>,
}

impl LinkSolids {
    /// Nothing: a link left out of a sweep.
    pub fn none() -> Self {
        Self { pieces: Vec::new() }
    }

    pub fn of(tree: &KinematicTree, link: usize) -> Self {
        let pieces = tree.links[link]
            .geometry
            .iter()
            .flat_map(|g| g.collision.iter())
            .filter_map(|piece| {
                let (lo, hi) = piece.bounds()?;
                Some((
                    ConvexPolyhedron::from_convex_hull(&piece.positions)?,
                    lo,
                    hi,
                ))
            })
            .collect();
        Self { pieces }
    }

    pub fn is_empty(&self) -> bool {
        self.pieces.is_empty()
    }
}

/// World-frame bounds of a local box under `pose`.
pub fn world_bounds(pose: &Affine3A, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let center = pose.transform_point3((lo + hi) / 2.0);
    let half = (hi - lo) / 2.0;
    let m = pose.matrix3;
    let extent = m.x_axis.abs() * half.x + m.y_axis.abs() * half.y + m.z_axis.abs() * half.z;
    (center - Vec3::from(extent), center + Vec3::from(extent))
}

/// The deepest overlap between two posed links, metres (0 when apart).
pub fn link_penetration(
    a: &LinkSolids,
    pose_a: &Affine3A,
    b: &LinkSolids,
    pose_b: &Affine3A,
) -> f32 {
    let mut deepest = 0.0f32;
    for (sa, alo, ahi) in &a.pieces {
        let (alo, ahi) = world_bounds(pose_a, *alo, *ahi);
        for (sb, blo, bhi) in &b.pieces {
            let (blo, bhi) = world_bounds(pose_b, *blo, *bhi);
            if !(alo.cmple(bhi).all() && blo.cmple(ahi).all()) {
                continue;
            }
            if let Some((depth, _)) = convex_penetration(sa, pose_a, sb, pose_b) {
                deepest = deepest.max(depth);
            }
        }
    }
    deepest
}

/// Sweeps every revolute and prismatic joint of `tree` (the others stay at their values).
pub fn sweep_joints(tree: &KinematicTree) -> Vec<JointSweep> {
    let solids: Vec<LinkSolids> = (0..tree.links.len())
        .map(|i| LinkSolids::of(tree, i))
        .collect();
    let joints: Vec<usize> = (0..tree.links.len())
        .filter(|&i| {
            matches!(
                tree.links[i].joint.kind,
                JointKind::Revolute | JointKind::Prismatic
            ) && tree.links[i].joint.limits.is_some()
        })
        .collect();
    joints
        .par_iter()
        .map(|&j| {
            let as_is = sweep_one(tree, &solids, j, &[]);
            let blocked_by_own_part = as_is.hits.as_ref().is_some_and(|(hit, _)| {
                let hit = tree.links.iter().find(|l| &l.name == hit);
                hit.is_some_and(|l| l.node.is_some() && l.node == tree.links[j].node)
            });
            if as_is.free || !blocked_by_own_part {
                return as_is;
            }
            // Open the object's other doors and drawers (not those carrying this one) and try again.
            let others: Vec<usize> = joints
                .iter()
                .copied()
                .filter(|&o| {
                    o != j
                        && tree.links[o].node == tree.links[j].node
                        && !tree.descends_from(j, o)
                        && !tree.descends_from(o, j)
                })
                .collect();
            let opened = sweep_one(tree, &solids, j, &others);
            if opened.free { opened } else { as_is }
        })
        .collect()
}

/// The open end of a joint's range: the limit farther from zero.
pub fn open_value(tree: &KinematicTree, link: usize) -> f32 {
    let (lo, hi) = tree.links[link].joint.limits.unwrap_or((0.0, 0.0));
    if hi.abs() >= lo.abs() { hi } else { lo }
}

/// The moving and the still links of one joint's sweep, and the tree posed as it goes.
pub(crate) struct SweepPose<'a> {
    posed: KinematicTree,
    joint: usize,
    /// The joint's link and what it carries.
    pub moving: Vec<usize>,
    /// Every other link with a solid.
    pub still: Vec<usize>,
    solids: &'a [LinkSolids],
}

impl<'a> SweepPose<'a> {
    /// Joint `joint` of `tree` (links' solids `solids`) to be swept, the joints `open` set to
    /// their open ends.
    pub(crate) fn new(
        tree: &KinematicTree,
        solids: &'a [LinkSolids],
        joint: usize,
        open: &[usize],
    ) -> Self {
        let moving: Vec<usize> = (0..tree.links.len())
            .filter(|&i| tree.descends_from(i, joint))
            .collect();
        let still: Vec<usize> = (0..tree.links.len())
            .filter(|i| !moving.contains(i) && !solids[*i].is_empty())
            .collect();
        let mut posed = tree.clone();
        for &o in open {
            posed.links[o].value = open_value(tree, o);
        }
        Self {
            posed,
            joint,
            moving,
            still,
            solids,
        }
    }

    /// The still link that overlap `index` of [`depths`](Self::depths) is with.
    pub(crate) fn still_of(&self, index: usize) -> usize {
        self.still[index % self.still.len()]
    }

    /// The overlap of every moving link with every still one (moving-major) at joint value
    /// `value`, metres.
    pub(crate) fn depths(&mut self, value: f32) -> Vec<f32> {
        self.posed.links[self.joint].value = value;
        let poses = self.posed.world_from_links();
        let mut depths = Vec::with_capacity(self.moving.len() * self.still.len());
        for &m in &self.moving {
            for &s in &self.still {
                depths.push(link_penetration(
                    &self.solids[m],
                    &poses[m],
                    &self.solids[s],
                    &poses[s],
                ));
            }
        }
        depths
    }
}

/// A door or drawer must move through this share of its model's range in the scene; one that
/// meets something sooner is a conflict, not a shorter joint (a door stopped by the wall at 85
/// degrees of 100 is narrowed to 85; one stopped at 20 is a conflict).
pub const MIN_FREE_SHARE: f32 = 0.8;

/// Sweeps joint `j` with the joints `open` set to their open ends: from its value at rest out to
/// each limit, recording the deepest overlap and where the moving part first meets another
/// object (or the room) deeper than `LIMIT_CONTACT_M` more than it does at rest.
fn sweep_one(tree: &KinematicTree, solids: &[LinkSolids], j: usize, open: &[usize]) -> JointSweep {
    let (lo, hi) = tree.links[j].joint.limits.unwrap_or((0.0, 0.0));
    let mut pose = SweepPose::new(tree, solids, j, open);
    // The object's own parts are the library's business (its doors clear their cabinet by
    // construction; a rack behind a closed door is what `after_opening` is for).
    let node = tree.links[j].node.as_ref();
    let counts_for_limit: Vec<bool> = pose
        .moving
        .iter()
        .flat_map(|_| {
            pose.still
                .iter()
                .map(|&s| node.is_none() || tree.links[s].node.as_ref() != node)
        })
        .collect();
    let rest = tree.links[j].value.clamp(lo, hi);
    let at_rest = pose.depths(rest);
    let touches_anew = |depths: &[f32]| {
        depths
            .iter()
            .zip(&at_rest)
            .zip(&counts_for_limit)
            .any(|((d, r), counts)| *counts && *d > r.max(0.0) + LIMIT_CONTACT_M)
    };
    // The deepest overlap: its depth, its index in `depths`, the joint's value.
    let mut worst: Option<(f32, usize, f32)> = None;
    let mut note_worst = |depths: &[f32], value: f32| {
        for (p, &depth) in depths.iter().enumerate() {
            if worst.is_none_or(|(d, _, _)| depth > d) {
                worst = Some((depth, p, value));
            }
        }
    };
    note_worst(&at_rest, rest);
    let mut stops = [lo, hi];
    for (end, stop) in [lo, hi].into_iter().zip(stops.iter_mut()) {
        // As many samples either way as the part of the range it covers.
        let share = if hi > lo {
            (end - rest).abs() / (hi - lo)
        } else {
            0.0
        };
        let steps = ((SWEEP_SAMPLES - 1) as f32 * share).ceil() as usize;
        let mut free_value = rest;
        let mut stopped = false;
        for k in 1..=steps {
            let value = rest + (end - rest) * k as f32 / steps as f32;
            let depths = pose.depths(value);
            note_worst(&depths, value);
            if stopped {
                continue;
            }
            if touches_anew(&depths) {
                // Where between the last free sample and this one the contact begins.
                let mut blocked_value = value;
                for _ in 0..LIMIT_BISECTIONS {
                    let middle = 0.5 * (free_value + blocked_value);
                    if touches_anew(&pose.depths(middle)) {
                        blocked_value = middle;
                    } else {
                        free_value = middle;
                    }
                }
                *stop = free_value;
                stopped = true;
            } else {
                free_value = value;
            }
        }
    }
    // A joint left less than an eighth of its range is blocked, not narrowed.
    let reachable = (stops != [lo, hi] && stops[1] - stops[0] >= (hi - lo) / 8.0)
        .then_some((stops[0], stops[1]));
    let max_penetration_m = worst.map_or(0.0, |(d, _, _)| d);
    let free = max_penetration_m <= SWEEP_TOLERANCE_M;
    let conflict = !free && reachable.is_none_or(|(a, b)| b - a < MIN_FREE_SHARE * (hi - lo));
    JointSweep {
        link: tree.links[j].name.clone(),
        max_penetration_m,
        hits: worst
            .filter(|(d, _, _)| *d > SWEEP_TOLERANCE_M)
            .map(|(_, p, v)| (tree.links[pose.still_of(p)].name.clone(), v)),
        free,
        reachable,
        conflict,
        after_opening: open.iter().map(|&o| tree.links[o].name.clone()).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cad::ParametricLibrary;
    use crate::geometry::TriMesh;
    use crate::kinematics::JointSpec;
    use crate::kinematics::tree::TreeLink;

    /// One model of the library as a tree under the world (scale 1, at the origin).
    fn model_tree(model: &crate::cad::model::CadModel) -> KinematicTree {
        let mut links = vec![TreeLink::root()];
        for (k, part) in model.parts.iter().enumerate() {
            let parent_from_link = if k == 0 {
                Affine3A::IDENTITY
            } else {
                part.parent_from_part
            };
            let mut link = TreeLink::body(
                &format!("{}_{}", model.id, part.name),
                &model.class,
                part.parent.map_or(0, |p| p + 1),
                part.joint,
                parent_from_link,
                part.mesh.clone(),
            );
            link.node = Some(model.id.clone());
            links.push(link);
        }
        KinematicTree { links }
    }

    #[test]
    fn every_door_and_drawer_of_the_library_moves_freely_through_its_range() {
        let mut stuck = Vec::new();
        for entry in ParametricLibrary::entries() {
            let model = entry.model();
            if !model.is_articulated() {
                continue;
            }
            for sweep in sweep_joints(&model_tree(&model)) {
                // Built to measure: no overlap over a millimetre anywhere in the range.
                if sweep.max_penetration_m > 0.001 {
                    stuck.push(format!("{}: {sweep:?}", model.id));
                }
            }
        }
        assert!(stuck.is_empty(), "{stuck:#?}");
    }

    #[test]
    fn a_door_swinging_into_a_wall_is_reported_with_the_wall() {
        let link = |name: &str, joint, at: Vec3, size: Vec3| {
            let mesh = TriMesh::cuboid(Vec3::ZERO, size);
            TreeLink::body(
                name,
                "cabinet",
                0,
                joint,
                Affine3A::from_translation(at),
                mesh,
            )
        };
        let mut tree = KinematicTree {
            links: vec![TreeLink::root()],
        };
        // A 0.5 m door along +x, hinged at the origin, opening towards -y; a wall 0.3 m in front.
        tree.links.push(link(
            "door",
            JointSpec::revolute(Vec3::Z, -1.6, 0.0),
            Vec3::ZERO,
            Vec3::new(0.5, 0.02, 1.0),
        ));
        tree.links.push(link(
            "wall",
            JointSpec::FIXED,
            Vec3::new(-1.0, -0.4, 0.0),
            Vec3::new(2.0, 0.1, 1.0),
        ));
        let sweeps = sweep_joints(&tree);
        assert_eq!(sweeps.len(), 1);
        assert!(!sweeps[0].free);
        assert_eq!(sweeps[0].hits.as_ref().map(|h| h.0.as_str()), Some("wall"));
        // It keeps the range from closed (0) to where its edge meets the wall: 0.5 sin(a) = 0.3.
        let (lower, upper) = sweeps[0].reachable.expect("narrowed");
        assert_eq!(upper, 0.0);
        assert!((lower + (0.3f32 / 0.5).asin()).abs() < 0.005, "{lower}");
        // Moved out of the way, the same door is free.
        tree.links[2].parent_from_link = Affine3A::from_translation(Vec3::new(-1.0, -0.8, 0.0));
        assert!(sweep_joints(&tree)[0].free);
    }

    /// A door whose edge presses 5 mm into the wall at its limit collides with nothing (contact
    /// up to 1 cm is allowed) but keeps only the range up to where it touches, in which nothing
    /// overlaps.
    #[test]
    fn a_door_grazing_a_wall_at_its_limit_stops_where_it_touches() {
        let mut tree = KinematicTree {
            links: vec![TreeLink::root()],
        };
        // The door's edge sweeps a 0.5 m circle; the wall's face is 0.495 m away.
        tree.links.push(TreeLink::body(
            "door",
            "cabinet",
            0,
            JointSpec::revolute(Vec3::Z, -1.6, 0.0),
            Affine3A::IDENTITY,
            TriMesh::cuboid(Vec3::ZERO, Vec3::new(0.5, 0.02, 1.0)),
        ));
        tree.links.push(TreeLink::body(
            "wall",
            "wall",
            0,
            JointSpec::FIXED,
            Affine3A::IDENTITY,
            TriMesh::cuboid(Vec3::new(-1.0, -0.6, 0.0), Vec3::new(1.0, -0.495, 1.0)),
        ));
        let sweep = &sweep_joints(&tree)[0];
        assert!(sweep.free, "{sweep:?}");
        assert!(sweep.max_penetration_m > 0.004, "{sweep:?}");
        let (lower, upper) = sweep.reachable.expect("narrowed");
        assert_eq!(upper, 0.0);
        // Touching where 0.5 sin(a) = 0.495, 1.43 rad.
        assert!((lower + (0.99f32).asin()).abs() < 0.01, "{lower}");
        tree.links[1].joint.limits = Some((lower, upper));
        let narrowed = &sweep_joints(&tree)[0];
        assert!(
            narrowed.max_penetration_m <= LIMIT_CONTACT_M,
            "{narrowed:?}"
        );
        assert_eq!(narrowed.reachable, None);
    }
}
