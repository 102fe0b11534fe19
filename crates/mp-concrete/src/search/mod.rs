//! Exact segmentation without a cost table: branch and bound over the DP of
//! [`crate::dp`], with segment moments updated in O(1) per candidate.
//!
//! For every end frame `n` the candidate starts `k = n − 1, n − 2, …, n − W`
//! are visited from the shortest segment to the longest, so that a good
//! incumbent `E[n]` is found early. Each joint keeps running moments of its
//! valid points over `k..n` (count, Σt, Σt², Σx, Σtx, Σx², third and fourth
//! order in x and y, bounding box, first and last valid frame), with time and
//! coordinates relative to frame `n − 1` (its point, or the last valid point
//! before it where it is missing), so adding frame `k` costs O(D) and the
//! sums stay local (no cancellation between large prefix sums).
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
//!   fitted point or line); for the stationary point instead Hölder's
//!   `Σ‖rᵢ‖ ≥ SSE^{3/2} / (Σ‖rᵢ‖⁴)^{1/2}` (4th moments about the mean, exact
//!   when the residuals are of equal size, and at least both of those) and
//!   `½ Σ aᵢ` over the step lengths
//!   `aᵢ` of consecutive frames; for the line (constant speed, like the
//!   circle) the step-variation bound; for the circle
//!   `Σ w |dᵢ − r| ≥ K / (A·(d_max + r))` with `A ≥ max |dᵢ² − r²|`.
//!
//! A joint's cost is the error of the kind chosen by the selection rules of
//! [`mp_geom::fit_best`], which is at least the smallest error over the kinds
//! considered; so `E[k] + λ + Σ_j lb_j > E[n]` proves that `k` cannot improve
//! `E[n]`. Candidates that survive get their stationary and line errors
//! (one pass over the segment, square roots only) and a second bound
//! for the circle (`Σ w |dᵢ − r|` + penalty: a point of the circle is at least
//! `|‖x − c‖ − r|` from `x`); the circle itself (angles, `atan2`) is fitted
//! only when that bound is below the best of stationary and line, and the
//! candidate is dropped as soon as its exact partial sum plus the remaining
//! bounds exceeds the incumbent. Joints are visited in the order of how much
//! their exact cost has exceeded their O(1) bound so far (re-sorted every 64
//! end frames), so a losing candidate is usually dropped after a few joints; a
//! joint's circle is fitted at once only if it could drop the candidate, else
//! after the other joints, if the candidate still survives. The candidate's
//! cost is summed in joint order, whatever the visiting order.
//!
//! That pass runs twice, cheap first (Euclidean norm, 2D joints): in single
//! precision over lanes the compiler vectorises, each sum lowered by a bound
//! of its rounding error (`coarse`), so that the joint's cost from it is a
//! lower bound (with the exact circle where one was fitted); only a
//! candidate that survives every joint's single-precision bound gets the
//! exact double-precision pass of each joint, and its exact cost. The costs are those of
//! [`mp_geom::fit_best`] (same fits, same rules) up to rounding, so the
//! optimum is the optimum of the exhaustive DP ([`Segmentation::exhaustive`](crate::Segmentation::exhaustive)).
//!
//! What the one pass measures (its single-precision lower bounds, then the
//! exact errors where they follow) is kept for the next candidates (per joint,
//! a ring of `W + 2` candidates, the latest measurement of each start): a
//! candidate that contains a measured segment — the same start with an end
//! frame up to 4 frames later, or the previous start at the same end frame —
//! gets each kind's bound raised by the triangle inequality from the measured
//! error (`carry`, Euclidean norm, 2D joints).
//!
//! Joints in 3D, or with the spline kind allowed, use [`fit_best_checked`]
//! for their exact cost (still with the bounds of the other joints and the
//! early exit).
//!
//! Steps, one file each: `moments` (running moments), `bounds` (the O(1)
//! fits and bounds), `carry` (bounds carried from a measured neighbour),
//! `coarse` (the single-precision pass), `exact` (the one-pass errors),
//! `circle` (the exact circle, four frames at a time); the search loop is
//! here.
//!
//! Memory: `O(T·J·D)` for the points, `O(T)` for the DP and `O(W·J)` for
//! what is carried; no `T × W` table.

use mp_geom::Checked;
use mp_geom::PrimitiveKind;
use mp_geom::{fit_best_checked, ErrorNorm, FitParams};
use ndarray::{s, Array2};

