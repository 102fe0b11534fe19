//! The refit under the Euclidean norm: iteratively reweighted least squares
//! from the least-squares solve (see the parent module's docs).

use mp_geom::FitParams;
use mp_geom::Primitive;

use super::elems::{primitives_of, Elem};
use super::solve::solve;
use super::{distance_at, refit_weight, JointSeries};

/// Largest number of reweighted solves of the Euclidean refit
/// ([`RefitNorm::Euclidean`](super::RefitNorm::Euclidean)).
pub const IRLS_STEPS: usize = 20;

/// Residuals below this (reference pixels) weigh as much as it does in the
/// reweighted solves.
pub const IRLS_FLOOR_PX: f64 = 0.05;

/// Per-frame residual lengths of `prims` on the joint's frames (into `out`).
fn residual_lengths(
    series: &JointSeries<'_>,
    bounds: &[usize],
    prims: &[Primitive],
    out: &mut [f64],
) {
    let mut buf = vec![0.0; series.points.ncols()];
    for (i, p) in prims.iter().enumerate() {
        for (t, k) in (bounds[i]..bounds[i + 1]).enumerate() {
            out[k] = distance_at(p, t, series, k, &mut buf);
        }
    }
}

/// The objective the reweighted solves lower, from the residual lengths:
/// `c·Σ 2f·ρ_f(‖rᵢ‖)` over the observed frames (Huber's loss with its corner
/// at `f`: `‖r‖²` below it, `2f‖r‖ − f²` above, so the Euclidean error up to
/// a constant for residuals above `f`) plus the least-squares terms of the
/// gap-filled frames, with their refit weights.
fn objective(series: &JointSeries<'_>, bounds: &[usize], res: &[f64], f: f64, c: f64) -> f64 {
    let mut total = 0.0;
    for seg in bounds.windows(2) {
        let observed = series.weights[seg[0]..seg[1]].iter().any(|&w| w > 0.0);
        for (k, &r) in res.iter().enumerate().take(seg[1]).skip(seg[0]) {
            total += if series.weights[k] > 0.0 {
                c * if r <= f { r * r } else { 2.0 * f * r - f * f }
            } else {
                refit_weight(series, observed, k) * r * r
            };
        }
    }
    total
}

