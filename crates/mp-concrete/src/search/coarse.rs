//! A single-precision pass before the exact one (Euclidean norm, 2D joints):
//! lower bounds of the one-pass errors of [`super::exact::cheap2`] at a
//! fraction of the price, so that most candidates that survive the O(1)
//! bounds are dropped without a double-precision pass.
//!
//! Each joint's points are kept once more in `f32`, relative to the centre
//! of the joint's bounding box, as separate arrays of x, y, weights and step
//! lengths (lanes the compiler turns into vector instructions). For a
//! candidate the pass sums, like `cheap2`, the distances to the stationary
//! point, to the line and to the moments' circle, and the step-length
//! deviation `Σ|aᵢ − ā|`, in `f32` with eight partial sums. Each sum is then
//! lowered by a bound of its rounding error, so it is below the exact value:
//!
//! * every term is within `2⁻¹⁹·B` of its exact value (`B`: the largest
//!   relative coordinate of the joint plus the model's reach over the
//!   segment; the rounding of the inputs, the differences, the squares and
//!   the square root add up to less than `12·2⁻²⁴·B`);
//! * the sums are within `(L + 64)·2⁻²³` of the sum of their terms, relative
//!   (each lane adds at most `L/8 + 1` terms);
//! * a sum that overflows `f32` (the distance to a nearly straight arc's huge
//!   circle can, even in pixels) bounds nothing and counts as 0.
//!
//! The joint's bound is the smallest over the kinds that take part, with the
//! stationary point alone where its bounding box decides it (the rule that
//! needs only the moments): the rule on the mean residual is not decided
//! here, and either way the joint's cost is at least that smallest bound.

use super::bounds::Quick;
use super::exact::circle_bound;
use super::moments::Acc2;
use super::{Rules, Stage};

/// Lanes of the partial sums.
const LANES: usize = 8;
/// Bound of one term's rounding error, relative to `B` (see the module docs).
const TERM_ERR: f64 = 1.0 / (1u64 << 19) as f64;
/// Summation error per frame, relative to the sum.
const SUM_ERR: f64 = 1.0 / (1u64 << 23) as f64;

/// One joint's points in single precision (see the module docs).
pub(super) struct Coarse {
    xs: Vec<f32>,
    ys: Vec<f32>,
    ws: Vec<f32>,
    /// Step length to the next frame (`−1` where either frame is missing).
    ss: Vec<f32>,
    ox: f64,
    oy: f64,
    /// Largest absolute relative coordinate of a valid frame.
    amax: f64,
}

impl Coarse {
    /// `pts` with missing frames at any position (their weight is 0),
    /// `steps` as in the search (`−1` where a frame is missing).
    pub(super) fn new(pts: &[[f64; 2]], wts: &[f64], steps: &[f64]) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for (p, &w) in pts.iter().zip(wts) {
            if w > 0.0 {
                for a in 0..2 {
                    lo[a] = lo[a].min(p[a]);
                    hi[a] = hi[a].max(p[a]);
                }
            }
        }
        let (ox, oy) = if lo[0].is_finite() {
            (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]))
        } else {
            (0.0, 0.0)
        };
        let mut amax = 0.0f64;
        let (mut xs, mut ys) = (Vec::with_capacity(pts.len()), Vec::with_capacity(pts.len()));
        for (p, &w) in pts.iter().zip(wts) {
            let (x, y) = if w > 0.0 {
                (p[0] - ox, p[1] - oy)
            } else {
                (0.0, 0.0)
            };
            amax = amax.max(x.abs()).max(y.abs());
            xs.push(x as f32);
            ys.push(y as f32);
        }
        Coarse {
            xs,
            ys,
            ws: wts.iter().map(|&w| w as f32).collect(),
            ss: steps.iter().map(|&s| s as f32).collect(),
            ox,
            oy,
            amax,
        }
    }
}

/// The models of one candidate, relative to the joint's origin, in `f32`.
struct Models {
    mx: f32,
    my: f32,
    lx: f32,
    ly: f32,
    vx: f32,
    vy: f32,
    cx: f32,
    cy: f32,
    r: f32,
    abar: f32,
    /// Local time of frame `first` (`first − (n − 1)`, exact).
    tau_first: f32,
}

/// Partial sums: stationary, line, circle distance, step deviation.
type Sums = [[f32; LANES]; 4];

