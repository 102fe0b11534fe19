//! Exact segmentation without a cost table: branch and bound over the DP of
//! [`crate::dp`], with segment moments updated in O(1) per candidate.
//!
//! For every end frame `n` the candidate starts `k = n − 1, n − 2, …, n − W`
//! are visited from the shortest segment to the longest, so that a good
//! incumbent `E[n]` is found early. Each joint keeps running moments of its
//! valid points over `k..n` (count, Σt, Σt², Σx, Σtx, Σx², third and fourth
//! order in x and y, bounding box, first and last valid frame), with time and
//! coordinates relative to frame `n − 1`, so adding frame `k` costs O(D) and
//! the sums stay local (no cancellation between large prefix sums).
//!
//! From the moments, in O(1) per joint:
//!
//! * the least-squares stationary point and line and their **squared**
//!   errors, exact;
//! * the Bullock (algebraic, Kåsa) circle and its algebraic residual
//!   `K = Σ w (‖x − c‖² − r²)²` (moments up to 4th order), and its radius
//!   penalty;
//! * lower bounds of the Euclidean errors: `Σ w‖rᵢ‖ ≥ max(√SSE, SSE / M)`
//!   where `M` bounds the largest residual (bounding box corners against the
//!   fitted point or line), and for the circle
//!   `Σ w |dᵢ − r| ≥ K / (A·(d_max + r))` with `A ≥ max |dᵢ² − r²|`.
//!
//! A joint's cost is the error of the kind chosen by the selection rules of
//! [`mp_geom::fit`], which is at least the smallest error over the kinds
//! considered; so `E[k] + λ + Σ_j lb_j > E[n]` proves that `k` cannot improve
//! `E[n]`. Candidates that survive get their stationary and line errors
//! exactly (one pass over the segment, square roots only) and a second bound
//! for the circle (`Σ w |dᵢ − r|` + penalty: a point of the circle is at least
//! `|‖x − c‖ − r|` from `x`); the circle itself (angles, `atan2`) is fitted
//! only when that bound is below the best of stationary and line, and the
//! candidate is dropped as soon as its exact partial sum plus the remaining
//! bounds exceeds the incumbent. The costs are those of
//! [`mp_geom::fit::fit_best`] (same fits, same rules) up to rounding, so the
//! optimum is the optimum of the exhaustive DP ([`crate::synth::segment_exhaustive`]).
//!
//! Joints in 3D, or with the spline kind allowed, use [`fit_best_unchecked`]
//! for their exact cost (still with the bounds of the other joints and the
//! early exit).
//!
//! Memory: `O(T·J·D)` for the points and `O(T)` for the DP; no `T × W` table.

use mp_geom::fit::{fit_best_unchecked, ErrorNorm, FitParams};
use mp_geom::PrimitiveKind;
use ndarray::{s, Array2};

use crate::dp::Segmentation;
use crate::error::{ConcreteError, Result};

/// Relative safety factor applied to every lower bound (rounding).
const LB_SAFETY: f64 = 1.0 - 1e-9;

/// One joint's trajectory, prepared for the search.
pub(crate) struct JointTrack<'a> {
    /// `T × D` gap-filled points.
    pub points: &'a Array2<f64>,
    /// Weight per frame (1 observed, 0 missing).
    pub weights: &'a [f64],
}

/// What the selection rules need, at the track's scale.
#[derive(Clone, Copy)]
struct Rules {
    stat: bool,
    line: bool,
    circle: bool,
    only_moving: bool,
    bbox_thr: f64,
    mean_res_thr: f64,
    span_thr: f64,
    squared: bool,
    quadratic: bool,
}

impl Rules {
    fn new(fit: &FitParams) -> Self {
        let s = fit.unit_scale;
        let has = |k| fit.kinds.contains(&k);
        Rules {
            stat: has(PrimitiveKind::Stationary),
            line: has(PrimitiveKind::Line),
            circle: has(PrimitiveKind::Circle),
            only_moving: fit
                .kinds
                .iter()
                .all(|k| matches!(k, PrimitiveKind::Line | PrimitiveKind::Circle)),
            bbox_thr: fit.stationary_bbox_px * s,
            mean_res_thr: fit.stationary_mean_residual_px * s,
            span_thr: fit.min_span_px * s,
            squared: fit.norm == ErrorNorm::Squared,
            quadratic: fit.quadratic_angle,
        }
    }
}

