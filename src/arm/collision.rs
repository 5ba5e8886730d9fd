//! Collision checking of the arm against the scene and against itself, with a clearance margin:
//! each link's convex collision pieces against convex obstacles (parry's GJK distance), after a
//! bounding-box test.
//!
//! Which pairs of the arm's own links are checked follows MoveIt's setup assistant: not links
//! that no joint or a single joint separates (their meshes meet at the joint by design), and not
//! pairs that touch in most random configurations (meshes drawn overlapping); every other pair is.

use glam::{Affine3A, Vec3};
use parry3d::math::Pose;
use parry3d::shape::ConvexPolyhedron;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::arm::{Arm, LinkMotion, random_configuration};
use crate::geometry::TriMesh;
use crate::geometry::convex_depth::rigid_pose;
use crate::geometry::mesh::points_bounds;
use crate::kinematics::joint_sweep::world_bounds;
use crate::kinematics::motion_bounds::overlaps;

/// Random configurations drawn to find the pairs of links that always touch.
const SELF_SAMPLES: usize = 200;
/// A pair touching in at least this fraction of them is never checked.
const ALWAYS_TOUCHING: f32 = 0.5;

/// A convex piece of something the arm must not touch, in the world.
#[derive(Clone)]
pub struct Obstacle {
    /// What it belongs to (a link of the scene's kinematic tree), for the reasons a plan fails.
    pub name: String,
    /// Part of the object being grasped: the fingers may touch it (up to `FINGER_DEPTH_M`
    /// deep), the rest of the arm not.
    pub fingers_may_touch: bool,
    hull: ConvexPolyhedron,
    pose: Pose,
    lo: Vec3,
    hi: Vec3,
}

impl Obstacle {
    /// Its highest point, metres up.
    pub fn top(&self) -> f32 {
        self.hi.z
    }
}

/// The obstacles of a scene.
#[derive(Clone, Default)]
pub struct Obstacles {
    pub items: Vec<Obstacle>,
}

impl Obstacles {
    /// Adds `piece` (a convex mesh in its own frame) placed at `world_from_piece`; a piece that
    /// spans no volume is skipped.
    pub fn add(&mut self, name: &str, piece: &TriMesh, world_from_piece: &Affine3A) {
        let Some(hull) = ConvexPolyhedron::from_convex_hull(&piece.positions) else {
            return;
        };
        let pose = rigid_pose(world_from_piece);
        let Some((lo, hi)) = piece.transformed(world_from_piece).bounds() else {
            return;
        };
        self.items.push(Obstacle {
            name: name.to_string(),
            fingers_may_touch: false,
            hull,
            pose,
            lo,
            hi,
        });
    }

    /// These obstacles as the object being grasped: only the fingers may touch them.
    pub fn grasped(mut self) -> Self {
        for item in &mut self.items {
            item.fingers_may_touch = true;
        }
        self
    }
}

/// What a link of the arm touches.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Touching {
    /// An obstacle, by its index.
    Obstacle(usize),
    /// Another link of the arm.
    Link(usize),
    /// The object in the hand touches an obstacle, by its index.
    Held(usize),
}

/// The arm's collision pieces and the pairs of its links worth checking.
pub struct ArmCollider {
    /// Per link: its convex pieces and their bounds, in the link's frame.
    pieces: Vec<Vec<(ConvexPolyhedron, Vec3, Vec3)>>,
    /// Pairs of links checked against each other.
    pub self_pairs: Vec<(usize, usize)>,
    /// Per link: whether it is a finger (it may touch what is being grasped).
    fingers: Vec<bool>,
}

