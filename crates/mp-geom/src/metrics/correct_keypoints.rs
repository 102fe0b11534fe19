//! PCK, the percentage of correct keypoints, after a per-frame scale and
//! translation fit, with its parameters ([`PckParams`]).

use super::poses::{check_pair, nanmean_or_err};
use super::Poses;
use crate::error::{GeomError, Result};

/// Parameters of `pck_with` / `pck_per_frame`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PckParams {
    /// Threshold as a fraction of the bounding-box size. Default 0.05.
    pub alpha: f64,
    /// Frames with fewer visible ground-truth joints are not scored (NaN). Default 6.
    pub min_visible: usize,
}

impl Default for PckParams {
    fn default() -> Self {
        PckParams {
            alpha: 0.05,
            min_visible: 6,
        }
    }
}

impl PckParams {
    /// `alpha` finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        if !(self.alpha.is_finite() && self.alpha >= 0.0) {
            return Err(GeomError::param(
                "alpha",
                format!("must be finite and ≥ 0, got {}", self.alpha),
            ));
        }
        Ok(())
    }
}

/// PCK per frame, in percent, NaN for frames that are not scored.
///
/// For frame t, the *visible* joints are those valid in `gt`; the frame is
/// scored when there are at least `min_visible` of them. The size of the
/// ground truth is the larger side of the axis-aligned bounding box of its
/// visible joints (the largest extent over the D axes). The prediction is
/// first mapped by the scale `s` and translation `τ` minimising
/// `Σ ‖s·Pⱼ + τ − Gⱼ‖²` over the visible joints that are also valid in
/// `pred` (closed form: with centred `P̃, G̃`, `s = ⟨P̃, G̃⟩ / ‖P̃‖²`, or
/// `s = 1` when all those predicted joints coincide; `τ = Ḡ − s·P̄`). A
/// visible joint is correct when `‖s·Pⱼ + τ − Gⱼ‖ ≤ α·size`; a visible joint
/// missing from `pred` counts as wrong. The frame's PCK is
/// `100 · correct / visible`.
pub fn pck_per_frame<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    params: &PckParams,
) -> Result<Vec<f64>> {
    pck_per_frame_sized(pred, gt, None, params)
}

/// `pck_per_frame` with the reference size of every ground-truth frame
/// given (e.g. the larger side of a data set's annotated person box) instead
/// of the extent of the visible joints. `sizes` must hold one entry per
/// ground-truth frame; a frame whose size is not finite and > 0 (a missing
/// annotation) falls back to the extent of its visible joints. `None` is
/// `pck_per_frame`.
pub fn pck_per_frame_sized<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    sizes: Option<&[f64]>,
    params: &PckParams,
) -> Result<Vec<f64>> {
    let (pred, gt) = (pred.into(), gt.into());
    params.validate()?;
    check_pair(&pred, &gt, "pck", true)?;
    if let Some(sz) = sizes {
        if sz.len() != gt.n_frames() {
            return Err(GeomError::Shape(format!(
                "pck: {} reference sizes for {} ground-truth frames",
                sz.len(),
                gt.n_frames()
            )));
        }
    }
    let (_, nj, d) = gt.positions.dim();
    let mut pm = vec![0.0; d];
    let mut gm = vec![0.0; d];
    let mut lo = vec![0.0; d];
    let mut hi = vec![0.0; d];
    let mut out = Vec::with_capacity(gt.n_frames());
    for t in 0..gt.n_frames() {
        let visible = (0..nj).filter(|&j| gt.valid(t, j)).count();
        if visible < params.min_visible.max(1) {
            out.push(f64::NAN);
            continue;
        }
        lo.fill(f64::INFINITY);
        hi.fill(f64::NEG_INFINITY);
        pm.fill(0.0);
        gm.fill(0.0);
        let mut both = 0usize;
        for j in 0..nj {
            if !gt.valid(t, j) {
                continue;
            }
            for k in 0..d {
                let g = gt.p(t, j, k);
                lo[k] = lo[k].min(g);
                hi[k] = hi[k].max(g);
            }
            if pred.valid(t, j) {
                both += 1;
                for k in 0..d {
                    pm[k] += pred.p(t, j, k);
                    gm[k] += gt.p(t, j, k);
                }
            }
        }
        let size = match sizes.map(|sz| sz[t]) {
            Some(v) if v.is_finite() && v > 0.0 => v,
            _ => lo.iter().zip(&hi).map(|(a, b)| b - a).fold(0.0, f64::max),
        };
        if both == 0 {
            out.push(0.0);
            continue;
        }
        for k in 0..d {
            pm[k] /= both as f64;
            gm[k] /= both as f64;
        }
        let (mut pg, mut pp) = (0.0, 0.0);
        for j in 0..nj {
            if gt.valid(t, j) && pred.valid(t, j) {
                for k in 0..d {
                    let p = pred.p(t, j, k) - pm[k];
                    pg += p * (gt.p(t, j, k) - gm[k]);
                    pp += p * p;
                }
            }
        }
        let s = if pp > 0.0 { pg / pp } else { 1.0 };
        let thr = params.alpha * size;
        let mut correct = 0usize;
        for j in 0..nj {
            if gt.valid(t, j) && pred.valid(t, j) {
                let mut e = 0.0;
                for k in 0..d {
                    let x = s * (pred.p(t, j, k) - pm[k]) + gm[k] - gt.p(t, j, k);
                    e += x * x;
                }
                if e.sqrt() <= thr {
                    correct += 1;
                }
            }
        }
        out.push(100.0 * correct as f64 / visible as f64);
    }
    Ok(out)
}

/// PCK in percent with the given parameters: the [`nanmean`](super::nanmean) of [`pck_per_frame`].
pub fn pck_with<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    params: &PckParams,
) -> Result<f64> {
    nanmean_or_err(&pck_per_frame(pred, gt, params)?, "pck")
}

/// PCK@α in percent (`min_visible` = 6): see `pck_per_frame`.
pub fn pck<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
    alpha: f64,
) -> Result<f64> {
    pck_with(
        pred,
        gt,
        &PckParams {
            alpha,
            ..PckParams::default()
        },
    )
}
