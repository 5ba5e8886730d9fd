//! Graph edit distance between two contact graphs, unit costs: inserting or deleting a node or an
//! edge costs 1, relabelling a node's class costs 1; a support edge to the wrong parent is one
//! deletion plus one insertion, 2. Exact by branch and bound for small graphs; for large ones the
//! bipartite bound (Riesen and Bunke): Kuhn-Munkres on node costs that include each node's local
//! edges, the node mapping it gives costed exactly (an upper bound), improved by swaps.

use std::collections::BTreeSet;

use glam::Vec3;
use pathfinding::kuhn_munkres::kuhn_munkres_min;
use pathfinding::matrix::Matrix;

use crate::graph::{ContactGraph, GraphEdge};

/// Exact search is used up to this many nodes in the larger graph.
pub const EXACT_MAX_NODES: usize = 9;

/// A graph reduced to what the edit distance looks at.
#[derive(Clone, Debug)]
pub struct EditGraph {
    pub classes: Vec<String>,
    /// Box centres, to prefer matching nodes where they are (ties between same-class nodes).
    pub centers: Vec<Vec3>,
    /// (parent, child) node indices.
    pub support: BTreeSet<(usize, usize)>,
    /// (a, b) with a < b.
    pub proximal: BTreeSet<(usize, usize)>,
}

impl EditGraph {
    pub fn from_contact_graph(g: &ContactGraph) -> Self {
        let index = |id: &str| g.nodes.iter().position(|n| n.id == id);
        let mut support = BTreeSet::new();
        let mut proximal = BTreeSet::new();
        for e in &g.edges {
            match e {
                GraphEdge::Support { parent, child } => {
                    if let (Some(p), Some(c)) = (index(parent), index(child)) {
                        support.insert((p, c));
                    }
                }
                GraphEdge::Proximal { a, b } => {
                    if let (Some(a), Some(b)) = (index(a), index(b)) {
                        proximal.insert((a.min(b), a.max(b)));
                    }
                }
            }
        }
        Self {
            classes: g.nodes.iter().map(|n| n.class.clone()).collect(),
            centers: g
                .nodes
                .iter()
                .map(|n| Vec3::from_array(n.bbox.center))
                .collect(),
            support,
            proximal,
        }
    }

    fn len(&self) -> usize {
        self.classes.len()
    }
}

/// The distance and whether it is exact (else an upper bound from the bipartite mapping), with
/// the edits of the path it was measured on by kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub struct EditDistance {
    pub cost: u32,
    pub exact: bool,
    pub parts: EditParts,
}

/// Edits by kind: nodes inserted, deleted or relabelled; support and proximal edges inserted or
/// deleted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct EditParts {
    pub nodes: u32,
    pub support: u32,
    pub proximal: u32,
}

/// Which node of `a` may stand for which node of `b` (`allowed[i][j]`); `None`: any.
pub type Allowed<'a> = Option<&'a [Vec<bool>]>;

fn may_map(allowed: Allowed<'_>, i: usize, j: usize) -> bool {
    allowed.is_none_or(|a| a[i][j])
}

/// The edit distance: exact when both graphs have at most `EXACT_MAX_NODES` nodes.
pub fn graph_edit_distance(a: &EditGraph, b: &EditGraph) -> EditDistance {
    graph_edit_distance_where(a, b, None)
}

/// The edit distance where node `i` of `a` may become node `j` of `b` only when `allowed` says
/// so (otherwise it is deleted and `j` inserted).
pub fn graph_edit_distance_where(
    a: &EditGraph,
    b: &EditGraph,
    allowed: Allowed<'_>,
) -> EditDistance {
    let (bound, mapping) = bipartite_bound_where(a, b, allowed);
    if a.len().max(b.len()) <= EXACT_MAX_NODES {
        let (cost, mapping) = exact_search(a, b, bound, mapping, allowed);
        EditDistance {
            cost,
            exact: true,
            parts: mapping_parts(a, b, &mapping),
        }
    } else {
        EditDistance {
            cost: bound,
            exact: false,
            parts: mapping_parts(a, b, &mapping),
        }
    }
}

