//! Selection: which hypotheses cross, and the memoised `Branch` recursion
//! that resolves crossing ones.

use std::collections::HashMap;

use rand::Rng;
use rand_chacha::ChaCha8Rng;

pub(super) fn crosses(a: (usize, usize), b: (usize, usize)) -> bool {
    (a.0 < b.0 && b.0 < a.1 && a.1 < b.1) || (b.0 < a.0 && a.0 < b.1 && b.1 < a.1)
}

/// Memoised best non-crossing subset of the crossing hypotheses inside
/// `(b, e)`: `(members, sum of scores)`.
pub(super) fn best_set(
    b: usize,
    e: usize,
    by_span: &HashMap<(usize, usize), usize>,
    scores: &[f64],
    memo: &mut HashMap<(usize, usize), (Vec<usize>, f64)>,
    rng: &mut ChaCha8Rng,
) -> (Vec<usize>, f64) {
    if let Some(v) = memo.get(&(b, e)) {
        return v.clone();
    }
    let mut best: (Vec<usize>, f64) = (Vec::new(), 0.0);
    if e > b + 1 {
        let mean = |v: &(Vec<usize>, f64)| {
            if v.0.is_empty() {
                f64::INFINITY
            } else {
                v.1 / v.0.len() as f64
            }
        };
        let mut first = true;
        let mut ties = 1u32;
        for k in (b + 1)..e {
            let l = best_set(b, k, by_span, scores, memo, rng);
            let r = best_set(k, e, by_span, scores, memo, rng);
            let mut set = l.0.clone();
            set.extend_from_slice(&r.0);
            let cand = (set, l.1 + r.1);
            if first {
                best = cand;
                first = false;
                continue;
            }
            let (mc, mb) = (mean(&cand), mean(&best));
            let better = if mc < mb {
                true
            } else if mc == mb || (mc.is_infinite() && mb.is_infinite()) {
                if cand.0.len() != best.0.len() {
                    cand.0.len() > best.0.len()
                } else {
                    // Reservoir choice among equal candidates (seeded).
                    ties += 1;
                    rng.random_range(0..ties) == 0
                }
            } else {
                false
            };
            if better {
                if mc < mb || cand.0.len() != best.0.len() {
                    ties = 1;
                }
                best = cand;
            }
        }
    }
    if let Some(&h) = by_span.get(&(b, e)) {
        best.0.push(h);
        best.1 += scores[h];
    }
    memo.insert((b, e), best.clone());
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing() {
        assert!(crosses((0, 3), (2, 5)));
        assert!(!crosses((0, 3), (1, 2)));
        assert!(!crosses((0, 3), (3, 5)));
    }
}
