//! Smooth programs: consecutive segments share their boundary pose (C0).
//!
//! With [`Continuity::C0`] the segmentation is the one the DP chose for
//! independently fitted segments; then, per joint, all of that joint's
//! primitives are refitted **jointly** so that every segment ends where the
//! next begins: segment `i` evaluated at `t = duration_i` (the first frame of
//! segment `i + 1`) equals segment `i + 1` at `t = 0`. Executing such a
//! program gives a continuous trajectory; the step between the last frame of
//! a segment and the first frame of the next is the primitive's own last step.
//!
//! # The refit
//!
//! The unknowns of a joint are its **knots** `v_0 … v_S` (the pose at each
//! boundary, `D` values each; `v_S` is the end of the last segment extended by
//! one frame) and, for splines, two interior coefficients per axis. With
//! `s = t / n` (`n` the segment's duration) each kind keeps its shape:
//!
//! * **line**: `p(t) = (1 − s)·v_i + s·v_{i+1}` (start `v_i`, velocity `(v_{i+1} − v_i) / n`);
//! * **spline**: the line plus `s(1 − s)·(a + b·s)` per axis (still a cubic);
//! * **circle (2D)**: the fitted arc moved by the similarity (rotation and
//!   scale, as complex numbers) that maps its chord `p(n) − p(0)` onto
//!   `v_{i+1} − v_i`: `p(t) = v_i + (v_{i+1} − v_i)·w(t)` with the fixed complex
//!   `w(t) = (p(t) − p(0)) / (p(n) − p(0))`. The result is a circle with the same
//!   angular velocity and acceleration, a scaled radius and a turned start angle.
//!   An arc whose `|w(t)|` exceeds [`MAX_SIMILARITY_GAIN`] (more than about
//!   240°, or a vanishing chord), and every circle in 3D, is **rigid** instead:
//!   translated as a whole, `v_{i+1} = v_i + p(n) − p(0)`;
//! * **stationary**: rigid with a zero chord, `v_{i+1} = v_i` (the held pose
//!   is the shared knot).
//!
//! Every position is linear in the unknowns, so the refit is one weighted
//! least-squares problem per joint: squared residuals over the observed
//! frames (weight 1), plus the gap-filled positions (linear between
//! observations) of the frames where the joint is not observed with weight
//! [`GAP_WEIGHT`], so that a segment cannot swing far from the track where
//! nothing pins it (a segment where the joint is never observed uses the
//! gap-filled positions with weight 1, as the independent fit does). Rigid segments tie their two
//! knots, which removes one knot; the normal equations are banded (each
//! segment couples its two knots and its interior coefficients) and are
//! solved by a banded Cholesky factorisation in `O(S·D³)` per joint. A ridge
//! of weight [`RIDGE`] towards the independent fits' boundary poses keeps the
//! system positive definite where a joint has no data at all.
//!
//! A rigid segment can be forced far from its data by its neighbours (a held
//! joint between two different positions). After the solve, a stationary
//! segment whose mean residual grew by more than `stationary_mean_residual_px`
//! (the threshold of the stationary rule, 3 px at the 512-px reference) over
//! its independent fit becomes a line, a rigid circle a cubic spline, and the
//! joint is solved again (until nothing changes). These are the only changes
//! of kind.
//!
//! With [`RefitNorm::Euclidean`] each solve above is followed by
//! iteratively reweighted least squares: every observed frame's weight is
//! multiplied by `c·f / max(‖rᵢ‖, f)` (its residual in the previous solve, `f` =
//! [`IRLS_FLOOR_PX`] reference pixels, `c` fixed so that the observed frames
//! weigh 1 on average in the first reweighted solve, as in the least-squares
//! one); gap-filled frames keep their weight (they are not data, and without
//! `c` the interpolated positions would outweigh the data).
//! Each step lowers the Euclidean error of the observed frames (Huber's loss
//! with its corner at `f`, the Euclidean error above it) plus the
//! least-squares terms of the gap-filled frames: a majorise–minimise step,
//! as in Weiszfeld's algorithm. It stops when a step gains less than 0.1 %
//! or after [`IRLS_STEPS`] solves and keeps the best solution. The default
//! is [`RefitNorm::Squared`].
//!
//! The segmentation's cost ([`crate::Synthesis::segmentation`]) stays that of
//! the independent fits the DP minimised.
//!
//! Steps, one file each: `elems` (how each kind depends on the knots, and the
//! primitives back from them), `solve` (the banded normal equations),
//! `irls` (the reweighted solves); the refit loop is here.

