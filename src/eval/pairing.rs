//! Greedy one-to-one pairing of truth and prediction, best candidate first: what the CAD and
//! articulation metrics pair objects and parts by.

/// Which prediction each truth gets from `candidates` (score, truth index, prediction index):
/// taken best first (highest score when `higher_is_better`, else lowest; ties by truth, then
/// prediction index), each truth and each prediction at most once.
pub fn greedy_pairs(
    mut candidates: Vec<(f32, usize, usize)>,
    truths: usize,
    predictions: usize,
    higher_is_better: bool,
) -> Vec<Option<usize>> {
    candidates.sort_by(|a, b| {
        let by_score = if higher_is_better {
            b.0.total_cmp(&a.0)
        } else {
            a.0.total_cmp(&b.0)
        };
        by_score.then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2))
    });
    let mut pred_of = vec![None; truths];
    let mut taken = vec![false; predictions];
    for (_, t, p) in candidates {
        if pred_of[t].is_none() && !taken[p] {
            pred_of[t] = Some(p);
            taken[p] = true;
        }
    }
    pred_of
}
