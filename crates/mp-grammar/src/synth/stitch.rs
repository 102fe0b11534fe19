//! Stitching: each selected segment placed after the previous one and
//! cross-faded into it, the result built as a track (and BVH), and
//! synthesis from a grammar or a finite-state machine.

use mp_geom::Track;
use mp_geom::{Bvh, BvhTrackParams};
use ndarray::{s, Array2, Array3};

use super::{Output, Piece, Stitcher, SynthesizedMotion, MAX_FRAME_JOINTS, MAX_SEGMENTS};
use crate::derive::{derive_at_least, Derivation, DeriveParams, Fsm};
use crate::distance::PoseFeatures;
use crate::error::{GrammarError, Result};
use crate::grammar::Grammar;

/// Blend weight `w_k` of the cosine ramp over `b` frames.
pub fn blend_weight(k: usize, b: usize) -> f64 {
    0.5 * (1.0 + (std::f64::consts::PI * (k + 1) as f64 / (b + 1) as f64).cos())
}

impl Stitcher {
    /// Appends segment `seg` to `out` (rows `0..len` in use), placed and
    /// head-blended after the rows already there. Returns the new length.
    pub(super) fn append(
        &self,
        out: &mut Array2<f64>,
        conf: &mut Array2<f64>,
        len: usize,
        seg: usize,
    ) -> usize {
        let s = self.segments[seg];
        let l = s.len();
        let mut block = self.rows.slice(s![s.start..s.end, ..]).to_owned();
        if len > 0 {
            let off = self.space.placement(out, len, &block, 0);
            self.space.translate(&mut block, 0..l, &off);
            let d = self.space.delta(out.row(len - 1), block.row(0));
            let b = self.params.blend_frames.min(l.saturating_sub(1));
            for k in 0..b {
                let w = blend_weight(k, b);
                let mut row = block.row_mut(k);
                for (v, dv) in row.iter_mut().zip(&d) {
                    *v += w * dv;
                }
            }
        }
        out.slice_mut(s![len..len + l, ..]).assign(&block);
        conf.slice_mut(s![len..len + l, ..])
            .assign(&self.conf.slice(s![s.start..s.end, ..]));
        len + l
    }

    pub(super) fn build(
        &self,
        symbols: Vec<usize>,
        pieces: Vec<Piece>,
        derivation: Option<Derivation>,
        rows: Array2<f64>,
        conf: Array2<f64>,
    ) -> Result<SynthesizedMotion> {
        let (track, bvh) = match &self.output {
            Output::Positions {
                n_joints,
                dims,
                fps,
                units,
                skeleton,
            } => {
                let t = rows.nrows();
                let pos: Array3<f64> = rows
                    .clone()
                    .into_shape_with_order((t, *n_joints, *dims))
                    .map_err(|e| GrammarError::Invalid(e.to_string()))?;
                (
                    Track::new(pos, Some(conf.clone()), *fps, *units, skeleton.clone())?,
                    None,
                )
            }
            Output::Bvh { template, units } => {
                let b = Bvh::from_parts(
                    template.joints().to_vec(),
                    template.frame_time_s(),
                    rows.clone(),
                )?;
                let t = b.to_track(&BvhTrackParams {
                    units: *units,
                    ..Default::default()
                })?;
                (t, Some(b))
            }
        };
        Ok(SynthesizedMotion {
            symbols,
            pieces,
            derivation,
            track,
            bvh,
            rows,
            conf,
        })
    }

    pub(super) fn pieces_of(&self, segs: &[usize], first_frame: usize) -> Vec<Piece> {
        let mut f = first_frame;
        segs.iter()
            .map(|&i| {
                let s = self.segments[i];
                let p = Piece {
                    symbol: s.symbol,
                    segment: i,
                    source: s.segment(),
                    start_frame: f,
                };
                f += s.len();
                p
            })
            .collect()
    }

    /// Checks a requested segment count against `MAX_SEGMENTS` and, at the
    /// source's longest segment, against [`MAX_FRAME_JOINTS`]; the error
    /// names `segments`, the value and the limit.
    pub fn check_segments(&self, segments: usize) -> Result<()> {
        let longest = self
            .segments
            .iter()
            .map(|s| s.len())
            .max()
            .unwrap_or(1)
            .max(1);
        let joints = self.conf.ncols().max(1);
        let by_frames = (MAX_FRAME_JOINTS / joints / longest).max(1);
        let limit = by_frames.min(MAX_SEGMENTS);
        if segments > limit {
            return Err(GrammarError::param(
                "segments",
                format!(
                    "{segments} is too large: at most {limit} segments ({MAX_SEGMENTS}, or \
                     {MAX_FRAME_JOINTS} frame·joints at {longest} frames × {joints} joints \
                     per segment, whichever is fewer)"
                ),
            ));
        }
        Ok(())
    }

