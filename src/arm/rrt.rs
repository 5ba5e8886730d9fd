//! Motion planning in joint space: RRT-Connect (Kuffner and LaValle 2000) between two
//! configurations, then random shortcutting of the path (Geraerts and Overmars 2007).
//!
//! Two trees grow from the start and the goal. Each round samples a configuration, extends one
//! tree a step towards it, then connects the other tree to the new node greedily; the trees
//! swap roles every round. Every edge is checked at a fixed joint-space resolution. Samples come
//! from a seeded generator: the same problem and seed give the same path.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// How the planner samples, steps and checks.
#[derive(Clone, Copy, Debug)]
pub struct PlanSettings {
    /// The longest edge of a tree (joint-space distance, radians).
    pub step: f32,
    /// The largest joint-space distance between two checked configurations along an edge.
    pub resolution: f32,
    /// Samples before the planner gives up.
    pub max_samples: usize,
    /// Shortcut attempts on the found path.
    pub shortcuts: usize,
    pub seed: u64,
}

impl Default for PlanSettings {
    fn default() -> Self {
        Self {
            step: 0.3,
            resolution: 0.02,
            max_samples: 4000,
            shortcuts: 150,
            seed: 0,
        }
    }
}

/// Why no path came out.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanError {
    #[error("the start configuration is in collision")]
    StartInCollision,
    #[error("the goal configuration is in collision")]
    GoalInCollision,
    #[error("no collision-free path found in {0} samples")]
    NoPath(usize),
}

