//! Lower bounds carried over from a neighbouring candidate (Euclidean norm,
//! 2D joints).
//!
//! When the one pass has evaluated a joint on a segment contained in the
//! candidate — `k..n−m` (the same start, an end frame `m ≤` [`MAX_GAP`]
//! earlier) or `k+1..n` (the same end frame, the previous start) — each
//! kind's error there is known, exactly or as a lower bound (the
//! single-precision pass of [`super::coarse`]), with the model it was
//! measured against (`f_old`). The candidate's model `f_new` of that kind is another
//! one, but by the triangle inequality, over the frames the two segments
//! share,
//!
//! `Σ‖xᵢ − f_new(tᵢ)‖ ≥ Σ‖xᵢ − f_old(tᵢ)‖ − Σ‖f_new(tᵢ) − f_old(tᵢ)‖`,
//!
//! and the new frames add their own distances to `f_new`. The last sum is
//! bounded in O(1):
//!
//! * stationary point and line: both models come from the moments; the line's
//!   difference is linear in time, `Σ‖a + b·(tᵢ − t̄)‖ ≤ n‖a‖ + ‖b‖·√(n·S)`;
//! * the distance to the moments' circle (a bound of the circle's error):
//!   `n·(‖Δc‖ + |Δr|)`;
//! * the exact circle: centre and radius from the moments (within the
//!   rounding slack of the exact fit's), and its least-squares angle line.
//!   Moving the centre by `Δc` turns every point's angle by at most
//!   `ε = asin(Δc / d_min)` (`d_min`: the old fit's smallest distance to its
//!   centre), which moves the fitted line by at most `ε(1 + |t − t̄|·M/S)` at
//!   time `t` (`M = Σ|tᵢ − t̄| ≤ √(n·S)`); each new frame's angle residual
//!   `e` against the old line moves it by `e·h(t)` (the least-squares hat
//!   function), and `e` is bounded without `atan2`, through the chord
//!   between the unit vectors of consecutive frames. So
//!   `Σ|Δφᵢ| ≤ ε(n_old + n) + Σ_new |e|(1 + |t_new − t̄|·√(n/S))`,
//!   and `‖f_new − f_old‖ ≤ ‖Δc‖ + |Δr| + r_old·|Δφ|`. The bound holds only
//!   while the unwrapping of the angles cannot change (the old largest step
//!   plus `2ε`, and every new frame's step with its uncertainty, below π);
//!   otherwise the circle keeps its O(1) bound.
//!
//! A kind's bound is the larger of its O(1) bound and the carried one; the
//! joint's bound is the smallest over the kinds that take part.

use std::f64::consts::PI;

use super::bounds::Quick;
use super::circle::CircleFit;
use super::moments::Acc2;
use super::{Rules, LB_SAFETY};

/// What the one pass measured for one joint on the segment `k..n`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Known {
    pub(super) k: usize,
    pub(super) n: usize,
    /// Euclidean errors of the stationary point, the line and the distance
    /// to the moments' circle, exact or lower bounds (`NaN`: not measured).
    pub(super) errors: [f64; 3],
    /// The models they were measured against: the mean, the line's value at
    /// frame `n − 1` and its velocity, the moments' circle.
    pub(super) mean: [f64; 2],
    pub(super) line_end: [f64; 2],
    pub(super) line_vel: [f64; 2],
    pub(super) circle_m: [f64; 3],
    /// The exact circle, where it was fitted.
    pub(super) circle: Option<CircleFit>,
}

impl Known {
    /// Nothing known (matches no candidate).
    pub(super) const NONE: Known = Known {
        k: usize::MAX,
        n: usize::MAX,
        errors: [f64::NAN; 3],
        mean: [0.0; 2],
        line_end: [0.0; 2],
        line_vel: [0.0; 2],
        circle_m: [0.0; 3],
        circle: None,
    };