/// Running moments of one 2D joint over `k..n`, relative to `(t, x) = (n − 1, ref)`.
#[derive(Clone, Copy, Default)]
struct Acc2 {
    rx: f64,
    ry: f64,
    count: usize,
    sw: f64,
    st: f64,
    stt: f64,
    sx: f64,
    sy: f64,
    stx: f64,
    sty: f64,
    sxx: f64,
    sxy: f64,
    syy: f64,
    sxxx: f64,
    sxxy: f64,
    sxyy: f64,
    syyy: f64,
    szz: f64,
    lo: [f64; 2],
    hi: [f64; 2],
    /// Smallest and largest valid frame (absolute).
    first: usize,
    last: usize,
    /// Frame of local time 0 (`n − 1`).
    end: usize,
    /// Step lengths `aᵢ = ‖xᵢ₊₁ − xᵢ‖` of consecutive valid frames: count, Σa, Σa², range.
    npairs: usize,
    sa: f64,
    saa: f64,
    amin: f64,
    amax: f64,
}

impl Acc2 {
    fn reset(&mut self, end: usize, rx: f64, ry: f64) {
        *self = Acc2 {
            rx,
            ry,
            end,
            lo: [f64::INFINITY; 2],
            hi: [f64::NEG_INFINITY; 2],
            amin: f64::INFINITY,
            amax: f64::NEG_INFINITY,
            ..Acc2::default()
        };
    }

    #[inline(always)]
    fn add(&mut self, i: usize, tau: f64, px: f64, py: f64, step: f64) {
        if step >= 0.0 && i < self.end {
            self.npairs += 1;
            self.sa += step;
            self.saa += step * step;
            self.amin = self.amin.min(step);
            self.amax = self.amax.max(step);
        }
        let (x, y) = (px - self.rx, py - self.ry);
        let (xx, yy, xy) = (x * x, y * y, x * y);
        let z = xx + yy;
        if self.count == 0 {
            self.last = i;
        }
        self.first = i;
        self.count += 1;
        self.sw += 1.0;
        self.st += tau;
        self.stt += tau * tau;
        self.sx += x;
        self.sy += y;
        self.stx += tau * x;
        self.sty += tau * y;
        self.sxx += xx;
        self.sxy += xy;
        self.syy += yy;
        self.sxxx += xx * x;
        self.sxxy += xx * y;
        self.sxyy += x * yy;
        self.syyy += yy * y;
        self.szz += z * z;
        self.lo[0] = self.lo[0].min(px);
        self.lo[1] = self.lo[1].min(py);
        self.hi[0] = self.hi[0].max(px);
        self.hi[1] = self.hi[1].max(py);
    }
}

/// O(1) facts about one joint on one candidate segment.
#[derive(Clone, Copy, Default)]
struct Quick {
    /// Lower bound of the joint's cost.
    lb: f64,
    /// Mean (absolute coordinates).
    mx: f64,
    my: f64,
    /// Line: value at the segment's local time 0 (frame `n − 1`) and velocity.
    lx: f64,
    ly: f64,
    vx: f64,
    vy: f64,
    /// Bounding-box diagonal.
    bbox: f64,
    /// Moving kinds rejected by the span rule.
    reject_moving: bool,
    /// Circle from the moments is usable for bounds (well conditioned).
    circle_ok: bool,
    cx: f64,
    cy: f64,
    r: f64,
    /// Lower bound of the circle's radius penalty.
    pen_lb: f64,
    /// Slack for the circle distance bound (rounding of the centre).
    circle_slack: f64,
    /// Squared errors of the stationary and line fits.
    sse_stat: f64,
    sse_line: f64,
    /// Bound on the largest stationary residual.
    max_res_stat: f64,
    /// O(1) lower bound of the circle's error with penalty.
    circle_lb: f64,
}

