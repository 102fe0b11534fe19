//! Spline segmentation of 3D joint sequences into anchors and transitions
//! (paper 004, §3.1.1, eq. 2).
//!
//! A sequence of `T` frames is cut into consecutive *transitions* that share
//! their junction frames: `{0..=k₁}, {k₁..=k₂}, …, {k_m..=T−1}`. Each
//! transition is fitted, per joint and per axis, by a cubic
//! `a t³ + b t² + c t + d` with `t = 0` at the transition's first frame
//! ([`mp_geom::fit_spline`]). The cut points minimise
//!
//! `E[n] = min_{k<n} E[k] + fit(P[k..=n]) + λ`
//!
//! which is [`mp_concrete::Segmentation::dp`] run over the `T − 1` frame
//! *intervals*: a DP segment of intervals `k..n` is the transition of frames
//! `k..=n`, so the DP boundaries are exactly the anchors, first and last frame
//! included.
//!
//! ## Units of the cost
//!
//! `fit(P[k..=n])` is the sum over joints of the spline fit error, each the
//! sum over frames of the Euclidean residual ([`ErrorNorm::Euclidean`], or its
//! square with [`ErrorNorm::Squared`]), multiplied by
//! [`SegmentParams::error_scale`] (error units per track unit). The default
//! `error_scale = 1000` expresses errors of metre tracks in **millimetres**,
//! and λ is in the same error units: `λ = 200` (the paper's value on
//! HumanAct12) costs as much as 200 mm of summed residual, e.g. 10 mm on each
//! of 20 joints in one frame. The paper does not state its unit convention;
//! the λ ablation in `tests/` shows how the number of anchors responds.

use mp_concrete::{CostTable, Segmentation};
use mp_geom::{fit_spline, ErrorNorm, FitParams};
use mp_geom::{Primitive, Track};
use ndarray::{s, Array2, Array3, ArrayView2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{RefineError, Result};

/// Parameters of the spline segmentation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentParams {
    /// Per-transition penalty λ in error units (see [`Self::error_scale`]).
    /// Default 200 (paper, HumanAct12). Must be finite and ≥ 0.
    pub lambda: f64,
    /// Error units per track unit. Default 1000: metres → millimetres.
    pub error_scale: f64,
    /// How residuals are summed. Default Euclidean (sum of distances).
    pub norm: ErrorNorm,
    /// Longest transition in frame intervals (a transition of `L` intervals
    /// spans `L + 1` frames). Default 30 (2 s at 15 fps). Caps the DP at O(T·W).
    pub max_transition_frames: usize,
    /// Shortest transition in frame intervals. Default 1 (the paper's
    /// recurrence allows any length).
    pub min_transition_frames: usize,
    /// Joints with confidence ≤ this are missing (weight 0 in the fits).
    /// Default 0.
    pub min_confidence: f64,
    /// When set, tracks must have exactly this many joints.
    pub n_joints: Option<usize>,
}

impl Default for SegmentParams {
    fn default() -> Self {
        SegmentParams {
            lambda: 200.0,
            error_scale: 1000.0,
            norm: ErrorNorm::Euclidean,
            max_transition_frames: 30,
            min_transition_frames: 1,
            min_confidence: 0.0,
            n_joints: None,
        }
    }
}

impl SegmentParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        if !(self.lambda.is_finite() && self.lambda >= 0.0) {
            return Err(RefineError::param(
                "lambda",
                format!("must be finite and ≥ 0, got {}", self.lambda),
            ));
        }
        if !(self.error_scale.is_finite() && self.error_scale > 0.0) {
            return Err(RefineError::param(
                "error_scale",
                format!("must be finite and > 0, got {}", self.error_scale),
            ));
        }
        if self.min_transition_frames == 0 {
            return Err(RefineError::param("min_transition_frames", "must be ≥ 1"));
        }
        if self.max_transition_frames < self.min_transition_frames {
            return Err(RefineError::param(
                "max_transition_frames",
                format!(
                    "must be ≥ min_transition_frames ({}), got {}",
                    self.min_transition_frames, self.max_transition_frames
                ),
            ));
        }
        if !(self.min_confidence.is_finite() && (0.0..1.0).contains(&self.min_confidence)) {
            return Err(RefineError::param(
                "min_confidence",
                format!("must be in [0, 1), got {}", self.min_confidence),
            ));
        }
        Ok(())
    }
}

