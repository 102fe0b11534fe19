//! Procrustes alignment: the best similarity transform between point sets
//! ([`procrustes`]) and PA-MPJPE, the MPJPE after that alignment.

use nalgebra::DMatrix;
use ndarray::{Array2, ArrayView2};

use super::poses::{check_pair, nanmean_or_err};
use super::Poses;
use crate::error::{GeomError, Result};

/// A similarity transform `x ↦ scale·R·x + translation`.
#[derive(Debug, Clone, PartialEq)]
pub struct Similarity {
    /// Scale (≥ 0).
    pub scale: f64,
    /// Rotation `D × D`, `det = +1`.
    pub rotation: DMatrix<f64>,
    /// Translation (length D).
    pub translation: Vec<f64>,
}

/// The similarity transform (Umeyama 1991) minimising `Σ ‖s·R·xᵢ + τ − yᵢ‖²`
/// over point pairs `x`, `y` (`N × D`), with `R` a proper rotation: the
/// reflection fix flips the sign of the last singular direction when
/// `det(U Vᵀ) < 0`. With all `x` coincident, `s = 0` and `τ = ȳ`.
pub fn procrustes(x: ArrayView2<'_, f64>, y: ArrayView2<'_, f64>) -> Result<Similarity> {
    let (n, d) = x.dim();
    if y.dim() != (n, d) {
        return Err(GeomError::Shape(format!(
            "procrustes: point sets have shapes {:?} and {:?}",
            x.dim(),
            y.dim()
        )));
    }
    if n == 0 || d == 0 {
        return Err(GeomError::NoData("procrustes: no points".into()));
    }
    if x.iter().chain(y.iter()).any(|v| !v.is_finite()) {
        return Err(GeomError::NonFinite(
            "procrustes: a coordinate is not finite".into(),
        ));
    }
    let xm: Vec<f64> = (0..d).map(|k| x.column(k).sum() / n as f64).collect();
    let ym: Vec<f64> = (0..d).map(|k| y.column(k).sum() / n as f64).collect();
    // cross-covariance Σ ỹ x̃ᵀ (D × D) and Σ ‖x̃‖²
    let mut h = DMatrix::<f64>::zeros(d, d);
    let mut xx = 0.0;
    for i in 0..n {
        for a in 0..d {
            let ya = y[[i, a]] - ym[a];
            for b in 0..d {
                h[(a, b)] += ya * (x[[i, b]] - xm[b]);
            }
            let xa = x[[i, a]] - xm[a];
            xx += xa * xa;
        }
    }
    let svd = h.clone().svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return Err(GeomError::NoData("procrustes: SVD failed".into()));
    };
    let mut sign = DMatrix::<f64>::identity(d, d);
    if (&u * &vt).determinant() < 0.0 {
        sign[(d - 1, d - 1)] = -1.0;
    }
    let rotation = &u * &sign * &vt;
    let trace: f64 = (0..d).map(|k| svd.singular_values[k] * sign[(k, k)]).sum();
    let scale = if xx > 0.0 { trace / xx } else { 0.0 };
    let translation: Vec<f64> = (0..d)
        .map(|a| ym[a] - scale * (0..d).map(|b| rotation[(a, b)] * xm[b]).sum::<f64>())
        .collect();
    Ok(Similarity {
        scale,
        rotation,
        translation,
    })
}

/// PA-MPJPE per frame: MPJPE after the best similarity transform
/// (`procrustes`, with the reflection fix) of the prediction onto the
/// ground truth, over the joints valid in both; NaN for frames with fewer
/// than 2 such joints.
pub fn pa_mpjpe_per_frame<'a, 'b>(
    pred: impl Into<Poses<'a>>,
    gt: impl Into<Poses<'b>>,
) -> Result<Vec<f64>> {
    let (pred, gt) = (pred.into(), gt.into());
    check_pair(&pred, &gt, "pa_mpjpe", true)?;
    let (_, nj, d) = gt.positions.dim();
    let mut out = Vec::with_capacity(gt.n_frames());
    for t in 0..gt.n_frames() {
        let joints: Vec<usize> = (0..nj)
            .filter(|&j| pred.valid(t, j) && gt.valid(t, j))
            .collect();
        if joints.len() < 2 {
            out.push(f64::NAN);
            continue;
        }
        let x = Array2::from_shape_fn((joints.len(), d), |(i, k)| pred.p(t, joints[i], k));
        let y = Array2::from_shape_fn((joints.len(), d), |(i, k)| gt.p(t, joints[i], k));
        let sim = procrustes(x.view(), y.view())?;
        let mut s = 0.0;
        for i in 0..joints.len() {
            let mut e = 0.0;
            for a in 0..d {
                let mut v = sim.translation[a];
                for b in 0..d {
                    v += sim.scale * sim.rotation[(a, b)] * x[[i, b]];
                }
                e += (v - y[[i, a]]) * (v - y[[i, a]]);
            }
            s += e.sqrt();
        }
        out.push(s / joints.len() as f64);
    }
    Ok(out)
}

/// PA-MPJPE: the [`nanmean`](super::nanmean) over frames of [`pa_mpjpe_per_frame`].
pub fn pa_mpjpe<'a, 'b>(pred: impl Into<Poses<'a>>, gt: impl Into<Poses<'b>>) -> Result<f64> {
    nanmean_or_err(&pa_mpjpe_per_frame(pred, gt)?, "pa_mpjpe")
}