use mp_geom::FitParams;
use mp_geom::Primitive;
use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

use crate::program::Program;

mod elems;
mod irls;
mod solve;

use elems::{elem_of, initial_knots, primitives_of, Elem};
use irls::reweighted;
use solve::solve;

/// Whether consecutive segments of a program share their boundary pose.
///
/// With [`Continuity::C0`] the segmentation is the one the DP chose for
/// independently fitted segments; then, per joint, all of that joint's
/// primitives are refitted **jointly** so that every segment ends where the
/// next begins: segment `i` evaluated at `t = duration_i` (the first frame of
/// segment `i + 1`) equals segment `i + 1` at `t = 0`. Executing such a
/// program gives a continuous trajectory; the step between the last frame of
/// a segment and the first frame of the next is the primitive's own last step.
///
/// # The refit
///
/// The unknowns of a joint are its **knots** `v_0 … v_S` (the pose at each
/// boundary, `D` values each; `v_S` is the end of the last segment extended by
/// one frame) and, for splines, two interior coefficients per axis. With
/// `s = t / n` (`n` the segment's duration) each kind keeps its shape:
///
/// * **line**: `p(t) = (1 − s)·v_i + s·v_{i+1}` (start `v_i`, velocity `(v_{i+1} − v_i) / n`);
/// * **spline**: the line plus `s(1 − s)·(a + b·s)` per axis (still a cubic);
/// * **circle (2D)**: the fitted arc moved by the similarity (rotation and
///   scale, as complex numbers) that maps its chord `p(n) − p(0)` onto
///   `v_{i+1} − v_i`: `p(t) = v_i + (v_{i+1} − v_i)·w(t)` with the fixed complex
///   `w(t) = (p(t) − p(0)) / (p(n) − p(0))`. The result is a circle with the same
///   angular velocity and acceleration, a scaled radius and a turned start angle.
///   An arc whose `|w(t)|` exceeds `MAX_SIMILARITY_GAIN` (more than about
///   240°, or a vanishing chord), and every circle in 3D, is **rigid** instead:
///   translated as a whole, `v_{i+1} = v_i + p(n) − p(0)`;
/// * **stationary**: rigid with a zero chord, `v_{i+1} = v_i` (the held pose
///   is the shared knot).
///
/// Every position is linear in the unknowns, so the refit is one weighted
/// least-squares problem per joint: squared residuals over the observed
/// frames (weight 1), plus the gap-filled positions (linear between
/// observations) of the frames where the joint is not observed with weight
/// `GAP_WEIGHT`, so that a segment cannot swing far from the track where
/// nothing pins it (a segment where the joint is never observed uses the
/// gap-filled positions with weight 1, as the independent fit does). Rigid segments tie their two
/// knots, which removes one knot; the normal equations are banded (each
/// segment couples its two knots and its interior coefficients) and are
/// solved by a banded Cholesky factorisation in `O(S·D³)` per joint. A ridge
/// of weight `RIDGE` towards the independent fits' boundary poses keeps the
/// system positive definite where a joint has no data at all.
///
/// A rigid segment can be forced far from its data by its neighbours (a held
/// joint between two different positions). After the solve, a stationary
/// segment whose mean residual grew by more than `stationary_mean_residual_px`
/// (the threshold of the stationary rule, 3 px at the 512-px reference) over
/// its independent fit becomes a line, a rigid circle a cubic spline, and the
/// joint is solved again (until nothing changes). These are the only changes
/// of kind.
///
/// With [`RefitNorm::Euclidean`] each solve above is followed by
/// iteratively reweighted least squares: every observed frame's weight is
/// multiplied by `c·f / max(‖rᵢ‖, f)` (its residual in the previous solve, `f` =
/// `IRLS_FLOOR_PX` reference pixels, `c` fixed so that the observed frames
/// weigh 1 on average in the first reweighted solve, as in the least-squares
/// one); gap-filled frames keep their weight (they are not data, and without
/// `c` the interpolated positions would outweigh the data).
/// Each step lowers the Euclidean error of the observed frames (Huber's loss
/// with its corner at `f`, the Euclidean error above it) plus the
/// least-squares terms of the gap-filled frames: a majorise–minimise step,
/// as in Weiszfeld's algorithm. It stops when a step gains less than 0.1 %
/// or after `IRLS_STEPS` solves and keeps the best solution. The default
/// is [`RefitNorm::Squared`].
///
/// The segmentation's cost ([`crate::Synthesis::segmentation`]) stays that of
/// the independent fits the DP minimised.
///
/// Steps, one file each: `elems` (how each kind depends on the knots, and the
/// primitives back from them), `solve` (the banded normal equations),
/// `irls` (the reweighted solves); the refit loop is here.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum Continuity {
    /// Segments fitted independently: the pose may jump at a boundary.
    /// Programs written before the field existed read as this.
    #[default]
    None,
    /// Segment `i` at `t = duration_i` equals segment `i + 1` at `t = 0`, for
    /// every joint (see above).
    C0,
}

