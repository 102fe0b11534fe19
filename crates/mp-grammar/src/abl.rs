//! Alignment-Based Learning (van Zaanen 2000): align → cluster → select,
//! then read a grammar off the selected constituents.
//!
//! Sentences are sequences of terminal ids. A *hypothesis* is a span
//! `(b, e)` of a sentence (`e` exclusive) with one or more nonterminal
//! labels; every sentence starts with `(0, n, [S])` (label 0).
//!
//! # Alignment ([`Aligner`])
//!
//! * [`EditDistanceAligner`] (`wm`; `wb` when `biased`): Wagner–Fischer with
//!   insert = delete = 1, substitute = 2, match = 0 (`wb`: a match costs
//!   `|i/|S| − j/|T|| · (|S| + |T|)/2`). The backtrace from `(|S|, |T|)`
//!   prefers, among optimal steps, match, then deletion (skip a word of S),
//!   then insertion, then substitution. The alignment is split into maximal
//!   runs of matched words (SAME) and the rest (DIFF); each DIFF run gives a
//!   pair of spans, one per sentence, that become hypotheses. Label merging:
//!   if both spans already carry labels, each gets the other's first label;
//!   if one does, the other inherits its first label; otherwise both get one
//!   fresh label. By default only pairs sharing a word are compared.
//! * [`SuffixTreeAligner`] (`st1`–`st4`): a generalised suffix array over
//!   all sentences. For every branch from the root, i.e. every first word `w`
//!   whose suffixes occur in ≥ 2 sentences, one fresh label; the branch's
//!   edge label is the longest common prefix `ℓ` of all suffixes starting
//!   with `w`, so each such suffix at position `i` records a *begin* at
//!   `i + ℓ`. `st1`: hypotheses `(i + ℓ, n)`; `st2`: the same on reversed
//!   sentences, giving `(0, n − i′ − ℓ)`; `st3`: both (separate labels) plus
//!   the start hypothesis; `st4`: every begin × end pair `(b, e)` with
//!   `b < e` in a sentence, labelled by the pair of branch labels (one label
//!   per distinct pair over the corpus). Empty spans are not recorded.
//!
//! # Clustering ([`Clustering`])
//!
//! Labels found on the same span name the same nonterminal. Two modes:
//!
//! * `Equivalence` (default): labels are one class when they sit on the
//!   same hypothesis or on hypotheses with the same words (the same phrase,
//!   in any sentence), closed transitively (union-find over all labels of
//!   all hypotheses; each class is named by its smallest label, so `S` stays
//!   `S`). Same-words matters: `st` alignments put one label per span, and
//!   the labels that name one constituent sit on equal phrases of different
//!   sentences (on the basketball strings below, `r` carries three labels
//!   and `p m` two; same-span merging alone changes nothing there). After
//!   the grammar is read (see
//!   below), nonterminals with identical rule sets are merged — their
//!   occurrences on right-hand sides renamed, duplicate rules joined (use
//!   counts added), a unit rule `X → X` that a merge creates dropped (its
//!   tree nodes collapse) — and this is repeated until no two nonterminals
//!   have the same rules.
//! * `FirstMapping` (the reference description, kept for comparison): one
//!   pass over the hypotheses of all sentences in order: for a hypothesis
//!   with labels `[l0, l1, …]`, the target is `l0`'s mapping if `l0` is
//!   already mapped, else `l0`; every `li` not yet mapped is mapped to the
//!   target. A label keeps its first mapping and chains are not followed
//!   (not a union-find), and nonterminals are not merged after reading.
//!
//! Each hypothesis then keeps its first (mapped) label. On the paper's
//! basketball strings (`rfdpm rfdsm rdfsm rdpm rdsm rpm`, `st3` + `branch`)
//! `FirstMapping` gives 8 nonterminals and 18 rules, with duplicates
//! (`X4 → p m | s m` beside `X7 → p m`; `X2` and `X6` both derive `r`);
//! `Equivalence` gives 4 nonterminals and 9 rules (`S → X1 X2 | X3 m`,
//! `X1 → r | X1 f | X1 d`, `X2 → p m | d X2 | s m`, `X3 → X1 f s`; the
//! paper's reference ABL: 5 and 11), tested in `basketball_six_strings`.
//!
//! # Selection ([`Selection`])
//!
//! A hypothesis scores `−ln(c(words[b..e], X) / c(X))` over the corpus. In
//! each sentence, hypotheses crossing no other (strict partial overlap;
//! nesting is fine) are kept. `Branch`: the crossing ones are resolved by the
//! memoised recursion `best(b, e)` = the hypothesis spanning `(b, e)` alone
//! if `e = b + 1`; otherwise the split `b < k < e` whose `best(b, k) ∪
//! best(k, e)` has the lowest mean score (the empty set's mean is +∞), ties
//! to more constituents, then to a seeded random choice; then the hypothesis
//! spanning exactly `(b, e)` is added, if any. `First`: hypotheses are kept in
//! the order they were learned when they cross no kept one.
//!
//! # Grammar
//!
//! The selected constituents of a sentence nest into a tree; each node
//! `X (b, e)` yields `X → (children's labels or words)`, ε for an empty span.
//! Identical rules merge and count their uses. Nonterminals are renumbered by
//! first appearance (`S`, `X1`, `X2`, …), and again after merging.

