//! "Statue" moments (paper 002 §4.3): the frame after which a forecaster's
//! accuracy improves the most.
//!
//! Definition used here. For every conditioning window that ends at frame `t`
//! (inclusive, `context_frames` long) and is followed by `future_frames` true
//! frames, the forecaster predicts those frames and the **error** `e(t)` is the
//! mean over the predicted frames of the mean distance over the joints valid in
//! the truth, divided by the context's torso scale ([`crate::normalize`]), so it
//! is unit-free. The low-pass difference
//!
//! `Δ(t) = mean(e(t−w) … e(t−1)) − mean(e(t) … e(t+w−1))`
//!
//! (`w = filter_frames`, terms outside the available range dropped) is the drop
//! in error when the conditioning window moves past frame `t`; with `w = 1` it
//! is exactly `e(t−1) − e(t)`. The statue frame is the `t` with the largest
//! `Δ(t)` (ties: the earliest).

use mp_geom::Track;
use serde::Serialize;

use crate::error::{ForecastError, Result};
use crate::forecaster::Forecaster;
use crate::normalize::{BodyJoints, Normalizer};

/// Parameters of [`find_statue`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StatueParams {
    /// Frames in each conditioning window. Default 15.
    pub context_frames: usize,
    /// Future frames scored after each window. Default 15 (paper: "the following 15 frames").
    pub future_frames: usize,
    /// Half-width `w` of the low-pass difference filter. Default 2.
    pub filter_frames: usize,
}

impl Default for StatueParams {
    fn default() -> Self {
        StatueParams {
            context_frames: 15,
            future_frames: 15,
            filter_frames: 2,
        }
    }
}

impl StatueParams {
    /// Every value ≥ 1.
    pub fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("context_frames", self.context_frames),
            ("future_frames", self.future_frames),
            ("filter_frames", self.filter_frames),
        ] {
            if v == 0 {
                return Err(ForecastError::param(n, "must be ≥ 1"));
            }
        }
        Ok(())
    }
}

/// Result of [`find_statue`].
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Statue {
    /// The statue frame (0-based frame index in the track).
    pub frame: usize,
    /// `Δ` at that frame (drop in normalised error).
    pub improvement: f64,
    /// The last frame of each conditioning window, in order.
    pub window_end_frames: Vec<usize>,
    /// `e(t)` per window (NaN where no truth joint was valid).
    pub errors: Vec<f64>,
    /// `Δ(t)` per window end frame (NaN for the first).
    pub improvements: Vec<f64>,
}

/// Finds the statue frame of `track` under `forecaster` (see the module docs).
pub fn find_statue(
    forecaster: &dyn Forecaster,
    track: &Track,
    params: &StatueParams,
) -> Result<Statue> {
    params.validate()?;
    let (c, f) = (params.context_frames, params.future_frames);
    let t = track.n_frames();
    // windows end at t_end = c-1 ..= t-1-f; at least two windows are needed for a difference
    let needed = c + f + 1;
    if t < needed {
        return Err(ForecastError::TooShort {
            what: "statue discovery (context + future + 1)",
            needed,
            got: t,
        });
    }
    let body = BodyJoints::from_skeleton(track.skeleton());
    let ends: Vec<usize> = (c - 1..=t - 1 - f).collect();
    let pasts = ends
        .iter()
        .map(|&e| track.slice_frames(e + 1 - c, e + 1))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let preds = forecaster.predict_batch(&pasts, f)?;
    let mut errors = Vec::with_capacity(ends.len());
    for ((&e, past), pred) in ends.iter().zip(&pasts).zip(&preds) {
        let scale = Normalizer::from_track_tail(past, c, &body)
            .map(|n| n.scale)
            .unwrap_or(f64::NAN);
        let (mut sum, mut n) = (0.0, 0usize);
        for h in 0..f {
            let tt = e + 1 + h;
            let (mut fs, mut fnn) = (0.0, 0usize);
            for j in 0..track.n_joints() {
                if track.confidence()[[tt, j]] > 0.0 && pred.confidence()[[h, j]] > 0.0 {
                    let d: f64 = (0..track.dims())
                        .map(|k| {
                            (track.positions()[[tt, j, k]] - pred.positions()[[h, j, k]]).powi(2)
                        })
                        .sum::<f64>()
                        .sqrt();
                    fs += d;
                    fnn += 1;
                }
            }
            if fnn > 0 {
                sum += fs / fnn as f64;
                n += 1;
            }
        }
        errors.push(if n > 0 {
            sum / n as f64 / scale
        } else {
            f64::NAN
        });
    }
    let w = params.filter_frames;
    let mean_range = |a: isize, b: isize| -> f64 {
        let lo = a.max(0) as usize;
        let hi = (b.max(0) as usize).min(errors.len());
        let v: Vec<f64> = errors.get(lo..hi).map(|s| s.to_vec()).unwrap_or_default();
        mp_geom::nanmean(&v)
    };
    let improvements: Vec<f64> = (0..errors.len())
        .map(|i| {
            if i == 0 {
                return f64::NAN;
            }
            let i = i as isize;
            let w = w as isize;
            mean_range(i - w, i) - mean_range(i, i + w)
        })
        .collect();
    let best = improvements
        .iter()
        .enumerate()
        .filter(|(_, v)| v.is_finite())
        .fold(None, |acc: Option<(usize, f64)>, (i, &v)| match acc {
            Some((_, b)) if b >= v => acc,
            _ => Some((i, v)),
        })
        .ok_or_else(|| {
            ForecastError::NoValidJoints("no two consecutive windows could be scored".into())
        })?;
    Ok(Statue {
        frame: ends[best.0],
        improvement: best.1,
        window_end_frames: ends,
        errors,
        improvements,
    })
}
