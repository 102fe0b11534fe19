//! O(L) per joint and candidate: the exact stationary and line errors with a
//! second bound for the circle, in one pass (the exact circle, where it can
//! still win, is [`super::circle`]).

use super::bounds::{euclid_lb, speed_lb, Quick};
use super::moments::Acc2;
use super::{Rules, LB_SAFETY};

/// Exact stationary and line errors of one 2D joint and a bound for its circle.
#[derive(Clone, Copy, Default)]
pub(super) struct Cheap {
    /// The joint's cost when already decided (stationary wins outright).
    pub(super) decided: Option<f64>,
    /// Best of the stationary and line errors that take part (`+∞` if none).
    pub(super) best: f64,
    /// Lower bound of the circle's error with penalty, when a circle takes part.
    pub(super) circle_lb: Option<f64>,
    /// The Euclidean errors of the one pass (`NaN` where not computed): the
    /// stationary point, the line, and the distance to the moments' circle
    /// (`Σ w |‖x − c‖ − r|`), for [`super::carry`].
    pub(super) errors: [f64; 3],
}

pub(super) fn cheap2(
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
            && (q.small_box || {
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
                errors: [f64::NAN; 3],
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
            errors: [f64::NAN; 3],
        };
    }
    if rules.stat && q.small_box {
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
            errors: [e, f64::NAN, f64::NAN],
        };
    }
    // Two frames per step with separate sums (independent lanes the
    // compiler can pair into vector instructions).
    let t_end = acc.end as f64;
    // Mean step length, for the step-variation bound of the circle.
    let abar = if acc.npairs > 0 {
        acc.sa / acc.npairs as f64
    } else {
        0.0
    };
    #[inline(always)]
    fn frame(q: &Quick, p: [f64; 2], w: f64, tau: f64, a: f64, abar: f64, s: &mut [f64; 7]) {
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
        // a step of a valid pair (a ≥ 0)
        s[6] += if a >= 0.0 { (a - abar).abs() } else { 0.0 };
    }
    let (mut sa, mut sb) = ([0.0f64; 7], [0.0f64; 7]);
    let last = acc.last;
    let step = |i: usize| if i < last { steps[i] } else { -1.0 };
    let mut i = acc.first;
    let end = last + 1;
    while i + 1 < end {
        frame(q, pts[i], wts[i], i as f64 - t_end, step(i), abar, &mut sa);
        frame(
            q,
            pts[i + 1],
            wts[i + 1],
            (i + 1) as f64 - t_end,
            step(i + 1),
            abar,
            &mut sb,
        );
        i += 2;
    }
    if i < end {
        frame(q, pts[i], wts[i], i as f64 - t_end, step(i), abar, &mut sa);
    }
    let dev = sa[6] + sb[6];
    let (es, es2, el, el2, ec, ec2) = (
        sa[0] + sb[0],
        sa[1] + sb[1],
        sa[2] + sb[2],
        sa[3] + sb[3],
        sa[4] + sb[4],
        sa[5] + sb[5],
    );
    let pick = |e: f64, e2: f64| if rules.squared { e2 } else { e };
    if rules.stat && (q.small_box || es / acc.sw < rules.mean_res_thr) {
        return Cheap {
            decided: Some(pick(es, es2)),
            best: pick(es, es2),
            circle_lb: None,
            errors: [es, el, if q.circle_ok { ec } else { f64::NAN }],
        };
    }
    let mut best = f64::INFINITY;
    if rules.stat {
        best = pick(es, es2);
    }
    if want_line {
        best = best.min(pick(el, el2));
    }
    let circle_lb = want_circle.then(|| circle_bound(q, acc, rules, ec, ec2, dev));
    Cheap {
        decided: None,
        best,
        circle_lb,
        errors: [es, el, if q.circle_ok { ec } else { f64::NAN }],
    }
}

/// Lower bound of the circle's error with penalty from the one pass's sums:
/// `ec` (`Σ w |‖x − c‖ − r|` to the moments' circle), `ec2` (its squares, for
/// the squared norm) and `dev` (`Σ|aᵢ − ā|` over the step lengths).
pub(super) fn circle_bound(
    q: &Quick,
    acc: &Acc2,
    rules: &Rules,
    ec: f64,
    ec2: f64,
    dev: f64,
) -> f64 {
    let speed = if rules.squared {
        speed_lb(acc, true)
    } else if acc.npairs >= 2 {
        (0.25 * dev * (1.0 - 1e-9) - 1e-12 * acc.sa).max(0.0)
    } else {
        0.0
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
}