    /// Stitches the given source segments in order.
    pub fn render(&self, segments: &[usize]) -> Result<SynthesizedMotion> {
        if segments.is_empty() {
            return Err(GrammarError::Empty("no segment to stitch".into()));
        }
        if let Some(&bad) = segments.iter().find(|&&i| i >= self.segments.len()) {
            return Err(GrammarError::Invalid(format!(
                "segment index {bad} outside 0..{}",
                self.segments.len()
            )));
        }
        let total: usize = segments.iter().map(|&i| self.segments[i].len()).sum();
        let joints = self.conf.ncols().max(1);
        if total.saturating_mul(joints) > MAX_FRAME_JOINTS {
            return Err(GrammarError::param(
                "segments",
                format!(
                    "{} segments of {total} frames are too large: at most {} frames of \
                     {joints} joints ({MAX_FRAME_JOINTS} frame·joints)",
                    segments.len(),
                    MAX_FRAME_JOINTS / joints
                ),
            ));
        }
        let mut rows = Array2::zeros((total, self.rows.ncols()));
        let mut conf = Array2::zeros((total, self.conf.ncols()));
        let mut len = 0;
        for &i in segments {
            len = self.append(&mut rows, &mut conf, len, i);
        }
        let pieces = self.pieces_of(segments, 0);
        let symbols = pieces.iter().map(|p| p.symbol).collect();
        self.build(symbols, pieces, None, rows, conf)
    }

    /// Greedy selection and stitching of a symbol string.
    pub fn stitch(&self, symbols: &[usize], seed: u64) -> Result<SynthesizedMotion> {
        let segs = self.select(symbols, seed)?;
        self.render(&segs)
    }

    /// Derives sentences from `grammar` until they hold at least
    /// `min_segments` terminals, then stitches them (seeded).
    pub fn synthesize(
        &self,
        grammar: &Grammar,
        derive: &DeriveParams,
        min_segments: usize,
        seed: u64,
    ) -> Result<SynthesizedMotion> {
        self.check_segments(min_segments)?;
        let map = self.terminal_symbols(grammar)?;
        let derivation = derive_at_least(grammar, derive, min_segments.max(1), seed)?;
        let symbols: Vec<usize> = derivation
            .terminals()
            .iter()
            .map(|&t| map[t as usize])
            .collect();
        let mut s = self.stitch(&symbols, seed)?;
        s.derivation = Some(derivation);
        Ok(s)
    }

    /// `n_segments` symbols from the finite-state machine, stitched (seeded).
    pub fn synthesize_fsm(
        &self,
        fsm: &Fsm,
        n_segments: usize,
        seed: u64,
    ) -> Result<SynthesizedMotion> {
        self.check_segments(n_segments)?;
        if fsm.k() != self.k() {
            return Err(GrammarError::Invalid(format!(
                "the state machine has {} symbols, the motion {}",
                fsm.k(),
                self.k()
            )));
        }
        let symbols: Vec<usize> = fsm
            .generate(n_segments.max(1), seed)
            .iter()
            .map(|&s| s as usize)
            .collect();
        self.stitch(&symbols, seed)
    }

    /// Seam pose distances of a synthesis after blending (frames `s − 1`
    /// and `s` of every seam), in the source's distance units (the source
    /// body size normalises them).
    pub fn seam_distances(&self, synth: &SynthesizedMotion) -> Result<Vec<f64>> {
        let f = PoseFeatures::from_track_with_scale(
            &synth.track,
            &self.params.distance,
            Some(self.features.body_scale()),
        )?;
        synth
            .seam_frames()
            .iter()
            .map(|&s| f.pose_distance(s - 1, s))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_fall_from_one_to_zero() {
        let b = 8;
        let w: Vec<f64> = (0..b).map(|k| blend_weight(k, b)).collect();
        assert!(w[0] < 1.0 && w[0] > 0.9);
        assert!(w[b - 1] > 0.0 && w[b - 1] < 0.1);
        for p in w.windows(2) {
            assert!(p[1] < p[0]);
        }
        // Symmetric ramp: w_k + w_{B-1-k} = 1.
        for k in 0..b {
            assert!((w[k] + w[b - 1 - k] - 1.0).abs() < 1e-12);
        }
    }
}
