//! Segment selection: seam distances between source segments, and the
//! greedy choice of one segment per symbol.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{FirstSegment, Stitcher};
use crate::error::{GrammarError, Result};
use crate::grammar::Grammar;
use crate::symbols::symbol_name;

impl Stitcher {
    /// Pose distance between the last frame of segment `a` and the first
    /// frame of segment `b` (the seam distance before blending).
    pub fn gap(&self, a: usize, b: usize) -> f64 {
        match (self.segments.get(a), self.segments.get(b)) {
            (Some(x), Some(y)) => self.features.dist_unchecked(x.end - 1, y.start),
            _ => f64::INFINITY,
        }
    }

    /// Seam distances before blending of a sequence of segment indices.
    pub fn gaps(&self, segments: &[usize]) -> Vec<f64> {
        segments.windows(2).map(|w| self.gap(w[0], w[1])).collect()
    }

    /// Symbol index of each grammar terminal (terminals are named by
    /// [`symbol_name`]).
    pub fn terminal_symbols(&self, grammar: &Grammar) -> Result<Vec<usize>> {
        grammar
            .terminals
            .iter()
            .map(|name| {
                (0..self.k())
                    .find(|&s| symbol_name(s) == *name)
                    .ok_or_else(|| {
                        GrammarError::Invalid(format!(
                            "grammar terminal `{name}` is none of the {} symbols of the motion",
                            self.k()
                        ))
                    })
            })
            .collect()
    }

    pub(super) fn check_symbols(&self, symbols: &[usize]) -> Result<()> {
        if symbols.is_empty() {
            return Err(GrammarError::Empty(
                "symbol string to synthesise is empty".into(),
            ));
        }
        for (i, &s) in symbols.iter().enumerate() {
            if self.members.get(s).is_none_or(|m| m.is_empty()) {
                return Err(GrammarError::Invalid(format!(
                    "symbol {s} at position {i} has no segment in the source motion"
                )));
            }
        }
        Ok(())
    }

    /// Greedy segment choice for `symbols`, after segment `prev` and before
    /// segment `next` when given.
    pub(super) fn select_between(
        &self,
        symbols: &[usize],
        prev: Option<usize>,
        next: Option<usize>,
        rng: &mut ChaCha8Rng,
    ) -> Vec<usize> {
        let mut out = Vec::with_capacity(symbols.len());
        let mut last = prev;
        let n = symbols.len();
        for (i, &s) in symbols.iter().enumerate() {
            let mem = &self.members[s];
            let follow = if i + 1 == n { next } else { None };
            let choice = match (last, follow) {
                (None, None) => match self.params.first_segment {
                    FirstSegment::Random => mem[rng.random_range(0..mem.len())],
                    FirstSegment::Medoid => self.medoids[s],
                },
                _ => {
                    let mut best = (f64::INFINITY, mem[0]);
                    for &c in mem {
                        let mut v = 0.0;
                        if let Some(p) = last {
                            v += self.gap(p, c);
                        }
                        if let Some(f) = follow {
                            v += self.gap(c, f);
                        }
                        if v < best.0 {
                            best = (v, c);
                        }
                    }
                    best.1
                }
            };
            out.push(choice);
            last = Some(choice);
        }
        out
    }

    /// Greedy segment choice (see the module documentation) for a symbol
    /// string, seeded (the first segment).
    pub fn select(&self, symbols: &[usize], seed: u64) -> Result<Vec<usize>> {
        self.check_symbols(symbols)?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(1);
        Ok(self.select_between(symbols, None, None, &mut rng))
    }
}