#[inline(always)]
fn frame(m: &Models, x: f32, y: f32, w: f32, tau: f32) -> [f32; 3] {
    let (dx, dy) = (m.mx - x, m.my - y);
    let es = w * (dx * dx + dy * dy).sqrt();
    let (ex, ey) = (m.lx + m.vx * tau - x, m.ly + m.vy * tau - y);
    let el = w * (ex * ex + ey * ey).sqrt();
    let (cx, cy) = (x - m.cx, y - m.cy);
    let ec = w * ((cx * cx + cy * cy).sqrt() - m.r).abs();
    [es, el, ec]
}

#[inline(always)]
fn step_dev(m: &Models, a: f32) -> f32 {
    if a >= 0.0 {
        (a - m.abar).abs()
    } else {
        0.0
    }
}

/// Sums over frames `first..last` (the step of each frame to the next
/// included) in `LANES` lanes.
fn sums(c: &Coarse, m: &Models, first: usize, last: usize) -> Sums {
    let mut s: Sums = [[0.0; LANES]; 4];
    let (xs, ys, ws, ss) = (
        &c.xs[first..last],
        &c.ys[first..last],
        &c.ws[first..last],
        &c.ss[first..last],
    );
    let chunks = xs.len() / LANES;
    for ch in 0..chunks {
        let o = ch * LANES;
        let (x, y, w, a) = (
            &xs[o..o + LANES],
            &ys[o..o + LANES],
            &ws[o..o + LANES],
            &ss[o..o + LANES],
        );
        let base = m.tau_first + o as f32;
        for l in 0..LANES {
            let [es, el, ec] = frame(m, x[l], y[l], w[l], base + l as f32);
            s[0][l] += es;
            s[1][l] += el;
            s[2][l] += ec;
            s[3][l] += step_dev(m, a[l]);
        }
    }
    for i in chunks * LANES..xs.len() {
        let l = i % LANES;
        let [es, el, ec] = frame(m, xs[i], ys[i], ws[i], m.tau_first + i as f32);
        s[0][l] += es;
        s[1][l] += el;
        s[2][l] += ec;
        s[3][l] += step_dev(m, ss[i]);
    }
    s
}