use crate::dp::{backtrack, Segmentation};
use crate::error::{ConcreteError, Result};

mod bounds;
mod carry;
mod circle;
mod coarse;
mod exact;
mod moments;
#[cfg(test)]
mod testutil;

use bounds::{quick, Quick};
use carry::{joint_lb, Known};
use circle::{circle2, CircleScratch, Span};
use coarse::{coarse_stage, Coarse};
use exact::cheap2;
use moments::{anchors, Acc2};

/// The work one search did: the same track and parameters give the same
/// counts on every machine, so they measure the bounds and the visiting
/// order where timings are noisy.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct SearchStats {
    /// Candidate segments `(k, n)` visited (at most `W` per end frame).
    pub candidates: u64,
    /// Dropped on `E[k] + λ` alone.
    pub pruned_lambda: u64,
    /// Dropped by the O(1) bounds of the joints.
    pub pruned_bounds: u64,
    /// Left for the one-pass stages (`candidates − pruned_lambda − pruned_bounds`).
    pub survivors: u64,
    /// Survivors dropped on the single-precision bounds (`coarse`, with the
    /// exact circles fitted there).
    pub dropped_coarse: u64,
    /// Survivors dropped on exact costs (the rest, `survivors −
    /// dropped_coarse − dropped_exact`, were each the best so far for their
    /// end frame).
    pub dropped_exact: u64,
    /// Single-precision joint evaluations, and the frames they read.
    pub coarse_joints: u64,
    pub coarse_frames: u64,
    /// One-pass joint evaluations in the exact stage, and the frames they read.
    pub exact_joints: u64,
    pub exact_frames: u64,
    /// Exact circle fits, and the frames they read.
    pub circle_fits: u64,
    pub circle_frames: u64,
}

impl SearchStats {
    /// Exact joint evaluations per survivor (0 without survivors).
    pub fn joints_per_survivor(&self) -> f64 {
        if self.survivors == 0 {
            0.0
        } else {
            self.exact_joints as f64 / self.survivors as f64
        }
    }
}

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

/// A joint's cost on `k..n` after the one-pass errors: exact, or the
/// stationary/line best and a circle still to be fitted.
enum Stage {
    /// Exact (`None`: no kind could be fitted).
    Done(Option<f64>),
    /// The circle may win: its lower bound and the best other kind.
    Circle { lb: f64, best: f64 },
}

/// A joint's [`Stage`] and the one pass's Euclidean errors where it ran
/// (for [`carry`]).
type Staged = (Stage, Option<[f64; 3]>);

/// The cheap stage of one joint's cost on `k..n` (see [`Stage`]).
#[allow(clippy::too_many_arguments)]
fn joint_stage(
    jt: &JointTrack<'_>,
    pts: Option<&[[f64; 2]]>,
    steps: &[f64],
    acc: &Acc2,
    q: &Quick,
    rules: &Rules,
    fit: &Checked<FitParams>,
    k: usize,
    n: usize,
) -> std::result::Result<Staged, mp_geom::GeomError> {
    if acc.count == 0 {
        return Ok((Stage::Done(Some(0.0)), None));
    }
    let p = match pts {
        Some(p) if !rules.quadratic => p,
        _ => {
            let e = fit_best_checked(jt.points.slice(s![k..n, ..]), Some(&jt.weights[k..n]), fit)?;
            return Ok((Stage::Done(Some(e.error)), None));
        }
    };
    let c = cheap2(q, acc, p, steps, jt.weights, rules);
    let errors = (!rules.squared).then_some(c.errors);
    if let Some(d) = c.decided {
        return Ok((Stage::Done(Some(d)), errors));
    }
    let stage = match c.circle_lb {
        Some(lb) if lb < c.best => Stage::Circle { lb, best: c.best },
        _ => Stage::Done(c.best.is_finite().then_some(c.best)),
    };
    Ok((stage, errors))
}

/// The circle stage: the joint's cost given the best other kind (`best`,
/// exact or a lower bound), and the circle's own exact cost (`+∞` where no
/// circle fits). Counted in `stats`; the fit is kept in `known` when that
/// holds this candidate's one-pass errors (for [`carry`]).
#[allow(clippy::too_many_arguments)]
fn joint_circle(
    jt: &JointTrack<'_>,
    pts: &[[f64; 2]],
    acc: &Acc2,
    best: f64,
    rules: &Rules,
    fit: &FitParams,
    stats: &mut SearchStats,
    known: &mut Known,
    scratch: &mut CircleScratch,
    k: usize,
    n: usize,
) -> (Option<f64>, f64) {
    stats.circle_fits += 1;
    stats.circle_frames += span_frames(acc, k, n, true);
    let span = Span {
        pts,
        wts: jt.weights,
        first: acc.first,
        last: acc.last,
    };
    let cf = circle2(span, rules, fit, scratch);
    if known.k == k && known.n == n {
        known.circle = cf;
    }
    let own = cf.map_or(f64::INFINITY, |c| c.cost);
    (with_circle(own, best), own)
}