/// The refit under the Euclidean norm: iteratively reweighted least squares.
/// Each observed frame's weight is multiplied by `c·f / max(‖rᵢ‖, f)` from the
/// previous solve (see the module docs for `c`); gap-filled frames keep their
/// least-squares weight (they are not data). Each solve lowers [`objective`]
/// (a majorise–minimise step). It stops when a step gains less than 0.1 % or
/// after [`IRLS_STEPS`], and keeps the best solution seen.
#[allow(clippy::too_many_arguments)]
pub(super) fn reweighted(
    series: &JointSeries<'_>,
    bounds: &[usize],
    durations: &[usize],
    elems: &[Elem],
    init: &[Vec<f64>],
    fit: &FitParams,
    prims: &[Primitive],
    start: Vec<Primitive>,
) -> Vec<Primitive> {
    let (t, d) = series.points.dim();
    let floor = IRLS_FLOOR_PX * fit.unit_scale;
    let mut res = vec![0.0; t];
    let mut best = start;
    residual_lengths(series, bounds, &best, &mut res);
    // Observed frames weigh 1 on average in the first reweighted solve, as
    // in the least-squares one, against the gap-filled frames.
    let (mut sum, mut n) = (0.0, 0usize);
    for (r, &obs) in res.iter().zip(series.weights) {
        if obs > 0.0 {
            sum += floor / r.max(floor);
            n += 1;
        }
    }
    if n == 0 || sum <= 0.0 {
        return best;
    }
    let c = n as f64 / sum;
    let mut best_err = objective(series, bounds, &res, floor, c);
    let mut weights = vec![0.0; t];
    let mut cand_res = vec![0.0; t];
    for _ in 0..IRLS_STEPS {
        for ((w, r), &obs) in weights.iter_mut().zip(&res).zip(series.weights) {
            *w = if obs > 0.0 {
                c * floor / r.max(floor)
            } else {
                1.0
            };
        }
        let Some((knots, interiors)) = solve(series, bounds, elems, init, d, Some(&weights)) else {
            break;
        };
        let cand = primitives_of(prims, elems, durations, &knots, &interiors);
        residual_lengths(series, bounds, &cand, &mut cand_res);
        let err = objective(series, bounds, &cand_res, floor, c);
        if err.is_nan() || err >= best_err {
            break;
        }
        let gain = (best_err - err) / best_err.max(f64::MIN_POSITIVE);
        best = cand;
        best_err = err;
        std::mem::swap(&mut res, &mut cand_res);
        if gain < 1e-3 {
            break;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)] // test code: failing loudly is the point

    use super::super::{refit_joint, RefitNorm};
    use super::*;
    use ndarray::Array2;

    /// Three lines (a zigzag) with small deterministic noise and a few
    /// large spikes; returns the points, 0/1 weights and the boundaries.
    fn zigzag() -> (Array2<f64>, Vec<f64>, Vec<usize>) {
        let t = 90;
        let mut pts = Array2::zeros((t, 2));
        for i in 0..t {
            let s = i as f64;
            let (x, y) = if i < 30 {
                (2.0 * s, s)
            } else if i < 60 {
                (60.0 + (s - 30.0), 30.0 - 2.0 * (s - 30.0))
            } else {
                (90.0 + 3.0 * (s - 60.0), -30.0 + 0.5 * (s - 60.0))
            };
            let noise = 0.3 * ((i * 7919) % 13) as f64 / 13.0 - 0.15;
            let spike = if i % 11 == 5 { 25.0 } else { 0.0 };
            pts[[i, 0]] = x + noise + spike;
            pts[[i, 1]] = y - noise;
        }
        let mut weights = vec![1.0; t];
        weights[44] = 0.0; // one missing frame (gap-filled position, small weight)
        (pts, weights, vec![0, 30, 60, 90])
    }

    fn line(a: [f64; 2], v: [f64; 2]) -> Primitive {
        Primitive::Line {
            start: a.to_vec(),
            velocity: v.to_vec(),
        }
    }

    #[test]
    fn euclidean_refit_lowers_the_euclidean_error_and_stays_c0() {
        let (pts, weights, bounds) = zigzag();
        let series = JointSeries {
            points: pts.view(),
            weights: &weights,
        };
        let prims = vec![
            line([0.0, 0.0], [2.0, 1.0]),
            line([60.0, 30.0], [1.0, -2.0]),
            line([90.0, -30.0], [3.0, 0.5]),
        ];
        let fit = FitParams::default();
        let sq = refit_joint(&series, &bounds, &prims, &fit, RefitNorm::Squared).unwrap();
        let eu = refit_joint(&series, &bounds, &prims, &fit, RefitNorm::Euclidean).unwrap();
        let mut res = vec![0.0; pts.nrows()];
        // Σ‖rᵢ‖ over the observed frames (`res` keeps the last one's residuals).
        let mut observed_sum = |p: &[Primitive]| {
            residual_lengths(&series, &bounds, p, &mut res);
            (0..pts.nrows())
                .filter(|&i| weights[i] > 0.0)
                .map(|i| res[i])
                .sum::<f64>()
        };
        let e_sq = observed_sum(&sq);
        let e_eu = observed_sum(&eu);
        // The spikes pull the least-squares lines; the Euclidean refit lies
        // on the clean frames (their noise is at most 0.15 per axis).
        assert!(e_eu < 0.8 * e_sq, "Σ‖r‖ {e_eu} vs least squares {e_sq}");
        let clean: Vec<f64> = (0..pts.nrows())
            .filter(|i| i % 11 != 5 && weights[*i] > 0.0)
            .map(|i| res[i])
            .collect();
        let worst = clean.iter().cloned().fold(0.0, f64::max);
        assert!(worst < 1.0, "largest residual on a clean frame {worst}");
        // Both share their boundary poses.
        for p in [&sq, &eu] {
            for i in 0..2 {
                let n = (bounds[i + 1] - bounds[i]) as f64;
                let (a, b) = (p[i].eval(n), p[i + 1].eval(0.0));
                let gap = ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
                assert!(gap < 1e-9, "boundary {i}: gap {gap}");
            }
        }
    }

    #[test]
    fn refit_norm_names_round_trip() {
        for n in [RefitNorm::Squared, RefitNorm::Euclidean] {
            assert_eq!(n.as_str().parse::<RefitNorm>().unwrap(), n);
        }
        let err = "l1".parse::<RefitNorm>().unwrap_err();
        assert!(err.contains("unknown refit norm `l1`"), "{err}");
    }
}
