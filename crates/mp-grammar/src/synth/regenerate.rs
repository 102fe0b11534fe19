//! Regeneration (the paper's authoring interaction): one region of a
//! synthesis derived anew from the grammar and re-stitched, the frames
//! around it kept.

use ndarray::{s, Array2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::{blend_weight, Piece, Regenerated, Stitcher, SynthesizedMotion};
use crate::derive::{regenerate, DeriveParams};
use crate::error::{GrammarError, Result};
use crate::grammar::Grammar;

impl Stitcher {
    /// The paper's authoring interaction: derives anew the nonterminal that
    /// produced terminal `terminal` (`levels` = 0: its nearest nonterminal
    /// ancestor; more climbs the tree) with `seed`, chooses segments for the
    /// new terminals (greedy from the segment before, the last one also
    /// leading into the segment after), and re-stitches only that region.
    ///
    /// Errors: a synthesis without derivation, a terminal out of range.
    pub fn regenerate(
        &self,
        grammar: &Grammar,
        synth: &SynthesizedMotion,
        terminal: usize,
        levels: usize,
        derive: &DeriveParams,
        seed: u64,
    ) -> Result<Regenerated> {
        let derivation = synth.derivation.as_ref().ok_or_else(|| {
            GrammarError::Invalid("the synthesis has no derivation to regenerate".into())
        })?;
        if derivation.len() != synth.pieces.len() {
            return Err(GrammarError::Invalid(format!(
                "derivation has {} terminals, the synthesis {} pieces",
                derivation.len(),
                synth.pieces.len()
            )));
        }
        let map = self.terminal_symbols(grammar)?;
        let regen = regenerate(grammar, derivation, terminal, levels, derive, seed)?;
        let old = regen.ancestor.terminals.clone();
        let all: Vec<u32> = regen.derivation.terminals();
        let new_syms: Vec<usize> = all[regen.new_terminals.clone()]
            .iter()
            .map(|&t| map[t as usize])
            .collect();
        if !new_syms.is_empty() {
            self.check_symbols(&new_syms)?;
        }
        let n_old = synth.pieces.len();
        let prev = old.start.checked_sub(1).map(|i| synth.pieces[i].segment);
        let next = (old.end < n_old).then(|| synth.pieces[old.end].segment);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(2);
        let new_segs = self.select_between(&new_syms, prev, next, &mut rng);

        let total_old = synth.n_frames();
        let f_b = synth
            .pieces
            .get(old.start)
            .map_or(total_old, |p| p.start_frame);
        let f_e = synth
            .pieces
            .get(old.end)
            .map_or(total_old, |p| p.start_frame);
        let span_len: usize = new_segs.iter().map(|&i| self.segments[i].len()).sum();
        let total = f_b + span_len + (total_old - f_e);
        if total == 0 {
            return Err(GrammarError::Empty(
                "the regenerated motion would have no frame".into(),
            ));
        }
        let mut rows = Array2::zeros((total, self.rows.ncols()));
        let mut conf = Array2::zeros((total, self.conf.ncols()));
        rows.slice_mut(s![..f_b, ..])
            .assign(&synth.rows.slice(s![..f_b, ..]));
        conf.slice_mut(s![..f_b, ..])
            .assign(&synth.conf.slice(s![..f_b, ..]));
        let mut len = f_b;
        for &i in &new_segs {
            len = self.append(&mut rows, &mut conf, len, i);
        }
        // The kept frames after the region, translated to follow it.
        let suffix = synth.rows.slice(s![f_e.., ..]).to_owned();
        if !suffix.is_empty() {
            let mut suffix = suffix;
            if len > 0 {
                let off = self.space.placement(&rows, len, &suffix, 0);
                let n_suf = suffix.nrows();
                self.space.translate(&mut suffix, 0..n_suf, &off);
                if let Some(&last) = new_segs.last() {
                    // Fade the region's tail towards the kept frame after it.
                    let d = self.space.delta(suffix.row(0), rows.row(len - 1));
                    let b = self
                        .params
                        .blend_frames
                        .min(self.segments[last].len().saturating_sub(1));
                    for k in 0..b {
                        let w = blend_weight(k, b);
                        let mut row = rows.row_mut(len - 1 - k);
                        for (v, dv) in row.iter_mut().zip(&d) {
                            *v += w * dv;
                        }
                    }
                }
            }
            rows.slice_mut(s![len.., ..]).assign(&suffix);
            conf.slice_mut(s![len.., ..])
                .assign(&synth.conf.slice(s![f_e.., ..]));
        }
        let mut pieces: Vec<Piece> = synth.pieces[..old.start].to_vec();
        pieces.extend(self.pieces_of(&new_segs, f_b));
        let shift = (f_b + span_len) as isize - f_e as isize;
        for p in &synth.pieces[old.end..] {
            let mut q = *p;
            q.start_frame = (p.start_frame as isize + shift) as usize;
            pieces.push(q);
        }
        let symbols = pieces.iter().map(|p| p.symbol).collect();
        let synthesis = self.build(symbols, pieces, Some(regen.derivation.clone()), rows, conf)?;
        Ok(Regenerated {
            synthesis,
            regeneration: regen,
            old_frames: f_b..f_e,
            new_frames: f_b..f_b + span_len,
        })
    }
}