impl ArmCollider {
    pub fn new(arm: &Arm) -> Self {
        let pieces: Vec<Vec<(ConvexPolyhedron, Vec3, Vec3)>> = arm
            .links
            .iter()
            .map(|link| {
                link.pieces
                    .iter()
                    .filter_map(|p| {
                        let (lo, hi) = p.bounds()?;
                        Some((ConvexPolyhedron::from_convex_hull(&p.positions)?, lo, hi))
                    })
                    .collect()
            })
            .collect();
        let mut collider = Self {
            pieces,
            self_pairs: Vec::new(),
            fingers: arm
                .motion
                .iter()
                .map(|m| *m == LinkMotion::Finger)
                .collect(),
        };
        let candidates: Vec<(usize, usize)> = (0..arm.links.len())
            .flat_map(|a| (a + 1..arm.links.len()).map(move |b| (a, b)))
            .filter(|&(a, b)| {
                !collider.pieces[a].is_empty()
                    && !collider.pieces[b].is_empty()
                    && joints_between(arm, a, b) > 1
            })
            .collect();
        let mut touching = vec![0usize; candidates.len()];
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let limits = arm.limits();
        for _ in 0..SELF_SAMPLES {
            let q = random_configuration(&limits, &mut rng);
            let poses = arm.link_poses(&Affine3A::IDENTITY, &q, 0.5);
            for (count, &(a, b)) in touching.iter_mut().zip(&candidates) {
                *count += usize::from(collider.links_within(a, &poses[a], b, &poses[b], 0.0));
            }
        }
        collider.self_pairs = candidates
            .into_iter()
            .zip(touching)
            .filter(|&(_, n)| (n as f32) < ALWAYS_TOUCHING * SELF_SAMPLES as f32)
            .map(|(pair, _)| pair)
            .collect();
        collider
    }

    /// This collider for the arm on a lift (`Arm::on_lift`): the lift moves every link alike and
    /// has no pieces, so the pairs checked are the arm's, one index further on.
    pub fn on_lift(self) -> Self {
        Self {
            pieces: std::iter::once(Vec::new()).chain(self.pieces).collect(),
            self_pairs: self
                .self_pairs
                .into_iter()
                .map(|(a, b)| (a + 1, b + 1))
                .collect(),
            fingers: std::iter::once(false).chain(self.fingers).collect(),
        }
    }

    /// The first thing a link of the arm (at `poses`) comes within `margin` of: an obstacle, or
    /// a link of a checked pair; `None` when the configuration is free.
    pub fn touching(
        &self,
        poses: &[Affine3A],
        obstacles: &Obstacles,
        margin: f32,
    ) -> Option<(usize, Touching)> {
        self.touching_obstacles(poses, obstacles, margin, &[])
            .or_else(|| {
                self.self_pairs
                    .iter()
                    .find(|&&(a, b)| self.links_within(a, &poses[a], b, &poses[b], margin))
                    .map(|&(a, b)| (a, Touching::Link(b)))
            })
    }

    /// The first link of the arm, but those in `skip`, that comes within `margin` of an
    /// obstacle, with the obstacle (the arm's own links not checked; a finger not against
    /// what is being grasped).
    pub fn touching_obstacles(
        &self,
        poses: &[Affine3A],
        obstacles: &Obstacles,
        margin: f32,
        skip: &[usize],
    ) -> Option<(usize, Touching)> {
        for (l, pieces) in self.pieces.iter().enumerate() {
            if skip.contains(&l) {
                continue;
            }
            let pose = rigid_pose(&poses[l]);
            for (hull, lo, hi) in pieces {
                let (wlo, whi) = world_bounds(&poses[l], *lo, *hi);
                for (o, obstacle) in obstacles.items.iter().enumerate() {
                    let finger_on_it = obstacle.fingers_may_touch && self.fingers[l];
                    if !overlaps((wlo, whi), (obstacle.lo, obstacle.hi), margin) {
                        continue;
                    }
                    let touches = if finger_on_it {
                        deeper(&pose, hull, &obstacle.pose, &obstacle.hull, FINGER_DEPTH_M)
                    } else {
                        within(&pose, hull, &obstacle.pose, &obstacle.hull, margin)
                    };
                    if touches {
                        return Some((l, Touching::Obstacle(o)));
                    }
                }
            }
        }
        None
    }