fn penalty_lb(fit: &FitParams, r: f64) -> f64 {
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
fn speed_lb(acc: &Acc2, squared: bool) -> f64 {
    if acc.npairs < 2 {
        return 0.0;
    }
    let var = (acc.saa - acc.sa * acc.sa / acc.npairs as f64).max(0.0);
    let var = var - 1e-12 * acc.saa;
    if var <= 0.0 {
        return 0.0;
    }
    if squared {
        0.25 * var
    } else {
        let range = acc.amax - acc.amin;
        if range > 0.0 {
            0.25 * var / range
        } else {
            0.0
        }
    }
}

/// Largest distance from `(px, py)` to a corner of the box.
fn far_corner(lo: [f64; 2], hi: [f64; 2], px: f64, py: f64) -> f64 {
    let dx = (px - lo[0]).abs().max((hi[0] - px).abs());
    let dy = (py - lo[1]).abs().max((hi[1] - py).abs());
    (dx * dx + dy * dy).sqrt()
}

/// Smallest distance from `(px, py)` to the box (0 inside).
fn near_box(lo: [f64; 2], hi: [f64; 2], px: f64, py: f64) -> f64 {
    let dx = (lo[0] - px).max(0.0).max(px - hi[0]);
    let dy = (lo[1] - py).max(0.0).max(py - hi[1]);
    (dx * dx + dy * dy).sqrt()
}

/// Euclidean lower bound from a squared error and a bound on the largest residual.
fn euclid_lb(sse: f64, max_res: f64) -> f64 {
    let sse = sse.max(0.0);
    let a = sse.sqrt();
    if max_res > 0.0 && max_res.is_finite() {
        a.max(sse / max_res)
    } else {
        a
    }
}

fn quick(acc: &Acc2, pts: &[[f64; 2]], rules: &Rules, fit: &FitParams) -> Quick {
    let w = acc.sw;
    let mut q = Quick::default();
    let (mux, muy) = (acc.sx / w, acc.sy / w);
    q.mx = mux + acc.rx;
    q.my = muy + acc.ry;
    let bx = acc.hi[0] - acc.lo[0];
    let by = acc.hi[1] - acc.lo[1];
    q.bbox = (bx * bx + by * by).sqrt();
    // centred second moments (unnormalised)
    let cxx = (acc.sxx - acc.sx * mux).max(0.0);
    let cyy = (acc.syy - acc.sy * muy).max(0.0);
    let cxy = acc.sxy - acc.sx * muy;
    let mut lb = f64::INFINITY;
    if rules.stat {
        let sse = cxx + cyy;
        q.sse_stat = sse;
        q.max_res_stat = far_corner(acc.lo, acc.hi, q.mx, q.my);
        let b = if rules.squared {
            sse
        } else {
            euclid_lb(sse, q.max_res_stat)
        };
        lb = lb.min(b);
    }
    let (a, b) = (pts[acc.first], pts[acc.last]);
    let span = ((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])).sqrt();
    q.reject_moving = span < rules.span_thr && !rules.only_moving;
    // line
    let tbar = acc.st / w;
    let vtt = acc.stt - acc.st * tbar;
    if acc.count >= 2 && vtt > 0.0 {
        q.vx = (acc.stx - acc.st * mux) / vtt;
        q.vy = (acc.sty - acc.st * muy) / vtt;
    }
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
            euclid_lb(sse, (rx * rx + ry * ry).sqrt())
        };
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
            let uc = (b1 * cyy - b2 * cxy) / det;
            let vc = (cxx * b2 - cxy * b1) / det;
            let r = (uc * uc + vc * vc + tr / w).sqrt();
            if uc.is_finite() && vc.is_finite() && r.is_finite() && r > 0.0 {
                q.circle_ok = true;
                q.cx = q.mx + uc;
                q.cy = q.my + vc;
                q.r = r;
                let scale = (tr / w).sqrt() + r;
                q.circle_slack = 1e-7 * scale;
                q.pen_lb = penalty_lb(fit, r);
                // Kåsa residual K = Σz_c² − 2 a·Σ z_c p_c − W m², m = tr / W
                let mu2 = m1 * m1 + m2 * m2;
                let sz = acc.sxx + acc.syy;
                let szx = acc.sxxx + acc.sxyy;
                let szy = acc.sxxy + acc.syyy;
                // Σ z_c² with z_c = z − 2μ·p + |μ|²
                let smp2 = m1 * m1 * acc.sxx + 2.0 * m1 * m2 * acc.sxy + m2 * m2 * acc.syy;
                let smp = m1 * acc.sx + m2 * acc.sy;
                let szc2 = acc.szz - 4.0 * (m1 * szx + m2 * szy) + 2.0 * mu2 * sz + 4.0 * smp2
                    - 4.0 * mu2 * smp
                    + mu2 * mu2 * w;
                let szcx = cxxx + cxyy;
                let szcy = cxxy + cyyy;
                let k = szc2 - 2.0 * (uc * szcx + vc * szcy) - tr * tr / w;
                let k = k - 1e-9 * szc2.abs();
                let dmax = far_corner(acc.lo, acc.hi, q.cx, q.cy);
                let dmin = near_box(acc.lo, acc.hi, q.cx, q.cy);
                if k > 0.0 && dmax.is_finite() {
                    b = if rules.squared {
                        k / ((dmax + r) * (dmax + r))
                    } else {
                        let amax = (dmax * dmax - r * r).max(r * r - dmin * dmin);
                        let e1 = k.sqrt() / (dmax + r);
                        let e2 = if amax > 0.0 {
                            k / (amax * (dmax + r))
                        } else {
                            0.0
                        };
                        e1.max(e2)
                    };
                    b = (b - w * q.circle_slack).max(0.0);
                }
            }
        }
        b = b.max(speed_lb(acc, rules.squared)) + q.pen_lb;
        q.circle_lb = b * LB_SAFETY;
        lb = lb.min(b);
    }
    q.lb = if lb.is_finite() { lb * LB_SAFETY } else { 0.0 };
    q
}