/// One transition: frames `start..=end` and one cubic spline per joint
/// (`t = 0` at `start`, `t = end − start` at `end`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SplineTransition {
    /// First frame (an anchor).
    pub start: usize,
    /// Last frame, inclusive (the next anchor).
    pub end: usize,
    /// `Primitive::Spline` per joint, `coeffs[axis] = [a, b, c, d]`.
    pub splines: Vec<Primitive>,
    /// Fit error of this transition in error units (without λ).
    pub error: f64,
}

impl SplineTransition {
    /// Duration in frame intervals (`end − start`, the paper's `T_s`).
    pub fn duration_frames(&self) -> usize {
        self.end - self.start
    }
}

/// A segmentation into anchors and transitions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Segmentation3d {
    /// Anchor frames, increasing: `0`, the junctions, `T − 1`.
    pub anchors: Vec<usize>,
    /// Transitions between consecutive anchors.
    pub transitions: Vec<SplineTransition>,
    /// Frames T of the segmented track.
    pub n_frames: usize,
    /// Joints J.
    pub n_joints: usize,
    /// Dimensions D.
    pub dims: usize,
    /// Total DP cost (fit errors + λ per transition), error units.
    pub cost: f64,
}

impl Segmentation3d {
    /// Positions `T × J × D` executed from the splines. A junction frame is
    /// the mean of the two transitions that share it.
    pub fn reconstruct(&self) -> Array3<f64> {
        let mut out = Array3::<f64>::zeros((self.n_frames, self.n_joints, self.dims));
        let mut count = vec![0.0f64; self.n_frames];
        let mut buf = vec![0.0; self.dims];
        for tr in &self.transitions {
            for f in tr.start..=tr.end.min(self.n_frames.saturating_sub(1)) {
                let t = (f - tr.start) as f64;
                for (j, sp) in tr.splines.iter().enumerate().take(self.n_joints) {
                    if sp.dims() != self.dims {
                        continue;
                    }
                    sp.eval_into(t, &mut buf);
                    for (k, v) in buf.iter().enumerate() {
                        out[[f, j, k]] += v;
                    }
                }
                count[f] += 1.0;
            }
        }
        for (f, c) in count.iter().enumerate() {
            if *c > 1.0 {
                out.slice_mut(s![f, .., ..]).mapv_inplace(|v| v / c);
            }
        }
        out
    }

    /// The reconstruction as a track with `like`'s confidence, frame rate,
    /// units and skeleton.
    pub fn reconstruct_track(&self, like: &Track) -> Result<Track> {
        check_same_shape(
            like,
            self.n_frames,
            self.n_joints,
            self.dims,
            "reconstruct_track",
        )?;
        Ok(Track::new(
            self.reconstruct(),
            Some(like.confidence().to_owned()),
            like.fps(),
            like.units(),
            like.skeleton().clone(),
        )?)
    }

    /// Number of spline parameters (`J · D · 4` per transition, plus its duration).
    pub fn n_params(&self) -> usize {
        self.transitions.len() * (self.n_joints * self.dims * 4 + 1)
    }
}

pub(crate) fn check_same_shape(
    track: &Track,
    t: usize,
    j: usize,
    d: usize,
    what: &str,
) -> Result<()> {
    if track.n_joints() != j {
        return Err(RefineError::JointCount {
            what: what.into(),
            expected: j,
            got: track.n_joints(),
        });
    }
    if track.dims() != d {
        return Err(RefineError::Dims {
            what: what.into(),
            expected: d,
            got: track.dims(),
        });
    }
    if track.n_frames() != t {
        return Err(RefineError::Shape(format!(
            "{what}: expected {t} frames, got {}",
            track.n_frames()
        )));
    }
    Ok(())
}