    /// What the one pass measured on `k..n`, with the O(1) models of `q`.
    pub(super) fn new(k: usize, n: usize, errors: [f64; 3], q: &Quick) -> Self {
        Known {
            k,
            n,
            errors,
            mean: [q.mx, q.my],
            line_end: [q.lx, q.ly],
            line_vel: [q.vx, q.vy],
            circle_m: [q.cx, q.cy, q.r],
            circle: None,
        }
    }
}

fn norm(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// An upper bound of `asin(x)` for `0 ≤ x < 1` (`x / √(1 − x²)`, the
/// tangent of the angle); `None` from 1 on (or NaN).
fn asin_ub(x: f64) -> Option<f64> {
    let c = 1.0 - x * x;
    (x < 1.0 && c > 0.0).then(|| x / c.sqrt())
}

/// How many frames longer than a measured segment a candidate may be, at
/// its end, and still get bounds carried from it.
pub(super) const MAX_GAP: usize = 4;

/// The joint's lower bound on `k..n`: for each kind that takes part, the
/// larger of its O(1) bound (`q`) and what carries from `olds`; the smallest
/// over the kinds, and never below `q.lb`.
#[allow(clippy::too_many_arguments)]
pub(super) fn joint_lb(
    olds: [&Known; 2],
    acc: &Acc2,
    q: &Quick,
    pts: &[[f64; 2]],
    wts: &[f64],
    rules: &Rules,
    k: usize,
    n: usize,
) -> f64 {
    let [a, b] = olds.map(|old| carried(old, acc, q, pts, wts, rules, k, n));
    if !a.iter().chain(&b).any(|&v| v > 0.0) {
        return q.lb;
    }
    let kinds = [
        q.stat_lb.max(a[0]).max(b[0]),
        q.line_lb.max(a[1]).max(b[1]),
        q.circle_lb.max(a[2]).max(b[2]),
    ];
    let m = kinds.iter().fold(f64::INFINITY, |m, &v| m.min(v));
    if m.is_finite() {
        q.lb.max(m * LB_SAFETY)
    } else {
        q.lb
    }
}

/// Lower bounds `[stationary, line, circle with penalty]` of the joint's
/// errors on `k..n` carried from `old` (`0` where nothing carries; the
/// caller takes the larger of these and the O(1) bounds).
#[allow(clippy::too_many_arguments)]
pub(super) fn carried(
    old: &Known,
    acc: &Acc2,
    q: &Quick,
    pts: &[[f64; 2]],
    wts: &[f64],
    rules: &Rules,
    k: usize,
    n: usize,
) -> [f64; 3] {
    let mut out = [0.0; 3];
    if rules.squared || acc.count == 0 {
        return out;
    }
    // The new frames, in the order of the unwrapping from the old segment
    // (away from it), and whether they precede it.
    let mut new = [0usize; MAX_GAP];
    let (m, at_start) = if old.k == k && old.n < n && n - old.n <= MAX_GAP {
        for (slot, f) in new.iter_mut().zip(old.n..n) {
            *slot = f;
        }
        (n - old.n, false)
    } else if old.k == k + 1 && old.n == n {
        new[0] = k;
        (1, true)
    } else {
        return out;
    };
    let new = &new[..m];
    let valid = |f: usize| wts[f] > 0.0;
    let n_new = acc.count as f64;
    let n_added = new.iter().filter(|&&f| valid(f)).count() as f64;
    let n_old = n_new - n_added;
    if n_old < 1.0 {
        return out;
    }
    // Local times (frame − (n − 1)) of the valid frames: the candidate's
    // moments, less the new frames for the old ones.
    let tau = |f: usize| f as f64 - (n - 1) as f64;
    let (mut st_old, mut stt_old) = (acc.st, acc.stt);
    for &f in new.iter().filter(|&&f| valid(f)) {
        st_old -= tau(f);
        stt_old -= tau(f) * tau(f);
    }
    // The new frames' own distances to a model.
    let own = |dist: &dyn Fn([f64; 2], f64) -> f64| -> f64 {
        new.iter()
            .filter(|&&f| valid(f))
            .map(|&f| dist(pts[f], tau(f)))
            .sum()
    };
    let [e_stat, e_line, e_rad] = old.errors;
    if e_stat.is_finite() {
        let d = n_old * norm(q.mx - old.mean[0], q.my - old.mean[1]);
        let o = own(&|p, _| norm(p[0] - q.mx, p[1] - q.my));
        out[0] = (e_stat - d + o).max(0.0);
    }
    if e_line.is_finite() {
        // Both lines at the old frames' mean time, and their velocities.
        let tbar = st_old / n_old;
        let s_old = (stt_old - st_old * tbar).max(0.0);
        let shift = (n - 1) as f64 - (old.n - 1) as f64;
        let ax = (q.lx + q.vx * tbar) - (old.line_end[0] + old.line_vel[0] * (tbar + shift));
        let ay = (q.ly + q.vy * tbar) - (old.line_end[1] + old.line_vel[1] * (tbar + shift));
        let b = norm(q.vx - old.line_vel[0], q.vy - old.line_vel[1]);
        let d = n_old * norm(ax, ay) + b * (n_old * s_old).sqrt();
        let o = own(&|p, t| norm(p[0] - (q.lx + q.vx * t), p[1] - (q.ly + q.vy * t)));
        out[1] = (e_line - d + o).max(0.0);
    }
    if !q.circle_ok {
        return out;
    }
    let slack = q.circle_slack;
    // The new frames' distances to any circle within the slack of the moments'.
    let o = own(&|p, _| ((norm(p[0] - q.cx, p[1] - q.cy) - q.r).abs() - 2.0 * slack).max(0.0));
    let mut circle = 0.0f64;
    if e_rad.is_finite() {
        let [cx, cy, r] = old.circle_m;
        let d = n_old * (norm(q.cx - cx, q.cy - cy) + (q.r - r).abs() + 2.0 * slack);
        circle = circle.max(e_rad - d + o);
    }
    if let Some(cf) = &old.circle {
        if let Some(b) = carried_circle(cf, acc, q, pts, wts, new, at_start, n_old, n) {
            circle = circle.max(b + o);
        }
    }
    out[2] = circle.max(0.0) + q.pen_lb;
    out
}

/// The exact circle's part of [`carried`] (without the new frames' own
/// distances), `None` where the unwrapping could change.
#[allow(clippy::too_many_arguments)]
fn carried_circle(
    cf: &CircleFit,
    acc: &Acc2,
    q: &Quick,
    pts: &[[f64; 2]],
    wts: &[f64],
    new: &[usize],
    at_start: bool,
    n_old: f64,
    n: usize,
) -> Option<f64> {
    let slack = q.circle_slack;
    let dc = norm(q.cx - cf.center[0], q.cy - cf.center[1]) + slack;
    let dr = (q.r - cf.radius).abs() + slack;
    let eps = asin_ub(dc / cf.d_min)?;
    // (Comparisons false for NaN.)
    let unwrap_kept = cf.max_step + 2.0 * eps < PI;
    if !unwrap_kept {
        return None;
    }
    let n_new = acc.count as f64;
    let tbar = acc.st / acc.sw;
    let s = acc.stt - acc.st * tbar;
    let spread = s > 0.0;
    if !spread {
        return None;
    }
    let mut dphi = eps * (n_old + n_new);
    // Each new frame is unwrapped against the previous one in the chain,
    // starting from the old segment's neighbouring frame: its angle about
    // the exact centre is within `step` (π/2 times the chord between unit
    // vectors, plus each direction's uncertainty) of its predecessor's.
    let (neighbour, mut dir, mut dir_eps) = if at_start {
        (cf.angle_first, cf.dir_first, eps)
    } else {
        (cf.angle_last, cf.dir_last, eps)
    };
    let mut drift = 0.0; // bound of |angle − neighbour| so far
    for &f in new.iter().filter(|&&f| wts[f] > 0.0) {
        let p = pts[f];
        let d = norm(p[0] - q.cx, p[1] - q.cy);
        // The frame's angle about the exact centre is within `eps_f` of its
        // angle about the moments' centre.
        let eps_f = asin_ub(slack / d)?;
        let u = [(p[0] - q.cx) / d, (p[1] - q.cy) / d];
        let step = 0.5 * PI * norm(u[0] - dir[0], u[1] - dir[1]) + dir_eps + eps_f;
        let same_branch = step < PI;
        if !same_branch {
            return None;
        }
        drift += step;
        let line_old = cf.angle0 + cf.angle_vel * (f as f64 - cf.first as f64);
        let e = drift + (neighbour - line_old).abs();
        let tau = f as f64 - (n - 1) as f64;
        dphi += e * (1.0 + (tau - tbar).abs() * (n_new / s).sqrt());
        dir = u;
        dir_eps = eps_f;
    }
    let d = n_old * (dc + dr) + cf.radius * dphi;
    Some(cf.error - d)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use super::*;
    use crate::search::bounds::quick;
    use crate::search::circle::{circle2, CircleScratch, Span};
    use crate::search::exact::cheap2;
    use crate::search::testutil::{acc_of, steps_of, track};
    use mp_geom::FitParams;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Every carried bound is below the exact error of its kind on the
    /// candidate, from a segment ending 1 to `MAX_GAP` frames earlier and
    /// from the one starting a frame later, on thousands of segments.
    #[test]
    fn carried_bounds_are_below_the_exact_errors() {
        let fit = FitParams::default();
        let rules = Rules::new(&fit);
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut checked, mut circles_carried) = (0, 0);
        let sc = std::cell::RefCell::new(CircleScratch::default());
        for _ in 0..40 {
            let t = 90;
            let (pts, wts) = track(&mut rng, t);
            let steps = steps_of(&pts, &wts);
            let measure = |k: usize, n: usize| {
                let acc = acc_of(&pts, &wts, &steps, k, n);
                if acc.count < 3 {
                    return None;
                }
                let q = quick(&acc, &pts, &rules, &fit);
                let c = cheap2(&q, &acc, &pts, &steps, &wts, &rules);
                let mut known = Known::new(k, n, c.errors, &q);
                let span = Span {
                    pts: &pts,
                    wts: &wts,
                    first: acc.first,
                    last: acc.last,
                };
                known.circle = circle2(span, &rules, &fit, &mut sc.borrow_mut());
                Some((acc, q, known))
            };
            for n in 4..=t {
                for k in n.saturating_sub(40)..n - 2 {
                    let Some((acc, q, new)) = measure(k, n) else {
                        continue;
                    };
                    let olds = (1..=MAX_GAP)
                        .filter(|&m| n - m > k + 2)
                        .map(|m| measure(k, n - m))
                        .chain([measure(k + 1, n)]);
                    for (_, _, old) in olds.flatten() {
                        let b = carried(&old, &acc, &q, &pts, &wts, &rules, k, n);
                        let [es, el, _] = new.errors;
                        let tol = |e: f64| 1e-9 * (1.0 + e.abs());
                        if es.is_finite() {
                            assert!(b[0] <= es + tol(es), "stat {k}..{n}: {} > {es}", b[0]);
                        }
                        if el.is_finite() {
                            assert!(b[1] <= el + tol(el), "line {k}..{n}: {} > {el}", b[1]);
                        }
                        if let Some(cf) = &new.circle {
                            assert!(
                                b[2] <= cf.cost + tol(cf.cost),
                                "circle {k}..{n}: {} > {}",
                                b[2],
                                cf.cost
                            );
                            if old.circle.is_some() && b[2] > q.pen_lb + 1e-9 {
                                circles_carried += 1;
                            }
                        }
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 150_000, "{checked}");
        assert!(circles_carried > 30_000, "{circles_carried}");
    }
}