/// Exact stationary and line errors of one 2D joint and a bound for its circle.
#[derive(Clone, Copy, Default)]
struct Cheap {
    /// The joint's cost when already decided (stationary wins outright).
    decided: Option<f64>,
    /// Best of the stationary and line errors that take part (`+∞` if none).
    best: f64,
    /// Lower bound of the circle's error with penalty, when a circle takes part.
    circle_lb: Option<f64>,
}

impl Cheap {
    /// Lower bound of the joint's cost.
    fn lb(&self) -> f64 {
        match (self.decided, self.circle_lb) {
            (Some(c), _) => c,
            (None, Some(c)) if c < self.best => c,
            (None, _) => self.best,
        }
    }
    /// Whether the exact circle is needed.
    fn needs_circle(&self) -> bool {
        self.decided.is_none() && self.circle_lb.is_some_and(|c| c < self.best)
    }
}

fn cheap2(
    q: &Quick,
    acc: &Acc2,
    pts: &[[f64; 2]],
    steps: &[f64],
    wts: &[f64],
    rules: &Rules,
) -> Cheap {
    let want_circle = rules.circle && !q.reject_moving && acc.count >= 3;
    let want_line = rules.line && !q.reject_moving;
    if rules.squared {
        // Squared errors from the moments; the Euclidean mean residual of the
        // stationary rule from bounds when they decide it.
        let w = acc.sw;
        let stat_rule = rules.stat
            && (q.bbox < rules.bbox_thr || {
                let hi = (q.sse_stat.max(0.0) / w).sqrt(); // ≥ mean residual (Jensen)
                let lo = euclid_lb(q.sse_stat, q.max_res_stat) * LB_SAFETY / w;
                if hi * (1.0 + 1e-9) < rules.mean_res_thr {
                    true
                } else if lo >= rules.mean_res_thr {
                    false
                } else {
                    let mut es = 0.0;
                    for i in acc.first..=acc.last {
                        let (dx, dy) = (q.mx - pts[i][0], q.my - pts[i][1]);
                        es += wts[i] * (dx * dx + dy * dy).sqrt();
                    }
                    es / w < rules.mean_res_thr
                }
            });
        if stat_rule {
            return Cheap {
                decided: Some(q.sse_stat),
                best: q.sse_stat,
                circle_lb: None,
            };
        }
        let mut best = f64::INFINITY;
        if rules.stat {
            best = q.sse_stat;
        }
        if want_line {
            best = best.min(q.sse_line);
        }
        return Cheap {
            decided: None,
            best,
            circle_lb: want_circle.then_some(q.circle_lb),
        };
    }
    if rules.stat && q.bbox < rules.bbox_thr {
        // Stationary wins outright: only its error is needed.
        let (mut e, mut e2) = (0.0, 0.0);
        for i in acc.first..=acc.last {
            let (dx, dy) = (q.mx - pts[i][0], q.my - pts[i][1]);
            let ds = dx * dx + dy * dy;
            e += wts[i] * ds.sqrt();
            e2 += wts[i] * ds;
        }
        let c = if rules.squared { e2 } else { e };
        return Cheap {
            decided: Some(c),
            best: c,
            circle_lb: None,
        };
    }
    // Two frames per step with separate sums (independent lanes the
    // compiler can pair into vector instructions).
    let t_end = acc.end as f64;
    #[inline(always)]
    fn frame(q: &Quick, p: [f64; 2], w: f64, tau: f64, s: &mut [f64; 6]) {
        let (dx, dy) = (q.mx - p[0], q.my - p[1]);
        let ds = dx * dx + dy * dy;
        s[0] += w * ds.sqrt();
        s[1] += w * ds;
        let (ex, ey) = (q.lx + q.vx * tau - p[0], q.ly + q.vy * tau - p[1]);
        let dl = ex * ex + ey * ey;
        s[2] += w * dl.sqrt();
        s[3] += w * dl;
        let (cx, cy) = (p[0] - q.cx, p[1] - q.cy);
        let dc = (cx * cx + cy * cy).sqrt() - q.r;
        s[4] += w * dc.abs();
        s[5] += w * dc * dc;
    }
    let (mut sa, mut sb) = ([0.0f64; 6], [0.0f64; 6]);
    let mut i = acc.first;
    let end = acc.last + 1;
    while i + 1 < end {
        frame(q, pts[i], wts[i], i as f64 - t_end, &mut sa);
        frame(q, pts[i + 1], wts[i + 1], (i + 1) as f64 - t_end, &mut sb);
        i += 2;
    }
    if i < end {
        frame(q, pts[i], wts[i], i as f64 - t_end, &mut sa);
    }
    let (es, es2, el, el2, ec, ec2) = (
        sa[0] + sb[0],
        sa[1] + sb[1],
        sa[2] + sb[2],
        sa[3] + sb[3],
        sa[4] + sb[4],
        sa[5] + sb[5],
    );
    let pick = |e: f64, e2: f64| if rules.squared { e2 } else { e };
    if rules.stat && (q.bbox < rules.bbox_thr || es / acc.sw < rules.mean_res_thr) {
        return Cheap {
            decided: Some(pick(es, es2)),
            best: pick(es, es2),
            circle_lb: None,
        };
    }
    let mut best = f64::INFINITY;
    if rules.stat {
        best = pick(es, es2);
    }
    if want_line {
        best = best.min(pick(el, el2));
    }
    let circle_lb = want_circle.then(|| {
        let speed = if acc.npairs >= 2 {
            let abar = acc.sa / acc.npairs as f64;
            let mut dev = 0.0;
            for &a in &steps[acc.first..acc.last] {
                if a >= 0.0 {
                    dev += (a - abar).abs();
                }
            }
            (0.25 * dev * (1.0 - 1e-9) - 1e-12 * acc.sa).max(0.0)
        } else {
            0.0
        };
        let speed = if rules.squared {
            speed_lb(acc, true)
        } else {
            speed
        };
        if q.circle_ok {
            let raw = if rules.squared {
                // Minkowski: ‖(|dᵢ − r|)‖₂ ≥ ‖(|d′ᵢ − r′|)‖₂ − √W·slack
                (ec2.sqrt() - acc.sw.sqrt() * q.circle_slack)
                    .max(0.0)
                    .powi(2)
            } else {
                (ec - acc.sw * q.circle_slack).max(0.0)
            };
            raw.max(speed) * LB_SAFETY + q.pen_lb
        } else {
            speed * LB_SAFETY
        }
    });
    Cheap {
        decided: None,
        best,
        circle_lb,
    }
}

