//! O(1) per joint and candidate, from the running moments: the exact
//! squared stationary and line errors, the Bullock/Kåsa circle and its
//! algebraic residual, and lower bounds of every kind's error.

use mp_geom::FitParams;

use super::moments::Acc2;
use super::{Rules, LB_SAFETY};

/// O(1) facts about one joint on one candidate segment.
#[derive(Clone, Copy, Default)]
pub(super) struct Quick {
    /// Lower bound of the joint's cost.
    pub(super) lb: f64,
    /// Mean (absolute coordinates).
    pub(super) mx: f64,
    pub(super) my: f64,
    /// Line: value at the segment's local time 0 (frame `n − 1`) and velocity.
    pub(super) lx: f64,
    pub(super) ly: f64,
    pub(super) vx: f64,
    pub(super) vy: f64,
    /// The bounding box's diagonal is below the stationary rule's threshold.
    pub(super) small_box: bool,
    /// Moving kinds rejected by the span rule.
    pub(super) reject_moving: bool,
    /// Circle from the moments is usable for bounds (well conditioned).
    pub(super) circle_ok: bool,
    pub(super) cx: f64,
    pub(super) cy: f64,
    pub(super) r: f64,
    /// Lower bound of the circle's radius penalty.
    pub(super) pen_lb: f64,
    /// Slack for the circle distance bound (rounding of the centre).
    pub(super) circle_slack: f64,
    /// Squared errors of the stationary and line fits.
    pub(super) sse_stat: f64,
    pub(super) sse_line: f64,
    /// Bound on the largest stationary residual (squared norm only: the
    /// Euclidean bound does not need it).
    pub(super) max_res_stat: f64,
    /// O(1) lower bound of the circle's error with penalty, after the safety
    /// factor (`+∞` where the circle takes no part).
    pub(super) circle_lb: f64,
    /// O(1) lower bounds of the stationary and line errors (`+∞` where the
    /// kind takes no part), before the safety factor.
    pub(super) stat_lb: f64,
    pub(super) line_lb: f64,
}

pub(super) fn penalty_lb(fit: &FitParams, r: f64) -> f64 {
    let a = fit.circle_penalty(r * (1.0 - 1e-8));
    let b = fit.circle_penalty(r * (1.0 + 1e-8));
    a.min(b).max(0.0)
}

/// Lower bound of the error of any constant-speed primitive (a circle with
/// linear angle moves `s = 2r·|sin(ω/2)|` per frame) from the step lengths:
/// `‖rᵢ‖ + ‖rᵢ₊₁‖ ≥ |aᵢ − s|`, each residual in at most two pairs, so
/// `Σ‖rᵢ‖ ≥ ½ min_s Σ|aᵢ − s| ≥ ¼ Σ|aᵢ − ā|` (the median's L1 deviation is at
/// least half the mean's) `≥ ¼ Σ(aᵢ − ā)² / (a_max − a_min)`; squared norm:
/// `Σ‖rᵢ‖² ≥ ¼ Σ(aᵢ − ā)²`.
pub(super) fn speed_lb(acc: &Acc2, squared: bool) -> f64 {
    if acc.npairs < 2 {
        return 0.0;
    }
    // `np·Σ(aᵢ − ā)²`, without a division.
    let np = acc.npairs as f64;
    let var_np = (acc.saa * np - acc.sa * acc.sa).max(0.0) - 1e-12 * acc.saa * np;
    if var_np <= 0.0 {
        return 0.0;
    }
    if squared {
        0.25 * var_np / np
    } else {
        let range = acc.amax - acc.amin;
        if range > 0.0 {
            0.25 * var_np / (np * range)
        } else {
            0.0
        }
    }
}

/// `√sq < thr`, without the square root unless `sq` is within 10⁻¹⁰ of
/// `thr²` (the same answer: the square root is correctly rounded).
pub(super) fn root_below(sq: f64, thr: f64) -> bool {
    // (Negative or NaN operands take the square root.)
    if thr >= 0.0 && sq >= 0.0 {
        let t2 = thr * thr;
        if sq < t2 * (1.0 - 1e-10) {
            return true;
        }
        if sq > t2 * (1.0 + 1e-10) {
            return false;
        }
    }
    sq.sqrt() < thr
}