use std::collections::HashMap;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};
use crate::grammar::{Grammar, Rule, Sym, Tree};

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

/// Selection method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Selection {
    /// Memoised best-combination recursion (reference `-s b`). Default.
    #[default]
    Branch,
    /// Earlier-learned hypotheses win (order-dependent baseline).
    First,
}

impl Selection {
    /// Lower-case name: `branch` or `first`.
    pub fn as_str(self) -> &'static str {
        match self {
            Selection::Branch => "branch",
            Selection::First => "first",
        }
    }
}

/// How hypothesis labels become nonterminals (see the module
/// documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Clustering {
    /// Labels sharing a span merged transitively (union-find), then
    /// nonterminals with identical rule sets merged to a fixed point.
    /// Default.
    #[default]
    Equivalence,
    /// One pass, first mapping wins, no merging after reading the grammar
    /// (the reference description; the only mode before `Equivalence`).
    FirstMapping,
}

impl Clustering {
    /// Lower-case name: `equivalence` or `first-mapping`.
    pub fn as_str(self) -> &'static str {
        match self {
            Clustering::Equivalence => "equivalence",
            Clustering::FirstMapping => "first-mapping",
        }
    }
    /// The mode of files written before the field existed.
    fn legacy() -> Self {
        Clustering::FirstMapping
    }
}

/// Parameters of ABL.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AblParams {
    /// Alignment. Default `st3` (the motion-grammar paper's setting).
    pub alignment: Alignment,
    /// Selection. Default `Branch` (the paper's setting).
    pub selection: Selection,
    /// Clustering of labels into nonterminals. Default `Equivalence`
    /// (`FirstMapping` when absent from a file: files written before the
    /// field existed were learned that way).
    #[serde(default = "Clustering::legacy")]
    pub clustering: Clustering,
    /// Seed for tie-breaking in `Branch` selection. Default 0.
    pub seed: u64,
}

impl Default for AblParams {
    fn default() -> Self {
        AblParams {
            alignment: Alignment::SuffixTree(SuffixTreeAligner::default()),
            selection: Selection::Branch,
            clustering: Clustering::Equivalence,
            seed: 0,
        }
    }
}

/// Counters of an ABL run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct AblStats {
    /// Hypotheses after alignment (including the start hypotheses).
    pub hypotheses: usize,
    /// Distinct labels after alignment.
    pub labels_before_clustering: usize,
    /// Distinct labels after clustering.
    pub labels_after_clustering: usize,
    /// Hypotheses kept by selection (including the start hypotheses).
    pub selected: usize,
    /// Nonterminals removed by merging identical rule sets
    /// (`Equivalence` clustering).
    #[serde(default)]
    pub nonterminals_merged: usize,
}

/// Result of ABL: the grammar, one derivation tree per sentence, the
/// selected constituents and counters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AblResult {
    /// The learned grammar (start symbol `S` = nonterminal 0).
    pub grammar: Grammar,
    /// Derivation tree of every training sentence.
    pub trees: Vec<Tree>,
    /// Selected constituents `(b, e, nonterminal)` per sentence.
    pub constituents: Vec<Vec<(usize, usize, u32)>>,
    /// Counters.
    pub stats: AblStats,
}