/// The exact cost of the edit path a node mapping implies: `mapping[i]` is the node of `b` that
/// node `i` of `a` becomes, `None` = deleted; nodes of `b` no one maps to are inserted.
pub fn mapping_cost(a: &EditGraph, b: &EditGraph, mapping: &[Option<usize>]) -> u32 {
    let p = mapping_parts(a, b, mapping);
    p.nodes + p.support + p.proximal
}

/// The edits, by kind, of the path `mapping` implies (see `mapping_cost`).
pub fn mapping_parts(a: &EditGraph, b: &EditGraph, mapping: &[Option<usize>]) -> EditParts {
    let mut cost = 0u32;
    let mut used = vec![false; b.len()];
    for (i, m) in mapping.iter().enumerate() {
        match m {
            Some(j) => {
                used[*j] = true;
                cost += u32::from(a.classes[i] != b.classes[*j]);
            }
            None => cost += 1,
        }
    }
    cost += used.iter().filter(|u| !**u).count() as u32;
    let mapped = |(p, c): &(usize, usize)| mapping[*p].zip(mapping[*c]);
    let kept_support = a
        .support
        .iter()
        .filter(|e| mapped(e).is_some_and(|m| b.support.contains(&m)))
        .count();
    let kept_proximal = a
        .proximal
        .iter()
        .filter(|e| mapped(e).is_some_and(|(x, y)| b.proximal.contains(&(x.min(y), x.max(y)))))
        .count();
    EditParts {
        nodes: cost,
        support: (a.support.len() - kept_support + b.support.len() - kept_support) as u32,
        proximal: (a.proximal.len() - kept_proximal + b.proximal.len() - kept_proximal) as u32,
    }
}

/// Kuhn-Munkres on node costs (class, local edges halved, a small pull towards the nearest
/// centre), then the mapping's exact cost, then pairwise swaps while they lower it.
pub fn bipartite_upper_bound(a: &EditGraph, b: &EditGraph) -> (u32, Vec<Option<usize>>) {
    bipartite_bound_where(a, b, None)
}

fn bipartite_bound_where(
    a: &EditGraph,
    b: &EditGraph,
    allowed: Allowed<'_>,
) -> (u32, Vec<Option<usize>>) {
    let (n, m) = (a.len(), b.len());
    let size = n + m;
    // Integer costs in thousandths of an edit.
    const UNIT: i64 = 1000;
    const FORBIDDEN: i64 = 1_000_000_000;
    let degree = |g: &EditGraph, i: usize| {
        (g.support.iter().filter(|(p, c)| *p == i || *c == i).count()
            + g.proximal
                .iter()
                .filter(|(x, y)| *x == i || *y == i)
                .count()) as i64
    };
    let has_parent = |g: &EditGraph, i: usize| g.support.iter().any(|(_, c)| *c == i);
    let parent_class = |g: &EditGraph, i: usize| {
        g.support
            .iter()
            .find(|(_, c)| *c == i)
            .map(|(p, _)| g.classes[*p].clone())
    };
    let mut rows = vec![vec![0i64; size]; size];
    for (i, row) in rows.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = match (i < n, j < m) {
                (true, true) if !may_map(allowed, i, j) => FORBIDDEN,
                (true, true) => {
                    let class = i64::from(a.classes[i] != b.classes[j]) * UNIT;
                    let edges = (degree(a, i) - degree(b, j)).abs() * UNIT / 2;
                    let parent =
                        i64::from(has_parent(a, i) && parent_class(a, i) != parent_class(b, j))
                            * UNIT;
                    let distance = (a.centers[i].distance(b.centers[j]) * 100.0).min(500.0) as i64;
                    class + edges + parent + distance
                }
                // Deleting node i of a (diagonal only).
                (true, false) => {
                    if j - m == i {
                        UNIT + degree(a, i) * UNIT / 2
                    } else {
                        FORBIDDEN
                    }
                }
                // Inserting node j of b.
                (false, true) => {
                    if i - n == j {
                        UNIT + degree(b, j) * UNIT / 2
                    } else {
                        FORBIDDEN
                    }
                }
                (false, false) => 0,
            };
        }
    }
    let mut mapping: Vec<Option<usize>> = vec![None; n];
    if size > 0
        && let Ok(matrix) = Matrix::from_rows(rows)
    {
        let (_, assignment) = kuhn_munkres_min(&matrix);
        for (i, m_i) in mapping.iter_mut().enumerate() {
            let j = assignment[i];
            *m_i = (j < m && may_map(allowed, i, j)).then_some(j);
        }
    }
    let mut cost = mapping_cost(a, b, &mapping);
    // Swaps (including with deletion) while any lowers the exact cost.
    loop {
        let mut improved = false;
        for i in 0..n {
            for k in (i + 1)..n {
                mapping.swap(i, k);
                let fits = |x: usize| mapping[x].is_none_or(|j| may_map(allowed, x, j));
                let c = if fits(i) && fits(k) {
                    mapping_cost(a, b, &mapping)
                } else {
                    u32::MAX
                };
                if c < cost {
                    cost = c;
                    improved = true;
                } else {
                    mapping.swap(i, k);
                }
            }
        }
        if !improved {
            break;
        }
    }
    (cost, mapping)
}