/// Largest squared distance from `(px, py)` to a corner of the box.
pub(super) fn far_corner2(lo: [f64; 2], hi: [f64; 2], px: f64, py: f64) -> f64 {
    let dx = (px - lo[0]).abs().max((hi[0] - px).abs());
    let dy = (py - lo[1]).abs().max((hi[1] - py).abs());
    dx * dx + dy * dy
}

/// Largest distance from `(px, py)` to a corner of the box.
pub(super) fn far_corner(lo: [f64; 2], hi: [f64; 2], px: f64, py: f64) -> f64 {
    far_corner2(lo, hi, px, py).sqrt()
}

/// Smallest squared distance from `(px, py)` to the box (0 inside).
pub(super) fn near_box2(lo: [f64; 2], hi: [f64; 2], px: f64, py: f64) -> f64 {
    let dx = (lo[0] - px).max(0.0).max(px - hi[0]);
    let dy = (lo[1] - py).max(0.0).max(py - hi[1]);
    dx * dx + dy * dy
}

/// Euclidean lower bound from a squared error and a bound on the largest residual.
pub(super) fn euclid_lb(sse: f64, max_res: f64) -> f64 {
    let sse = sse.max(0.0);
    let a = sse.sqrt();
    if max_res > 0.0 && max_res.is_finite() {
        a.max(sse / max_res)
    } else {
        a
    }
}

/// [`euclid_lb`] from the largest residual's square, with one square root
/// and a division only where it wins (`SSE / M ≥ √SSE` iff `SSE ≥ M²`).
fn euclid_lb2(sse: f64, max_res2: f64) -> f64 {
    let sse = sse.max(0.0);
    if sse >= max_res2 && max_res2 > 0.0 && max_res2.is_finite() {
        sse / max_res2.sqrt()
    } else {
        sse.sqrt()
    }
}

/// The terms of `Σ w‖xᵢ − μ‖⁴` expanded in the moments, `μ = (m1, m2)`: their
/// sum (in this order) is the value.
fn fourth_about(acc: &Acc2, m1: f64, m2: f64) -> [f64; 6] {
    let mu2 = m1 * m1 + m2 * m2;
    let sz = acc.sxx + acc.syy;
    let szx = acc.sxxx + acc.sxyy;
    let szy = acc.sxxy + acc.syyy;
    let smp2 = m1 * m1 * acc.sxx + 2.0 * m1 * m2 * acc.sxy + m2 * m2 * acc.syy;
    let smp = m1 * acc.sx + m2 * acc.sy;
    [
        acc.szz,
        -4.0 * (m1 * szx + m2 * szy),
        2.0 * mu2 * sz,
        4.0 * smp2,
        -4.0 * mu2 * smp,
        mu2 * mu2 * acc.sw,
    ]
}