impl AblResult {
    /// `B(Z | G)` from the learned trees.
    pub fn data_bits(&self) -> f64 {
        self.trees.iter().map(|t| self.grammar.tree_bits(t)).sum()
    }
    /// `DL = B(G) + B(Z | G)` with the learned trees.
    pub fn description_length(&self) -> crate::grammar::DescriptionLength {
        let g = self.grammar.grammar_bits();
        let z = self.data_bits();
        crate::grammar::DescriptionLength {
            grammar_bits: g,
            data_bits: z,
            total_bits: g + z,
        }
    }
}

/// Runs the alignment only (for inspection and tests); labels are
/// canonicalised by clustering.
pub fn align_and_cluster(corpus: &[Vec<u32>], params: &AblParams) -> (HypothesisStore, AblStats) {
    let mut store = HypothesisStore::new(corpus);
    params.alignment.align(corpus, &mut store);
    let mut stats = AblStats {
        hypotheses: store.count(),
        labels_before_clustering: store.distinct_labels(),
        ..Default::default()
    };
    match params.clustering {
        Clustering::Equivalence => cluster_union_find(corpus, &mut store),
        Clustering::FirstMapping => cluster(&mut store),
    }
    stats.labels_after_clustering = store.distinct_labels();
    (store, stats)
}

/// Union-find over labels: all labels of a hypothesis, and all labels of
/// hypotheses with the same words, are one class, named by its smallest
/// label.
fn cluster_union_find(corpus: &[Vec<u32>], store: &mut HypothesisStore) {
    let mut parent: HashMap<u32, u32> = HashMap::new();
    fn find(parent: &mut HashMap<u32, u32>, x: u32) -> u32 {
        let mut root = x;
        while let Some(&p) = parent.get(&root) {
            if p == root {
                break;
            }
            root = p;
        }
        // Path compression.
        let mut cur = x;
        while let Some(&p) = parent.get(&cur) {
            if p == root {
                break;
            }
            parent.insert(cur, root);
            cur = p;
        }
        root
    }
    // First label seen on each phrase.
    let mut phrase_label: HashMap<&[u32], u32> = HashMap::new();
    for (s, hyps) in store.sentences.iter().enumerate() {
        for h in hyps {
            for &l in &h.labels {
                parent.entry(l).or_insert(l);
            }
            let Some(&l0) = h.labels.first() else {
                continue;
            };
            let phrase = corpus.get(s).and_then(|w| w.get(h.b..h.e)).unwrap_or(&[]);
            let same_words = *phrase_label.entry(phrase).or_insert(l0);
            for &l in h.labels[1..].iter().chain(std::iter::once(&same_words)) {
                let (a, b) = (find(&mut parent, l0), find(&mut parent, l));
                if a != b {
                    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                    parent.insert(hi, lo);
                }
            }
        }
    }
    for hyps in &mut store.sentences {
        for h in hyps.iter_mut() {
            let mut v: Vec<u32> = Vec::new();
            for &l in &h.labels {
                let m = find(&mut parent, l);
                if !v.contains(&m) {
                    v.push(m);
                }
            }
            h.labels = v;
        }
    }
}

fn cluster(store: &mut HypothesisStore) {
    let mut map: HashMap<u32, u32> = HashMap::new();
    for hyps in &store.sentences {
        for h in hyps {
            let Some(&l0) = h.labels.first() else {
                continue;
            };
            let target = *map.get(&l0).unwrap_or(&l0);
            for &l in &h.labels {
                map.entry(l).or_insert(target);
            }
        }
    }
    for hyps in &mut store.sentences {
        for h in hyps.iter_mut() {
            let mut v: Vec<u32> = Vec::new();
            for &l in &h.labels {
                let m = *map.get(&l).unwrap_or(&l);
                if !v.contains(&m) {
                    v.push(m);
                }
            }
            h.labels = v;
        }
    }
}

fn crosses(a: (usize, usize), b: (usize, usize)) -> bool {
    (a.0 < b.0 && b.0 < a.1 && a.1 < b.1) || (b.0 < a.0 && a.0 < b.1 && b.1 < a.1)
}

