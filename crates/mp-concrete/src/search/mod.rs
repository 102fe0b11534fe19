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
mod candidate;
mod carry;
mod circle;
mod coarse;
mod exact;
mod moments;
#[cfg(test)]
mod testutil;

use bounds::Quick;
use candidate::{Inputs, JointPaths, SearchState};
use carry::Known;
use circle::{circle2, CircleScratch, Span};
use exact::cheap2;
use moments::Acc2;

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
    let spline = fit.kinds.contains(&PrimitiveKind::Spline);
    let inputs = Inputs {
        joints,
        names,
        fit,
        rules,
        paths: JointPaths::new(joints, &rules, spline, t),
    };
    let mut state = SearchState::new(joints.len(), t, window);
    for n in 1..=t {
        state.end_frame(&inputs, n, lambda[n - 1], window)?;
    }
    let (best, arg, stats) = state.finish();
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
