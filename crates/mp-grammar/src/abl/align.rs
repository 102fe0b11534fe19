//! Alignment: the hypotheses of every sentence, and the edit-distance
//! (`wm`, `wb`) and suffix-tree (`st1`–`st4`) aligners that add them.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};

/// A hypothesis: span `(b, e)` with labels (first = current label).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Hypothesis {
    /// First word.
    pub b: usize,
    /// One past the last word.
    pub e: usize,
    /// Nonterminal labels, in the order they were attached.
    pub labels: Vec<u32>,
}

/// Hypotheses of every sentence, with fresh-label allocation.
#[derive(Debug, Clone, Default)]
pub struct HypothesisStore {
    /// Per sentence, in learning order.
    pub sentences: Vec<Vec<Hypothesis>>,
    index: Vec<HashMap<(usize, usize), usize>>,
    next_label: u32,
}

impl HypothesisStore {
    /// One start hypothesis `(0, n, [0])` per sentence.
    pub fn new(corpus: &[Vec<u32>]) -> Self {
        let mut st = HypothesisStore {
            sentences: vec![Vec::new(); corpus.len()],
            index: vec![HashMap::new(); corpus.len()],
            next_label: 1,
        };
        for (s, words) in corpus.iter().enumerate() {
            st.add_label(s, 0, words.len(), 0);
        }
        st
    }
    /// A label never used before.
    pub fn fresh(&mut self) -> u32 {
        let l = self.next_label;
        self.next_label += 1;
        l
    }
    /// Labels of a span, if it is a hypothesis.
    pub fn labels(&self, s: usize, b: usize, e: usize) -> Option<&[u32]> {
        let i = *self.index[s].get(&(b, e))?;
        Some(&self.sentences[s][i].labels)
    }
    /// Attaches `label` to span `(b, e)` of sentence `s` (creating it).
    pub fn add_label(&mut self, s: usize, b: usize, e: usize, label: u32) {
        match self.index[s].get(&(b, e)) {
            Some(&i) => {
                let h = &mut self.sentences[s][i];
                if !h.labels.contains(&label) {
                    h.labels.push(label);
                }
            }
            None => {
                self.index[s].insert((b, e), self.sentences[s].len());
                self.sentences[s].push(Hypothesis {
                    b,
                    e,
                    labels: vec![label],
                });
            }
        }
    }
    /// Total hypotheses.
    pub fn count(&self) -> usize {
        self.sentences.iter().map(|v| v.len()).sum()
    }
    /// Distinct labels in use.
    pub fn distinct_labels(&self) -> usize {
        let mut v: Vec<u32> = self
            .sentences
            .iter()
            .flatten()
            .flat_map(|h| h.labels.iter().copied())
            .collect();
        v.sort_unstable();
        v.dedup();
        v.len()
    }
}

/// The seam between alignment methods.
pub trait Aligner {
    /// Adds hypotheses for `corpus` to `store`.
    fn align(&self, corpus: &[Vec<u32>], store: &mut HypothesisStore);
}

/// Edit-distance alignment (`wm`, or `wb` when `biased`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct EditDistanceAligner {
    /// Position-dependent match cost (`wb`). Default false.
    pub biased: bool,
    /// Compare all pairs, not only pairs sharing a word. Default false.
    pub all_pairs: bool,
    /// Record empty spans (ε constituents). Default true.
    pub allow_empty: bool,
}