/// Learns a grammar from sentences of terminal ids; `terminals` names them.
///
/// Errors: an empty corpus, an empty sentence, or a symbol id without a name.
pub fn learn(corpus: &[Vec<u32>], terminals: &[String], params: &AblParams) -> Result<AblResult> {
    if corpus.is_empty() {
        return Err(GrammarError::Empty("no sentence to learn from".into()));
    }
    for (i, s) in corpus.iter().enumerate() {
        if s.is_empty() {
            return Err(GrammarError::Empty(format!("sentence {i} is empty")));
        }
        if let Some(&w) = s.iter().find(|&&w| w as usize >= terminals.len()) {
            return Err(GrammarError::Invalid(format!(
                "sentence {i}: symbol id {w} has no name ({} terminals)",
                terminals.len()
            )));
        }
    }
    let (store, mut stats) = align_and_cluster(corpus, params);

    // Scores.
    let mut c_nt: HashMap<u32, usize> = HashMap::new();
    let mut c_phrase: HashMap<(&[u32], u32), usize> = HashMap::new();
    for (s, hyps) in store.sentences.iter().enumerate() {
        for h in hyps {
            let l = h.labels[0];
            *c_nt.entry(l).or_default() += 1;
            *c_phrase.entry((&corpus[s][h.b..h.e], l)).or_default() += 1;
        }
    }
    let score = |s: usize, h: &Hypothesis| -> f64 {
        let l = h.labels[0];
        let a = c_phrase[&(&corpus[s][h.b..h.e], l)] as f64;
        let b = c_nt[&l] as f64;
        -(a / b).ln()
    };

    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut constituents = Vec::with_capacity(corpus.len());
    for (s, hyps) in store.sentences.iter().enumerate() {
        let n = corpus[s].len();
        let spans: Vec<(usize, usize)> = hyps.iter().map(|h| (h.b, h.e)).collect();
        let keep: Vec<usize> = match params.selection {
            Selection::First => {
                let mut kept: Vec<usize> = Vec::new();
                for (i, &sp) in spans.iter().enumerate() {
                    if !kept.iter().any(|&k| crosses(spans[k], sp)) {
                        kept.push(i);
                    }
                }
                kept
            }
            Selection::Branch => {
                let crossing: Vec<bool> = (0..spans.len())
                    .map(|i| (0..spans.len()).any(|j| crosses(spans[i], spans[j])))
                    .collect();
                let mut kept: Vec<usize> = (0..spans.len()).filter(|&i| !crossing[i]).collect();
                if crossing.iter().any(|&c| c) {
                    let scores: Vec<f64> = hyps.iter().map(|h| score(s, h)).collect();
                    let by_span: HashMap<(usize, usize), usize> = (0..spans.len())
                        .filter(|&i| crossing[i])
                        .map(|i| (spans[i], i))
                        .collect();
                    let mut memo: HashMap<(usize, usize), (Vec<usize>, f64)> = HashMap::new();
                    let (set, _) = best_set(0, n, &by_span, &scores, &mut memo, &mut rng);
                    kept.extend(set);
                }
                kept.sort_unstable();
                kept
            }
        };
        constituents.push(
            keep.iter()
                .map(|&i| (hyps[i].b, hyps[i].e, hyps[i].labels[0]))
                .collect::<Vec<_>>(),
        );
    }
    stats.selected = constituents.iter().map(|c| c.len()).sum();
    let (mut grammar, mut trees, mut constituents) = read_grammar(corpus, terminals, constituents);
    if params.clustering == Clustering::Equivalence {
        stats.nonterminals_merged =
            merge_equivalent_nonterminals(&mut grammar, &mut trees, &mut constituents);
    }
    Ok(AblResult {
        grammar,
        trees,
        constituents,
        stats,
    })
}