/// Per-joint `T × D` points and 0/1 weights of a track.
pub(crate) struct JointData {
    pub points: Vec<Array2<f64>>,
    pub weights: Vec<Vec<f64>>,
}

impl JointData {
    pub fn new(track: &Track, min_confidence: f64) -> Self {
        let conf = track.confidence();
        let mut points = Vec::with_capacity(track.n_joints());
        let mut weights = Vec::with_capacity(track.n_joints());
        for j in 0..track.n_joints() {
            points.push(track.joint(j).to_owned());
            weights.push(
                conf.column(j)
                    .iter()
                    .map(|&c| if c > min_confidence { 1.0 } else { 0.0 })
                    .collect(),
            );
        }
        JointData { points, weights }
    }
}

/// Fits one spline to frames `a..=b` of one joint; a joint with no valid
/// frame there is fitted to its stored (gap-filled) positions.
pub(crate) fn fit_joint(
    pts: ArrayView2<'_, f64>,
    w: &[f64],
    fit: &FitParams,
) -> std::result::Result<mp_geom::Fit, mp_geom::GeomError> {
    if w.iter().any(|&x| x > 0.0) {
        fit_spline(pts, Some(w), fit)
    } else {
        fit_spline(pts, None, fit)
    }
}

fn fit_params(norm: ErrorNorm) -> FitParams {
    FitParams {
        kinds: vec![mp_geom::PrimitiveKind::Spline],
        norm,
        ..FitParams::default()
    }
}

fn scaled(err: f64, params: &SegmentParams) -> f64 {
    match params.norm {
        ErrorNorm::Euclidean => err * params.error_scale,
        ErrorNorm::Squared => err * params.error_scale * params.error_scale,
    }
}

fn transition_fit(
    data: &JointData,
    fit: &FitParams,
    params: &SegmentParams,
    a: usize,
    b: usize,
) -> Result<(Vec<Primitive>, f64)> {
    let mut total = 0.0;
    let mut splines = Vec::with_capacity(data.points.len());
    for (j, (pts, w)) in data.points.iter().zip(&data.weights).enumerate() {
        let f = fit_joint(pts.slice(s![a..=b, ..]), &w[a..=b], fit).map_err(|e| {
            RefineError::NonFinite(format!("spline fit of joint {j} on frames {a}..={b}: {e}"))
        })?;
        total += scaled(f.error, params);
        splines.push(f.primitive);
    }
    Ok((splines, total))
}

/// Checks a track for segmentation: ≥ 2 frames, ≥ 1 joint, the expected joint count.
pub(crate) fn check_track(track: &Track, n_joints: Option<usize>, what: &str) -> Result<()> {
    if let Some(j) = n_joints {
        if track.n_joints() != j {
            return Err(RefineError::JointCount {
                what: what.into(),
                expected: j,
                got: track.n_joints(),
            });
        }
    }
    if track.n_joints() == 0 {
        return Err(RefineError::Shape(format!(
            "{what}: the track has no joints"
        )));
    }
    if track.n_frames() < 2 {
        return Err(RefineError::TooShort {
            what: what.into(),
            needed: 2,
            got: track.n_frames(),
        });
    }
    Ok(())
}

/// The DP cost table over frame intervals: entry `(k, n)` is the fit error of
/// frames `k..=n` plus λ (`+∞` outside the allowed transition lengths).
/// Filled in parallel.
pub(crate) fn transition_costs(track: &Track, params: &SegmentParams) -> Result<CostTable> {
    params.validate()?;
    check_track(track, params.n_joints, "spline segmentation")?;
    let data = JointData::new(track, params.min_confidence);
    let fit = fit_params(params.norm);
    let n_int = track.n_frames() - 1;
    let window = params.max_transition_frames.min(n_int).max(1);
    let min_len = params.min_transition_frames;
    CostTable::try_from_fn_parallel(n_int, window, |k, n| {
        if n - k < min_len && !(k == 0 && n == n_int) {
            // Too short, unless it is the whole (short) sequence.
            return Ok(f64::INFINITY);
        }
        let (_, e) = transition_fit(&data, &fit, params, k, n)?;
        Ok(e + params.lambda)
    })
}

