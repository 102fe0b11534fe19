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
//!
//! # Layout
//!
//! * `align`: the hypothesis store and the aligners ([`Aligner`],
//!   [`Alignment`]).
//! * `cluster`: both clustering modes, and the merging of nonterminals with
//!   identical rule sets after the grammar is read.
//! * `select`: the crossing test and the memoised `Branch` recursion.
//! * `read`: reading trees and rules off the selected constituents.
//! * this module: the parameters and results, [`align_and_cluster`],
//!   [`learn`] (which runs the steps in order, scoring and selecting per
//!   sentence) and [`Corpus`].

use std::collections::HashMap;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{GrammarError, Result};
use crate::grammar::{Grammar, Tree};

mod align;
mod cluster;
mod read;
mod select;

pub use align::Alignment;
pub(crate) use align::{Aligner, Hypothesis, HypothesisStore, SuffixTreeAligner};

use cluster::{cluster, cluster_union_find, merge_equivalent_nonterminals};
use read::read_grammar;
use select::{best_set, crosses};

/// Selection method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[non_exhaustive]
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
#[non_exhaustive]
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

type Constituents = Vec<Vec<(usize, usize, u32)>>;

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
}