/// Memoised best non-crossing subset of the crossing hypotheses inside
/// `(b, e)`: `(members, sum of scores)`.
fn best_set(
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

type Constituents = Vec<Vec<(usize, usize, u32)>>;

/// Merges nonterminals with identical rule sets until none are left;
/// returns how many nonterminals were removed. Trees and constituents are
/// renamed to match.
fn merge_equivalent_nonterminals(
    g: &mut Grammar,
    trees: &mut [Tree],
    constituents: &mut Constituents,
) -> usize {
    let before = g.nonterminals.len();
    // Each round removes at least one nonterminal, so this terminates.
    for _ in 0..before {
        let n = g.nonterminals.len();
        let mut sets: Vec<Vec<Vec<Sym>>> = vec![Vec::new(); n];
        for r in &g.rules {
            if let Some(v) = sets.get_mut(r.lhs as usize) {
                v.push(r.rhs.clone());
            }
        }
        for v in sets.iter_mut() {
            v.sort();
            v.dedup();
        }
        let mut first: HashMap<&[Vec<Sym>], u32> = HashMap::new();
        let mut rep: Vec<u32> = (0..n as u32).collect();
        for (x, set) in sets.iter().enumerate() {
            if set.is_empty() {
                continue;
            }
            rep[x] = *first.entry(set.as_slice()).or_insert(x as u32);
        }
        if rep.iter().enumerate().all(|(i, &r)| r as usize == i) {
            break;
        }
        apply_nonterminal_map(g, trees, constituents, &rep);
    }
    before - g.nonterminals.len()
}

/// Renames nonterminal `x` to `rep[x]` (a representative `≤ x`), then
/// renumbers the remaining ones compactly in order.
fn apply_nonterminal_map(
    g: &mut Grammar,
    trees: &mut [Tree],
    constituents: &mut Constituents,
    rep: &[u32],
) {
    let n = rep.len();
    let mut new_id = vec![0u32; n];
    let mut names = Vec::new();
    let mut next = 0u32;
    for x in 0..n {
        if rep[x] as usize == x {
            new_id[x] = next;
            names.push(if next == 0 {
                "S".to_string()
            } else {
                format!("X{next}")
            });
            next += 1;
        }
    }
    for x in 0..n {
        new_id[x] = new_id[rep[x] as usize];
    }
    let map_sym = |s: Sym| match s {
        Sym::N(x) => Sym::N(new_id[x as usize]),
        t => t,
    };
    // Rewritten rules, duplicates joined; `None` for a dropped `X → X`.
    let mut rules: Vec<Rule> = Vec::new();
    let mut index: HashMap<(u32, Vec<Sym>), usize> = HashMap::new();
    let mut rule_map: Vec<Option<usize>> = Vec::with_capacity(g.rules.len());
    for r in &g.rules {
        let lhs = new_id[r.lhs as usize];
        let rhs: Vec<Sym> = r.rhs.iter().map(|&s| map_sym(s)).collect();
        if rhs == [Sym::N(lhs)] {
            rule_map.push(None);
            continue;
        }
        let i = *index.entry((lhs, rhs.clone())).or_insert_with(|| {
            rules.push(Rule { lhs, rhs, count: 0 });
            rules.len() - 1
        });
        rules[i].count += r.count;
        rule_map.push(Some(i));
    }
    // Group by left-hand side again (stable).
    let mut order: Vec<usize> = (0..rules.len()).collect();
    order.sort_by_key(|&i| (rules[i].lhs, i));
    let mut pos = vec![0; rules.len()];
    for (new, &old) in order.iter().enumerate() {
        pos[old] = new;
    }
    let rule_map: Vec<Option<usize>> = rule_map.iter().map(|m| m.map(|i| pos[i])).collect();
    g.rules = order.iter().map(|&i| rules[i].clone()).collect();
    g.nonterminals = names;
    g.start = new_id[g.start as usize];

    fn fix(t: &mut Tree, new_id: &[u32], rule_map: &[Option<usize>]) {
        loop {
            let collapse = match t {
                Tree::Leaf(_) => return,
                Tree::Node { rule, children, .. } => {
                    rule_map.get(*rule).copied().flatten().is_none() && children.len() == 1
                }
            };
            if !collapse {
                break;
            }
            let child = match t {
                Tree::Node { children, .. } => children.pop(),
                Tree::Leaf(_) => None,
            };
            match child {
                Some(c) => *t = c,
                None => break,
            }
        }
        if let Tree::Node { nt, rule, children } = t {
            *nt = new_id.get(*nt as usize).copied().unwrap_or(*nt);
            if let Some(Some(r)) = rule_map.get(*rule) {
                *rule = *r;
            }
            for c in children.iter_mut() {
                fix(c, new_id, rule_map);
            }
        }
    }
    for t in trees.iter_mut() {
        fix(t, &new_id, &rule_map);
    }
    for c in constituents.iter_mut() {
        for x in c.iter_mut() {
            x.2 = new_id.get(x.2 as usize).copied().unwrap_or(x.2);
        }
        let mut seen = std::collections::HashSet::new();
        c.retain(|x| seen.insert(*x));
    }
}

/// Builds trees and rules from the selected constituents.
fn read_grammar(
    corpus: &[Vec<u32>],
    terminals: &[String],
    constituents: Constituents,
) -> (Grammar, Vec<Tree>, Constituents) {
    // Renumber labels by first appearance in a pre-order walk (S first).
    let mut rename: HashMap<u32, u32> = HashMap::new();
    rename.insert(0, 0);
    let mut rules: Vec<Rule> = Vec::new();
    let mut rule_index: HashMap<(u32, Vec<Sym>), usize> = HashMap::new();
    let mut trees = Vec::with_capacity(corpus.len());
    let mut renamed_constituents = Vec::with_capacity(corpus.len());

    for (s, cons) in constituents.iter().enumerate() {
        let words = &corpus[s];
        // Sort: start asc, end desc (parents before children); empty spans
        // after non-empty spans that start at the same place.
        let mut c = cons.clone();
        c.sort_by(|a, b| a.0.cmp(&b.0).then(b.1.cmp(&a.1)));
        if !c
            .iter()
            .any(|&(b, e, l)| b == 0 && e == words.len() && l == 0)
        {
            c.insert(0, (0, words.len(), 0));
        }
        let tree = build_node(0, &c, words, &mut rename, &mut rules, &mut rule_index);
        renamed_constituents.push(
            c.iter()
                .map(|&(b, e, l)| (b, e, *rename.get(&l).unwrap_or(&l)))
                .collect(),
        );
        trees.push(tree);
    }
    let n_nt = rename.len();
    let mut nonterminals = vec![String::new(); n_nt];
    for (_, &new) in rename.iter() {
        nonterminals[new as usize] = if new == 0 {
            "S".to_string()
        } else {
            format!("X{new}")
        };
    }
    // Group rules by left-hand side (stable), fixing tree rule indices.
    let mut order: Vec<usize> = (0..rules.len()).collect();
    order.sort_by_key(|&i| (rules[i].lhs, i));
    let mut new_index = vec![0; rules.len()];
    for (new, &old) in order.iter().enumerate() {
        new_index[old] = new;
    }
    let rules: Vec<Rule> = order.iter().map(|&i| rules[i].clone()).collect();
    fn fix(t: &mut Tree, map: &[usize]) {
        if let Tree::Node { rule, children, .. } = t {
            *rule = map[*rule];
            children.iter_mut().for_each(|c| fix(c, map));
        }
    }
    for t in trees.iter_mut() {
        fix(t, &new_index);
    }
    (
        Grammar {
            terminals: terminals.to_vec(),
            nonterminals,
            start: 0,
            rules,
        },
        trees,
        renamed_constituents,
    )
}

fn build_node(
    idx: usize,
    c: &[(usize, usize, u32)],
    words: &[u32],
    rename: &mut HashMap<u32, u32>,
    rules: &mut Vec<Rule>,
    rule_index: &mut HashMap<(u32, Vec<Sym>), usize>,
) -> Tree {
    let (b, e, label) = c[idx];
    let next = rename.len() as u32;
    let nt = *rename.entry(label).or_insert(next);
    // Direct children: constituents inside (b, e) (an empty span may sit at
    // either end), other than (b, e) itself, not inside another such
    // non-empty constituent (an empty span is inside one only strictly).
    let inside_parent = |j: usize| {
        let (cb, ce, _) = c[j];
        j != idx && b <= cb && ce <= e && (cb, ce) != (b, e)
    };
    let strictly_in = |outer: usize, inner: usize| {
        let (ob, oe, _) = c[outer];
        let (ib, ie, _) = c[inner];
        if ob == oe || (ob, oe) == (ib, ie) {
            false
        } else if ib == ie {
            ob < ib && ib < oe
        } else {
            ob <= ib && ie <= oe
        }
    };
    let candidates: Vec<usize> = (0..c.len()).filter(|&j| inside_parent(j)).collect();
    let mut kids: Vec<usize> = candidates
        .iter()
        .copied()
        .filter(|&j| !candidates.iter().any(|&o| o != j && strictly_in(o, j)))
        .collect();
    kids.sort_by(|&x, &y| {
        let (xb, xe, _) = c[x];
        let (yb, ye, _) = c[y];
        // Position order; at equal start, an empty span comes first.
        xb.cmp(&yb).then((xe > xb).cmp(&(ye > yb)))
    });
    let mut children = Vec::new();
    let mut rhs = Vec::new();
    let mut pos = b;
    let mut k = 0;
    while pos < e || k < kids.len() {
        if k < kids.len() && c[kids[k]].0 == pos {
            let child = build_node(kids[k], c, words, rename, rules, rule_index);
            if let Tree::Node { nt: cn, .. } = &child {
                rhs.push(Sym::N(*cn));
            }
            pos = c[kids[k]].1;
            children.push(child);
            k += 1;
        } else if pos < e {
            rhs.push(Sym::T(words[pos]));
            children.push(Tree::Leaf(words[pos]));
            pos += 1;
        } else {
            // A child that does not start at the current position cannot
            // occur for non-crossing sets; skip it defensively.
            k += 1;
        }
    }
    let key = (nt, rhs.clone());
    let ri = match rule_index.get(&key) {
        Some(&i) => i,
        None => {
            rules.push(Rule {
                lhs: nt,
                rhs,
                count: 0,
            });
            rule_index.insert(key, rules.len() - 1);
            rules.len() - 1
        }
    };
    rules[ri].count += 1;
    Tree::Node {
        nt,
        rule: ri,
        children,
    }
}

/// A corpus of sentences of named symbols, interned to ids.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Corpus {
    /// Symbol names (id = index).
    pub vocab: Vec<String>,
    /// Sentences of ids.
    pub sentences: Vec<Vec<u32>>,
}