impl Continuity {
    /// The name used in the DSL header and on the command line (`none`, `c0`).
    pub fn as_str(self) -> &'static str {
        match self {
            Continuity::None => "none",
            Continuity::C0 => "c0",
        }
    }

    /// Parses [`Continuity::as_str`]'s names.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "none" => Some(Continuity::None),
            "c0" => Some(Continuity::C0),
            _ => None,
        }
    }
}

impl std::fmt::Display for Continuity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for Continuity {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        Continuity::from_name(&s.to_ascii_lowercase())
            .ok_or_else(|| format!("unknown continuity `{s}` (expected `none` or `c0`)"))
    }
}

/// What the C0 refit minimises per joint.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[non_exhaustive]
pub enum RefitNorm {
    /// `Σ w‖rᵢ‖²`: one least-squares solve per joint.
    #[default]
    Squared,
    /// `Σ w‖rᵢ‖` (the Euclidean error the segmentation minimises under the
    /// default norm): iteratively reweighted least squares, starting from
    /// the least-squares solution (see [`Continuity`]).
    Euclidean,
}

impl RefitNorm {
    /// The name used on the command line (`squared`, `euclidean`).
    pub fn as_str(self) -> &'static str {
        match self {
            RefitNorm::Squared => "squared",
            RefitNorm::Euclidean => "euclidean",
        }
    }
}

impl std::fmt::Display for RefitNorm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

impl std::str::FromStr for RefitNorm {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "squared" => Ok(RefitNorm::Squared),
            "euclidean" => Ok(RefitNorm::Euclidean),
            _ => Err(format!(
                "unknown refit norm `{s}` (expected `squared` or `euclidean`)"
            )),
        }
    }
}

/// Largest `|w(t)|` (the arc's distance from its start relative to its chord)
/// for which a 2D circle is refitted by a similarity; beyond it the circle
/// is moved rigidly. 3 allows arcs up to about 240°.
pub const MAX_SIMILARITY_GAIN: f64 = 3.0;

/// Weight of a frame where the joint is not observed (the gap-filled
/// position, interpolated between observations) in a segment where it is
/// observed elsewhere; an observed frame weighs 1.
pub const GAP_WEIGHT: f64 = 0.01;

/// Weight of the ridge towards the independent fits' boundary poses (per
/// unknown; a frame of data weighs 1).
pub const RIDGE: f64 = 1e-6;

/// One joint's data: positions `T × D` (gap-filled) and 0/1 weights.
pub(crate) struct JointSeries<'a> {
    pub points: ArrayView2<'a, f64>,
    pub weights: &'a [f64],
}

