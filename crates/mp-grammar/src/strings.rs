//! Suffix array, LCP array and repeated substrings of a symbol string.
//!
//! * [`suffix_array`]: prefix doubling with radix-free sorting, `O(n log² n)`.
//! * [`lcp_array`]: Kasai et al., `O(n)`; `lcp[r]` is the longest common
//!   prefix of the suffixes of rank `r − 1` and `r` (`lcp[0] = 0`).
//! * [`repeat_classes`]: the LCP intervals (internal nodes of the suffix
//!   tree): each is a set of start positions sharing a prefix of length in
//!   `(parent_len, len]`, i.e. every substring of those lengths occurring at
//!   exactly those positions (≥ 2 of them).
//! * [`protected_spans`]: occurrences that a sentence partition must not
//!   split (paper §5.2), chosen greedily: every repeated substring of length
//!   ≥ `min_len`, longest first (ties: earlier first occurrence), protects
//!   each of its occurrences (left to right) that does not overlap an already
//!   protected occurrence. On `abxcdabycdabxcd` this protects `abxcd` (twice),
//!   `ab` and `cd` — exactly the paper's examples.

/// Suffix array of `s` (start positions in lexicographic order of suffixes).
pub fn suffix_array(s: &[u32]) -> Vec<usize> {
    let n = s.len();
    let mut sa: Vec<usize> = (0..n).collect();
    if n <= 1 {
        return sa;
    }
    let mut rank: Vec<i64> = s.iter().map(|&c| c as i64).collect();
    let mut tmp = vec![0i64; n];
    let mut k = 1;
    loop {
        let key = |i: usize, rank: &[i64]| -> (i64, i64) {
            (rank[i], if i + k < n { rank[i + k] } else { -1 })
        };
        sa.sort_by_key(|&a| key(a, &rank));
        tmp[sa[0]] = 0;
        for w in 1..n {
            tmp[sa[w]] = tmp[sa[w - 1]] + i64::from(key(sa[w - 1], &rank) < key(sa[w], &rank));
        }
        std::mem::swap(&mut rank, &mut tmp);
        if rank[sa[n - 1]] as usize == n - 1 {
            break;
        }
        k *= 2;
    }
    sa
}

/// LCP array (Kasai): `lcp[r] = LCP(suffix sa[r − 1], suffix sa[r])`, `lcp[0] = 0`.
pub fn lcp_array(s: &[u32], sa: &[usize]) -> Vec<usize> {
    let n = s.len();
    let mut rank = vec![0; n];
    for (r, &p) in sa.iter().enumerate() {
        rank[p] = r;
    }
    let mut lcp = vec![0; n];
    let mut h = 0usize;
    for i in 0..n {
        if rank[i] > 0 {
            let j = sa[rank[i] - 1];
            while i + h < n && j + h < n && s[i + h] == s[j + h] {
                h += 1;
            }
            lcp[rank[i]] = h;
            h = h.saturating_sub(1);
        } else {
            h = 0;
        }
    }
    lcp
}

/// A class of repeated substrings: the substrings starting at `positions`
/// with any length in `min_len..=max_len` (all occur exactly there).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RepeatClass {
    /// Shortest length in the class (parent length + 1).
    pub min_len: usize,
    /// Longest length (the LCP value of the interval).
    pub max_len: usize,
    /// Start positions, ascending (≥ 2).
    pub positions: Vec<usize>,
}

/// All LCP intervals of `s` (see the module documentation), `O(n)` many.
pub fn repeat_classes(s: &[u32]) -> Vec<RepeatClass> {
    let n = s.len();
    if n < 2 {
        return Vec::new();
    }
    let sa = suffix_array(s);
    let lcp = lcp_array(s, &sa);
    // Stack of (lcp value, left boundary rank).
    let mut out = Vec::new();
    let mut stack: Vec<(usize, usize)> = vec![(0, 0)];
    for r in 1..=n {
        let cur = if r < n { lcp[r] } else { 0 };
        let mut left = r - 1;
        while let Some(&(h, lb)) = stack.last() {
            if h <= cur {
                break;
            }
            stack.pop();
            let parent = stack.last().map_or(0, |t| t.0).max(cur);
            let mut positions: Vec<usize> = sa[lb..r].to_vec();
            positions.sort_unstable();
            out.push(RepeatClass {
                min_len: parent + 1,
                max_len: h,
                positions,
            });
            left = lb;
        }
        if stack.last().is_none_or(|t| t.0 < cur) {
            stack.push((cur, left));
        }
    }
    out
}