/// A joint's cost from the circle's own cost and the best other kind's.
fn with_circle(circle: f64, best: f64) -> Option<f64> {
    if circle < best {
        Some(circle)
    } else {
        best.is_finite().then_some(best)
    }
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

/// What the search reads of each joint besides its points: the 2D fast
/// path's points (missing frames zeroed), the points the moments are taken
/// about, the step lengths between consecutive valid frames, and the
/// single-precision copy. `None` (or empty) for a joint off the fast path
/// (3D, or with the spline kind allowed).
struct JointPaths {
    fast: Vec<Option<Vec<[f64; 2]>>>,
    anchor: Vec<Option<Vec<[f64; 2]>>>,
    steps: Vec<Vec<f64>>,
    coarse: Vec<Option<Coarse>>,
}

impl JointPaths {
    fn new(joints: &[JointTrack<'_>], rules: &Rules, spline: bool, t: usize) -> Self {
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
        // Per joint: the points the moments are taken about (see `moments::anchors`).
        let anchor: Vec<Option<Vec<[f64; 2]>>> = fast
            .iter()
            .zip(joints)
            .map(|(f, jt)| f.as_ref().map(|p| anchors(p, jt.weights)))
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
        // Per joint: the single-precision copy (Euclidean norm, fast path).
        let coarse: Vec<Option<Coarse>> = fast
            .iter()
            .zip(joints)
            .zip(&steps)
            .map(|((f, jt), st)| match f {
                Some(p) if !rules.squared && !rules.quadratic => {
                    Some(Coarse::new(p, jt.weights, st))
                }
                _ => None,
            })
            .collect();
        JointPaths {
            fast,
            anchor,
            steps,
            coarse,
        }
    }
}

/// The search's running state: the DP's best costs and arguments, the
/// per-joint accumulators and bounds of the candidate in hand, the joint
/// order, the statistics and the ring of what the exact stage measured.
struct SearchState {
    best: Vec<f64>,
    arg: Vec<usize>,
    accs: Vec<Acc2>,
    quicks: Vec<Quick>,
    lbs: Vec<f64>,
    costs: Vec<f64>,
    deferred: Vec<(usize, f64, f64)>,
    circ: Vec<f64>,
    bounded: Vec<bool>,
    gaps: Vec<f64>,
    order: Vec<usize>,
    stats: SearchStats,
    scratch: CircleScratch,
    ring: usize,
    known: Vec<Known>,
}

impl SearchState {
    fn new(nj: usize, t: usize, window: usize) -> Self {
        let mut best = vec![f64::INFINITY; t + 1];
        let arg = vec![0usize; t + 1];
        best[0] = 0.0;
        let accs = vec![Acc2::default(); nj];
        let quicks = vec![Quick::default(); nj];
        let lbs = vec![0.0f64; nj];
        let costs = vec![0.0f64; nj];
        let deferred: Vec<(usize, f64, f64)> = Vec::with_capacity(nj);
        // Per joint, for the candidate in hand: the exact circle's own cost
        // where it was fitted (`NaN`: not fitted), and whether its cost so far is
        // a single-precision bound.
        let circ = vec![f64::NAN; nj];
        let bounded = vec![false; nj];
        // Joints by how much their exact cost has exceeded their O(1) bound so
        // far (most first): the candidates that cannot win are dropped sooner.
        let gaps = vec![0.0f64; nj];
        let order: Vec<usize> = (0..nj).collect();
        let stats = SearchStats::default();
        let scratch = CircleScratch::default();
        // What the exact stage measured, per joint, on the candidates of this
        // end frame and the previous one (slot `k mod (W + 2)`).
        let ring = window + 2;
        let known = vec![Known::NONE; nj * ring];
        SearchState {
            best,
            arg,
            accs,
            quicks,
            lbs,
            costs,
            deferred,
            circ,
            bounded,
            gaps,
            order,
            stats,
            scratch,
            ring,
            known,
        }
    }
}

/// Branch-and-bound DP (see the module docs): the optimal segmentation of
/// `0..T` with segments of at most `window` frames, `lambda[n − 1]` paid by a
/// segment ending at `n`.
pub(crate) fn segment_search(
    joints: &[JointTrack<'_>],
    names: &[String],
    fit: &Checked<FitParams>,
    lambda: &[f64],
    window: usize,
) -> Result<(Segmentation, SearchStats)> {
    let t = lambda.len();
    if t == 0 {
        return Err(ConcreteError::Track("cannot segment 0 frames".into()));
    }
    if window == 0 {
        return Err(ConcreteError::param("max_segment_frames", "must be ≥ 1"));
    }
    let rules = Rules::new(fit);
    let nj = joints.len();
    let JointPaths {
        fast,
        anchor,
        steps,
        coarse,
    } = JointPaths::new(
        joints,
        &rules,
        fit.kinds.contains(&PrimitiveKind::Spline),
        t,
    );
    let SearchState {
        mut best,
        mut arg,
        mut accs,
        mut quicks,
        mut lbs,
        mut costs,
        mut deferred,
        mut circ,
        mut bounded,
        mut gaps,
        mut order,
        mut stats,
        mut scratch,
        ring,
        mut known,
    } = SearchState::new(nj, t, window);
    for n in 1..=t {
        if n % 64 == 0 {
            order.sort_by(|&a, &b| gaps[b].total_cmp(&gaps[a]).then(a.cmp(&b)));
            for g in gaps.iter_mut() {
                *g *= 0.5;
            }
        }
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
                let (rx, ry) = match &anchor[j] {
                    Some(a) => (a[n - 1][0], a[n - 1][1]),
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
                stats.candidates += 1;
                let base = best[k];
                // Prune on λ alone (costs are ≥ 0).
                if !base.is_finite() || base + lam > best_n {
                    stats.pruned_lambda += 1;
                    continue;
                }
                // O(1) bounds, joints in the current order.
                let mut lb_sum = 0.0;
                let mut dead = false;
                for &j in &order {
                    let acc = &accs[j];
                    let lb = if acc.count == 0 {
                        0.0
                    } else if let Some(p) = &fast[j] {
                        quicks[j] = quick(acc, p, &rules, fit);
                        let olds = [
                            &known[j * ring + k % ring],
                            &known[j * ring + (k + 1) % ring],
                        ];
                        joint_lb(olds, acc, &quicks[j], p, joints[j].weights, &rules, k, n)
                    } else {
                        0.0
                    };
                    lbs[j] = lb;
                    lb_sum += lb;
                    if base + (lb_sum + lam) > best_n {
                        dead = true;
                        break;
                    }
                }
                if dead {
                    stats.pruned_bounds += 1;
                    continue;
                }
                stats.survivors += 1;
                // Costs joint by joint (circles only where one can win),
                // dropped as soon as the partial sum plus the remaining
                // bounds exceeds the incumbent: first with single-precision
                // bounds of the one-pass errors where there are (`coarse`),
                // then, if the candidate survives, exactly.
                let mut rest = lb_sum;
                let mut sum = 0.0;
                let mut any_coarse = false;
                deferred.clear();
                let no_fit = |j: usize| -> Result<f64> {
                    if best_n.is_finite() {
                        Ok(f64::INFINITY)
                    } else {
                        Err(joint_err(
                            names,
                            j,
                            k,
                            n,
                            "no primitive kind could be fitted",
                        ))
                    }
                };
                let exact_stage = |j: usize| {
                    joint_stage(
                        &joints[j],
                        fast[j].as_deref(),
                        &steps[j],
                        &accs[j],
                        &quicks[j],
                        &rules,
                        fit,
                        k,
                        n,
                    )
                    .map_err(|e| joint_err(names, j, k, n, e))
                };
                let fit_circle = |j: usize,
                                  best: f64,
                                  st: &mut SearchStats,
                                  kn: &mut Known,
                                  sc: &mut CircleScratch| {
                    let p = fast[j].as_deref().unwrap_or(&[]);
                    joint_circle(&joints[j], p, &accs[j], best, &rules, fit, st, kn, sc, k, n)
                };
                for &j in &order {
                    rest -= lbs[j];
                    circ[j] = f64::NAN;
                    bounded[j] = false;
                    let (stage, errors) = match (&coarse[j], accs[j].count) {
                        (Some(c), 1..) => {
                            stats.coarse_joints += 1;
                            stats.coarse_frames += span_frames(&accs[j], k, n, true);
                            bounded[j] = true;
                            any_coarse = true;
                            let (stage, errors) = coarse_stage(c, &quicks[j], &accs[j], &rules);
                            (stage, Some(errors))
                        }
                        _ => {
                            stats.exact_joints += 1;
                            stats.exact_frames += span_frames(&accs[j], k, n, fast[j].is_some());
                            exact_stage(j)?
                        }
                    };
                    let slot = j * ring + k % ring;
                    if let Some(errors) = errors {
                        known[slot] = Known::new(k, n, errors, &quicks[j]);
                    }
                    let cost = match stage {
                        Stage::Done(Some(c)) => c,
                        Stage::Done(None) => no_fit(j)?,
                        Stage::Circle { lb, best } => {
                            // Fitted now only if it can drop the candidate;
                            // otherwise later, if the candidate survives.
                            if base + (sum + best + rest.max(0.0) + lam) > best_n {
                                let (c, own) =
                                    fit_circle(j, best, &mut stats, &mut known[slot], &mut scratch);
                                circ[j] = own;
                                match c {
                                    Some(c) => c,
                                    None => no_fit(j)?,
                                }
                            } else {
                                // Provisionally its largest known bound.
                                let lb = lb.max(lbs[j]);
                                deferred.push((j, lb, best));
                                lb
                            }
                        }
                    };
                    costs[j] = cost;
                    let g = cost - lbs[j];
                    if g.is_finite() {
                        gaps[j] += g;
                    }
                    sum += cost;
                    if base + (sum + rest.max(0.0) + lam) > best_n {
                        dead = true;
                        break;
                    }
                }
                if dead {
                    deferred.clear();
                }
                // The deferred circles, those that may rise most first.
                deferred.sort_by(|a, b| (b.2 - b.1).total_cmp(&(a.2 - a.1)));
                for &(j, lb, best) in &deferred {
                    let slot = j * ring + k % ring;
                    let (c, own) = fit_circle(j, best, &mut stats, &mut known[slot], &mut scratch);
                    circ[j] = own;
                    let cost = match c {
                        Some(c) => c,
                        None => no_fit(j)?,
                    };
                    costs[j] = cost;
                    let g = cost - lb;
                    if g.is_finite() {
                        gaps[j] += g;
                    }
                    sum += cost - lb;
                    if base + (sum + lam) > best_n {
                        dead = true;
                        break;
                    }
                }
                if dead {
                    if any_coarse {
                        stats.dropped_coarse += 1;
                    } else {
                        stats.dropped_exact += 1;
                    }
                    continue;
                }
                // The exact one-pass costs where the first stage had bounds.
                for j in (0..nj).filter(|&j| bounded[j]) {
                    stats.exact_joints += 1;
                    stats.exact_frames += span_frames(&accs[j], k, n, true);
                    let (stage, errors) = exact_stage(j)?;
                    let slot = j * ring + k % ring;
                    if let Some(errors) = errors {
                        // (Keeping the exact circle fitted in the first stage.)
                        known[slot].errors = errors;
                    }
                    let cost = match stage {
                        Stage::Done(Some(c)) => c,
                        Stage::Done(None) => no_fit(j)?,
                        Stage::Circle { best, .. } => {
                            let own = if circ[j].is_nan() {
                                fit_circle(j, best, &mut stats, &mut known[slot], &mut scratch).1
                            } else {
                                circ[j]
                            };
                            match with_circle(own, best) {
                                Some(c) => c,
                                None => no_fit(j)?,
                            }
                        }
                    };
                    sum += cost - costs[j];
                    costs[j] = cost;
                    if base + (sum + lam) > best_n {
                        dead = true;
                        break;
                    }
                }
                if dead {
                    stats.dropped_exact += 1;
                    continue;
                }
                // In joint order, whatever order the bounds took.
                let total: f64 = costs.iter().sum();
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
    Ok((backtrack(&best, &arg, window)?, stats))
}

/// Frames an exact evaluation of a joint on `k..n` reads: its valid span on
/// the 2D fast path, the whole segment otherwise.
fn span_frames(acc: &Acc2, k: usize, n: usize, fast: bool) -> u64 {
    if acc.count == 0 {
        0
    } else if !fast {
        (n - k) as u64
    } else {
        (acc.last + 1 - acc.first) as u64
    }
}