/// The circle of [`mp_geom::fit::fit_circle`] (2D, linear angle) with its
/// error and radius penalty, computed without allocation: Bullock's centre,
/// unwrapped angles, the least-squares angle line, residuals by rotating the
/// fitted angle frame to frame. `None` when the points are collinear (the
/// circle takes no part, as in `fit_best`).
fn circle2(
    pts: &[[f64; 2]],
    wts: &[f64],
    first: usize,
    last: usize,
    rules: &Rules,
    fit: &FitParams,
) -> Option<f64> {
    let (mut w_sum, mut mx, mut my) = (0.0, 0.0, 0.0);
    for i in first..=last {
        let w = wts[i];
        if w == 0.0 {
            continue;
        }
        w_sum += w;
        mx += w * pts[i][0];
        my += w * pts[i][1];
    }
    mx /= w_sum;
    my /= w_sum;
    let (mut suu, mut suv, mut svv) = (0.0, 0.0, 0.0);
    let (mut suuu, mut suvv, mut svvv, mut svuu) = (0.0, 0.0, 0.0, 0.0);
    for i in first..=last {
        let w = wts[i];
        if w == 0.0 {
            continue;
        }
        let (u, v) = (pts[i][0] - mx, pts[i][1] - my);
        let (uu, vv) = (u * u, v * v);
        suu += w * uu;
        suv += w * u * v;
        svv += w * vv;
        suuu += w * uu * u;
        suvv += w * u * vv;
        svvv += w * vv * v;
        svuu += w * v * uu;
    }
    let inv = 1.0 / w_sum;
    let (suu, suv, svv) = (suu * inv, suv * inv, svv * inv);
    let b1 = 0.5 * (suuu + suvv) * inv;
    let b2 = 0.5 * (svvv + svuu) * inv;
    let det = suu * svv - suv * suv;
    let tr = suu + svv;
    if tr.is_nan() || tr <= 0.0 || det <= 1e-12 * tr * tr {
        return None;
    }
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (suu * b2 - suv * b1) / det;
    let r = (uc * uc + vc * vc + tr).sqrt();
    if !(uc.is_finite() && vc.is_finite() && r.is_finite() && r > 0.0) {
        return None;
    }
    let (cx, cy) = (mx + uc, my + vc);
    // unwrapped angles (degrees) against segment time, least-squares line
    let (mut st, mut sth, mut stt, mut stth) = (0.0, 0.0, 0.0, 0.0);
    let mut prev: Option<f64> = None;
    let t_ref = ((first + last) / 2) as f64;
    for i in first..=last {
        let w = wts[i];
        if w == 0.0 {
            continue;
        }
        let mut th = (pts[i][1] - cy).atan2(pts[i][0] - cx).to_degrees();
        if let Some(p) = prev {
            th += 360.0 * ((p - th) / 360.0).round();
        }
        prev = Some(th);
        let t = i as f64 - t_ref;
        st += w * t;
        sth += w * th;
        stt += w * t * t;
        stth += w * t * th;
    }
    let tbar = st / w_sum;
    let thbar = sth / w_sum;
    let vtt = stt - st * tbar;
    let vel = if vtt > 0.0 {
        (stth - st * thbar) / vtt
    } else {
        0.0
    };
    // angle at frame `first`: θ̄ + vel·(t_first − t̄)
    let th0 = (thbar + vel * (first as f64 - t_ref - tbar)).to_radians();
    let (mut sn, mut cs) = th0.sin_cos();
    let (ds, dc) = vel.to_radians().sin_cos();
    let (mut e, mut e2) = (0.0, 0.0);
    for i in first..=last {
        let w = wts[i];
        if w > 0.0 {
            let ex = cx + r * cs - pts[i][0];
            let ey = cy + r * sn - pts[i][1];
            let d2 = ex * ex + ey * ey;
            e += w * d2.sqrt();
            e2 += w * d2;
        }
        let (c2, s2) = (cs * dc - sn * ds, sn * dc + cs * ds);
        cs = c2;
        sn = s2;
    }
    let err = if rules.squared { e2 } else { e } + fit.circle_penalty(r);
    err.is_finite().then_some(err)
}