/// Occurrence spans `[start, end)` that must not be split (see the module
/// documentation), sorted by start.
pub fn protected_spans(s: &[u32], min_len: usize) -> Vec<(usize, usize)> {
    let min_len = min_len.max(1);
    let classes = repeat_classes(s);
    let max = classes.iter().map(|c| c.max_len).max().unwrap_or(0);
    let mut covered = vec![false; s.len()];
    let mut spans = Vec::new();
    for len in (min_len..=max).rev() {
        let mut cls: Vec<&RepeatClass> = classes
            .iter()
            .filter(|c| c.min_len <= len && len <= c.max_len)
            .collect();
        cls.sort_by_key(|c| c.positions[0]);
        for c in cls {
            for &p in &c.positions {
                if p + len <= s.len() && !covered[p..p + len].iter().any(|&x| x) {
                    covered[p..p + len].iter_mut().for_each(|x| *x = true);
                    spans.push((p, p + len));
                }
            }
        }
    }
    spans.sort_unstable();
    spans
}

/// Cut positions `c` (a cut before symbol `c`, `1 ≤ c < n`) that split no
/// protected span.
pub fn allowed_cuts(n: usize, protected: &[(usize, usize)]) -> Vec<bool> {
    let mut ok = vec![true; n + 1];
    ok[0] = false;
    if n > 0 {
        ok[n] = false;
    }
    for &(a, b) in protected {
        for c in (a + 1)..b {
            if c < ok.len() {
                ok[c] = false;
            }
        }
    }
    ok
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ids(s: &str) -> Vec<u32> {
        s.bytes().map(|b| b as u32).collect()
    }

    #[test]
    fn suffix_array_and_lcp_match_naive() {
        for s in [
            "banana",
            "abxcdabycdabxcd",
            "aaaaaa",
            "a",
            "",
            "mississippi",
        ] {
            let v = ids(s);
            let sa = suffix_array(&v);
            let mut naive: Vec<usize> = (0..v.len()).collect();
            naive.sort_by(|&a, &b| v[a..].cmp(&v[b..]));
            assert_eq!(sa, naive, "{s}");
            let lcp = lcp_array(&v, &sa);
            for r in 1..v.len() {
                let (a, b) = (&v[sa[r - 1]..], &v[sa[r]..]);
                let h = a.iter().zip(b).take_while(|(x, y)| x == y).count();
                assert_eq!(lcp[r], h, "{s} rank {r}");
            }
        }
    }

    #[test]
    fn repeat_classes_cover_every_repeat() {
        let v = ids("abxcdabycdabxcd");
        let classes = repeat_classes(&v);
        // Every substring occurring ≥ 2 times is in exactly one class, with
        // exactly its occurrences.
        for len in 1..v.len() {
            for p in 0..=v.len() - len {
                let sub = &v[p..p + len];
                let occ: Vec<usize> = (0..=v.len() - len)
                    .filter(|&q| &v[q..q + len] == sub)
                    .collect();
                let hits: Vec<&RepeatClass> = classes
                    .iter()
                    .filter(|c| c.min_len <= len && len <= c.max_len && c.positions.contains(&p))
                    .collect();
                if occ.len() >= 2 {
                    assert_eq!(hits.len(), 1, "{:?}", sub);
                    assert_eq!(hits[0].positions, occ);
                } else {
                    assert!(hits.is_empty());
                }
            }
        }
    }

    #[test]
    fn paper_protected_spans() {
        let v = ids("abxcdabycdabxcd");
        let spans = protected_spans(&v, 2);
        assert_eq!(spans, vec![(0, 5), (5, 7), (8, 10), (10, 15)]);
        let ok = allowed_cuts(v.len(), &spans);
        let cuts: Vec<usize> = (0..=v.len()).filter(|&c| ok[c]).collect();
        assert_eq!(cuts, vec![5, 7, 8, 10]);
    }
}