/// Segments a track into anchors and transitions (see the module docs).
///
/// Errors: invalid parameters (e.g. λ < 0); fewer than 2 frames; a joint
/// count other than [`SegmentParams::n_joints`]; non-finite fits.
pub fn segment_track(track: &Track, params: &SegmentParams) -> Result<Segmentation3d> {
    let table = transition_costs(track, params)?;
    let seg: Segmentation =
        Segmentation::dp(table.n_frames(), table.window(), |k, n| table.get(k, n))?;
    from_anchors(track, &seg.boundaries, params, seg.cost)
}

/// Builds the transitions for given anchors (increasing, first 0, last T − 1).
pub fn segmentation_from_anchors(
    track: &Track,
    anchors: &[usize],
    params: &SegmentParams,
) -> Result<Segmentation3d> {
    params.validate()?;
    check_track(track, params.n_joints, "segmentation_from_anchors")?;
    let t = track.n_frames();
    if anchors.first() != Some(&0) || anchors.last() != Some(&(t - 1)) {
        return Err(RefineError::param(
            "anchors",
            format!("must start at frame 0 and end at frame {}", t - 1),
        ));
    }
    if anchors.windows(2).any(|w| w[1] <= w[0]) {
        return Err(RefineError::param("anchors", "must be strictly increasing"));
    }
    from_anchors(track, anchors, params, f64::NAN)
}

fn from_anchors(
    track: &Track,
    anchors: &[usize],
    params: &SegmentParams,
    cost: f64,
) -> Result<Segmentation3d> {
    let data = JointData::new(track, params.min_confidence);
    let fit = fit_params(params.norm);
    let transitions = anchors
        .windows(2)
        .collect::<Vec<_>>()
        .into_par_iter()
        .map(|w| {
            let (splines, error) = transition_fit(&data, &fit, params, w[0], w[1])?;
            Ok(SplineTransition {
                start: w[0],
                end: w[1],
                splines,
                error,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let cost = if cost.is_nan() {
        transitions.iter().map(|t| t.error + params.lambda).sum()
    } else {
        cost
    };
    Ok(Segmentation3d {
        anchors: anchors.to_vec(),
        transitions,
        n_frames: track.n_frames(),
        n_joints: track.n_joints(),
        dims: track.dims(),
        cost,
    })
}

/// Mean Euclidean joint error between two pose sequences **without any
/// alignment** (absolute positions), over joints valid in `reference`
/// (confidence > 0), in track units. This is the MPJPE used for
/// reconstruction and refinement here: root alignment would hide flaws that
/// move the whole body (a temporal jump, a wrong anchor's root).
pub fn mpjpe_abs(pred: &Track, reference: &Track) -> Result<f64> {
    check_same_shape(
        pred,
        reference.n_frames(),
        reference.n_joints(),
        reference.dims(),
        "mpjpe_abs",
    )?;
    let per = per_frame_error(pred.positions(), reference);
    let v: Vec<f64> = per.into_iter().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return Err(RefineError::NonFinite(
            "mpjpe_abs: no valid joint in the reference".into(),
        ));
    }
    Ok(v.iter().sum::<f64>() / v.len() as f64)
}

/// Mean joint error per frame (NaN where the reference has no valid joint).
pub fn per_frame_error(pred: ndarray::ArrayView3<'_, f64>, reference: &Track) -> Vec<f64> {
    let r = reference.positions();
    let c = reference.confidence();
    let (t, j, d) = r.dim();
    (0..t)
        .map(|f| {
            let mut s = 0.0;
            let mut n = 0usize;
            for jj in 0..j {
                if c[[f, jj]] <= 0.0 {
                    continue;
                }
                let mut e = 0.0;
                for k in 0..d {
                    let x = pred[[f, jj, k]] - r[[f, jj, k]];
                    e += x * x;
                }
                s += e.sqrt();
                n += 1;
            }
            if n == 0 {
                f64::NAN
            } else {
                s / n as f64
            }
        })
        .collect()
}