    /// [`Self::touching`] with an object in the hand: its convex pieces `held`, in the frame of
    /// link `tool`, checked against the obstacles too.
    /// `beside`: names of obstacles the held object may touch (it stood against them where the
    /// hand took it), the arm's links may not.
    #[allow(clippy::too_many_arguments, reason = "the arm, its load and the scene")]
    pub fn touching_holding(
        &self,
        poses: &[Affine3A],
        tool: usize,
        held: &[ConvexPolyhedron],
        beside: &[String],
        obstacles: &Obstacles,
        margin: f32,
    ) -> Option<(usize, Touching)> {
        if let Some(touch) = self.touching(poses, obstacles, margin) {
            return Some(touch);
        }
        self.held_touching(&poses[tool], held, obstacles, margin)
            .into_iter()
            .find(|&o| !beside.contains(&obstacles.items[o].name))
            .map(|o| (tool, Touching::Held(o)))
    }

    /// The obstacles `held` (pieces in the tool's frame, the tool at `world_from_tool`) comes
    /// within `margin` of, in order.
    pub fn held_touching(
        &self,
        world_from_tool: &Affine3A,
        held: &[ConvexPolyhedron],
        obstacles: &Obstacles,
        margin: f32,
    ) -> Vec<usize> {
        let pose = rigid_pose(world_from_tool);
        let mut found: Vec<usize> = Vec::new();
        for hull in held {
            let (lo, hi) = hull_bounds(hull);
            let (wlo, whi) = world_bounds(world_from_tool, lo, hi);
            for (o, obstacle) in obstacles.items.iter().enumerate() {
                if !found.contains(&o)
                    && overlaps((wlo, whi), (obstacle.lo, obstacle.hi), margin)
                    && within(&pose, hull, &obstacle.pose, &obstacle.hull, margin)
                {
                    found.push(o);
                }
            }
        }
        found.sort_unstable();
        found
    }

    fn links_within(&self, a: usize, pa: &Affine3A, b: usize, pb: &Affine3A, margin: f32) -> bool {
        let (ra, rb) = (rigid_pose(pa), rigid_pose(pb));
        self.pieces[a].iter().any(|(ha, alo, ahi)| {
            let (wlo_a, whi_a) = world_bounds(pa, *alo, *ahi);
            self.pieces[b].iter().any(|(hb, blo, bhi)| {
                let (wlo_b, whi_b) = world_bounds(pb, *blo, *bhi);
                overlaps((wlo_a, whi_a), (wlo_b, whi_b), margin) && within(&ra, ha, &rb, hb, margin)
            })
        })
    }
}

/// How many moving joints lie on the tree path between links `a` and `b`.
fn joints_between(arm: &Arm, a: usize, b: usize) -> usize {
    let ancestors = |mut l: usize| {
        let mut path = vec![l];
        while let Some(p) = arm.links[l].parent {
            path.push(p);
            l = p;
        }
        path
    };
    let (pa, pb) = (ancestors(a), ancestors(b));
    let common = pa.iter().find(|l| pb.contains(l)).copied();
    let moving = |path: &[usize]| {
        path.iter()
            .take_while(|&&l| Some(l) != common)
            .filter(|&&l| arm.motion[l] != LinkMotion::Welded)
            .count()
    };
    moving(&pa) + moving(&pb)
}

/// How deep a finger may press into what it grasps, metres: the fingers close on it, but no
/// further than contact allows (the motion check in rapier refuses 5 mm).
pub const FINGER_DEPTH_M: f32 = 0.004;

/// Whether two convex pieces overlap by more than `depth`.
fn deeper(pa: &Pose, a: &ConvexPolyhedron, pb: &Pose, b: &ConvexPolyhedron, depth: f32) -> bool {
    parry3d::query::contact(pa, a, pb, b, 0.0)
        .ok()
        .flatten()
        .is_some_and(|c| c.dist < -depth)
}

/// Whether two convex pieces come within `margin` of each other.
fn within(pa: &Pose, a: &ConvexPolyhedron, pb: &Pose, b: &ConvexPolyhedron, margin: f32) -> bool {
    if margin <= 0.0 {
        return parry3d::query::intersection_test(pa, a, pb, b).unwrap_or(true);
    }
    parry3d::query::distance(pa, a, pb, b).map_or(true, |d| d < margin)
}

fn hull_bounds(hull: &ConvexPolyhedron) -> (Vec3, Vec3) {
    points_bounds(hull.points()).unwrap_or_default()
}
