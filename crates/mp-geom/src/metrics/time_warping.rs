//! Dynamic time warping between pose sequences ([`dtw`]) and a prediction
//! resampled onto the ground truth's frames along the DTW path
//! ([`dtw_align`]).

use ndarray::{Array2, Array3};

use super::poses::check_pair;
use super::Poses;
use crate::error::{GeomError, Result};

/// How DTW scores frame pairs and sums them. Let `d(i, j)` be the mean
/// Euclidean distance between frame `i` of `a` and frame `j` of `b` over the
/// joints valid in both, and `q(i, j)` the mean **squared** distance over the
/// same joints.
///
/// Libraries disagree here: e.g. tslearn's `dtw` is `SquaredThenSqrt` on
/// whole-frame vectors, i.e. with the *sum* over joints where this uses the
/// mean (for fully visible frames, tslearn's value = `sqrt(J)·` ours).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum DtwCost {
    /// Local cost `d(i, j)`; distance = sum along the path.
    #[default]
    Euclidean,
    /// Local cost `q(i, j)`; distance = sum along the path.
    SquaredEuclidean,
    /// Local cost `q(i, j)`; distance = square root of the sum along the path.
    SquaredThenSqrt,
}

/// Result of [`dtw`].
#[derive(Debug, Clone, PartialEq)]
pub struct DtwResult {
    /// Total cost per the [`DtwCost`] convention.
    pub distance: f64,
    /// Matched frame pairs `(i in a, j in b)`, from `(0, 0)` to `(Ta−1, Tb−1)`,
    /// each step advancing `i`, `j` or both by 1: monotone, every frame of
    /// both sequences matched at least once.
    pub path: Vec<(usize, usize)>,
}

/// Largest DTW cost matrix (`Ta · Tb` cells) accepted: 2²⁶ (one byte per cell
/// is kept for the path).
pub const MAX_DTW_CELLS: usize = 1 << 26;

/// Dynamic time warping between two pose sequences (same J and D; T may
/// differ), with steps (1, 0), (0, 1), (1, 1) and the cost convention `cost`.
///
/// A pair of frames without a joint valid in both has infinite local cost;
/// when no path has a finite cost the result is [`GeomError::NoData`]. Ties
/// between predecessors prefer the diagonal step, then the step in `a`.
pub fn dtw<'a, 'b>(
    a: impl Into<Poses<'a>>,
    b: impl Into<Poses<'b>>,
    cost: DtwCost,
) -> Result<DtwResult> {
    let (a, b) = (a.into(), b.into());
    check_pair(&a, &b, "dtw", false)?;
    let (na, nb) = (a.n_frames(), b.n_frames());
    if na.saturating_mul(nb) > MAX_DTW_CELLS {
        return Err(GeomError::param(
            "dtw",
            format!("{na} × {nb} frames exceed the {MAX_DTW_CELLS}-cell limit"),
        ));
    }
    let nj = a.n_joints();
    let local = |i: usize, j: usize| -> f64 {
        let (mut s, mut n) = (0.0, 0usize);
        for jj in 0..nj {
            if a.valid(i, jj) && b.valid(j, jj) {
                let dd = a.dist(i, &b, j, jj);
                s += match cost {
                    DtwCost::Euclidean => dd,
                    DtwCost::SquaredEuclidean | DtwCost::SquaredThenSqrt => dd * dd,
                };
                n += 1;
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            s / n as f64
        }
    };
    // dir: 0 = diagonal, 1 = from (i−1, j), 2 = from (i, j−1)
    let mut dir = vec![0u8; na * nb];
    let mut prev = vec![f64::INFINITY; nb];
    let mut cur = vec![f64::INFINITY; nb];
    for i in 0..na {
        for j in 0..nb {
            let c = local(i, j);
            let (best, from) = if i == 0 && j == 0 {
                (0.0, 0u8)
            } else {
                let diag = if i > 0 && j > 0 {
                    prev[j - 1]
                } else {
                    f64::INFINITY
                };
                let up = if i > 0 { prev[j] } else { f64::INFINITY };
                let left = if j > 0 { cur[j - 1] } else { f64::INFINITY };
                let mut best = (diag, 0u8);
                if up < best.0 {
                    best = (up, 1);
                }
                if left < best.0 {
                    best = (left, 2);
                }
                best
            };
            cur[j] = best + c;
            dir[i * nb + j] = from;
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    let total = prev[nb - 1];
    if !total.is_finite() {
        return Err(GeomError::NoData(
            "dtw: no alignment where every matched pair of frames shares a valid joint".into(),
        ));
    }
    let mut path = Vec::with_capacity(na + nb);
    let (mut i, mut j) = (na - 1, nb - 1);
    path.push((i, j));
    while i > 0 || j > 0 {
        match dir[i * nb + j] {
            0 => {
                i -= 1;
                j -= 1;
            }
            1 => i -= 1,
            _ => j -= 1,
        }
        path.push((i, j));
    }
    path.reverse();
    let distance = match cost {
        DtwCost::SquaredThenSqrt => total.sqrt(),
        _ => total,
    };
    Ok(DtwResult { distance, path })
}

/// A prediction resampled onto the ground truth's frames by [`dtw_align`].
#[derive(Debug, Clone, PartialEq)]
pub struct Aligned {
    /// Positions `T_gt × J × D`.
    pub positions: Array3<f64>,
    /// Confidence `T_gt × J` (0 where no matched prediction frame had the joint).
    pub confidence: Array2<f64>,
    /// The DTW result used.
    pub dtw: DtwResult,
}

impl Aligned {
    /// A [`Poses`] view, ready for [`pck`](super::pck), [`mpjpe`](super::mpjpe), ….
    pub fn poses(&self) -> Poses<'_> {
        Poses {
            positions: self.positions.view(),
            confidence: Some(self.confidence.view()),
        }
    }
}

/// Resamples `pred` to `gt`'s length along the DTW path ("metric with DTW"):
/// frame `j` of the result is, joint by joint, the mean of the prediction
/// frames matched to ground-truth frame `j` where that joint is valid, with
/// the mean of their confidences (1 for valid joints without confidence).
pub fn dtw_align<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    cost: DtwCost,
) -> Result<Aligned> {
    let (pred, gt) = (pred.into(), gt.into());
    let res = dtw(pred, gt, cost)?;
    let (tg, nj, d) = gt.positions.dim();
    let mut positions = Array3::<f64>::zeros((tg, nj, d));
    let mut confidence = Array2::<f64>::zeros((tg, nj));
    let mut count = Array2::<f64>::zeros((tg, nj));
    let mut matched = vec![0usize; tg];
    for &(i, j) in &res.path {
        matched[j] += 1;
        for jj in 0..nj {
            if pred.valid(i, jj) {
                count[[j, jj]] += 1.0;
                confidence[[j, jj]] += pred.confidence.map_or(1.0, |c| c[[i, jj]]);
                for k in 0..d {
                    positions[[j, jj, k]] += pred.p(i, jj, k);
                }
            }
        }
    }
    for j in 0..tg {
        for jj in 0..nj {
            let c = count[[j, jj]];
            if c > 0.0 {
                for k in 0..d {
                    positions[[j, jj, k]] /= c;
                }
                confidence[[j, jj]] /= c;
            }
        }
    }
    Ok(Aligned {
        positions,
        confidence,
        dtw: res,
    })
}
