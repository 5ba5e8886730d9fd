//! Walks up a tree stored as each node's parent index (kinematic trees, an arm's links).

/// Each node's children, in node order, from each node's parent (`None` for a root or a node
/// left out).
pub fn children(parents: impl ExactSizeIterator<Item = Option<usize>>) -> Vec<Vec<usize>> {
    let mut children = vec![Vec::new(); parents.len()];
    for (node, parent) in parents.enumerate() {
        if let Some(p) = parent {
            children[p].push(node);
        }
    }
    children
}

/// Whether `node` is `ancestor` or hangs below it, `parent` giving each node's parent.
pub fn descends_from(
    mut node: usize,
    ancestor: usize,
    parent: impl Fn(usize) -> Option<usize>,
) -> bool {
    loop {
        if node == ancestor {
            return true;
        }
        match parent(node) {
            Some(p) => node = p,
            None => return false,
        }
    }
}