impl Default for EditDistanceAligner {
    fn default() -> Self {
        EditDistanceAligner {
            biased: false,
            all_pairs: false,
            allow_empty: true,
        }
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Op {
    Match,
    Del,
    Ins,
    Sub,
}

fn edit_alignment(s: &[u32], t: &[u32], biased: bool) -> Vec<Op> {
    let (n, m) = (s.len(), t.len());
    let mean = (n + m) as f64 / 2.0;
    let match_cost = |i: usize, j: usize| -> f64 {
        if biased {
            ((i as f64 / n.max(1) as f64) - (j as f64 / m.max(1) as f64)).abs() * mean
        } else {
            0.0
        }
    };
    let w = m + 1;
    let mut d = vec![0f64; (n + 1) * w];
    for i in 0..=n {
        d[i * w] = i as f64;
    }
    for (j, v) in d.iter_mut().take(m + 1).enumerate() {
        *v = j as f64;
    }
    for i in 1..=n {
        for j in 1..=m {
            let mut best = d[(i - 1) * w + j] + 1.0;
            best = best.min(d[i * w + j - 1] + 1.0);
            best = best.min(d[(i - 1) * w + j - 1] + 2.0);
            if s[i - 1] == t[j - 1] {
                best = best.min(d[(i - 1) * w + j - 1] + match_cost(i - 1, j - 1));
            }
            d[i * w + j] = best;
        }
    }
    let eq = |a: f64, b: f64| (a - b).abs() <= 1e-9;
    let mut ops = Vec::with_capacity(n + m);
    let (mut i, mut j) = (n, m);
    while i > 0 || j > 0 {
        let cur = d[i * w + j];
        if i > 0
            && j > 0
            && s[i - 1] == t[j - 1]
            && eq(cur, d[(i - 1) * w + j - 1] + match_cost(i - 1, j - 1))
        {
            ops.push(Op::Match);
            i -= 1;
            j -= 1;
        } else if i > 0 && eq(cur, d[(i - 1) * w + j] + 1.0) {
            ops.push(Op::Del);
            i -= 1;
        } else if j > 0 && eq(cur, d[i * w + j - 1] + 1.0) {
            ops.push(Op::Ins);
            j -= 1;
        } else {
            ops.push(Op::Sub);
            i -= 1;
            j -= 1;
        }
    }
    ops.reverse();
    ops
}

fn merge_pair(
    store: &mut HypothesisStore,
    (s1, b1, e1): (usize, usize, usize),
    (s2, b2, e2): (usize, usize, usize),
) {
    let l1 = store.labels(s1, b1, e1).and_then(|l| l.first().copied());
    let l2 = store.labels(s2, b2, e2).and_then(|l| l.first().copied());
    match (l1, l2) {
        (Some(a), Some(b)) => {
            store.add_label(s1, b1, e1, b);
            store.add_label(s2, b2, e2, a);
        }
        (Some(a), None) => store.add_label(s2, b2, e2, a),
        (None, Some(b)) => store.add_label(s1, b1, e1, b),
        (None, None) => {
            let l = store.fresh();
            store.add_label(s1, b1, e1, l);
            store.add_label(s2, b2, e2, l);
        }
    }
}

impl Aligner for EditDistanceAligner {
    fn align(&self, corpus: &[Vec<u32>], store: &mut HypothesisStore) {
        for i in 0..corpus.len() {
            for j in (i + 1)..corpus.len() {
                let (s, t) = (&corpus[i], &corpus[j]);
                if !self.all_pairs && !s.iter().any(|w| t.contains(w)) {
                    continue;
                }
                let ops = edit_alignment(s, t, self.biased);
                let (mut pi, mut pj) = (0, 0);
                let mut k = 0;
                while k < ops.len() {
                    if ops[k] == Op::Match {
                        pi += 1;
                        pj += 1;
                        k += 1;
                        continue;
                    }
                    let (bi, bj) = (pi, pj);
                    while k < ops.len() && ops[k] != Op::Match {
                        match ops[k] {
                            Op::Del => pi += 1,
                            Op::Ins => pj += 1,
                            _ => {
                                pi += 1;
                                pj += 1;
                            }
                        }
                        k += 1;
                    }
                    if !self.allow_empty && (bi == pi || bj == pj) {
                        continue;
                    }
                    merge_pair(store, (i, bi, pi), (j, bj, pj));
                }
            }
        }
    }
}

/// Suffix-tree alignment variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum StVariant {
    /// Hypotheses `(begin, n)`.
    St1,
    /// Hypotheses `(0, end)` from the reversed sentences.
    St2,
    /// Both (the motion-grammar paper's choice).
    St3,
    /// Every begin × end pair.
    St4,
}

/// Suffix-tree (suffix-array) alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SuffixTreeAligner {
    /// Which variant. Default `St3`.
    pub variant: StVariant,
}

impl Default for SuffixTreeAligner {
    fn default() -> Self {
        SuffixTreeAligner {
            variant: StVariant::St3,
        }
    }
}

/// For every root branch shared by ≥ 2 sentences: `(label, [(sentence,
/// begin)])` with `begin = i + ℓ` (non-empty remainder only).
fn root_branches(
    corpus: &[Vec<u32>],
    store: &mut HypothesisStore,
) -> Vec<Vec<(usize, usize, u32)>> {
    // Generalised suffixes, sorted lexicographically with an end marker that
    // is unique per sentence (so no common prefix crosses a sentence end).
    let mut suffixes: Vec<(usize, usize)> = Vec::new();
    for (s, w) in corpus.iter().enumerate() {
        for i in 0..w.len() {
            suffixes.push((s, i));
        }
    }
    suffixes.sort_by(|&(s1, i1), &(s2, i2)| {
        let (a, b) = (&corpus[s1][i1..], &corpus[s2][i2..]);
        a.cmp(b).then(s1.cmp(&s2)).then(i1.cmp(&i2))
    });
    let mut per_sentence: Vec<Vec<(usize, usize, u32)>> = vec![Vec::new(); corpus.len()];
    let mut g = 0;
    while g < suffixes.len() {
        let (s0, i0) = suffixes[g];
        let w = corpus[s0][i0];
        let mut h = g + 1;
        while h < suffixes.len() && corpus[suffixes[h].0][suffixes[h].1] == w {
            h += 1;
        }
        let group = &suffixes[g..h];
        let multi = group.iter().any(|&(s, _)| s != s0);
        if multi {
            // Longest common prefix of the whole group (min of adjacent LCPs).
            let mut l = usize::MAX;
            for p in 1..group.len() {
                let (a, b) = (
                    &corpus[group[p - 1].0][group[p - 1].1..],
                    &corpus[group[p].0][group[p].1..],
                );
                let c = a.iter().zip(b).take_while(|(x, y)| x == y).count();
                l = l.min(c);
            }
            let label = store.fresh();
            for &(s, i) in group {
                let begin = i + l;
                if begin < corpus[s].len() {
                    per_sentence[s].push((begin, 0, label));
                }
            }
        }
        g = h;
    }
    per_sentence
}

