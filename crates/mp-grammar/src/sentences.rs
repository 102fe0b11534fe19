//! Partitioning a symbol string into sentences (paper §5): random candidate
//! partitions under the paper's constraints, scored by description length.
//!
//! Constraints: every sentence has at least `min_sentence_len` symbols, and
//! no cut splits a protected occurrence of a repeated substring
//! ([`crate::strings::protected_spans`]). A candidate is drawn left to right:
//! from the current position `p`, the next cut is uniform among the allowed
//! cuts in `[p + min_sentence_len, p + max_sentence_len]` that leave at least
//! `min_sentence_len` symbols after them; when there is none, the nearest
//! allowed cut beyond that window is used, and when there is no allowed cut
//! left the rest is one sentence. The whole string as one sentence is a
//! candidate only when `include_whole_string` is set: on real symbol strings
//! it usually has the lowest description length (one rule, nothing to
//! encode) and yields a grammar that can only reproduce its input, which is
//! why the paper draws candidates with cuts only. Each candidate's grammar
//! is learned with ABL and scored by
//! `DL = B(G) + B(Z | G)` (§5.1, with the learned derivation trees); the
//! lowest wins (ties: the earlier candidate). Candidates are scored in
//! parallel; the result depends only on the seed.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::abl::{learn, AblParams, AblResult};
use crate::error::{GrammarError, Result};
use crate::grammar::DescriptionLength;
use crate::strings::{allowed_cuts, protected_spans};

/// Parameters of the sentence partition search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PartitionParams {
    /// Random candidates drawn (besides the whole string). Default 200.
    pub candidates: usize,
    /// Shortest sentence, symbols. Default 3.
    pub min_sentence_len: usize,
    /// Preferred longest sentence, symbols (exceeded only when no allowed
    /// cut exists in the window). Default 12.
    pub max_sentence_len: usize,
    /// Shortest repeated substring that may not be split; 0 disables the
    /// constraint. Default 2.
    pub min_repeat_len: usize,
    /// Also score the whole string as one sentence. Default false.
    #[serde(default)]
    pub include_whole_string: bool,
    /// Grammar induction.
    pub abl: AblParams,
    /// Seed. Default 0.
    pub seed: u64,
}

impl Default for PartitionParams {
    fn default() -> Self {
        PartitionParams {
            candidates: 200,
            min_sentence_len: 3,
            max_sentence_len: 12,
            min_repeat_len: 2,
            include_whole_string: false,
            abl: AblParams::default(),
            seed: 0,
        }
    }
}

impl PartitionParams {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<()> {
        if self.min_sentence_len == 0 {
            return Err(GrammarError::param("min_sentence_len", "must be ≥ 1"));
        }
        if self.max_sentence_len < self.min_sentence_len {
            return Err(GrammarError::param(
                "max_sentence_len",
                format!(
                    "must be ≥ min_sentence_len ({}), got {}",
                    self.min_sentence_len, self.max_sentence_len
                ),
            ));
        }
        Ok(())
    }
}

/// A scored partition.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Partition {
    /// Cut positions (a cut before symbol `c`), ascending.
    pub cuts: Vec<usize>,
    /// The sentences.
    pub sentences: Vec<Vec<u32>>,
    /// Its description length.
    pub dl: DescriptionLength,
    /// The grammar learned from it, with trees.
    pub learned: AblResult,
}

/// Splits `s` at `cuts`.
pub fn split(s: &[u32], cuts: &[usize]) -> Vec<Vec<u32>> {
    let mut out = Vec::with_capacity(cuts.len() + 1);
    let mut p = 0;
    for &c in cuts {
        out.push(s[p..c].to_vec());
        p = c;
    }
    out.push(s[p..].to_vec());
    out
}

/// Scores one partition (learns its grammar with ABL).
pub fn score_partition(
    s: &[u32],
    cuts: &[usize],
    terminals: &[String],
    abl: &AblParams,
) -> Result<Partition> {
    if let Some(w) = cuts.windows(2).find(|w| w[1] <= w[0]) {
        return Err(GrammarError::Invalid(format!(
            "cuts must increase, got {} then {}",
            w[0], w[1]
        )));
    }
    if cuts.first().is_some_and(|&c| c == 0) || cuts.last().is_some_and(|&c| c >= s.len()) {
        return Err(GrammarError::Invalid(format!(
            "cuts must lie in 1..{} (inside the string)",
            s.len()
        )));
    }
    let sentences = split(s, cuts);
    let learned = learn(&sentences, terminals, abl)?;
    Ok(Partition {
        cuts: cuts.to_vec(),
        dl: learned.description_length(),
        sentences,
        learned,
    })
}

fn draw(ok: &[bool], n: usize, p: &PartitionParams, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let mut cuts = Vec::new();
    let mut pos = 0;
    loop {
        let lo = pos + p.min_sentence_len;
        if lo + p.min_sentence_len > n {
            break;
        }
        let last = n - p.min_sentence_len;
        let hi = (pos + p.max_sentence_len).min(last);
        let window: Vec<usize> = (lo..=hi).filter(|&c| ok[c]).collect();
        let c = if !window.is_empty() {
            window[rng.random_range(0..window.len())]
        } else if let Some(c) = (hi + 1..=last).find(|&c| ok[c]) {
            c
        } else {
            break;
        };
        cuts.push(c);
        pos = c;
    }
    cuts
}

/// Searches for the partition of `s` with the lowest description length.
///
/// Errors: invalid parameters, an empty string, or a symbol id without a name.
pub fn search_partition(
    s: &[u32],
    terminals: &[String],
    params: &PartitionParams,
) -> Result<Partition> {
    params.validate()?;
    if s.is_empty() {
        return Err(GrammarError::Empty("symbol string is empty".into()));
    }
    let protected = if params.min_repeat_len > 0 {
        protected_spans(s, params.min_repeat_len)
    } else {
        Vec::new()
    };
    let ok = allowed_cuts(s.len(), &protected);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    let mut cands: Vec<Vec<usize>> = Vec::new();
    if params.include_whole_string {
        cands.push(Vec::new());
    }
    for _ in 0..params.candidates {
        let c = draw(&ok, s.len(), params, &mut rng);
        if !cands.contains(&c) {
            cands.push(c);
        }
    }
    if cands.is_empty() {
        // No allowed cut (or no candidate asked for): one sentence.
        cands.push(Vec::new());
    }
    let scored: Vec<Result<Partition>> = cands
        .par_iter()
        .map(|c| score_partition(s, c, terminals, &params.abl))
        .collect();
    let mut best: Option<Partition> = None;
    for r in scored {
        let p = r?;
        if best
            .as_ref()
            .is_none_or(|b| p.dl.total_bits < b.dl.total_bits)
        {
            best = Some(p);
        }
    }
    best.ok_or_else(|| GrammarError::Empty("no candidate partition".into()))
}