/// A collision-free path from `start` to `goal` (both included) within `limits`, every
/// configuration on its straight segments at `settings.resolution` accepted by `free`.
pub fn plan(
    start: &[f32],
    goal: &[f32],
    limits: &[(f32, f32)],
    free: &dyn Fn(&[f32]) -> bool,
    settings: &PlanSettings,
) -> Result<Vec<Vec<f32>>, PlanError> {
    if !free(start) {
        return Err(PlanError::StartInCollision);
    }
    if !free(goal) {
        return Err(PlanError::GoalInCollision);
    }
    if segment_free(start, goal, free, settings.resolution) {
        return Ok(vec![start.to_vec(), goal.to_vec()]);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let mut a = Tree::new(start);
    let mut b = Tree::new(goal);
    let mut a_is_start = true;
    for _ in 0..settings.max_samples {
        let sample = crate::arm::random_configuration(limits, &mut rng);
        if let Some(new) = a.extend(&sample, free, settings) {
            let target = a.nodes[new].clone();
            if let Some(reached) = b.connect(&target, free, settings) {
                let (from_start, from_goal) = if a_is_start {
                    (a.path_to(new), b.path_to(reached))
                } else {
                    (b.path_to(reached), a.path_to(new))
                };
                let mut path = from_start;
                path.extend(from_goal.into_iter().rev().skip(1));
                return Ok(shortcut(path, free, settings, &mut rng));
            }
        }
        std::mem::swap(&mut a, &mut b);
        a_is_start = !a_is_start;
    }
    Err(PlanError::NoPath(settings.max_samples))
}

/// Joint-space distance.
pub fn distance(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f32>()
        .sqrt()
}

fn lerp(a: &[f32], b: &[f32], t: f32) -> Vec<f32> {
    a.iter().zip(b).map(|(x, y)| x + t * (y - x)).collect()
}

/// Whether every configuration on the straight segment from `a` to `b`, at `resolution`, is
/// free (`a` is taken as checked).
pub fn segment_free(a: &[f32], b: &[f32], free: &dyn Fn(&[f32]) -> bool, resolution: f32) -> bool {
    let steps = (distance(a, b) / resolution).ceil().max(1.0) as usize;
    (1..=steps).all(|i| free(&lerp(a, b, i as f32 / steps as f32)))
}

/// The configurations along `path` at `resolution` (joint-space distance), ends included: what
/// an executed motion passes through.
pub fn densify(path: &[Vec<f32>], resolution: f32) -> Vec<Vec<f32>> {
    let mut out: Vec<Vec<f32>> = path.first().cloned().into_iter().collect();
    for pair in path.windows(2) {
        let steps = (distance(&pair[0], &pair[1]) / resolution).ceil().max(1.0) as usize;
        out.extend((1..=steps).map(|i| lerp(&pair[0], &pair[1], i as f32 / steps as f32)));
    }
    out
}

/// Total joint-space length of a path.
pub fn path_length(path: &[Vec<f32>]) -> f32 {
    path.windows(2).map(|w| distance(&w[0], &w[1])).sum()
}

struct Tree {
    nodes: Vec<Vec<f32>>,
    parents: Vec<Option<usize>>,
}

enum Step {
    Reached(usize),
    Advanced(usize),
    Trapped,
}

impl Tree {
    fn new(root: &[f32]) -> Self {
        Self {
            nodes: vec![root.to_vec()],
            parents: vec![None],
        }
    }

    fn nearest(&self, q: &[f32]) -> usize {
        (0..self.nodes.len())
            .min_by(|&i, &j| distance(&self.nodes[i], q).total_cmp(&distance(&self.nodes[j], q)))
            .expect("a tree has its root")
    }

    /// One step from the nearest node towards `q`.
    fn step(&mut self, q: &[f32], free: &dyn Fn(&[f32]) -> bool, settings: &PlanSettings) -> Step {
        let near = self.nearest(q);
        let d = distance(&self.nodes[near], q);
        let (new, reached) = if d <= settings.step {
            (q.to_vec(), true)
        } else {
            (lerp(&self.nodes[near], q, settings.step / d), false)
        };
        if !segment_free(&self.nodes[near], &new, free, settings.resolution) {
            return Step::Trapped;
        }
        self.nodes.push(new);
        self.parents.push(Some(near));
        let id = self.nodes.len() - 1;
        if reached {
            Step::Reached(id)
        } else {
            Step::Advanced(id)
        }
    }

    fn extend(
        &mut self,
        q: &[f32],
        free: &dyn Fn(&[f32]) -> bool,
        settings: &PlanSettings,
    ) -> Option<usize> {
        match self.step(q, free, settings) {
            Step::Reached(id) | Step::Advanced(id) => Some(id),
            Step::Trapped => None,
        }
    }

    /// Steps towards `q` until it is reached (its node) or the way is blocked (`None`).
    fn connect(
        &mut self,
        q: &[f32],
        free: &dyn Fn(&[f32]) -> bool,
        settings: &PlanSettings,
    ) -> Option<usize> {
        loop {
            match self.step(q, free, settings) {
                Step::Reached(id) => return Some(id),
                Step::Advanced(_) => {}
                Step::Trapped => return None,
            }
        }
    }

    /// The configurations from the root to node `id`.
    fn path_to(&self, mut id: usize) -> Vec<Vec<f32>> {
        let mut path = vec![self.nodes[id].clone()];
        while let Some(p) = self.parents[id] {
            path.push(self.nodes[p].clone());
            id = p;
        }
        path.reverse();
        path
    }
}

/// Random shortcuts: two points on the path (anywhere along its segments) are joined by a
/// straight segment when that segment is free, dropping what lay between.
fn shortcut(
    mut path: Vec<Vec<f32>>,
    free: &dyn Fn(&[f32]) -> bool,
    settings: &PlanSettings,
    rng: &mut ChaCha8Rng,
) -> Vec<Vec<f32>> {
    for _ in 0..settings.shortcuts {
        if path.len() < 3 {
            break;
        }
        let (mut i, mut j) = (
            rng.random_range(0..path.len() - 1),
            rng.random_range(0..path.len() - 1),
        );
        if i > j {
            std::mem::swap(&mut i, &mut j);
        }
        if j <= i {
            continue;
        }
        let (s, t) = (rng.random_range(0.0..1.0), rng.random_range(0.0..1.0));
        let a = lerp(&path[i], &path[i + 1], s);
        let b = lerp(&path[j], &path[j + 1], t);
        if !segment_free(&a, &b, free, settings.resolution) {
            continue;
        }
        let mut shorter: Vec<Vec<f32>> = path[..=i].to_vec();
        shorter.push(a);
        shorter.push(b);
        shorter.extend_from_slice(&path[j + 1..]);
        // Drop repeated points a shortcut at a segment's end leaves.
        shorter.dedup_by(|x, y| distance(x, y) < 1e-6);
        if path_length(&shorter) < path_length(&path) {
            path = shorter;
        }
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point in the unit square around a wall with a gap at its top.
    #[test]
    fn finds_the_way_around_a_wall_and_shortens_it() {
        let wall = |q: &[f32]| !(q[0] > 0.45 && q[0] < 0.55 && q[1] < 0.8);
        let limits = [(0.0, 1.0), (0.0, 1.0)];
        let settings = PlanSettings {
            step: 0.1,
            resolution: 0.005,
            ..PlanSettings::default()
        };
        let path = plan(&[0.1, 0.1], &[0.9, 0.1], &limits, &wall, &settings).expect("a path");
        assert_eq!(path.first().expect("start"), &vec![0.1, 0.1]);
        assert_eq!(path.last().expect("goal"), &vec![0.9, 0.1]);
        for q in densify(&path, 0.005) {
            assert!(wall(&q), "{q:?} is in the wall");
        }
        // Over the wall's top corners and back down: about 0.7 + 0.1 + 0.7.
        let length = path_length(&path);
        assert!(length < 1.9, "length {length}");
        // Deterministic.
        let again = plan(&[0.1, 0.1], &[0.9, 0.1], &limits, &wall, &settings).expect("a path");
        assert_eq!(path, again);
        // A goal in the wall is refused at once.
        assert_eq!(
            plan(&[0.1, 0.1], &[0.5, 0.1], &limits, &wall, &settings),
            Err(PlanError::GoalInCollision)
        );
    }
}