pub(super) fn quick(acc: &Acc2, pts: &[[f64; 2]], rules: &Rules, fit: &FitParams) -> Quick {
    let w = acc.sw;
    let mut q = Quick {
        stat_lb: f64::INFINITY,
        line_lb: f64::INFINITY,
        circle_lb: f64::INFINITY,
        ..Quick::default()
    };
    let (mux, muy) = (acc.sx / w, acc.sy / w);
    // (Divisions are the costly part: where it is safe, a divisor is
    // inverted once. The mean stays a division, as in the fits.)
    let iw = 1.0 / w;
    q.mx = mux + acc.rx;
    q.my = muy + acc.ry;
    let bx = acc.hi[0] - acc.lo[0];
    let by = acc.hi[1] - acc.lo[1];
    q.small_box = root_below(bx * bx + by * by, rules.bbox_thr);
    // centred second moments (unnormalised)
    let cxx = (acc.sxx - acc.sx * mux).max(0.0);
    let cyy = (acc.syy - acc.sy * muy).max(0.0);
    let cxy = acc.sxy - acc.sx * muy;
    let mut lb = f64::INFINITY;
    // Σ w‖xᵢ − x̄‖⁴ from its terms, for Hölder's bound and the Kåsa residual.
    let fourth = fourth_about(acc, mux, muy);
    let fourth_sum: f64 = fourth.iter().sum();
    if rules.stat {
        let sse = cxx + cyy;
        q.sse_stat = sse;
        let b = if rules.squared {
            q.max_res_stat = far_corner(acc.lo, acc.hi, q.mx, q.my);
            sse
        } else {
            // Hölder: Σ‖r‖ ≥ (Σ‖r‖²)^{3/2} / (Σ‖r‖⁴)^{1/2}, with an upper
            // bound of Σ‖r‖⁴ (4th moments about the mean, plus rounding);
            // the steps: ‖rᵢ‖ + ‖rᵢ₊₁‖ ≥ aᵢ, each residual in two pairs.
            // (Since Σ‖r‖⁴ ≤ M²·Σ‖r‖² ≤ (Σ‖r‖²)² for the largest residual
            // M, Hölder's bound is at least `euclid_lb`'s √SSE and SSE / M.)
            // (An upper bound of Σ‖r‖⁴: the sum plus a margin for its rounding.)
            let r4 = fourth_sum + 1e-9 * fourth.iter().map(|t| t.abs()).sum::<f64>();
            let holder = if r4 > 0.0 && r4.is_finite() {
                sse * (sse / r4).sqrt()
            } else {
                euclid_lb(sse, far_corner(acc.lo, acc.hi, q.mx, q.my))
            };
            holder.max(0.5 * acc.sa)
        };
        q.stat_lb = b;
        lb = lb.min(b);
    }
    let (a, b) = (pts[acc.first], pts[acc.last]);
    let span2 = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]);
    q.reject_moving = root_below(span2, rules.span_thr) && !rules.only_moving;
    // line
    let tbar = acc.st / w;
    let vtt = acc.stt - acc.st * tbar;
    if acc.count >= 2 && vtt > 0.0 {
        let ivtt = 1.0 / vtt;
        q.vx = (acc.stx - acc.st * mux) * ivtt;
        q.vy = (acc.sty - acc.st * muy) * ivtt;
    }
    // The step-variation bound, shared by the line (Euclidean norm only) and
    // the circle.
    let speed = speed_lb(acc, rules.squared);
    q.lx = q.mx - q.vx * tbar;
    q.ly = q.my - q.vy * tbar;
    if rules.line && !q.reject_moving {
        let sse = (cxx - q.vx * q.vx * vtt).max(0.0) + (cyy - q.vy * q.vy * vtt).max(0.0);
        q.sse_line = sse;
        let b = if rules.squared {
            sse
        } else {
            // residual per axis over the (t, x) box: corners
            let tf = acc.first as f64 - acc.end as f64; // local times of the valid frames (≤ 0)
            let tl = acc.last as f64 - acc.end as f64;
            let ax = |lo: f64, hi: f64, m: f64, v: f64| {
                let mut best = 0.0f64;
                for x in [lo, hi] {
                    for t in [tf, tl] {
                        best = best.max((x - m - v * (t - tbar)).abs());
                    }
                }
                best
            };
            let rx = ax(acc.lo[0] - acc.rx, acc.hi[0] - acc.rx, mux, q.vx);
            let ry = ax(acc.lo[1] - acc.ry, acc.hi[1] - acc.ry, muy, q.vy);
            // a line moves ‖v‖ per frame: the step-variation bound
            euclid_lb2(sse, rx * rx + ry * ry).max(speed)
        };
        q.line_lb = b;
        lb = lb.min(b);
    }
    // circle
    if rules.circle && !q.reject_moving && acc.count >= 3 {
        let mut b = 0.0;
        let tr = cxx + cyy;
        let det = cxx * cyy - cxy * cxy;
        if tr > 0.0 && det > 1e-6 * tr * tr {
            // centred third moments (unnormalised)
            let (m1, m2) = (mux, muy);
            let cxxx = acc.sxxx - 3.0 * m1 * acc.sxx + 3.0 * m1 * m1 * acc.sx - w * m1 * m1 * m1;
            let cyyy = acc.syyy - 3.0 * m2 * acc.syy + 3.0 * m2 * m2 * acc.sy - w * m2 * m2 * m2;
            let cxxy = acc.sxxy - 2.0 * m1 * acc.sxy - m2 * acc.sxx
                + m1 * m1 * acc.sy
                + 2.0 * m1 * m2 * acc.sx
                - w * m1 * m1 * m2;
            let cxyy = acc.sxyy - 2.0 * m2 * acc.sxy - m1 * acc.syy
                + m2 * m2 * acc.sx
                + 2.0 * m1 * m2 * acc.sy
                - w * m1 * m2 * m2;
            let b1 = 0.5 * (cxxx + cxyy);
            let b2 = 0.5 * (cyyy + cxxy);
            let idet = 1.0 / det;
            let uc = (b1 * cyy - b2 * cxy) * idet;
            let vc = (cxx * b2 - cxy * b1) * idet;
            let trw = tr * iw;
            let r = (uc * uc + vc * vc + trw).sqrt();
            if uc.is_finite() && vc.is_finite() && r.is_finite() && r > 0.0 {
                q.circle_ok = true;
                q.cx = q.mx + uc;
                q.cy = q.my + vc;
                q.r = r;
                let scale = trw.sqrt() + r;
                q.circle_slack = 1e-7 * scale;
                q.pen_lb = penalty_lb(fit, r);
                // Kåsa residual K = Σz_c² − 2 a·Σ z_c p_c − W m², m = tr / W
                // Σ z_c² with z_c = z − 2μ·p + |μ|²
                let szc2 = fourth_sum;
                let szcx = cxxx + cxyy;
                let szcy = cxxy + cyyy;
                let k = szc2 - 2.0 * (uc * szcx + vc * szcy) - tr * trw;
                let k = k - 1e-9 * szc2.abs();
                let dmax2 = far_corner2(acc.lo, acc.hi, q.cx, q.cy);
                let dmax = dmax2.sqrt();
                if k > 0.0 && dmax.is_finite() {
                    let d = dmax + r;
                    b = if rules.squared {
                        k / (d * d)
                    } else {
                        // The larger of √K / D and K / (A·D): the second
                        // iff K ≥ A².
                        let dmin2 = near_box2(acc.lo, acc.hi, q.cx, q.cy);
                        let amax = (dmax2 - r * r).max(r * r - dmin2);
                        if amax > 0.0 && k >= amax * amax {
                            k / (amax * d)
                        } else {
                            k.sqrt() / d
                        }
                    };
                    b = (b - w * q.circle_slack).max(0.0);
                }
            }
        }
        b = b.max(speed) + q.pen_lb;
        q.circle_lb = b * LB_SAFETY;
        lb = lb.min(b);
    }
    q.lb = if lb.is_finite() { lb * LB_SAFETY } else { 0.0 };
    q
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;
    use crate::search::testutil::{acc_of, moved, steps_of, track};
    use mp_geom::Validate;
    use mp_geom::{fit_best_checked, fit_kind};
    use mp_geom::{Primitive, PrimitiveKind};
    use ndarray::Array2;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The rules' comparisons without square roots give the answers of the
    /// square roots, at and around the threshold, for NaN, ±0, negative
    /// values and infinity;
    /// and `euclid_lb2` is `euclid_lb` of the square root.
    #[test]
    fn squared_comparisons_agree_with_square_roots() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut cases = 0;
        for thr in [
            5.0,
            0.005,
            1.0 / 3.0,
            7e3,
            0.0,
            f64::INFINITY,
            -5.0,
            f64::NAN,
        ] {
            let t2 = thr * thr;
            let mut sqs = vec![
                0.0,
                -0.0,
                -1.0,
                t2,
                f64::NAN,
                f64::INFINITY,
                f64::MIN_POSITIVE,
            ];
            // The neighbours of thr² and of every float whose root is thr.
            let mut v = t2;
            for _ in 0..64 {
                v = v.next_down();
                sqs.push(v);
            }
            let mut v = t2;
            for _ in 0..64 {
                v = v.next_up();
                sqs.push(v);
            }
            for _ in 0..10_000 {
                sqs.push(t2 * rng.random_range(0.5..1.5));
            }
            for sq in sqs {
                assert_eq!(root_below(sq, thr), sq.sqrt() < thr, "√{sq} < {thr}");
                cases += 1;
            }
        }
        for _ in 0..10_000 {
            let sse = rng.random_range(0.0..100.0f64);
            let m2 = sse * rng.random_range(0.0..2.0f64);
            let (a, b) = (euclid_lb2(sse, m2), euclid_lb(sse, m2.sqrt()));
            assert!(
                (a - b).abs() <= 4.0 * f64::EPSILON * b,
                "{sse} {m2}: {a} vs {b}"
            );
        }
        assert!(cases > 60_000);
    }

    /// Every O(1) bound is below the error it bounds — the joint's cost
    /// under the selection rules, and each kind's own error (the circle's
    /// with its radius penalty) — on tracks in pixels, far from the origin,
    /// in metres and spread wide, with missing frames (up to rounding, see
    /// below).
    #[test]
    fn bounds_are_below_the_exact_errors() {
        let fit = FitParams::default().check().unwrap();
        let rules = Rules::new(&fit);
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let (mut checked, mut circles) = (0, 0);
        for (scale, offset) in [(1.0, 0.0), (1.0, 1e5), (1e-3, 0.0), (40.0, -3e4)] {
            for _ in 0..4 {
                let t = 100;
                let (mut pts, wts) = track(&mut rng, t);
                moved(&mut pts, &wts, scale, offset);
                let steps = steps_of(&pts, &wts);
                let arr = Array2::from_shape_fn((t, 2), |(i, a)| pts[i][a]);
                for n in 2..=t {
                    for k in n.saturating_sub(50)..n - 1 {
                        let acc = acc_of(&pts, &wts, &steps, k, n);
                        if acc.count == 0 {
                            continue;
                        }
                        let q = quick(&acc, &pts, &rules, &fit);
                        let seg = arr.slice(ndarray::s![k..n, ..]);
                        let w = Some(&wts[k..n]);
                        // (Up to rounding: a square root of a rounded sum of
                        // squares, √SSE, is off by up to √(ε·Σx²), 10⁻⁴ px here.)
                        let below = |lb: f64, e: f64| lb <= e * (1.0 + 1e-9) + 1e-4 * scale;
                        let cost = fit_best_checked(seg, w, &fit).unwrap().error;
                        assert!(below(q.lb, cost), "joint {k}..{n}: {} > {cost}", q.lb);
                        let kind = |kd| fit_kind(kd, seg, w, &fit).ok();
                        let e = kind(PrimitiveKind::Stationary).unwrap().error;
                        assert!(below(q.stat_lb * LB_SAFETY, e), "stationary {k}..{n}");
                        if q.reject_moving {
                            checked += 1;
                            continue;
                        }
                        if let Some(f) = kind(PrimitiveKind::Line) {
                            assert!(
                                below(q.line_lb * LB_SAFETY, f.error),
                                "line {k}..{n}: {} > {}",
                                q.line_lb,
                                f.error
                            );
                        }
                        if acc.count >= 3 {
                            if let Some(f) = kind(PrimitiveKind::Circle) {
                                let Primitive::Circle { radius, .. } = f.primitive else {
                                    panic!("not a circle");
                                };
                                let e = f.error + fit.circle_penalty(radius);
                                assert!(
                                    below(q.circle_lb, e),
                                    "circle {k}..{n}: {} > {e}",
                                    q.circle_lb
                                );
                                circles += 1;
                            }
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 50_000 && circles > 30_000, "{checked} {circles}");
    }
}