impl Aligner for SuffixTreeAligner {
    fn align(&self, corpus: &[Vec<u32>], store: &mut HypothesisStore) {
        let want_begin = matches!(
            self.variant,
            StVariant::St1 | StVariant::St3 | StVariant::St4
        );
        let want_end = matches!(
            self.variant,
            StVariant::St2 | StVariant::St3 | StVariant::St4
        );
        let begins = if want_begin {
            root_branches(corpus, store)
        } else {
            vec![Vec::new(); corpus.len()]
        };
        let ends = if want_end {
            let rev: Vec<Vec<u32>> = corpus
                .iter()
                .map(|w| w.iter().rev().copied().collect())
                .collect();
            root_branches(&rev, store)
                .into_iter()
                .zip(corpus)
                .map(|(v, w)| {
                    v.into_iter()
                        .map(|(rb, _, l)| (w.len() - rb, 0, l))
                        .collect::<Vec<_>>()
                })
                .collect()
        } else {
            vec![Vec::new(); corpus.len()]
        };
        match self.variant {
            StVariant::St1 | StVariant::St2 | StVariant::St3 => {
                for (s, w) in corpus.iter().enumerate() {
                    for &(b, _, l) in &begins[s] {
                        store.add_label(s, b, w.len(), l);
                    }
                    for &(e, _, l) in &ends[s] {
                        if e > 0 {
                            store.add_label(s, 0, e, l);
                        }
                    }
                }
            }
            StVariant::St4 => {
                let mut pair_label: HashMap<(u32, u32), u32> = HashMap::new();
                for s in 0..corpus.len() {
                    for &(b, _, lb) in &begins[s] {
                        for &(e, _, le) in &ends[s] {
                            if b < e {
                                let l =
                                    *pair_label.entry((lb, le)).or_insert_with(|| store.fresh());
                                store.add_label(s, b, e, l);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Alignment method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[non_exhaustive]
pub enum Alignment {
    /// Edit distance (`wm` / `wb`).
    EditDistance(EditDistanceAligner),
    /// Suffix tree (`st1`–`st4`).
    SuffixTree(SuffixTreeAligner),
}

impl Alignment {
    /// Parses the reference flags `wm`, `wb`, `st1`–`st4`.
    pub fn from_flag(flag: &str) -> Result<Self> {
        Ok(match flag {
            "wm" => Alignment::EditDistance(EditDistanceAligner::default()),
            "wb" => Alignment::EditDistance(EditDistanceAligner {
                biased: true,
                ..Default::default()
            }),
            "st1" => Alignment::SuffixTree(SuffixTreeAligner {
                variant: StVariant::St1,
            }),
            "st2" => Alignment::SuffixTree(SuffixTreeAligner {
                variant: StVariant::St2,
            }),
            "st3" => Alignment::SuffixTree(SuffixTreeAligner {
                variant: StVariant::St3,
            }),
            "st4" => Alignment::SuffixTree(SuffixTreeAligner {
                variant: StVariant::St4,
            }),
            other => {
                return Err(GrammarError::param(
                    "alignment",
                    format!("unknown `{other}` (wm, wb, st1, st2, st3, st4)"),
                ))
            }
        })
    }
}

impl Alignment {
    /// The reference flag of this alignment (`wm`, `wb`, `st1`–`st4`), the
    /// inverse of [`Self::from_flag`].
    pub fn flag(&self) -> &'static str {
        match self {
            Alignment::EditDistance(a) if a.biased => "wb",
            Alignment::EditDistance(_) => "wm",
            Alignment::SuffixTree(a) => match a.variant {
                StVariant::St1 => "st1",
                StVariant::St2 => "st2",
                StVariant::St3 => "st3",
                StVariant::St4 => "st4",
            },
        }
    }
}

impl Aligner for Alignment {
    fn align(&self, corpus: &[Vec<u32>], store: &mut HypothesisStore) {
        match self {
            Alignment::EditDistance(a) => a.align(corpus, store),
            Alignment::SuffixTree(a) => a.align(corpus, store),
        }
    }
}
