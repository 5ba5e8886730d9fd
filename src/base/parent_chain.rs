//! Walks up a tree stored as each node's parent index (kinematic trees, an arm's links).

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