/// Branch and bound over the nodes of `a`, each mapped to an unused node of `b` or deleted,
/// starting from the bound `upper`. Exponential: for small graphs only.
pub fn exact_distance(a: &EditGraph, b: &EditGraph, upper: u32) -> u32 {
    exact_search(a, b, upper, vec![None; a.len()], None).0
}

/// The exact distance and a mapping that reaches it; `upper` and `start` are a known cost and
/// the mapping that reaches it (returned when nothing beats it).
fn exact_search(
    a: &EditGraph,
    b: &EditGraph,
    upper: u32,
    start: Vec<Option<usize>>,
    allowed: Allowed<'_>,
) -> (u32, Vec<Option<usize>>) {
    let mut best = (upper, start);
    let mut mapping = vec![None; a.len()];
    let mut used = vec![false; b.len()];
    search(a, b, allowed, 0, &mut mapping, &mut used, &mut best);
    best
}

fn search(
    a: &EditGraph,
    b: &EditGraph,
    allowed: Allowed<'_>,
    i: usize,
    mapping: &mut [Option<usize>],
    used: &mut [bool],
    best: &mut (u32, Vec<Option<usize>>),
) {
    if i == a.len() {
        let cost = mapping_cost(a, b, mapping);
        if cost < best.0 {
            *best = (cost, mapping.to_vec());
        }
        return;
    }
    if partial_lower_bound(a, b, i, mapping, used) >= best.0 {
        return;
    }
    for j in 0..b.len() {
        if used[j] || !may_map(allowed, i, j) {
            continue;
        }
        used[j] = true;
        mapping[i] = Some(j);
        search(a, b, allowed, i + 1, mapping, used, best);
        used[j] = false;
    }
    mapping[i] = None;
    search(a, b, allowed, i + 1, mapping, used, best);
}