fn joint_err(
    names: &[String],
    j: usize,
    k: usize,
    n: usize,
    e: impl std::fmt::Display,
) -> ConcreteError {
    let name = names.get(j).cloned().unwrap_or_else(|| format!("{j}"));
    ConcreteError::Track(format!("fitting joint `{name}` on frames {k}..{n}: {e}"))
}

/// Branch-and-bound DP (see the module docs): the optimal segmentation of
/// `0..T` with segments of at most `window` frames, `lambda[n − 1]` paid by a
/// segment ending at `n`.
pub(crate) fn segment_search(
    joints: &[JointTrack<'_>],
    names: &[String],
    fit: &FitParams,
    lambda: &[f64],
    window: usize,
) -> Result<Segmentation> {
    let t = lambda.len();
    if t == 0 {
        return Err(ConcreteError::Track("cannot segment 0 frames".into()));
    }
    if window == 0 {
        return Err(ConcreteError::param("max_segment_frames", "must be ≥ 1"));
    }
    let rules = Rules::new(fit);
    let spline = fit.kinds.contains(&PrimitiveKind::Spline);
    let nj = joints.len();
    // Per joint: 2D fast path data (points with missing frames zeroed).
    let fast: Vec<Option<Vec<[f64; 2]>>> = joints
        .iter()
        .map(|jt| {
            if jt.points.ncols() != 2 || spline {
                return None;
            }
            Some(
                jt.points
                    .outer_iter()
                    .zip(jt.weights)
                    .map(|(r, &w)| if w > 0.0 { [r[0], r[1]] } else { [0.0, 0.0] })
                    .collect(),
            )
        })
        .collect();
    // Step lengths of consecutive valid frames (−1 where a frame is missing).
    let steps: Vec<Vec<f64>> = fast
        .iter()
        .zip(joints)
        .map(|(f, jt)| match f {
            Some(p) => (0..t)
                .map(|i| {
                    if i + 1 < t && jt.weights[i] > 0.0 && jt.weights[i + 1] > 0.0 {
                        let (dx, dy) = (p[i + 1][0] - p[i][0], p[i + 1][1] - p[i][1]);
                        (dx * dx + dy * dy).sqrt()
                    } else {
                        -1.0
                    }
                })
                .collect(),
            None => Vec::new(),
        })
        .collect();
    let mut best = vec![f64::INFINITY; t + 1];
    let mut arg = vec![0usize; t + 1];
    best[0] = 0.0;
    let mut accs = vec![Acc2::default(); nj];
    let mut quicks = vec![Quick::default(); nj];
    let mut lbs = vec![0.0f64; nj];
    let mut cheaps = vec![Cheap::default(); nj];
    let mut order: Vec<usize> = Vec::with_capacity(nj);
    for n in 1..=t {
        let lo = n.saturating_sub(window);
        let lam = lambda[n - 1];
        let mut best_n = f64::INFINITY;
        let mut arg_n = n - 1;
        // First the start of the previous frame's last segment (the segment
        // extended by one frame: usually near the optimum, a strong
        // incumbent), then every start from the shortest segment up.
        let seed = arg[n - 1].max(lo);
        for pass in 0..2 {
            if pass == 0 && (n < 2 || seed + 1 >= n) {
                continue;
            }
            for (j, acc) in accs.iter_mut().enumerate() {
                let (rx, ry) = match &fast[j] {
                    Some(p) => (p[n - 1][0], p[n - 1][1]),
                    None => (0.0, 0.0),
                };
                acc.reset(n - 1, rx, ry);
            }
            let stop = if pass == 0 { seed } else { lo };
            for k in (stop..n).rev() {
                let tau = k as f64 - (n - 1) as f64;
                for (j, acc) in accs.iter_mut().enumerate() {
                    if joints[j].weights[k] > 0.0 {
                        match &fast[j] {
                            Some(p) => acc.add(k, tau, p[k][0], p[k][1], steps[j][k]),
                            None => {
                                if acc.count == 0 {
                                    acc.last = k;
                                }
                                acc.first = k;
                                acc.count += 1;
                            }
                        }
                    }
                }
                if (pass == 0 && k != seed) || (pass == 1 && k == seed && seed + 1 < n && n >= 2) {
                    continue;
                }
                let base = best[k];
                if !base.is_finite() {
                    continue;
                }
                // Prune on λ alone (costs are ≥ 0).
                if base + lam > best_n {
                    continue;
                }
                // O(1) bounds.
                let mut lb_sum = 0.0;
                for j in 0..nj {
                    let acc = &accs[j];
                    let lb = if acc.count == 0 {
                        0.0
                    } else if let Some(p) = &fast[j] {
                        quicks[j] = quick(acc, p, &rules, fit);
                        quicks[j].lb
                    } else {
                        0.0
                    };
                    lbs[j] = lb;
                    lb_sum += lb;
                    if base + (lb_sum + lam) > best_n {
                        break;
                    }
                }
                if base + (lb_sum + lam) > best_n {
                    continue;
                }
                // Exact stationary and line errors, circle bounds, joint by joint.
                let mut rest = lb_sum;
                let mut sum2 = 0.0;
                let mut alive = true;
                for j in 0..nj {
                    rest -= lbs[j];
                    let acc = &accs[j];
                    let c = if acc.count == 0 {
                        Cheap {
                            decided: Some(0.0),
                            ..Cheap::default()
                        }
                    } else {
                        match &fast[j] {
                            Some(p) if !rules.quadratic => {
                                cheap2(&quicks[j], acc, p, &steps[j], joints[j].weights, &rules)
                            }
                            _ => {
                                let e = fit_best_unchecked(
                                    joints[j].points.slice(s![k..n, ..]),
                                    Some(&joints[j].weights[k..n]),
                                    fit,
                                )
                                .map_err(|e| joint_err(names, j, k, n, e))?
                                .error;
                                Cheap {
                                    decided: Some(e),
                                    ..Cheap::default()
                                }
                            }
                        }
                    };
                    cheaps[j] = c;
                    sum2 += c.lb();
                    if base + (sum2 + rest.max(0.0) + lam) > best_n {
                        alive = false;
                        break;
                    }
                }
                if !alive {
                    continue;
                }
                // Circles, while the candidate can still win: the joints whose
                // bound may rise most first.
                order.clear();
                order.extend(0..nj);
                order.sort_by(|&a, &b| {
                    let gain = |c: &Cheap| {
                        if c.needs_circle() {
                            c.best - c.lb()
                        } else {
                            -1.0
                        }
                    };
                    gain(&cheaps[b]).total_cmp(&gain(&cheaps[a]))
                });
                let mut total = 0.0;
                let mut rest = sum2;
                for &j in &order {
                    let c = cheaps[j];
                    rest -= c.lb();
                    let cost = if c.needs_circle() {
                        let acc = &accs[j];
                        let p = fast[j].as_deref().unwrap_or(&[]);
                        match circle2(p, joints[j].weights, acc.first, acc.last, &rules, fit) {
                            Some(e) if e < c.best => e,
                            _ if c.best.is_finite() => c.best,
                            _ => {
                                return Err(joint_err(
                                    names,
                                    j,
                                    k,
                                    n,
                                    "no primitive kind could be fitted",
                                ))
                            }
                        }
                    } else {
                        match c.decided {
                            Some(d) => d,
                            None if c.best.is_finite() => c.best,
                            None => {
                                return Err(joint_err(
                                    names,
                                    j,
                                    k,
                                    n,
                                    "no primitive kind could be fitted",
                                ))
                            }
                        }
                    };
                    total += cost;
                    if base + (total + rest.max(0.0) + lam) > best_n {
                        alive = false;
                        break;
                    }
                }
                if !alive {
                    continue;
                }
                let e = base + (total + lam);
                if e.is_nan() {
                    return Err(ConcreteError::Track(format!(
                        "segment cost of frames {k}..{n} is NaN"
                    )));
                }
                if e < best_n || (e == best_n && k < arg_n) {
                    best_n = e;
                    arg_n = k;
                }
            }
        }
        best[n] = best_n;
        arg[n] = arg_n;
    }
    if !best[t].is_finite() {
        return Err(ConcreteError::Track(format!(
            "no finite-cost segmentation of {t} frames with segments of at most {window} frames"
        )));
    }
    let mut b = vec![t];
    let mut n = t;
    while n > 0 {
        n = arg[n];
        b.push(n);
    }
    b.reverse();
    Ok(Segmentation {
        boundaries: b,
        cost: best[t],
    })
}