/// Lower bounds of the one-pass errors of the joint on the candidate
/// (`[stationary, line, circle distance]`, Euclidean, `NaN` for the
/// circle's where the moments' circle is not usable), and the joint's
/// [`Stage`] with every value a lower bound: `Done` with the smallest bound
/// over the kinds (see the module docs), or `Circle` with the circle's bound
/// and the smallest bound of the other kinds. `q` must be this candidate's
/// O(1) facts.
pub(super) fn coarse_stage(c: &Coarse, q: &Quick, acc: &Acc2, rules: &Rules) -> (Stage, [f64; 3]) {
    let (first, last) = (acc.first, acc.last);
    let abar = if acc.npairs > 0 {
        acc.sa / acc.npairs as f64
    } else {
        0.0
    };
    let m = Models {
        mx: (q.mx - c.ox) as f32,
        my: (q.my - c.oy) as f32,
        lx: (q.lx - c.ox) as f32,
        ly: (q.ly - c.oy) as f32,
        vx: q.vx as f32,
        vy: q.vy as f32,
        cx: if q.circle_ok {
            (q.cx - c.ox) as f32
        } else {
            0.0
        },
        cy: if q.circle_ok {
            (q.cy - c.oy) as f32
        } else {
            0.0
        },
        r: if q.circle_ok { q.r as f32 } else { 0.0 },
        abar: abar as f32,
        tau_first: (first as f64 - acc.end as f64) as f32,
    };
    let mut s = sums(c, &m, first, last);
    // The last valid frame, without its step to the next (outside the segment).
    let [es, el, ec] = frame(
        &m,
        c.xs[last],
        c.ys[last],
        c.ws[last],
        m.tau_first + (last - first) as f32,
    );
    s[0][0] += es;
    s[1][0] += el;
    s[2][0] += ec;
    let total = |k: usize| s[k].iter().map(|&v| v as f64).sum::<f64>();
    let len = (last + 1 - first) as f64;
    let rel = 1.0 - (len + 64.0) * SUM_ERR;
    let span = (acc.end - first) as f64;
    let reach = |mag: f64| len * TERM_ERR * (c.amax + mag);
    // (0 where the sum overflowed `f32`: a bound still, if a useless one.)
    let lower = |v: f64, err: f64| {
        if v.is_finite() {
            (v * rel - err).max(0.0)
        } else {
            0.0
        }
    };
    let mx = (q.mx - c.ox).abs().max((q.my - c.oy).abs());
    let ml = (q.lx - c.ox).abs().max((q.ly - c.oy).abs()) + q.vx.abs().max(q.vy.abs()) * span;
    let es = lower(total(0), reach(mx));
    let el = lower(total(1), reach(ml));
    let ec = if q.circle_ok {
        let mc = (q.cx - c.ox).abs().max((q.cy - c.oy).abs()) + q.r.abs();
        lower(total(2), reach(mc))
    } else {
        f64::NAN
    };
    let dev = lower(total(3), len * TERM_ERR * (acc.amax.max(0.0) + abar));
    let errors = [es, el, ec];
    if rules.stat && q.small_box {
        return (Stage::Done(Some(es)), errors);
    }
    let mut best = f64::INFINITY;
    if rules.stat {
        best = es;
    }
    if rules.line && !q.reject_moving {
        best = best.min(el);
    }
    let circle = rules.circle && !q.reject_moving && acc.count >= 3;
    let stage = match circle.then(|| circle_bound(q, acc, rules, ec, f64::NAN, dev)) {
        Some(lb) if lb < best => Stage::Circle { lb, best },
        _ => Stage::Done(best.is_finite().then_some(best)),
    };
    (stage, errors)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;
    use crate::search::bounds::quick;
    use crate::search::exact::cheap2;
    use crate::search::testutil::{acc_of, moved, steps_of, track};
    use mp_geom::Validate;
    use mp_geom::{fit_best_checked, FitParams};
    use ndarray::Array2;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// The single-precision errors are below the exact one-pass errors and
    /// within 1e-4 of them plus 0.01 px per frame (the tracks span about 400
    /// px) unless their squares overflow `f32`, and the stage's bound is below the joint's exact
    /// cost, on noisy, gappy tracks of arcs and pauses in pixels, far from
    /// the origin, in metres, spread over 10⁴ pixels and so large that their
    /// squares overflow `f32`.
    #[test]
    fn single_precision_bounds_are_below_the_exact_errors() {
        let fit = FitParams::default().check().unwrap();
        let rules = Rules::new(&fit);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut checked = 0;
        for (scale, offset) in [
            (1.0, 0.0),
            (1.0, 1e5),
            (1e-3, 0.0),
            (40.0, -3e4),
            (1e18, 0.0),
        ] {
            for _ in 0..6 {
                let t = 120;
                let (mut pts, wts) = track(&mut rng, t);
                moved(&mut pts, &wts, scale, offset);
                let steps = steps_of(&pts, &wts);
                let c = Coarse::new(&pts, &wts, &steps);
                let arr = Array2::from_shape_fn((t, 2), |(i, a)| pts[i][a]);
                for n in 2..=t {
                    for k in n.saturating_sub(60)..n - 1 {
                        let acc = acc_of(&pts, &wts, &steps, k, n);
                        if acc.count == 0 {
                            continue;
                        }
                        let q = quick(&acc, &pts, &rules, &fit);
                        let exact = cheap2(&q, &acc, &pts, &steps, &wts, &rules).errors;
                        let (stage, lower) = coarse_stage(&c, &q, &acc, &rules);
                        for (kind, (&lo, &ex)) in lower.iter().zip(&exact).enumerate() {
                            if !ex.is_finite() {
                                continue;
                            }
                            let len = acc.count as f64;
                            assert!(
                                lo <= ex * (1.0 + 1e-12),
                                "kind {kind} {k}..{n}: {lo} > {ex}"
                            );
                            // (Where the squares overflow, the bound is 0.)
                            let overflow = scale > 1e10;
                            assert!(
                                overflow || lo >= ex * (1.0 - 1e-4) - 1e-2 * scale * len,
                                "kind {kind} {k}..{n}: {lo} far below {ex} (scale {scale})"
                            );
                        }
                        let cost = fit_best_checked(
                            arr.slice(ndarray::s![k..n, ..]),
                            Some(&wts[k..n]),
                            &fit,
                        )
                        .unwrap()
                        .error;
                        let lb = match stage {
                            Stage::Done(v) => v.unwrap_or(f64::INFINITY),
                            Stage::Circle { lb, best } => lb.min(best),
                        };
                        assert!(lb <= cost * (1.0 + 1e-9), "joint {k}..{n}: {lb} > {cost}");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100_000, "{checked}");
    }
}