/// A lower bound on any completion of the first `i` assignments: the node and edge edits among
/// decided nodes are final, and the undecided nodes of the larger side cost at least their
/// surplus.
fn partial_lower_bound(
    a: &EditGraph,
    b: &EditGraph,
    i: usize,
    mapping: &[Option<usize>],
    used: &[bool],
) -> u32 {
    let mut cost = 0u32;
    for (k, m) in mapping[..i].iter().enumerate() {
        cost += match m {
            Some(j) => u32::from(a.classes[k] != b.classes[*j]),
            None => 1,
        };
    }
    let decided = |x: usize| x < i;
    let image = |x: usize| mapping[x];
    // Edges of a between decided nodes are settled: kept or deleted.
    for &(p, c) in &a.support {
        if decided(p) && decided(c) {
            let kept = image(p)
                .zip(image(c))
                .is_some_and(|e| b.support.contains(&e));
            cost += u32::from(!kept);
        }
    }
    for &(x, y) in &a.proximal {
        if decided(x) && decided(y) {
            let kept = image(x)
                .zip(image(y))
                .is_some_and(|(u, v)| b.proximal.contains(&(u.min(v), u.max(v))));
            cost += u32::from(!kept);
        }
    }
    // Edges of b between used nodes that no decided pair of a maps onto must be inserted.
    let preimage = |j: usize| mapping[..i].iter().position(|m| *m == Some(j));
    for &(p, c) in &b.support {
        if used[p] && used[c] {
            let covered = preimage(p)
                .zip(preimage(c))
                .is_some_and(|e| a.support.contains(&e));
            cost += u32::from(!covered);
        }
    }
    for &(x, y) in &b.proximal {
        if used[x] && used[y] {
            let covered = preimage(x)
                .zip(preimage(y))
                .is_some_and(|(u, v)| a.proximal.contains(&(u.min(v), u.max(v))));
            cost += u32::from(!covered);
        }
    }
    let left_a = a.len() - i;
    let left_b = used.iter().filter(|u| !**u).count();
    cost + left_a.abs_diff(left_b) as u32
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    const CLASSES: [&str; 4] = ["floor", "table", "cup", "chair"];

    fn random_graph(rng: &mut ChaCha8Rng, n: usize) -> EditGraph {
        let classes: Vec<String> = (0..n)
            .map(|_| CLASSES[rng.random_range(0..CLASSES.len())].to_string())
            .collect();
        let mut support = BTreeSet::new();
        for c in 1..n {
            if rng.random_bool(0.7) {
                support.insert((rng.random_range(0..c), c));
            }
        }
        let mut proximal = BTreeSet::new();
        for _ in 0..n / 2 {
            let (x, y) = (rng.random_range(0..n), rng.random_range(0..n));
            if x != y {
                proximal.insert((x.min(y), x.max(y)));
            }
        }
        EditGraph {
            classes,
            centers: (0..n).map(|i| Vec3::splat(i as f32)).collect(),
            support,
            proximal,
        }
    }

    #[test]
    fn a_graph_is_at_distance_zero_from_itself_and_known_edits_cost_what_they_should() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let g = random_graph(&mut rng, 7);
        let same = graph_edit_distance(&g, &g);
        assert_eq!((same.cost, same.exact), (0, true));
        // A wrong support parent costs 2.
        let mut wrong = g.clone();
        let &(p, c) = g.support.iter().next().expect("an edge");
        wrong.support.remove(&(p, c));
        let other = (0..7)
            .find(|&q| q != p && q != c && !g.support.contains(&(q, c)))
            .expect("node");
        wrong.support.insert((other, c));
        let d = graph_edit_distance(&g, &wrong);
        assert!(d.cost <= 2);
        assert_eq!(d.cost, d.parts.nodes + d.parts.support + d.parts.proximal);
        // A missing leaf with its one edge costs 2.
        let mut small = g.clone();
        small.classes.push("cup".into());
        small.centers.push(Vec3::splat(100.0));
        small.support.insert((0, 7));
        assert_eq!(graph_edit_distance(&g, &small).cost, 2);
    }

    #[test]
    fn the_bipartite_bound_is_never_below_the_exact_distance_and_usually_equal() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut equal = 0;
        let trials = 40;
        for _ in 0..trials {
            let n = rng.random_range(2..7);
            let a = random_graph(&mut rng, n);
            let m = rng.random_range(2..7);
            let b = random_graph(&mut rng, m);
            let (bound, mapping) = bipartite_upper_bound(&a, &b);
            assert_eq!(bound, mapping_cost(&a, &b, &mapping));
            let exact = exact_distance(&a, &b, u32::MAX);
            assert!(exact <= bound, "exact {exact} above the bound {bound}");
            assert_eq!(
                exact,
                exact_distance(&a, &b, bound),
                "the bound only prunes"
            );
            equal += usize::from(exact == bound);
        }
        assert!(
            equal * 2 >= trials,
            "the bound was exact in {equal} of {trials}"
        );
    }
}