/// A frame's weight in the refit: its 0/1 weight raised to [`GAP_WEIGHT`]
/// in a segment where the joint is observed somewhere (`observed`), 1 in a
/// segment where it never is.
fn refit_weight(series: &JointSeries<'_>, observed: bool, i: usize) -> f64 {
    if observed {
        series.weights[i].max(GAP_WEIGHT)
    } else {
        1.0
    }
}

/// Distance between `p` at segment time `t` and the joint's position at frame `i`.
fn distance_at(
    p: &Primitive,
    t: usize,
    series: &JointSeries<'_>,
    i: usize,
    buf: &mut [f64],
) -> f64 {
    p.eval_into(t as f64, buf);
    buf.iter()
        .zip(series.points.row(i).iter())
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        .sqrt()
}

/// Mean Euclidean residual of `p` on frames `k0..k1` (weights as in the refit).
fn mean_residual(p: &Primitive, series: &JointSeries<'_>, k0: usize, k1: usize) -> f64 {
    let observed = series.weights[k0..k1].iter().any(|&w| w > 0.0);
    let (mut sum, mut wsum) = (0.0, 0.0);
    let mut buf = vec![0.0; series.points.ncols()];
    for t in 0..(k1 - k0) {
        let w = if observed {
            series.weights[k0 + t]
        } else {
            1.0
        };
        if w <= 0.0 {
            continue;
        }
        sum += w * distance_at(p, t, series, k0 + t, &mut buf);
        wsum += w;
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        0.0
    }
}

/// Refits one joint's primitives (one per segment of `bounds`) so that
/// consecutive ones share their boundary pose. `None` when the normal
/// equations cannot be solved (non-finite input).
pub(crate) fn refit_joint(
    series: &JointSeries<'_>,
    bounds: &[usize],
    prims: &[Primitive],
    fit: &FitParams,
    norm: RefitNorm,
) -> Option<Vec<Primitive>> {
    let d = series.points.ncols();
    if prims.is_empty() || d == 0 || bounds.len() != prims.len() + 1 {
        return None;
    }
    let durations: Vec<usize> = bounds.windows(2).map(|w| w[1] - w[0]).collect();
    let mut elems: Vec<Elem> = prims
        .iter()
        .zip(&durations)
        .map(|(p, &n)| elem_of(p, n, d))
        .collect();
    let init = initial_knots(prims, &durations);
    let before: Vec<f64> = prims
        .iter()
        .enumerate()
        .map(|(i, p)| mean_residual(p, series, bounds[i], bounds[i + 1]))
        .collect();
    let limit = fit.stationary_mean_residual_px * fit.unit_scale;
    // Each pass turns at least one rigid segment into a flexible one, so this ends.
    loop {
        let (knots, interiors) = solve(series, bounds, &elems, &init, d, None)?;
        let mut out = primitives_of(prims, &elems, &durations, &knots, &interiors);
        if norm == RefitNorm::Euclidean {
            out = reweighted(series, bounds, &durations, &elems, &init, fit, prims, out);
        }
        let mut changed = false;
        for (i, e) in elems.iter_mut().enumerate() {
            if !matches!(e, Elem::Rigid { .. }) {
                continue;
            }
            let after = mean_residual(&out[i], series, bounds[i], bounds[i + 1]);
            if after > before[i] + limit {
                *e = match prims[i] {
                    Primitive::Stationary { .. } => Elem::Linear,
                    _ => Elem::Cubic,
                };
                changed = true;
            }
        }
        if !changed {
            return Some(out);
        }
    }
}

impl Program {
    /// The largest distance, over joints and boundaries, between the end of a
    /// segment (its primitive at `t = duration`) and the start of the next.
    pub fn max_boundary_gap(&self) -> f64 {
        let mut worst: f64 = 0.0;
        for pair in self.segments.windows(2) {
            let n = pair[0].duration_frames as f64;
            for (p, q) in pair[0].primitives.iter().zip(&pair[1].primitives) {
                let a = p.eval(n);
                let b = q.eval(0.0);
                let dist = a
                    .iter()
                    .zip(&b)
                    .map(|(x, y)| (x - y) * (x - y))
                    .sum::<f64>()
                    .sqrt();
                worst = worst.max(dist);
            }
        }
        worst
    }
}