impl Corpus {
    /// Interns sentences of names (ids in first-appearance order).
    pub fn from_sentences<S: AsRef<str>>(sentences: &[Vec<S>]) -> Self {
        let mut vocab: Vec<String> = Vec::new();
        let mut ids: HashMap<String, u32> = HashMap::new();
        let sentences = sentences
            .iter()
            .map(|s| {
                s.iter()
                    .map(|w| {
                        let w = w.as_ref();
                        *ids.entry(w.to_string()).or_insert_with(|| {
                            vocab.push(w.to_string());
                            (vocab.len() - 1) as u32
                        })
                    })
                    .collect()
            })
            .collect();
        Corpus { vocab, sentences }
    }
    /// One sentence per non-empty line, symbols separated by whitespace.
    pub fn from_lines(text: &str) -> Result<Self> {
        let sentences: Vec<Vec<&str>> = text
            .lines()
            .map(|l| l.split_whitespace().collect::<Vec<_>>())
            .filter(|v| !v.is_empty())
            .collect();
        if sentences.is_empty() {
            return Err(GrammarError::Empty("no sentence in the text".into()));
        }
        Ok(Self::from_sentences(&sentences))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn corpus(lines: &[&str]) -> Corpus {
        let s: Vec<Vec<&str>> = lines
            .iter()
            .map(|l| l.split_whitespace().collect())
            .collect();
        Corpus::from_sentences(&s)
    }

    fn spans(store: &HypothesisStore, s: usize) -> Vec<(usize, usize, u32)> {
        let mut v: Vec<(usize, usize, u32)> = store.sentences[s]
            .iter()
            .map(|h| (h.b, h.e, h.labels[0]))
            .collect();
        v.sort_unstable();
        v
    }

    #[test]
    fn alignment_flags_round_trip() {
        for flag in ["wm", "wb", "st1", "st2", "st3", "st4"] {
            assert_eq!(Alignment::from_flag(flag).unwrap().flag(), flag);
        }
        assert_eq!(AblParams::default().alignment.flag(), "st3");
        assert_eq!(AblParams::default().selection.as_str(), "branch");
    }

    #[test]
    fn she_is_smart_both_aligners() {
        let c = corpus(&["she is smart", "she is tired"]);
        for flag in ["wm", "wb", "st1", "st3"] {
            let p = AblParams {
                alignment: Alignment::from_flag(flag).unwrap(),
                ..Default::default()
            };
            let (store, _) = align_and_cluster(&c.sentences, &p);
            for s in 0..2 {
                let v = spans(&store, s);
                assert_eq!(v.len(), 2, "{flag}: {v:?}");
                assert_eq!((v[0].0, v[0].1, v[0].2), (0, 3, 0), "{flag}");
                assert_eq!((v[1].0, v[1].1), (2, 3), "{flag}");
                assert_ne!(v[1].2, 0);
            }
            assert_eq!(spans(&store, 0)[1].2, spans(&store, 1)[1].2, "{flag}");
        }
    }

    #[test]
    fn crossing() {
        assert!(crosses((0, 3), (2, 5)));
        assert!(!crosses((0, 3), (1, 2)));
        assert!(!crosses((0, 3), (3, 5)));
    }
}
